// One long diffusion system: the parts-in-lanes path of solve_diffusion
// (detail/partitioned_diffusion.hpp), against Thomas on the expanded matrix in long double,
// written here. Conductances from 1e-3 to 1e7 (where a general-form elimination in float loses
// the 1 of 1 + 2 beta), runs of zero conductance, the sizes around the parts, strided and
// in-place storage, the maximum principle, and the bad-input and overflow fallbacks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

#include "tridiff/solvers/solve.hpp"

namespace tridiff::test {
namespace {

template <class T>
class LongDiffusion : public ::testing::Test {};
using Reals = ::testing::Types<float, double>;
TYPED_TEST_SUITE(LongDiffusion, Reals);

// -beta[i-1] x[i-1] + (1 + beta[i-1] + beta[i]) x[i] - beta[i] x[i+1] = d[i], by Thomas on the
// three diagonals in long double: independent of the code under test (no parts, no lanes, the
// textbook elimination with its subtractions, exact enough in 64 bits for beta <= 1e7).
template <class T>
std::vector<long double> long_double_diffusion(const std::vector<T>& beta,
                                               const std::vector<T>& d) {
  using W = long double;
  const std::ptrdiff_t n = std::ptrdiff_t(d.size());
  auto link = [&](std::ptrdiff_t i) { return i >= 0 && i + 1 < n ? W(beta[i]) : W(0); };
  std::vector<W> upper(n), x(n);
  W pivot = 1 + link(0);
  x[0] = W(d[0]) / pivot;
  for (std::ptrdiff_t i = 1; i < n; ++i) {
    upper[i - 1] = -link(i - 1) / pivot;
    pivot = 1 + link(i - 1) + link(i) + link(i - 1) * upper[i - 1];
    x[i] = (W(d[i]) + link(i - 1) * x[i - 1]) / pivot;
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) x[i] -= upper[i] * x[i + 1];
  return x;
}

// The same system by the diffusion kernel's subtraction-free elimination (diffusion_form.hpp),
// in long double: the reference for conductances beyond 2^64, where the textbook elimination
// above loses the 1 of 1 + beta + beta' even in long double. Independent of the parts and lanes
// (one sweep, 64-bit mantissa, the exponent range of 1e4932).
template <class T>
std::vector<long double> long_double_diffusion_without_subtractions(const std::vector<T>& beta,
                                                                    const std::vector<T>& d) {
  using W = long double;
  const std::ptrdiff_t n = std::ptrdiff_t(d.size());
  std::vector<W> multiplier(n), x(n);
  W beta_before = 0, e_before = 1, carry = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const W beta_here = i + 1 < n ? W(beta[i]) : W(0);
    const W g = 1 + beta_before * e_before;
    const W pivot = g + beta_here;
    carry = (W(d[i]) + beta_before * carry) / pivot;
    x[i] = carry;
    multiplier[i] = beta_here / pivot;
    e_before = g / pivot;
    beta_before = beta_here;
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) x[i] += multiplier[i] * x[i + 1];
  return x;
}

// Conductances log-uniform over [largest * 1e-4, largest], with a run of zeros (the system falls
// into independent pieces) and a run of the largest value; beta[n-1] is NaN: it is not part of
// the system and must not be read.
template <class T>
std::vector<T> conductances(std::ptrdiff_t n, double largest, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> exponent(-4, 0);
  std::vector<T> beta(n);
  for (auto& b : beta) b = T(largest * std::pow(10.0, exponent(random)));
  std::fill(beta.begin() + n / 3, beta.begin() + n / 3 + 700, T(0));
  std::fill(beta.begin() + n / 2, beta.begin() + n / 2 + 1500, T(largest));
  beta[n - 1] = std::numeric_limits<T>::quiet_NaN();
  return beta;
}

// A step between 0 and 1 every 97 rows, and noise in [0, 1] on a third of the rows.
template <class T>
std::vector<T> step_rhs(std::ptrdiff_t n, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<T> d(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) d[i] = T((i / 97) % 2);
  for (std::ptrdiff_t i = 0; i < n; i += 3) d[i] = T(unit(random));
  return d;
}

// The largest error over the system, relative to max |d| (the diffusion matrix's inverse has
// row sums 1, so that is the scale of x).
template <class T>
double relative_error(const std::vector<T>& x, const std::vector<long double>& reference,
                      const std::vector<T>& d) {
  long double scale = 0, error = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    scale = std::max(scale, std::fabs((long double)d[i]));
    error = std::max(error, std::fabs((long double)x[i] - reference[i]));
  }
  return double(error / scale);
}

template <class T>
SolveReport solve_long(const std::vector<T>& beta, const std::vector<T>& d, std::vector<T>& x,
                       int threads, std::ptrdiff_t stride = 1) {
  const std::ptrdiff_t n = std::ptrdiff_t(d.size());
  SolveOptions options;
  options.threads = threads;
  if (stride == 1)
    return solve_diffusion(beta.data(), d.data(), x.data(), BatchLayout::single(n), options);
  // Stored as an image column: NaN between the rows, which a stray read would carry into x.
  const T nan = std::numeric_limits<T>::quiet_NaN();
  std::vector<T> beta_s((n - 1) * stride + 1, nan), d_s(beta_s.size(), nan), x_s(beta_s.size());
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    beta_s[i * stride] = beta[i];
    d_s[i * stride] = d[i];
  }
  const SolveReport report =
      solve_diffusion(beta_s.data(), d_s.data(), x_s.data(), BatchLayout{n, 1, stride, 1}, options);
  for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = x_s[i * stride];
  return report;
}

// Measured on the first test's cases: at most 8.2 eps (float) and 41 eps (double, at beta up to
// 1e7, where the system's condition grows), against 13.4 and 41.7 eps for the scalar kernel
// (diffusion_thomas) on the same systems.
template <class T>
double error_bound() {
  return 64 * std::numeric_limits<T>::epsilon();
}

TYPED_TEST(LongDiffusion, MatchesLongDoubleAtEveryConductanceScale) {
  using T = TypeParam;
  const std::ptrdiff_t n = (std::ptrdiff_t(1) << 16) + 1;
  const auto d = step_rhs<T>(n, 3);
  for (double largest : {1e-3, 1.0, 1e3, 1e7}) {
    const auto beta = conductances<T>(n, largest, 17);
    const auto reference = long_double_diffusion(beta, d);
    for (int threads : {1, 2}) {
      SCOPED_TRACE(::testing::Message()
                   << "beta up to " << largest << ", " << threads << " threads");
      std::vector<T> x(n);
      const SolveReport report = solve_long(beta, d, x, threads);
      EXPECT_GT(report.parts, 1);  // the parts path, not one scalar sweep
      EXPECT_LE(relative_error(x, reference, d), error_bound<T>());
      // The maximum principle: x is a convex combination of d, which lies in [0, 1].
      const auto [low, high] = std::minmax_element(x.begin(), x.end());
      EXPECT_GE(*low, T(0));
      EXPECT_LE(*high, T(1) + 4 * std::numeric_limits<T>::epsilon());
    }
  }
}

// The sizes around the cut: the first size on the path, 2^k - 1, 2^k + 1, a whole number of
// parts (the last row, n-1, is then a separator, read straight from the caller's arrays) and
// one row on either side of it, signed rhs.
TYPED_TEST(LongDiffusion, EverySizeAroundThePartsMatches) {
  using T = TypeParam;
  constexpr int W = detail::kPartLanes<T>;
  constexpr std::ptrdiff_t line = 64 / sizeof(T);
  const std::ptrdiff_t whole = 8 * W * (detail::kPartRowsTarget / line - 1) * line;
  const auto cut = detail::make_part_layout<T, W>(whole, 2);
  ASSERT_EQ(cut.parts * cut.rows, whole);  // eight groups of parts of 31 (float) lines each
  for (std::ptrdiff_t n : {detail::kPartitionedMinRows, (std::ptrdiff_t(1) << 17) - 1,
                           (std::ptrdiff_t(1) << 17) + 1, whole - 1, whole, whole + 1}) {
    std::mt19937_64 random(n);
    std::uniform_real_distribution<double> signed_unit(-1, 1);
    std::vector<T> d(n);
    for (auto& v : d) v = T(signed_unit(random));
    const auto beta = conductances<T>(n, 50.0, n + 1);
    const auto reference = long_double_diffusion(beta, d);
    for (int threads : {1, 2}) {
      SCOPED_TRACE(::testing::Message() << "n = " << n << ", " << threads << " threads");
      std::vector<T> x(n);
      EXPECT_GT(solve_long(beta, d, x, threads).parts, 1);
      EXPECT_LE(relative_error(x, reference, d), error_bound<T>());
    }
  }
}

TYPED_TEST(LongDiffusion, StridedAndInPlaceSolvesMatch) {
  using T = TypeParam;
  const std::ptrdiff_t n = detail::kPartitionedMinRows + 5;
  const auto d = step_rhs<T>(n, 5);
  const auto beta = conductances<T>(n, 1e3, 9);
  const auto reference = long_double_diffusion(beta, d);
  std::vector<T> x(n);
  solve_long(beta, d, x, 2, 3);
  EXPECT_LE(relative_error(x, reference, d), error_bound<T>());
  std::vector<T> in_place = d;
  SolveOptions options;
  options.threads = 2;
  EXPECT_GT(solve_diffusion(beta.data(), in_place.data(), in_place.data(), BatchLayout::single(n),
                            options)
                .parts,
            1);
  EXPECT_LE(relative_error(in_place, reference, d), error_bound<T>());
}

// Conductances near the top of the range: the parts' decaying values (the responses to a
// separator, the products of multipliers) must not be dropped where a huge link multiplies
// them again. Two patterns: "glue", every link 0.5 or huge (one in ten), and huge links on
// both sides of every separator with 1e6 inside the parts. Then links above max() / 2 on both
// sides of a part's first row, whose diagonal overflows: the path must notice and hand the
// system to the scalar kernel.
TYPED_TEST(LongDiffusion, HugeConductancesStayAccurate) {
  using T = TypeParam;
  constexpr int W = detail::kPartLanes<T>;
  const std::ptrdiff_t n = 100003;
  const T huge = std::is_same_v<T, float> ? T(1e30) : T(1e300);
  std::mt19937_64 random(8);
  std::uniform_real_distribution<double> signed_unit(-1, 1);
  std::vector<T> d(n);
  for (auto& v : d) v = T(signed_unit(random));
  for (int threads : {1, 2}) {
    const std::ptrdiff_t rows = detail::make_part_layout<T, W>(n, threads).rows;
    std::vector<T> glue(n), separated(n, T(1e6)), overflowing(n, T(1));
    for (auto& b : glue) b = random() % 10 == 0 ? huge : T(0.5);
    for (std::ptrdiff_t i = rows - 1; i < n; i += rows) {
      separated[i - 1] = separated[i] = huge;
      separated[i - 2] = huge;
    }
    overflowing[3 * rows - 1] = overflowing[3 * rows] = std::numeric_limits<T>::max() * T(0.6);
    for (const auto* beta : {&glue, &separated, &overflowing}) {
      SCOPED_TRACE(::testing::Message() << (beta == &glue        ? "glue"
                                            : beta == &separated ? "separators"
                                                                 : "overflowing")
                                        << ", " << threads << " threads");
      std::vector<T> x(n);
      solve_long(*beta, d, x, threads);
      EXPECT_LE(relative_error(x, long_double_diffusion_without_subtractions(*beta, d), d),
                error_bound<T>());
    }
  }
}

// Bad input on the path: the error names the argument and the row, as for short systems, and a
// failed in-place solve leaves rhs as it was.
TYPED_TEST(LongDiffusion, BadInputNamesTheRowAndLeavesRhsAlone) {
  using T = TypeParam;
  const std::ptrdiff_t n = detail::kPartitionedMinRows * 2 + 3;
  const auto d = step_rhs<T>(n, 2);
  const auto good_beta = conductances<T>(n, 1.0, 4);
  struct Case {
    const char* argument;
    std::ptrdiff_t row;
    T value;
  };
  const T nan = std::numeric_limits<T>::quiet_NaN();
  for (const Case& bad :
       {Case{"beta", 12345, nan}, Case{"beta", n - 2, T(-0.5)},
        Case{"rhs", 40000, std::numeric_limits<T>::infinity()}, Case{"rhs", n - 1, nan}}) {
    SCOPED_TRACE(::testing::Message() << bad.argument << " at row " << bad.row);
    auto beta = good_beta;
    auto rhs = d;
    (std::string(bad.argument) == "beta" ? beta : rhs)[bad.row] = bad.value;
    const auto before = rhs;
    SolveOptions options;
    options.threads = 2;
    try {
      solve_diffusion(beta.data(), rhs.data(), rhs.data(), BatchLayout::single(n), options);
      ADD_FAILURE() << "bad input accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_EQ(e.argument(), bad.argument);
      EXPECT_EQ(e.row(), bad.row);
    }
    for (std::ptrdiff_t i = 0; i < n; ++i)
      if (!(rhs[i] == before[i] || (std::isnan(rhs[i]) && std::isnan(before[i]))))
        FAIL() << "rhs changed at row " << i;
  }
}

// An rhs near max(): the solution (here equal to the rhs) is representable, the eliminated
// values on the way are not; the solve falls back to the rescaling kernel and does not report
// an overflow.
TYPED_TEST(LongDiffusion, RhsNearTheLargestValueIsSolved) {
  using T = TypeParam;
  const std::ptrdiff_t n = detail::kPartitionedMinRows + 1;
  const T huge = std::numeric_limits<T>::max() * T(0.9);
  std::vector<T> beta(n, T(1)), d(n, huge), x(n);
  SolveOptions options;
  options.threads = 2;
  solve_diffusion(beta.data(), d.data(), x.data(), BatchLayout::single(n), options);
  for (std::ptrdiff_t i = 0; i < n; i += 997)
    EXPECT_NEAR(double(x[i] / huge), 1.0, 64 * std::numeric_limits<T>::epsilon()) << "row " << i;
}

}  // namespace
}  // namespace tridiff::test
