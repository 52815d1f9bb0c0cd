// The numerical stability stress suite: every matrix class of stability_matrices.hpp, in float
// and double, against LAPACK ?gtsv on the same system, with errors measured in long double
// against a long-double reference (refined_reference in stability_measure.hpp).
// bench/stability_table.cpp prints the same comparison for every method and larger n.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <utility>

#include "stability_matrices.hpp"
#include "stability_measure.hpp"

namespace tridiff::test {
namespace {

// Small enough for the AddressSanitizer build of CI (the reference LU runs in long double);
// 16 is a single SIMD-lane block, 257 and 4097 are 2^k + 1 (an odd last level for CR).
constexpr std::ptrdiff_t kSizes[] = {16, 257, 4097};

// The seed of a class at size n; bench/stability_table.cpp uses the same (with its default
// --seed), so a failure here can be looked up in the table.
constexpr std::uint64_t kSeed = 2024;

// "Within ten times LAPACK": tridiff may lose one decimal digit against LAPACK's ?gtsv on the
// same system, in both the forward and the normwise backward error; LAPACK's error is floored
// at eps first (lapack_floor in stability_measure.hpp says why).
constexpr long double kTimesLapack = 10;

template <class T>
long double ten_times_lapack(long double lapack_error) {
  return kTimesLapack * std::max(lapack_error, lapack_floor<T>());
}

// Where kappa_1(A) u >= 1 (LAPACK's estimate, condition_estimate) no method can promise one
// correct digit, and forward errors, LAPACK's and ours alike, are noise: only the backward
// errors are compared there: dorr_1e-4 (kappa_1 ~ 1e20), and dorr_1e-2 in float at large n.
template <class T>
bool forward_error_is_meaningful(const System<T>& s) {
  return condition_estimate(s) * unit_roundoff<T>() < 1;
}

// Diagonal dominance by rows or by columns, the property the pivot-free methods require,
// decided in long double with the library's slack of 4 eps (detail::first_non_dominant_row)
// so that the weakly dominant classes count as dominant.
template <class T>
bool dominant_by_rows_or_columns(const System<T>& s) {
  const long double slack = 1 - 4 * std::numeric_limits<T>::epsilon();
  const std::ptrdiff_t n = s.n();
  auto entry = [](const std::vector<T>& v, std::ptrdiff_t i) {
    return std::abs(static_cast<long double>(v[i]));
  };
  bool by_rows = true, by_columns = true;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const long double diagonal = entry(s.b, i);
    const long double row = (i > 0 ? entry(s.a, i) : 0) + (i + 1 < n ? entry(s.c, i) : 0);
    const long double column =
        (i > 0 ? entry(s.c, i - 1) : 0) + (i + 1 < n ? entry(s.a, i + 1) : 0);
    by_rows = by_rows && diagonal >= slack * row;
    by_columns = by_columns && diagonal >= slack * column;
  }
  return by_rows || by_columns;
}

// The backward-error bound of the pivot-free methods on a dominant matrix is reference.hpp's
// backward_bound: LU without pivoting of a matrix dominant by rows or columns has
// |L||U| <= 3|A| (Higham, Accuracy and Stability, Thm 9.12), and cyclic reduction adds one
// round of updates per level.
// The pivot-free rows of the method table (Thomas, CR, PCR, CR-PCR today).
const std::vector<Method> kPivotFreeMethods = [] {
  std::vector<Method> methods;
  for (const MethodRow& row : kMethodTable)
    if (row.pivot_free) methods.push_back(row.method);
  return methods;
}();

::testing::Message where(const MatrixClass& matrix_class, std::ptrdiff_t n, Method method) {
  return ::testing::Message() << "class " << matrix_class.name << ", n = " << n << ", method "
                              << to_string(method);
}

template <class T>
class Stability : public ::testing::Test {};
using Precisions = ::testing::Types<float, double>;
TYPED_TEST_SUITE(Stability, Precisions);

// Where LAPACK gives no answer there is no yardstick; an answer must then be as good as the
// accuracy test demands of Thomas and pivoting on well-conditioned systems: a normwise
// backward error within 16 u.
template <class T>
long double backward_bound_without_lapack() {
  return 16 * unit_roundoff<T>();
}

// A method that must be as good as LAPACK on every class: within 10x of ?gtsv's forward and
// backward error. Where ?gtsv fails (info > 0, an exactly zero pivot) the method must throw
// NumericalError or return an x within backward_bound_without_lapack: the only such case among
// the classes is rows_scaled_1e+-30 in float, which is well posed (row scaling does not change
// x) but where ?gtsv's multipliers, quotients of entries 1e60 apart, underflow to 0 and leave
// an exactly zero pivot (info = n); Thomas, without row interchanges, never forms them.
template <class T>
void expect_within_ten_times_lapack(Method method) {
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    for (std::ptrdiff_t n : kSizes) {
      SCOPED_TRACE(where(matrix_class, n, method));
      const System<T> system = matrix_class.make<T>(n, kSeed + static_cast<std::uint64_t>(n));
      const WideVector<T> reference = refined_reference(system);
      const Measurement lapack = measure_lapack(system, reference);
      const Measurement ours = measure_tridiff(system, method, reference);
      if (lapack.outcome != Outcome::Solved) {
        EXPECT_NE(ours.outcome, Outcome::NonFinite);
        EXPECT_NE(ours.outcome, Outcome::Error) << ours.message;
        EXPECT_NE(ours.outcome, Outcome::Refused) << ours.message;
        if (ours.outcome == Outcome::Solved) {
          EXPECT_LE(ours.backward, backward_bound_without_lapack<T>())
              << "LAPACK: " << lapack.message;
        }
        continue;
      }
      ASSERT_EQ(ours.outcome, Outcome::Solved) << ours.message;
      if (forward_error_is_meaningful(system)) {
        EXPECT_LE(ours.forward, ten_times_lapack<T>(lapack.forward))
            << "LAPACK forward error " << static_cast<double>(lapack.forward);
      }
      EXPECT_LE(ours.backward, ten_times_lapack<T>(lapack.backward))
          << "LAPACK backward error " << static_cast<double>(lapack.backward);
    }
  }
}

TYPED_TEST(Stability, AutoStaysWithinTenTimesLapackOnEveryClass) {
  expect_within_ten_times_lapack<TypeParam>(Method::Auto);
}

// Pivoting is ?gtsv's algorithm, so it must match LAPACK just as closely. (Compiled with
// -ffp-contract=off it returns bit for bit what Debian's dgtsv does on every class; with
// -march=native, GCC fuses a * b + c into FMAs and the roundings differ.)
TYPED_TEST(Stability, PivotingStaysWithinTenTimesLapackOnEveryClass) {
  expect_within_ten_times_lapack<TypeParam>(Method::Pivoting);
}

// One long system on several threads: Thomas, and Auto on a dominant matrix, split it into
// parts run in SIMD lanes (the partitioned method, detail/partitioned_lanes.hpp) from
// detail::kPartitionedMinRows rows on; the smaller sizes above never reach it. Auto must still
// stay within 10x of LAPACK, and must actually have split the system. Only the classes that
// are dominant at this size: on the others Auto pivots, on one thread, as tested above.
// Four threads whatever the core count, so the partition is the same on every machine.
TYPED_TEST(Stability, AutoOnFourThreadsStaysWithinTenTimesLapackOnLongSystems) {
  using T = TypeParam;
  constexpr int kThreads = 4;
  const std::ptrdiff_t n = detail::kPartitionedMinRows;
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    SCOPED_TRACE(where(matrix_class, n, Method::Auto) << ", " << kThreads << " threads");
    const System<T> system = matrix_class.make<T>(n, kSeed + static_cast<std::uint64_t>(n));
    if (!dominant_by_rows_or_columns(system)) continue;
    const WideVector<T> reference = refined_reference(system);
    const Measurement lapack = measure_lapack(system, reference);
    const Measurement ours = measure_tridiff(system, Method::Auto, reference, kThreads);
    ASSERT_EQ(ours.outcome, Outcome::Solved) << ours.message;
    if (lapack.outcome != Outcome::Solved) {  // rows_scaled_1e+-30 in float, as above
      EXPECT_LE(ours.backward, backward_bound_without_lapack<T>());
      continue;
    }
    // Unless Thomas broke down and Auto fell back to pivoting (dorr_1e-4): one part then.
    EXPECT_EQ(ours.parts > 1, ours.pivoted == 0);
    if (forward_error_is_meaningful(system)) {
      EXPECT_LE(ours.forward, ten_times_lapack<T>(lapack.forward))
          << "LAPACK forward error " << static_cast<double>(lapack.forward);
    }
    EXPECT_LE(ours.backward, ten_times_lapack<T>(lapack.backward))
        << "LAPACK backward error " << static_cast<double>(lapack.backward);
  }
}

// The generators' claims about dominance hold at the sizes tested, so the two tests below
// check the solvers rather than the generators.
TYPED_TEST(Stability, ClassesAreDominantAsDeclared) {
  using T = TypeParam;
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    if (matrix_class.dominance == Dominance::Varies) continue;
    for (std::ptrdiff_t n : kSizes) {
      SCOPED_TRACE(::testing::Message() << "class " << matrix_class.name << ", n = " << n);
      const System<T> system = matrix_class.make<T>(n, kSeed + static_cast<std::uint64_t>(n));
      EXPECT_EQ(dominant_by_rows_or_columns(system), matrix_class.dominance == Dominance::Dominant);
    }
  }
}

// Thomas, CR, PCR and the hybrid are unsafe without dominance: on a matrix dominant neither by
// rows nor by columns they must throw NumericalError saying so, not attempt a solve.
TYPED_TEST(Stability, PivotFreeMethodsRefuseNonDominantMatrices) {
  using T = TypeParam;
  int refusals = 0;
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    for (std::ptrdiff_t n : kSizes) {
      const System<T> system = matrix_class.make<T>(n, kSeed + static_cast<std::uint64_t>(n));
      if (dominant_by_rows_or_columns(system)) continue;
      const WideVector<T> reference = refined_reference(system);
      for (Method method : kPivotFreeMethods) {
        SCOPED_TRACE(where(matrix_class, n, method));
        const Measurement ours = measure_tridiff(system, method, reference);
        EXPECT_EQ(ours.outcome, Outcome::Refused) << ours.message;
        ++refusals;
      }
    }
  }
  // random_nondominant and nearly_singular_indefinite at every size, at least.
  EXPECT_GE(refusals, 2 * int(std::size(kSizes)) * int(std::size(kPivotFreeMethods)));
}

// On dominant matrices the pivot-free methods must accept the matrix and either solve it, with
// a backward error within backward_bound and a forward error within 10x LAPACK's
// (where ?gtsv gives an answer), or throw NumericalError for a vanishing pivot or an overflow
// (CR, PCR and the hybrid do on rows_scaled_1e+-30 in float: their multipliers a[i]/b[i-1],
// quotients of rows 1e60 apart, overflow) or for an answer that failed their backward-error
// check (PCR and the hybrid on dorr_1e-4). They must never return a non-finite x, refuse a
// dominant matrix, or throw anything else.
TYPED_TEST(Stability, PivotFreeMethodsSolveDominantMatricesWithinBoundOrThrow) {
  using T = TypeParam;
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    for (std::ptrdiff_t n : kSizes) {
      const System<T> system = matrix_class.make<T>(n, kSeed + static_cast<std::uint64_t>(n));
      if (!dominant_by_rows_or_columns(system)) continue;
      const WideVector<T> reference = refined_reference(system);
      const Measurement lapack = measure_lapack(system, reference);
      for (Method method : kPivotFreeMethods) {
        SCOPED_TRACE(where(matrix_class, n, method));
        const Measurement ours = measure_tridiff(system, method, reference);
        if (ours.outcome == Outcome::Singular || ours.outcome == Outcome::Overflow ||
            ours.outcome == Outcome::Inaccurate)
          continue;
        ASSERT_EQ(ours.outcome, Outcome::Solved) << to_string(ours.outcome) << ": " << ours.message;
        EXPECT_LE(ours.backward, backward_bound<T>(method, n));
        if (lapack.outcome == Outcome::Solved && forward_error_is_meaningful(system)) {
          EXPECT_LE(ours.forward, ten_times_lapack<T>(lapack.forward))
              << "LAPACK forward error " << static_cast<double>(lapack.forward);
        }
      }
    }
  }
}

// Genuinely singular matrices, where ?gtsv reports info > 0: every method must throw
// NumericalError (a refusal, for a pivot-free method on a non-dominant matrix, also counts).
//  - The Neumann Laplacian tridiag(-1, 2, -1) with 1 in both corners: every row sums to zero,
//    so A (1, ..., 1) = 0; weakly dominant, so the pivot-free methods accept it and must detect
//    the zero pivot (Thomas: pivots are exactly 1, ..., 1, 0).
//  - random_nondominant with its first row zeroed: a zero row.
TYPED_TEST(Stability, SingularMatricesRaiseNumericalErrorWhereLapackFails) {
  using T = TypeParam;
  for (std::ptrdiff_t n : kSizes) {
    System<T> neumann = poisson_system<T>(n, kSeed);
    neumann.b.front() = neumann.b.back() = T(1);
    System<T> zero_row = random_nondominant_system<T>(n, kSeed);
    zero_row.b[0] = zero_row.c[0] = T(0);
    for (const auto& [name, system] :
         {std::pair{"neumann_laplacian", neumann}, std::pair{"zero_first_row", zero_row}}) {
      const WideVector<T> no_reference = WideVector<T>::Zero(n);
      const Measurement lapack = measure_lapack(system, no_reference);
      ASSERT_EQ(lapack.outcome, Outcome::Singular) << name << ", n = " << n;
      for (Method method : kAllMethods) {
        SCOPED_TRACE(::testing::Message()
                     << name << ", n = " << n << ", method " << to_string(method));
        const Measurement ours = measure_tridiff(system, method, no_reference);
        const bool may_refuse = is_pivot_free(method) && !dominant_by_rows_or_columns(system);
        EXPECT_TRUE(ours.outcome == Outcome::Singular ||
                    (may_refuse && ours.outcome == Outcome::Refused))
            << to_string(ours.outcome) << ": " << ours.message;
      }
    }
  }
}

// The API's promise, on every class, size and method: a finite x or an exception.
TYPED_TEST(Stability, NoMethodReturnsANonFiniteSolution) {
  using T = TypeParam;
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    for (std::ptrdiff_t n : kSizes) {
      const System<T> system = matrix_class.make<T>(n, kSeed + static_cast<std::uint64_t>(n));
      for (Method method : kAllMethods) {
        SCOPED_TRACE(where(matrix_class, n, method));
        SolveOptions options;
        options.method = method;
        try {
          const std::vector<T> x = solve_system(system, options);
          EXPECT_TRUE(all_finite(x));
        } catch (const Error&) {
          // Any tridiff exception is an acceptable answer here; which one is tested above.
        }
      }
    }
  }
}

}  // namespace
}  // namespace tridiff::test
