// tridiff::solvers, installed: solves [4 1 0; 1 4 1; 0 1 4] x = (6, 12, 14), whose exact
// solution is x = (1, 2, 3), by every method, and checks that a bad call throws. Exits 0 only if
// every answer is right.
#include <tridiff/solvers.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

int main() {
  const double sub[3] = {0, 1, 1}, diag[3] = {4, 4, 4}, super[3] = {1, 1, 0};
  const double rhs[3] = {6, 12, 14};
  const double exact[3] = {1, 2, 3};
  // Forward error <= kappa * backward error <= 3 * 16 u * max|x|, with Varah's bound
  // kappa <= ||A|| / min_i(|b_i| - |a_i| - |c_i|) = 6 / 2 and u = eps / 2.
  const double tolerance = 3 * 16 * (std::numeric_limits<double>::epsilon() / 2) * 3;
  int failures = 0;
  for (tridiff::Method method : tridiff::kAllMethods) {
    double x[3] = {};
    tridiff::SolveOptions options;
    options.method = method;
    tridiff::solve(sub, diag, super, rhs, x, tridiff::BatchLayout::single(3), options);
    for (int i = 0; i < 3; ++i) {
      if (!(std::abs(x[i] - exact[i]) <= tolerance)) {
        std::printf("%s: x[%d] = %.17g, expected %g\n", tridiff::to_string(method), i, x[i],
                    exact[i]);
        ++failures;
      }
    }
  }
  try {
    double x[3];
    tridiff::solve(sub, diag, super, rhs, x, tridiff::BatchLayout::single(0));
    std::printf("n = 0 was accepted\n");
    ++failures;
  } catch (const tridiff::InvalidArgument& e) {
    if (e.argument() != "n") {
      std::printf("n = 0 blamed on '%s'\n", e.argument().c_str());
      ++failures;
    }
  }
  std::printf("%s\n", failures == 0 ? "tridiff consumer: ok" : "tridiff consumer: FAILED");
  return failures == 0 ? 0 : 1;
}
