// Every method, scalar type and size against Eigen's LU in long double: forward and backward
// error within bounds derived from the unit roundoff, the size and the condition number.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "reference.hpp"

namespace tridiff::test {
namespace {

constexpr std::ptrdiff_t kSizes[] = {1, 2, 3, 4, 5, 7, 8, 15, 16, 17, 31, 32, 33, 1000, 65537};

template <class T>
class SolverAccuracy : public ::testing::Test {};
using Scalars = ::testing::Types<float, double, std::complex<float>, std::complex<double>>;
TYPED_TEST_SUITE(SolverAccuracy, Scalars);

template <class T>
void check_every_method(bool periodic) {
  for (std::ptrdiff_t n : kSizes) {
    const auto system = random_dominant<T>(n, 1000 + n, periodic);
    const auto reference = reference_solve(system);
    const long double kappa = condition_bound(system);
    for (Method method : kAllMethods) {
      SCOPED_TRACE(::testing::Message() << "n = " << n << ", method = " << to_string(method)
                                        << (periodic ? ", periodic" : ""));
      SolveOptions options;
      options.method = method;
      const auto x = solve_system(system, options);
      const long double eta = backward_error(system, x);
      EXPECT_LE(eta, backward_bound<T>(method, n));
      EXPECT_LE(forward_error(x, reference), kappa * backward_bound<T>(method, n));
    }
  }
}

TYPED_TEST(SolverAccuracy, EveryMethodMatchesLongDoubleLu) { check_every_method<TypeParam>(false); }

TYPED_TEST(SolverAccuracy, PeriodicSystemsMatchLongDoubleLu) {
  check_every_method<TypeParam>(true);
}

// Partial pivoting on random matrices that are far from dominant, with b[0] = 0 so that
// elimination without pivoting would divide by zero at once.
TYPED_TEST(SolverAccuracy, PivotingSolvesNonDominantSystems) {
  using T = TypeParam;
  for (std::ptrdiff_t n : {2, 3, 16, 1000}) {
    System<T> system;
    std::mt19937_64 random(n);
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      system.a.push_back(i > 0 ? random_scalar<T>(random, -1, 1) : T(0));
      system.b.push_back(i > 0 ? random_scalar<T>(random, -1, 1) : T(0));
      system.c.push_back(i + 1 < n ? random_scalar<T>(random, -1, 1) : T(0));
      system.d.push_back(random_scalar<T>(random, -1, 1));
    }
    SCOPED_TRACE(::testing::Message() << "n = " << n);
    for (Method method : {Method::Pivoting, Method::Auto}) {
      SolveOptions options;
      options.method = method;
      const auto x = solve_system(system, options);
      EXPECT_LE(backward_error(system, x), backward_bound<T>(Method::Pivoting, n));
    }
  }
}

// The exact answer is known: for A = tridiag(-1, 2, -1) and x_i = i + 1, d = A x is zero
// inside and (0, ..., 0, n + 1) at the last row.
TEST(SolverAccuracy, PoissonMatrixKnownSolution) {
  const std::ptrdiff_t n = 100;
  std::vector<double> a(n, -1.0), b(n, 2.0), c(n, -1.0), d(n, 0.0), x(n);
  d[n - 1] = n + 1.0;
  for (Method method : kAllMethods) {
    SolveOptions options;
    options.method = method;
    solve(a.data(), b.data(), c.data(), d.data(), x.data(), BatchLayout::single(n), options);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      ASSERT_NEAR(x[i], i + 1.0, 1e-12 * n * n) << to_string(method) << " row " << i;
  }
}

}  // namespace
}  // namespace tridiff::test
