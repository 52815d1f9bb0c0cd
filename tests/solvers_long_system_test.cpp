// One long system: the parts-in-lanes path of Thomas and Auto (detail/partitioned_lanes.hpp)
// and the single-system pivoting path, against a long-double Thomas written here (dominant
// systems) and Eigen's dense LU (small n); refusals, fallbacks and error rows.
#include <gtest/gtest.h>

#include <complex>
#include <vector>

#include "reference.hpp"

namespace tridiff::test {
namespace {

template <class T>
class LongSystem : public ::testing::Test {};
using Scalars = ::testing::Types<float, double, std::complex<float>, std::complex<double>>;
TYPED_TEST_SUITE(LongSystem, Scalars);

// Thomas in long double: stable on the dominant systems it is used for, and independent of
// the code under test (no parts, no lanes, no float rounding).
template <class T>
WideVector<T> long_double_thomas(const System<T>& s) {
  using W = Wide<T>;
  const std::ptrdiff_t n = s.n();
  std::vector<W> upper(n);
  WideVector<T> x(n);
  W pivot = W(s.b[0]);
  x[0] = W(s.d[0]) / pivot;
  for (std::ptrdiff_t i = 1; i < n; ++i) {
    upper[i - 1] = W(s.c[i - 1]) / pivot;
    pivot = W(s.b[i]) - W(s.a[i]) * upper[i - 1];
    x[i] = (W(s.d[i]) - W(s.a[i]) * x[i - 1]) / pivot;
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) x[i] -= upper[i] * x[i + 1];
  return x;
}

// random_dominant's matrix (dominant by rows, in modulus).
template <class T>
System<T> dominant_system(std::ptrdiff_t n, std::uint64_t seed) {
  return random_dominant<T>(n, seed);
}

// The independent reference: dense LU where Eigen can afford it, long-double Thomas beyond.
template <class T>
WideVector<T> reference_of(const System<T>& s) {
  return s.n() <= 64 ? reference_solve(s) : long_double_thomas(s);
}

// The system stored with `stride` elements between equations (as an image column), the
// entries in between filled with NaN so that a read of one of them shows.
template <class T>
std::vector<T> strided(const std::vector<T>& values, std::ptrdiff_t stride) {
  std::vector<T> out((values.size() - 1) * stride + 1,
                     T(std::numeric_limits<real_t<T>>::quiet_NaN()));
  for (std::size_t i = 0; i < values.size(); ++i) out[i * stride] = values[i];
  return out;
}

template <class T>
std::vector<T> solve_strided(const System<T>& s, SolveOptions options, std::ptrdiff_t stride,
                             SolveReport* report = nullptr) {
  const auto a = strided(s.a, stride), b = strided(s.b, stride), c = strided(s.c, stride),
             d = strided(s.d, stride);
  std::vector<T> x(d.size());
  const BatchLayout layout{s.n(), 1, stride, 1};
  const SolveReport r = solve(a.data(), b.data(), c.data(), d.data(), x.data(), layout, options);
  if (report != nullptr) *report = r;
  std::vector<T> out(s.n());
  for (std::ptrdiff_t i = 0; i < s.n(); ++i) out[i] = x[i * stride];
  return out;
}

template <class T>
void expect_accurate(const System<T>& s, const std::vector<T>& x, Method method) {
  const auto reference = reference_of(s);
  const long double bound = backward_bound<T>(method, s.n());
  EXPECT_LE(backward_error(s, x), bound);
  EXPECT_LE(forward_error(x, reference), condition_bound(s) * bound);
}

// Sizes on the path: its first size, 2^16 + 1, and one row past three whole groups of parts
// (a group is `lanes` parts of about kPartRowsTarget rows); the small sizes and the part
// boundaries are the next test's.
std::vector<std::ptrdiff_t> long_sizes(std::ptrdiff_t lanes) {
  return {detail::kPartitionedMinRows, (1 << 16) + 1, 3 * lanes * detail::kPartRowsTarget + 1};
}

TYPED_TEST(LongSystem, ThomasAndAutoMatchTheReference) {
  using T = TypeParam;
  for (std::ptrdiff_t n : long_sizes(detail::kPartLanes<T>)) {
    const auto system = dominant_system<T>(n, 7 + n);
    for (Method method : {Method::Thomas, Method::Auto})
      for (int threads : {1, 2}) {
        if (method == Method::Auto && threads == 1) continue;  // the same path as Thomas
        SCOPED_TRACE(::testing::Message()
                     << "n = " << n << ", " << to_string(method) << ", " << threads << " threads");
        SolveOptions options;
        options.method = method;
        options.threads = threads;
        SolveReport report;
        const auto x = solve_strided(system, options, 1, &report);
        if (n >= detail::kPartitionedMinRows) {
          EXPECT_GT(report.parts, 1);  // the parts path, not one scalar sweep
        }
        EXPECT_EQ(report.pivoted_systems, 0);
        expect_accurate(system, x, Method::Thomas);
      }
  }
}

// The kernel itself at the sizes solve() sends elsewhere: one part, a system shorter than one
// group (rows past its end are padding), and a last part full, one row short and one row over.
TYPED_TEST(LongSystem, PartsInLanesMatchDenseLuAtEverySmallSize) {
  using T = TypeParam;
  const auto cut = detail::make_part_layout<T, detail::kPartLanes<T>>(20000, 1);
  const std::ptrdiff_t full = (20000 + cut.rows - 1) / cut.rows * cut.rows;
  for (std::ptrdiff_t n : {std::ptrdiff_t(1), std::ptrdiff_t(2), std::ptrdiff_t(3),
                           std::ptrdiff_t(17), std::ptrdiff_t(1000), full - 1, full, full + 1}) {
    const auto system = dominant_system<T>(n, 100 + n);
    for (int threads : {1, 2}) {
      SCOPED_TRACE(::testing::Message() << "n = " << n << ", " << threads << " threads");
      std::vector<T> x(n);
      const detail::SystemView<T> view{{system.a.data(), 1},
                                       {system.b.data(), 1},
                                       {system.c.data(), 1},
                                       {system.d.data(), 1},
                                       n,
                                       false};
      for (bool check : {false, true}) {
        SCOPED_TRACE(check ? "checked" : "unchecked");
        ASSERT_EQ(detail::partitioned_lanes(view, detail::Strided<T>{x.data(), 1}, threads, check),
                  detail::PartOutcome::Solved);
        expect_accurate(system, x, Method::Thomas);
      }
    }
  }
}

TYPED_TEST(LongSystem, StridedAndInPlaceSolvesMatch) {
  using T = TypeParam;
  const std::ptrdiff_t n = detail::kPartitionedMinRows + 5;
  const auto system = dominant_system<T>(n, 3);
  for (Method method : {Method::Thomas, Method::Pivoting}) {
    SCOPED_TRACE(to_string(method));
    SolveOptions options;
    options.method = method;
    options.threads = 2;
    expect_accurate(system, solve_strided(system, options, 3), method);
    std::vector<T> in_place = system.d;
    solve_in_place(system.a.data(), system.b.data(), system.c.data(), in_place.data(),
                   BatchLayout::single(n), options);
    expect_accurate(system, in_place, method);
  }
}

TYPED_TEST(LongSystem, PivotingMatchesTheReferenceOnLongDominantSystems) {
  using T = TypeParam;
  for (std::ptrdiff_t n : {detail::kPartitionedMinRows, std::ptrdiff_t(1) << 16 | 1}) {
    SCOPED_TRACE(::testing::Message() << "n = " << n);
    const auto system = dominant_system<T>(n, 11 + n);
    SolveOptions options;
    options.method = Method::Pivoting;
    expect_accurate(system, solve_strided(system, options, 1), Method::Pivoting);
  }
}

// About a million rows, the size the path is for (float: the errors in long double take
// most of the time).
TEST(LongSystemMillion, FloatMatchesTheReference) {
  const auto system = dominant_system<float>(1000003, 5);
  SolveOptions options;
  options.threads = 2;
  expect_accurate(system, solve_strided(system, options, 1), Method::Thomas);
}

// A long random matrix far from dominant: Auto pivots it, Thomas refuses it.
template <class T>
System<T> long_nondominant(std::ptrdiff_t n) {
  System<T> s;
  std::mt19937_64 random(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    s.a.push_back(i > 0 ? random_scalar<T>(random, -1, 1) : T(0));
    s.b.push_back(random_scalar<T>(random, -1, 1));
    s.c.push_back(i + 1 < n ? random_scalar<T>(random, -1, 1) : T(0));
    s.d.push_back(random_scalar<T>(random, -1, 1));
  }
  return s;
}

TYPED_TEST(LongSystem, NonDominantSystemIsPivotedByAutoAndRefusedByThomas) {
  using T = TypeParam;
  const std::ptrdiff_t n = detail::kPartitionedMinRows + 17;
  const auto system = long_nondominant<T>(n);
  SolveOptions options;
  options.threads = 2;
  SolveReport report;
  const auto x = solve_strided(system, options, 1, &report);
  EXPECT_EQ(report.pivoted_systems, 1);
  EXPECT_LE(backward_error(system, x), backward_bound<T>(Method::Pivoting, n));
  options.method = Method::Thomas;
  EXPECT_THROW(solve_strided(system, options, 1), NumericalError);
}

// b = 4, a = c = 0.5, with rows a = c = 3 (not dominant; columns still are: 3 + 0.5 <= 4) at
// `row_failures`, and columns c = 3 above, a = 3 below (not dominant; rows still are) at
// `column_failures`. Rows and columns two or more apart.
template <class T>
System<T> rows_and_columns_failing(std::ptrdiff_t n,
                                   const std::vector<std::ptrdiff_t>& row_failures,
                                   const std::vector<std::ptrdiff_t>& column_failures) {
  System<T> s;
  std::mt19937_64 random(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    s.a.push_back(T(i > 0 ? 0.5 : 0));
    s.b.push_back(T(4));
    s.c.push_back(T(i + 1 < n ? 0.5 : 0));
    s.d.push_back(random_scalar<T>(random, -1, 1));
  }
  for (std::ptrdiff_t i : row_failures) s.a[i] = s.c[i] = T(3);
  for (std::ptrdiff_t j : column_failures) s.c[j - 1] = s.a[j + 1] = T(3);
  return s;
}

// The dominance test fused into the parts' first step judges rows and columns across the
// parts' ends (a column's neighbours there lie in two parts, and two groups): a matrix
// dominant by columns only is solved by the fused path; rows failing in one group and a
// column at a part's first row failing in another make it dominant neither way: the fused
// test leaves it to the exact one, which has Thomas name the first failing row and Auto pivot.
TYPED_TEST(LongSystem, FusedDominanceTestJudgesRowsAndColumnsAcrossParts) {
  using T = TypeParam;
  const std::ptrdiff_t n = (std::ptrdiff_t(1) << 16) + 5;
  const int threads = 2;
  const std::ptrdiff_t rows = detail::make_part_layout<T, detail::kPartLanes<T>>(n, threads).rows;
  const std::ptrdiff_t group = rows * detail::kPartLanes<T>;
  ASSERT_GT(n, 2 * group) << "the test wants rows in two groups";
  const std::vector<std::ptrdiff_t> failing_rows = {rows * 3, rows * 5 - 1, rows * 7 + 40, n - 3};
  auto solve_fused = [&](const System<T>& system, std::vector<T>& x) {
    const detail::SystemView<T> view{{system.a.data(), 1},
                                     {system.b.data(), 1},
                                     {system.c.data(), 1},
                                     {system.d.data(), 1},
                                     n,
                                     false};
    return detail::partitioned_lanes(view, detail::Strided<T>{x.data(), 1}, threads, true);
  };
  {
    SCOPED_TRACE("dominant by columns only");
    const auto system = rows_and_columns_failing<T>(n, failing_rows, {});
    std::vector<T> x(n);
    ASSERT_EQ(solve_fused(system, x), detail::PartOutcome::Solved);
    // Thomas is backward stable on matrices dominant by columns too. (condition_bound is
    // Varah's bound by rows, which does not apply; kappa_1 <= 7.5 / 0.5 by columns, and the
    // forward error, measured at 2 ulps, is held to a loose multiple of the backward bound.)
    const long double bound = backward_bound<T>(Method::Thomas, n);
    EXPECT_LE(backward_error(system, x), bound);
    EXPECT_LE(forward_error(x, reference_of(system)), 100 * bound);
  }
  {
    // -1 2 -1: weakly dominant, accepted by the fused test as by the exact one.
    SCOPED_TRACE("weakly dominant");
    auto system = rows_and_columns_failing<T>(n, {}, {});
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      system.a[i] = T(i > 0 ? -1 : 0);
      system.b[i] = T(2);
      system.c[i] = T(i + 1 < n ? -1 : 0);
    }
    std::vector<T> x(n);
    ASSERT_EQ(solve_fused(system, x), detail::PartOutcome::Solved);
    EXPECT_LE(backward_error(system, x), backward_bound<T>(Method::Thomas, n));
  }
  // Rows failing as above, and one column: inside a part, at a part's last row, or the
  // system's last column (inside the last, padded part). Not dominant either way, so the
  // fused test must refuse; it would accept (by columns) if it missed that column.
  for (const std::ptrdiff_t column : {group + rows * 2 + 100, rows * 6 - 1, n - 1}) {
    SCOPED_TRACE(::testing::Message() << "column " << column << " not dominant");
    auto system = rows_and_columns_failing<T>(
        n, failing_rows, column < n - 1 ? std::vector{column} : std::vector<std::ptrdiff_t>{});
    if (column == n - 1) {  // no row below: |b| = 1 against |c| = 2 above (rows n-2, n-1 hold)
      system.b[n - 1] = T(1);
      system.c[n - 2] = T(2);
    }
    std::vector<T> x(n, T(7));
    EXPECT_EQ(solve_fused(system, x), detail::PartOutcome::NotChecked);
  }
  {
    SCOPED_TRACE("dominant neither way");
    const std::ptrdiff_t column = group + rows * 2;  // a part's first row, in the second group
    const auto system = rows_and_columns_failing<T>(n, failing_rows, {column});
    std::vector<T> x(n, T(7));
    ASSERT_EQ(solve_fused(system, x), detail::PartOutcome::NotChecked);
    EXPECT_EQ(x, std::vector<T>(n, T(7))) << "nothing written";
    SolveOptions options;
    options.threads = threads;
    options.method = Method::Thomas;
    try {
      solve_strided(system, options, 1);
      ADD_FAILURE() << "no error";
    } catch (const NumericalError& error) {
      EXPECT_EQ(error.row(), failing_rows[0]);
    }
    options.method = Method::Auto;
    SolveReport report;
    const auto pivoted = solve_strided(system, options, 1, &report);
    EXPECT_EQ(report.pivoted_systems, 1);
    EXPECT_LE(backward_error(system, pivoted), backward_bound<T>(Method::Pivoting, n));
  }
}

// A zero row inside part k: the pivot vanishes there; Thomas names that row, and an in-place
// solve leaves rhs as it was.
TYPED_TEST(LongSystem, ZeroPivotInAPartNamesItsRowAndKeepsRhs) {
  using T = TypeParam;
  const std::ptrdiff_t n = std::ptrdiff_t(1) << 16;
  const auto cut = detail::make_part_layout<T, detail::kPartLanes<T>>(n, 2);
  for (std::ptrdiff_t row : {cut.rows * 5, cut.rows * 5 + 1, cut.rows * 7 - 1, cut.rows * 9 + 17}) {
    SCOPED_TRACE(::testing::Message() << "row " << row << " (parts of " << cut.rows << ")");
    auto system = dominant_system<T>(n, 21);
    system.a[row] = system.b[row] = system.c[row] = T(0);
    SolveOptions options;
    options.method = Method::Thomas;
    options.threads = 2;
    std::vector<T> rhs = system.d;
    try {
      solve_in_place(system.a.data(), system.b.data(), system.c.data(), rhs.data(),
                     BatchLayout::single(n), options);
      ADD_FAILURE() << "no error";
    } catch (const NumericalError& error) {
      EXPECT_EQ(error.row(), row);
      EXPECT_EQ(error.system(), 0);
    }
    EXPECT_EQ(rhs, system.d);
  }
}

TYPED_TEST(LongSystem, NonFiniteInputNamesItsRowAndKeepsRhs) {
  using T = TypeParam;
  const std::ptrdiff_t n = detail::kPartitionedMinRows * 2 + 3;
  const std::ptrdiff_t row = n / 3;
  const T nan = T(std::numeric_limits<real_t<T>>::quiet_NaN());
  for (Method method : {Method::Auto, Method::Thomas, Method::Pivoting})
    for (const char* argument : {"rhs", "diag"}) {
      SCOPED_TRACE(::testing::Message() << to_string(method) << ", NaN in " << argument);
      auto system = dominant_system<T>(n, 4);
      (std::string(argument) == "rhs" ? system.d : system.b)[row] = nan;
      SolveOptions options;
      options.method = method;
      options.threads = 2;
      std::vector<T> rhs = system.d;
      try {
        solve_in_place(system.a.data(), system.b.data(), system.c.data(), rhs.data(),
                       BatchLayout::single(n), options);
        ADD_FAILURE() << "no error";
      } catch (const InvalidArgument& error) {
        EXPECT_EQ(error.argument(), argument);
        EXPECT_EQ(error.row(), row);
      }
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        if (i == row) continue;
        ASSERT_EQ(rhs[i], system.d[i]) << "row " << i;
      }
    }
}

}  // namespace
}  // namespace tridiff::test
