// tridiff_heat_adi: the heat equation by ADI on MPI ranks (heat_adi.hpp), checked against the
// analytic solution; with --compare, the two ways of solving along the cut axis timed side by
// side. Only rank 0 prints.
//   mpirun -n 2 tridiff_heat_adi [--dims 2|3] [--n N] [--steps S] [--dt DT]
//                                [--strategy distributed|transpose] [--compare]
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "heat_adi.hpp"

namespace {

struct Arguments {
  int dims = 2;
  std::ptrdiff_t n = 255;
  int steps = 16;
  double dt = 0;  // 0: h, so that the time and space errors shrink together
  heat::Strategy strategy = heat::Strategy::Transpose;  // the faster here: docs/distributed.md
  bool compare = false;
};

Arguments parse(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(flag + " needs a value");
      return argv[++i];
    };
    if (flag == "--dims")
      a.dims = std::stoi(value());
    else if (flag == "--n")
      a.n = std::stol(value());
    else if (flag == "--steps")
      a.steps = std::stoi(value());
    else if (flag == "--dt")
      a.dt = std::stod(value());
    else if (flag == "--compare")
      a.compare = true;
    else if (flag == "--strategy") {
      const std::string name = value();
      if (name != "distributed" && name != "transpose")
        throw std::invalid_argument("--strategy is distributed or transpose, got " + name);
      a.strategy = name == "distributed" ? heat::Strategy::Distributed : heat::Strategy::Transpose;
    } else {
      throw std::invalid_argument("unknown argument " + flag);
    }
  }
  return a;
}

// Runs the steps; returns the seconds per step (slowest rank) and prints on rank 0.
void run(const Arguments& a, heat::Strategy strategy, int rank, int ranks) {
  const double dt = a.dt > 0 ? a.dt : 1.0 / double(a.n + 1);
  heat::HeatAdi solver(a.dims, a.n, dt, strategy, MPI_COMM_WORLD);
  MPI_Barrier(MPI_COMM_WORLD);
  const double start = MPI_Wtime();
  for (int s = 0; s < a.steps; ++s) solver.step();
  double seconds = MPI_Wtime() - start, cut = solver.seconds_on_cut_axis();
  MPI_Allreduce(MPI_IN_PLACE, &seconds, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &cut, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  const double error = solver.relative_error();
  if (rank == 0)
    std::printf(
        "%dD n=%td ranks=%d %-11s steps=%d dt=%.3g t=%.3g  relative error %.3e  "
        "step %.3f ms  cut-axis solve %.3f ms\n",
        a.dims, a.n, ranks, strategy == heat::Strategy::Distributed ? "distributed" : "transpose",
        a.steps, dt, solver.time(), error, 1e3 * seconds / a.steps, 1e3 * cut / a.steps);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, ranks = 1, status = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  try {
    const Arguments a = parse(argc, argv);
    if (a.compare) {
      run(a, heat::Strategy::Distributed, rank, ranks);
      run(a, heat::Strategy::Transpose, rank, ranks);
    } else {
      run(a, a.strategy, rank, ranks);
    }
  } catch (const std::exception& e) {
    if (rank == 0) std::fprintf(stderr, "tridiff_heat_adi: %s\n", e.what());
    status = 1;
  }
  MPI_Finalize();
  return status;
}
