// tridiff::distributed, installed: MPI initialised as a singleton (one rank, no mpirun), the
// system [4 1 0; 1 4 1; 0 1 4] x = (6, 12, 14), exact solution (1, 2, 3), solved across the
// ranks of MPI_COMM_WORLD, and MPI_COMM_NULL refused by name. Exits 0 only if both hold.
#include <mpi.h>
#include <tridiff/distributed/solve.hpp>

#include <cmath>
#include <cstdio>
#include <limits>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int failures = 0;
  int ranks = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (ranks == 1) {  // the whole system on this rank
    const double sub[3] = {0, 1, 1}, diag[3] = {4, 4, 4}, super[3] = {1, 1, 0};
    const double rhs[3] = {6, 12, 14}, exact[3] = {1, 2, 3};
    double x[3] = {};
    tridiff::distributed::solve(sub, diag, super, rhs, x, tridiff::BatchLayout::single(3),
                                MPI_COMM_WORLD);
    // Forward error <= kappa * 16 u * max|x| with kappa <= 6 / 2 (Varah), as the solvers'
    // consumer.
    const double tolerance = 3 * 16 * (std::numeric_limits<double>::epsilon() / 2) * 3;
    for (int i = 0; i < 3; ++i)
      if (!(std::abs(x[i] - exact[i]) <= tolerance)) {
        std::printf("x[%d] = %.17g, expected %g\n", i, x[i], exact[i]);
        ++failures;
      }
  }
  try {
    const double one = 1;
    double x = 0;
    tridiff::distributed::solve(&one, &one, &one, &one, &x, tridiff::BatchLayout::single(1),
                                MPI_COMM_NULL);
    std::printf("MPI_COMM_NULL was accepted\n");
    ++failures;
  } catch (const tridiff::InvalidArgument& e) {
    if (e.argument() != "comm") {
      std::printf("MPI_COMM_NULL blamed on '%s'\n", e.argument().c_str());
      ++failures;
    }
  }
  std::printf("%s\n", failures == 0 ? "tridiff distributed consumer: ok"
                                    : "tridiff distributed consumer: FAILED");
  MPI_Finalize();
  return failures == 0 ? 0 : 1;
}
