// Factor once, solve many (factor.hpp) and what the factors say about the answers (refine.hpp):
// solutions against a dense LU in long double and LAPACK ?gttrf/?gttrs, condition estimates
// against ?gtcon and the exact condition number, refinement against ?gtrfs and the true error,
// mixed precision on a well- and an ill-conditioned system.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <vector>

#include "reference.hpp"
#include "stability_matrices.hpp"
#include "lapack.hpp"
#include "tridiff/solvers.hpp"

namespace tridiff {
namespace {

using namespace tridiff::test;  // System, the matrix classes, the long-double reference

template <class T>
using DenseWide = Eigen::Matrix<Wide<T>, Eigen::Dynamic, Eigen::Dynamic>;

// op(A) of one system, densely, in long double.
template <class T>
DenseWide<T> dense(const System<T>& s, Apply apply) {
  DenseWide<T> m = test::wide_matrix(s);
  if (apply == Apply::Transpose) return m.transpose();
  if (apply == Apply::Adjoint) return m.adjoint();
  return m;
}

template <class T>
WideVector<T> dense_solve(const System<T>& s, Apply apply, const std::vector<T>& rhs) {
  WideVector<T> b(s.n());
  for (std::ptrdiff_t i = 0; i < s.n(); ++i) b[i] = static_cast<Wide<T>>(rhs[i]);
  return dense(s, apply).partialPivLu().solve(b);
}

// The exact ||A||_1 ||A^{-1}||_1 from the dense inverse in long double.
template <class T>
long double exact_condition1(const System<T>& s) {
  const DenseWide<T> m = dense(s, Apply::Matrix);
  const DenseWide<T> inverse = m.partialPivLu().inverse();
  auto norm1 = [](const DenseWide<T>& a) {
    long double best = 0;
    for (Eigen::Index j = 0; j < a.cols(); ++j)
      best = std::max(best, (long double)a.col(j).cwiseAbs().sum());
    return best;
  };
  return norm1(m) * norm1(inverse);
}

// A batch of `count` copies of nothing in particular: the systems laid out by `layout`, with
// nrhs right-hand sides, and where each system's entries live.
template <class T>
struct Batch {
  BatchLayout layout;
  std::ptrdiff_t nrhs;
  std::vector<System<T>> systems;
  std::vector<T> sub, diag, super, rhs;  // rhs: nrhs blocks of layout.extent()

  Batch(BatchLayout l, std::ptrdiff_t right_hand_sides, std::vector<System<T>> s)
      : layout(l), nrhs(right_hand_sides), systems(std::move(s)) {
    const std::ptrdiff_t extent = layout.extent();
    sub.assign(extent, T(7));  // padding that a solve must not read as coefficients
    diag.assign(extent, T(7));
    super.assign(extent, T(7));
    rhs.assign(extent * nrhs, T(7));
    for (std::ptrdiff_t k = 0; k < layout.count; ++k)
      for (std::ptrdiff_t i = 0; i < layout.n; ++i) {
        const std::ptrdiff_t o = layout.offset(k, i);
        sub[o] = systems[k].a[i];
        diag[o] = systems[k].b[i];
        super[o] = systems[k].c[i];
        for (std::ptrdiff_t j = 0; j < nrhs; ++j)
          rhs[j * extent + o] = systems[k].d[i] * T(real_t<T>(j + 1)) + T(real_t<T>(j));
      }
  }
  std::vector<T> rhs_of(const std::vector<T>& all, std::ptrdiff_t k, std::ptrdiff_t j) const {
    std::vector<T> v(layout.n);
    for (std::ptrdiff_t i = 0; i < layout.n; ++i)
      v[i] = all[j * layout.extent() + layout.offset(k, i)];
    return v;
  }
};

template <class T>
std::vector<BatchLayout> layouts_for(std::ptrdiff_t n, std::ptrdiff_t count) {
  return {BatchLayout::rows(n, count, n + 3), BatchLayout::columns(n, count, count + 2),
          BatchLayout{n, count, 2, 2 * n + 1}};
}

constexpr std::ptrdiff_t kSizes[] = {1, 2, 3, 15, 16, 17, 31};

template <class T>
class FactorTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double, std::complex<float>, std::complex<double>>;
TYPED_TEST_SUITE(FactorTest, Scalars);

// Normwise backward error of x for op(A) x = b, in long double straight from the definition:
// ||b - op(A) x||_inf / (||op(A)||_inf ||x||_inf + ||b||_inf).
template <class T>
long double backward_error_of(const System<T>& s, Apply apply, const std::vector<T>& x,
                              const std::vector<T>& b) {
  const std::ptrdiff_t n = s.n();
  auto entry = [&](std::ptrdiff_t i, std::ptrdiff_t j) -> Wide<T> {  // op(A)(i, j)
    const std::ptrdiff_t r = apply == Apply::Matrix ? i : j, c = apply == Apply::Matrix ? j : i;
    const T value = c == r ? s.b[r] : c == r - 1 ? s.a[r] : s.c[r];
    const Wide<T> wide = static_cast<Wide<T>>(value);
    if constexpr (is_complex_v<T>)
      return apply == Apply::Adjoint ? std::conj(wide) : wide;
    else
      return wide;
  };
  long double residual = 0, norm = 0, x_norm = 0, b_norm = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    Wide<T> sum = static_cast<Wide<T>>(b[i]);
    long double row = 0;
    for (std::ptrdiff_t j = std::max<std::ptrdiff_t>(0, i - 1); j <= std::min(n - 1, i + 1); ++j) {
      sum -= entry(i, j) * static_cast<Wide<T>>(x[j]);
      row += std::abs(entry(i, j));
    }
    residual = std::max(residual, (long double)std::abs(sum));
    norm = std::max(norm, row);
    x_norm = std::max(x_norm, (long double)std::abs(static_cast<Wide<T>>(x[i])));
    b_norm = std::max(b_norm, (long double)std::abs(static_cast<Wide<T>>(b[i])));
  }
  return residual / (norm * x_norm + b_norm);
}

// Every solution of the batch backward stable: error a small multiple of u (pivoting's growth
// is at most 2 per step in theory and small in practice on these matrices).
template <class T>
void expect_solves(const Batch<T>& batch, const std::vector<T>& x, Apply apply) {
  const long double bound = 16 * test::unit_roundoff<T>();
  for (std::ptrdiff_t k = 0; k < batch.layout.count; ++k)
    for (std::ptrdiff_t j = 0; j < batch.nrhs; ++j) {
      const long double error = backward_error_of(batch.systems[k], apply, batch.rhs_of(x, k, j),
                                                  batch.rhs_of(batch.rhs, k, j));
      ASSERT_LE(error, bound) << "system " << k << " rhs " << j << " apply " << int(apply) << " n "
                              << batch.layout.n;
    }
}

// A mix of dominant and non-dominant systems (chunks of them pivoted); every apply, layout, size and
// several right-hand sides.
TYPED_TEST(FactorTest, FactoredSolvesMatchDenseLu) {
  using T = TypeParam;
  for (std::ptrdiff_t n : kSizes) {
    // A full chunk (detail::kLanes<T> systems) and a padded one.
    const std::ptrdiff_t count = detail::kLanes<T> + 5;
    std::vector<System<T>> systems;
    for (std::ptrdiff_t k = 0; k < count; ++k)
      systems.push_back(k % 3 == 1 ? random_nondominant_system<T>(n, 100 + k)
                                   : test::random_dominant<T>(n, 200 + k));
    for (const BatchLayout& layout : layouts_for<T>(n, count)) {
      const Batch<T> batch(layout, 3, systems);
      const auto factors = factor(batch.sub.data(), batch.diag.data(), batch.super.data(), layout);
      for (Apply apply : {Apply::Matrix, Apply::Transpose, Apply::Adjoint}) {
        std::vector<T> x(batch.rhs.size(), T(0));
        FactoredSolveOptions options;
        options.apply = apply;
        options.nrhs = 3;
        solve(factors, batch.rhs.data(), x.data(), layout, options);
        expect_solves(batch, x, apply);
        std::vector<T> in_place = batch.rhs;
        solve(factors, in_place.data(), in_place.data(), layout, options);
        // The same arithmetic; complex products may contract to FMA differently in the
        // streaming and the slab path, so equal to a few ulps.
        for (std::ptrdiff_t k = 0; k < count; ++k)
          for (std::ptrdiff_t j = 0; j < 3; ++j) {
            const auto a = batch.rhs_of(in_place, k, j), b = batch.rhs_of(x, k, j);
            for (std::ptrdiff_t i = 0; i < n; ++i)
              ASSERT_LE(std::abs(a[i] - b[i]), 4 * detail::epsilon<T> * std::abs(b[i]))
                  << k << " " << j << " " << i;
          }
      }
    }
  }
}

// Dominant systems, a full chunk and a padded one, every layout (the streaming paths for
// image rows and columns among them) and every factorization.
TYPED_TEST(FactorTest, EveryFactorizationSolvesDominantSystems) {
  using T = TypeParam;
  const std::ptrdiff_t count = detail::kLanes<T> + 3;
  for (std::ptrdiff_t n : {1, 2, 17, 65}) {
    std::vector<System<T>> systems;
    for (std::ptrdiff_t k = 0; k < count; ++k)
      systems.push_back(test::random_dominant<T>(n, 300 + k));
    for (const BatchLayout& layout : layouts_for<T>(n, count)) {
      const Batch<T> batch(layout, 1, systems);
      for (Factorization method :
           {Factorization::Auto, Factorization::NoPivoting, Factorization::Pivoting}) {
        FactorOptions options;
        options.method = method;
        const auto factors =
            factor(batch.sub.data(), batch.diag.data(), batch.super.data(), layout, options);
        EXPECT_EQ(factors.pivoted(0), method == Factorization::Pivoting);
        std::vector<T> x(batch.rhs.size());
        solve(factors, batch.rhs.data(), x.data(), layout);
        expect_solves(batch, x, Apply::Matrix);
      }
    }
  }
}

// An overflowing solution is an error naming the system, out of place (the streaming paths)
// and in place (rhs then left as it was).
TYPED_TEST(FactorTest, OverflowIsNamed) {
  using T = TypeParam;
  using R = real_t<T>;
  const std::ptrdiff_t n = 8, count = detail::kLanes<T>;
  std::vector<System<T>> systems;
  for (std::ptrdiff_t k = 0; k < count; ++k) {
    System<T> s = test::random_dominant<T>(n, 40 + k);
    // Dominant and nonsingular, but with |x| ~ |rhs| / 1e-3: rhs near the top of the range.
    if (k == 5) {
      for (std::ptrdiff_t i = 0; i < n; ++i) s.a[i] = s.c[i] = T(0), s.b[i] = T(R(1e-3));
      s.d.assign(n, T(std::numeric_limits<R>::max() / 2));
    }
    systems.push_back(s);
  }
  for (const BatchLayout& layout : layouts_for<T>(n, count)) {
    const Batch<T> batch(layout, 1, systems);
    const auto factors = factor(batch.sub.data(), batch.diag.data(), batch.super.data(), layout);
    std::vector<T> x(batch.rhs.size());
    std::vector<T> in_place = batch.rhs;
    for (T* out : {x.data(), in_place.data()}) {
      const T* in = out == x.data() ? batch.rhs.data() : in_place.data();
      try {
        solve(factors, in, out, layout);
        ADD_FAILURE() << "no NumericalError";
      } catch (const NumericalError& e) {
        EXPECT_EQ(e.system(), 5);
      }
    }
    EXPECT_EQ(in_place, batch.rhs);
  }
}

TYPED_TEST(FactorTest, DiffusionFactorsSolveTheDiffusionSystem) {
  using T = TypeParam;
  using R = real_t<T>;
  const std::ptrdiff_t n = 33, count = 9;
  std::mt19937_64 random(5);
  std::vector<R> beta(n * count);
  for (R& b : beta) b = std::uniform_real_distribution<R>(0, 10)(random);
  std::vector<System<T>> systems;
  for (std::ptrdiff_t k = 0; k < count; ++k) {
    System<T> s = stability::zero_system<T>(n);
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const R left = i > 0 ? beta[k * n + i - 1] : 0, right = i + 1 < n ? beta[k * n + i] : 0;
      s.a[i] = T(-left);
      s.b[i] = T(1 + left + right);
      s.c[i] = T(-right);
      s.d[i] = test::random_scalar<T>(random, -1, 1);
    }
    systems.push_back(s);
  }
  const Batch<T> batch(BatchLayout::rows(n, count, n), 1, systems);
  const auto factors = factor_diffusion<T>(beta.data(), batch.layout);
  std::vector<T> x(batch.rhs.size());
  solve(factors, batch.rhs.data(), x.data(), batch.layout);
  expect_solves(batch, x, Apply::Matrix);
}

// The LAPACK ?gttrf / ?gttrs pair on the same non-dominant systems: same answers to within
// what two correct orderings of the same arithmetic may differ by.
template <class T>
void expect_like_lapack_gttrs() {
  for (std::ptrdiff_t n : {1, 2, 3, 31, 32, 33, 129}) {
    std::vector<System<T>> systems;
    for (int k = 0; k < 4; ++k) systems.push_back(random_nondominant_system<T>(n, 400 + k));
    const Batch<T> batch(BatchLayout::columns(n, 4, 4), 1, systems);
    const auto factors =
        factor(batch.sub.data(), batch.diag.data(), batch.super.data(), batch.layout);
    for (Apply apply : {Apply::Matrix, Apply::Transpose}) {
      std::vector<T> x(batch.rhs.size());
      FactoredSolveOptions options;
      options.apply = apply;
      solve(factors, batch.rhs.data(), x.data(), batch.layout, options);
      for (int k = 0; k < 4; ++k) {
        const System<T>& s = systems[k];
        std::vector<T> dl(s.a.begin() + 1, s.a.end()), d = s.b, du(s.c.begin(), s.c.end() - 1),
                                                       du2(n), b = batch.rhs_of(batch.rhs, k, 0);
        if (n == 1) dl.assign(1, T(0)), du.assign(1, T(0));
        std::vector<int> ipiv(n);
        const int size = int(n), one = 1;
        int info = 0;
        const char trans = apply == Apply::Matrix ? 'N' : 'T';
        if constexpr (std::is_same_v<T, float>) {
          sgttrf_(&size, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), &info);
          sgttrs_(&trans, &size, &one, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(),
                  b.data(), &size, &info, 1);
        } else {
          dgttrf_(&size, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), &info);
          dgttrs_(&trans, &size, &one, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(),
                  b.data(), &size, &info, 1);
        }
        ASSERT_EQ(info, 0);
        const WideVector<T> reference = dense_solve(s, apply, batch.rhs_of(batch.rhs, k, 0));
        const long double lapack = test::forward_error(b, reference);
        const long double ours = test::forward_error(batch.rhs_of(x, k, 0), reference);
        EXPECT_LE(ours, 4 * lapack + 8 * n * test::unit_roundoff<T>())
            << "n " << n << " system " << k << " apply " << int(apply);
      }
    }
  }
}

TEST(FactorLapack, FloatSolvesLikeSgttrs) { expect_like_lapack_gttrs<float>(); }
TEST(FactorLapack, DoubleSolvesLikeDgttrs) { expect_like_lapack_gttrs<double>(); }

// A singular system in the middle of a batch: named, system and row, at factor time; the row
// is LAPACK's INFO - 1.
TYPED_TEST(FactorTest, SingularSystemIsNamedAtFactorTime) {
  using T = TypeParam;
  const std::ptrdiff_t n = 9, count = 70;
  std::vector<System<T>> systems;
  for (int k = 0; k < count; ++k) systems.push_back(random_nondominant_system<T>(n, 500 + k));
  // Row and column 4 of system 66 zero: zero pivot at row 4 (columns 0..3 are independent).
  System<T>& bad = systems[66];
  bad.b[4] = bad.a[4] = bad.c[4] = bad.c[3] = bad.a[5] = T(0);
  const Batch<T> batch(BatchLayout::rows(n, count, n), 1, systems);
  for (Factorization method : {Factorization::Auto, Factorization::Pivoting}) {
    FactorOptions options;
    options.method = method;
    try {
      factor(batch.sub.data(), batch.diag.data(), batch.super.data(), batch.layout, options);
      FAIL() << "no NumericalError";
    } catch (const NumericalError& e) {
      EXPECT_EQ(e.system(), 66);
      EXPECT_EQ(e.row(), 4);
    }
  }
}

TYPED_TEST(FactorTest, NoPivotingRefusesANonDominantSystem) {
  using T = TypeParam;
  std::vector<System<T>> systems{test::random_dominant<T>(8, 1),
                                 random_nondominant_system<T>(8, 2)};
  const Batch<T> batch(BatchLayout::rows(8, 2, 8), 1, systems);
  FactorOptions options;
  options.method = Factorization::NoPivoting;
  try {
    factor(batch.sub.data(), batch.diag.data(), batch.super.data(), batch.layout, options);
    FAIL() << "no NumericalError";
  } catch (const NumericalError& e) {
    EXPECT_EQ(e.system(), 1);
  }
}

TEST(FactorErrors, BadArgumentsAreNamed) {
  const auto s = test::random_dominant<double>(5, 3);
  const auto factors = factor(s.a.data(), s.b.data(), s.c.data(), BatchLayout::single(5));
  std::vector<double> x(10);
  auto argument_of = [](auto&& action) {
    try {
      action();
    } catch (const InvalidArgument& e) {
      return e.argument();
    }
    return std::string("none");
  };
  EXPECT_EQ(argument_of([&] { solve(factors, s.d.data(), x.data(), BatchLayout::single(4)); }),
            "layout");
  FactoredSolveOptions two;
  two.nrhs = 2;
  two.rhs_stride = 3;
  EXPECT_EQ(argument_of([&] { solve(factors, x.data(), x.data(), BatchLayout::single(5), two); }),
            "rhs_stride");
  EXPECT_EQ(argument_of([&] {
              solve(factors, s.d.data(), x.data() + 0, BatchLayout::single(5),
                    FactoredSolveOptions{Apply(7), 1, 0, 0});
            }),
            "apply");
  std::vector<double> nan_rhs(5, std::nan(""));
  EXPECT_EQ(argument_of([&] { solve(factors, nan_rhs.data(), x.data(), BatchLayout::single(5)); }),
            "rhs");
  std::vector<double> b = s.b;
  b[2] = INFINITY;
  EXPECT_EQ(argument_of([&] { factor(s.a.data(), b.data(), s.c.data(), BatchLayout::single(5)); }),
            "diag");
}

// rcond within a factor of 3 of dgtcon's (the same estimator, so closer in practice) and of
// the exact 1 / (||A||_1 ||A^{-1}||_1).
TEST(FactorCondition, RcondMatchesDgtconAndTheExactCondition) {
  for (std::ptrdiff_t n : {1, 2, 3, 17, 64}) {
    std::vector<System<double>> systems;
    for (int k = 0; k < 3; ++k) {
      systems.push_back(random_nondominant_system<double>(n, 600 + k));
      systems.push_back(test::random_dominant<double>(n, 700 + k));
      systems.push_back(poisson_system<double>(n, 0));
      if (n > 2) systems.push_back(nearly_singular_indefinite_system<double>(n, 800 + k));
    }
    const std::ptrdiff_t count = std::ptrdiff_t(systems.size());
    const Batch<double> batch(BatchLayout::rows(n, count, n), 1, systems);
    const auto factors =
        factor(batch.sub.data(), batch.diag.data(), batch.super.data(), batch.layout);
    const std::vector<double> rcond = estimate_rcond(factors);
    for (std::ptrdiff_t k = 0; k < count; ++k) {
      const System<double>& s = systems[k];
      const double exact = double(1 / exact_condition1(s));
      EXPECT_LE(rcond[k], 3 * exact) << "n " << n << " system " << k;
      EXPECT_GE(rcond[k], exact / 3 * (1 - 1e-12)) << "n " << n << " system " << k;
      std::vector<double> dl(s.a.begin() + 1, s.a.end()), d = s.b, du(s.c.begin(), s.c.end() - 1),
                                                          du2(n), work(2 * n);
      if (n == 1) dl.assign(1, 0), du.assign(1, 0);
      std::vector<int> ipiv(n), iwork(n);
      const int size = int(n);
      int info = 0;
      dgttrf_(&size, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), &info);
      double lapack = 0;
      const double anorm = factors.norm1(k);
      dgtcon_("1", &size, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), &anorm, &lapack,
              work.data(), iwork.data(), &info, 1);
      EXPECT_LE(rcond[k], 3 * lapack) << "n " << n << " system " << k;
      EXPECT_GE(rcond[k], lapack / 3) << "n " << n << " system " << k;
    }
  }
}

TEST(FactorCondition, ComplexRcondMatchesTheExactCondition) {
  using T = std::complex<double>;
  for (std::ptrdiff_t n : {1, 2, 17, 33}) {
    std::vector<System<T>> systems{random_nondominant_system<T>(n, 1),
                                   test::random_dominant<T>(n, 2)};
    const Batch<T> batch(BatchLayout::rows(n, 2, n), 1, systems);
    const auto factors =
        factor(batch.sub.data(), batch.diag.data(), batch.super.data(), batch.layout);
    const auto rcond = estimate_rcond(factors);
    for (int k = 0; k < 2; ++k) {
      const double exact = double(1 / exact_condition1(systems[k]));
      EXPECT_LE(rcond[k], 3 * exact);
      EXPECT_GE(rcond[k], exact / 3);
    }
  }
}

// Refinement: a backward error at the double level (as dgtrfs reaches), a forward bound that
// bounds the true error, and one within a factor of 10 of dgtrfs's.
TEST(FactorRefine, BackwardErrorAtDoubleLevelAndForwardBoundHolds) {
  for (std::ptrdiff_t n : {1, 2, 3, 17, 63, 65}) {
    std::vector<System<double>> systems;
    for (int k = 0; k < 2; ++k) {
      systems.push_back(random_nondominant_system<double>(n, 900 + k));
      systems.push_back(test::random_dominant<double>(n, 950 + k));
      if (n > 2) systems.push_back(nearly_singular_indefinite_system<double>(n, 990 + k));
    }
    const std::ptrdiff_t count = std::ptrdiff_t(systems.size());
    for (Apply apply : {Apply::Matrix, Apply::Transpose}) {
      const Batch<double> batch(BatchLayout::columns(n, count, count), 2, systems);
      const auto factors =
          factor(batch.sub.data(), batch.diag.data(), batch.super.data(), batch.layout);
      std::vector<double> x(batch.rhs.size());
      FactoredSolveOptions solve_options;
      solve_options.apply = apply;
      solve_options.nrhs = 2;
      solve(factors, batch.rhs.data(), x.data(), batch.layout, solve_options);
      RefineOptions options;
      options.apply = apply;
      options.nrhs = 2;
      const auto report = refine(batch.sub.data(), batch.diag.data(), batch.super.data(), factors,
                                 batch.rhs.data(), x.data(), batch.layout, options);
      for (std::ptrdiff_t k = 0; k < count; ++k)
        for (int j = 0; j < 2; ++j) {
          const std::ptrdiff_t r = k * 2 + j;
          const auto b = batch.rhs_of(batch.rhs, k, j), got = batch.rhs_of(x, k, j);
          EXPECT_LE(report.backward_error[r], 2 * test::unit_roundoff<double>())
              << "n " << n << " system " << k;
          const WideVector<double> reference = dense_solve(systems[k], apply, b);
          long double worst = 0, largest = 0;
          for (std::ptrdiff_t i = 0; i < n; ++i) {
            worst = std::max(worst, std::abs(got[i] - reference[i]));
            largest = std::max(largest, (long double)std::abs(got[i]));
          }
          EXPECT_LE(worst / largest, report.forward_error[r]) << "n " << n << " system " << k;
          // dgtrfs on the same start.
          const System<double>& s = systems[k];
          std::vector<double> dl(s.a.begin() + 1, s.a.end()), d = s.b,
                                                              du(s.c.begin(), s.c.end() - 1);
          if (n == 1) dl.assign(1, 0), du.assign(1, 0);
          std::vector<double> dlf = dl, df = d, duf = du, du2(n), xl = b, work(3 * n);
          std::vector<int> ipiv(n), iwork(n);
          const int size = int(n), one = 1;
          int info = 0;
          const char trans = apply == Apply::Matrix ? 'N' : 'T';
          dgttrf_(&size, dlf.data(), df.data(), duf.data(), du2.data(), ipiv.data(), &info);
          dgttrs_(&trans, &size, &one, dlf.data(), df.data(), duf.data(), du2.data(), ipiv.data(),
                  xl.data(), &size, &info, 1);
          double ferr = 0, berr = 0;
          dgtrfs_(&trans, &size, &one, dl.data(), d.data(), du.data(), dlf.data(), df.data(),
                  duf.data(), du2.data(), ipiv.data(), b.data(), &size, xl.data(), &size, &ferr,
                  &berr, work.data(), iwork.data(), &info, 1);
          EXPECT_LE(report.forward_error[r], 10 * ferr + 1e-15) << "n " << n << " system " << k;
        }
    }
  }
}

TEST(FactorRefine, FloatRefinementBoundsTheTrueError) {
  using T = std::complex<float>;
  const std::ptrdiff_t n = 40;
  std::vector<System<T>> systems{random_nondominant_system<T>(n, 1),
                                 test::random_dominant<T>(n, 2)};
  const Batch<T> batch(BatchLayout::rows(n, 2, n), 1, systems);
  const auto factors =
      factor(batch.sub.data(), batch.diag.data(), batch.super.data(), batch.layout);
  std::vector<T> x(batch.rhs.size());
  solve(factors, batch.rhs.data(), x.data(), batch.layout);
  const auto report = refine(batch.sub.data(), batch.diag.data(), batch.super.data(), factors,
                             batch.rhs.data(), x.data(), batch.layout);
  for (int k = 0; k < 2; ++k) {
    const auto got = batch.rhs_of(x, k, 0);
    const WideVector<T> reference =
        dense_solve(systems[k], Apply::Matrix, batch.rhs_of(batch.rhs, k, 0));
    long double worst = 0, largest = 0;
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      worst = std::max(worst, std::abs(Wide<T>(got[i]) - reference[i]));
      largest = std::max(largest, (long double)std::abs(got[i]));
    }
    EXPECT_LE(worst / largest, report.forward_error[k]);
    EXPECT_LE(report.backward_error[k], 4 * test::unit_roundoff<T>());
  }
}

// Mixed precision: float factors, double answers. A well-conditioned system reaches a double
// backward error (checked independently in long double); one with condition > 1 / u_float
// cannot, and is reported, with the backward error it really has.
template <class T>
void expect_mixed_precision() {
  for (std::ptrdiff_t n : {1, 2, 3, 64, 65}) {
    std::vector<System<T>> systems{test::random_dominant<T>(n, 11),
                                   random_nondominant_system<T>(n, 12)};
    // (At n = 3 the ill-conditioned class rounds to a matrix singular in float, which the
    // float factorization refuses by throwing, naming the system.)
    const bool ill = n > 3;
    if (ill) {  // the class is real: complex data with real values, for the complex type
      const System<double> real = nearly_singular_indefinite_system<double>(n, 13);
      System<T> s = stability::zero_system<T>(n);
      for (std::ptrdiff_t i = 0; i < n; ++i)
        s.a[i] = T(real.a[i]), s.b[i] = T(real.b[i]), s.c[i] = T(real.c[i]), s.d[i] = T(real.d[i]);
      systems.push_back(s);
    }
    const std::ptrdiff_t count = std::ptrdiff_t(systems.size());
    const Batch<T> batch(BatchLayout::columns(n, count, count), 1, systems);
    std::vector<T> x(batch.rhs.size());
    const MixedReport report = solve_mixed(batch.sub.data(), batch.diag.data(), batch.super.data(),
                                           batch.rhs.data(), x.data(), batch.layout);
    for (std::ptrdiff_t k = 0; k < count; ++k) {
      System<T> s = systems[k];
      s.d = batch.rhs_of(batch.rhs, k, 0);
      const auto got = batch.rhs_of(x, k, 0);
      // Componentwise backward error in long double.
      long double worst = 0;
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        Wide<T> r = Wide<T>(s.d[i]) - Wide<T>(s.b[i]) * Wide<T>(got[i]);
        long double scale = std::abs(Wide<T>(s.d[i])) + std::abs(Wide<T>(s.b[i]) * Wide<T>(got[i]));
        if (i > 0)
          r -= Wide<T>(s.a[i]) * Wide<T>(got[i - 1]),
              scale += std::abs(Wide<T>(s.a[i]) * Wide<T>(got[i - 1]));
        if (i + 1 < n)
          r -= Wide<T>(s.c[i]) * Wide<T>(got[i + 1]),
              scale += std::abs(Wide<T>(s.c[i]) * Wide<T>(got[i + 1]));
        worst = std::max(worst, std::abs(r) / scale);
      }
      if (k < 2) {
        EXPECT_EQ(report.status[k], MixedStatus::Converged) << "n " << n << " system " << k;
        EXPECT_LE(worst, 8 * test::unit_roundoff<T>()) << "n " << n << " system " << k;
      } else {
        EXPECT_NE(report.status[k], MixedStatus::Converged) << "n " << n;
        EXPECT_EQ(report.status[k], MixedStatus::IllConditioned) << "rcond " << report.rcond[k];
        EXPECT_GT(worst, 8 * test::unit_roundoff<T>());
      }
      // The reported backward error is the one x has (CABS1 versus modulus: within sqrt 2).
      // The residual in double adds up to about 4u to what is reported.
      EXPECT_LE(worst, 1.5 * report.backward_error[k] + 4 * test::unit_roundoff<T>());
    }
    EXPECT_EQ(report.not_converged, ill ? 1 : 0);
  }
}

TEST(FactorMixed, DoubleReachesDoubleBackwardErrorOrReports) { expect_mixed_precision<double>(); }
TEST(FactorMixed, ComplexDoubleReachesDoubleBackwardErrorOrReports) {
  expect_mixed_precision<std::complex<double>>();
}

}  // namespace
}  // namespace tridiff
