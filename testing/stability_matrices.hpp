// Named classes of tridiagonal systems for the numerical stability stress suite: each class is
// built for a given scalar type, size n and seed, and kStabilityClasses lists them all, so that
// the stability test (tests/solvers_stability_test.cpp) and the stability table
// (bench/stability_table.cpp) enumerate exactly the same classes.
//
// Random numbers come from std::mt19937_64(seed). Most generators draw in double (or compute in
// long double) and round to T once, so the float and the double system of a class are the same
// matrix up to that rounding; the exceptions are strictly_dominant (random_dominant of
// reference.hpp draws in T) and the classes defined relative to T's epsilon or range (nearly
// singular, near overflow, near underflow). The right-hand side is random too.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <string_view>
#include <type_traits>
#include <vector>

#include "reference.hpp"

namespace tridiff::test {

// Whether the class is diagonally dominant (by rows or columns) in the sense of
// detail::first_non_dominant_row, i.e. whether the pivot-free methods accept it.
enum class Dominance {
  Dominant,     // for every n and seed: the pivot-free methods must accept it
  NotDominant,  // for every n >= 16 and the seeds used: the pivot-free methods must refuse it
  Varies,       // depends on n and the type (see the class's description)
};

namespace stability {

// Random numbers drawn in double, to be rounded to T by the caller.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : random_(seed) {}
  double uniform(double low, double high) {
    return std::uniform_real_distribution<double>(low, high)(random_);
  }
  double sign() { return std::bernoulli_distribution(0.5)(random_) ? 1.0 : -1.0; }
  // A magnitude in [low, high] with a random sign.
  double signed_magnitude(double low, double high) { return sign() * uniform(low, high); }
  bool coin() { return std::bernoulli_distribution(0.5)(random_); }

 private:
  std::mt19937_64 random_;
};

template <class T>
System<T> zero_system(std::ptrdiff_t n) {
  System<T> s;
  s.a.assign(n, T(0));
  s.b.assign(n, T(0));
  s.c.assign(n, T(0));
  s.d.assign(n, T(0));
  return s;
}

// Strictly dominant by rows with every nonzero magnitude in [scale/2, 3 scale]: off-diagonals
// of magnitude in [1/2, 1], a diagonal exceeding their sum by [1/2, 1], a right-hand side of
// magnitude in [1/2, 1], all times `scale` (computed in long double, rounded once). The
// solution is O(1) whatever the scale. Magnitudes are bounded away from zero so that scaled
// near the bottom of the range no entry is subnormal.
template <class T>
System<T> dominant_at_scale(std::ptrdiff_t n, std::uint64_t seed, long double scale) {
  Draw draw(seed);
  auto s = zero_system<T>(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const long double a = i > 0 ? draw.signed_magnitude(0.5, 1) : 0;
    const long double c = i + 1 < n ? draw.signed_magnitude(0.5, 1) : 0;
    const long double b = draw.sign() * (std::abs(a) + std::abs(c) + draw.uniform(0.5, 1));
    s.a[i] = static_cast<T>(a * scale);
    s.b[i] = static_cast<T>(b * scale);
    s.c[i] = static_cast<T>(c * scale);
    s.d[i] = static_cast<T>(draw.signed_magnitude(0.5, 1) * scale);
  }
  return s;
}

}  // namespace stability

// Strictly diagonally dominant: random_dominant of reference.hpp, |b_i| >= |a_i| + |c_i| + 1.
// The well-conditioned baseline (Varah: kappa_inf <= 3).
template <class T>
System<T> strictly_dominant_system(std::ptrdiff_t n, std::uint64_t seed) {
  return random_dominant<T>(n, seed);
}

// Weakly dominant: |b_i| = |a_i| + |c_i| exactly in every row but row n/2, where
// |b| = |a| + |c| + 1/2; off-diagonal magnitudes in [1/16, 1], all signs random. The matrix is
// irreducible (no zero off-diagonal) with one strict row, hence nonsingular (Taussky), and the
// pivot-free methods accept it (weak dominance is their stability condition), but pivots of
// Thomas can come close to |c_i| (dgtcon's kappa_1 at the table's seeds: 90, 170, 400 for
// n = 16, 1000, 65537). The magnitude of a[i+1]
// equals that of c[i]: with independent magnitudes the weak rows form a biased random walk in
// a random environment whose condition number grows like exp(sqrt(n)), far past what even the
// long-double reference can resolve. Entries are multiples of 2^-20, so |a| + |c| is exact in
// float and the stored matrix is exactly weakly dominant.
template <class T>
System<T> weakly_dominant_system(std::ptrdiff_t n, std::uint64_t seed) {
  stability::Draw draw(seed);
  const double grid = std::ldexp(1.0, 20);
  auto on_grid = [&](double v) { return std::round(v * grid) / grid; };
  auto s = stability::zero_system<T>(n);
  for (std::ptrdiff_t i = 0; i + 1 < n; ++i) {
    const double coupling = on_grid(draw.uniform(1.0 / 16, 1));
    s.c[i] = static_cast<T>(draw.sign() * coupling);
    s.a[i + 1] = static_cast<T>(draw.sign() * coupling);
  }
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const double strict = i == n / 2 ? 0.5 : 0.0;
    s.b[i] = static_cast<T>(draw.sign() *
                            (std::abs(double(s.a[i])) + std::abs(double(s.c[i])) + strict));
    s.d[i] = static_cast<T>(draw.uniform(-1, 1));
  }
  return s;
}

// The 1D Poisson matrix tridiag(-1, 2, -1): weakly dominant (strict in the first and last row),
// symmetric positive definite, kappa_2 = cot^2(pi / (2(n+1))) ~ 0.4 n^2.
template <class T>
System<T> poisson_system(std::ptrdiff_t n, std::uint64_t seed) {
  stability::Draw draw(seed);
  auto s = stability::zero_system<T>(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    s.a[i] = i > 0 ? T(-1) : T(0);
    s.b[i] = T(2);
    s.c[i] = i + 1 < n ? T(-1) : T(0);
    s.d[i] = static_cast<T>(draw.uniform(-1, 1));
  }
  return s;
}

// Random and not dominant: every entry uniform in [-1, 1]. Needs pivoting; nonsingular with
// probability 1, with a condition number that grows with n (dgtcon's kappa_1 at the table's
// seeds: 4e3, 9e4, 9e5 for n = 16, 1000, 65537).
template <class T>
System<T> random_nondominant_system(std::ptrdiff_t n, std::uint64_t seed) {
  stability::Draw draw(seed);
  auto s = stability::zero_system<T>(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    s.a[i] = i > 0 ? static_cast<T>(draw.uniform(-1, 1)) : T(0);
    s.b[i] = static_cast<T>(draw.uniform(-1, 1));
    s.c[i] = i + 1 < n ? static_cast<T>(draw.uniform(-1, 1)) : T(0);
    s.d[i] = static_cast<T>(draw.uniform(-1, 1));
  }
  return s;
}

// The target smallest singular value of the nearly singular classes: 1000 eps ||A||.
template <class T>
long double nearly_singular_sigma(long double norm) {
  return 1000.0L * std::numeric_limits<T>::epsilon() * norm;
}

// The smallest singular value of the stored nearly_singular_spd_system(n) (b is one number).
// tridiag(-1, beta, -1) has eigenvalues beta - 2 cos(k pi / (n+1)), k = 1..n, so sigma_min is
// exactly the stored beta minus 2 cos(pi / (n+1)) (its rounding to T shifts every eigenvalue
// by the same amount, at most eps, against a target of 4000 eps).
template <class T>
long double nearly_singular_spd_sigma_min(const System<T>& s) {
  const long double pi = 3.141592653589793238462643383279502884L;
  const long double n = static_cast<long double>(s.n());
  return static_cast<long double>(s.b[0]) - 2 * std::cos(pi / (n + 1));
}

// Nearly singular, positive definite: tridiag(-1, 2 - lambda_1 + sigma, -1), where
// lambda_1 = 2 - 2 cos(pi/(n+1)) is the smallest eigenvalue of the Poisson matrix and
// sigma = 1000 eps ||A||_inf with ||A||_inf = 4; the smallest eigenvalue, which is the smallest
// singular value since the matrix is symmetric positive definite, is sigma (see
// nearly_singular_spd_sigma_min), so kappa_2 ~ 4 / sigma = 1e-3 / eps. The diagonal is
// 2 - lambda_1 + sigma: below 2, so not dominant, when lambda_1 > sigma (double: every n below
// 3e6; float: n < 143), and dominant otherwise (float, n >= 143). Hence Dominance::Varies.
template <class T>
System<T> nearly_singular_spd_system(std::ptrdiff_t n, std::uint64_t seed) {
  stability::Draw draw(seed);
  const long double pi = 3.141592653589793238462643383279502884L;
  const long double lambda_1 = 2 - 2 * std::cos(pi / (static_cast<long double>(n) + 1));
  const T diagonal = static_cast<T>(2 - lambda_1 + nearly_singular_sigma<T>(4));
  auto s = stability::zero_system<T>(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    s.a[i] = i > 0 ? T(-1) : T(0);
    s.b[i] = diagonal;
    s.c[i] = i + 1 < n ? T(-1) : T(0);
    s.d[i] = static_cast<T>(draw.uniform(-1, 1));
  }
  return s;
}

// Nearly singular, indefinite and not dominant: a planted null vector, then a shift. A random
// symmetric tridiagonal A0 with A0 v = 0 exactly: off-diagonals c_i = a_{i+1} uniform in
// [-1, 1], v_i of magnitude in [1/2, 1] with random signs, and
//   b_i = -(a_i v_{i-1} + c_i v_{i+1}) / v_i   (|b_i| <= 4),
// computed in long double; then A = A0 + sigma I with sigma = 1000 eps ||A0||_inf. A is
// symmetric, so its singular values are |lambda_j(A0) + sigma|: the planted eigenvalue 0
// becomes sigma, and sigma_min(A) = min_j |lambda_j(A0) + sigma| <= sigma. Rounding b to T
// moves each eigenvalue by at most 4u, 1/2000 of sigma. The other eigenvalues of A0 are spread
// over [-6, 6] about 12/n apart, so in double (sigma ~ 1e-12) sigma_min = sigma for the sizes
// used, while in float (sigma ~ 7e-4) at large n a neighbouring eigenvalue may come closer to
// -sigma than sigma; dgtcon's kappa in the stability table shows the value reached.
// The signs of b are mixed, so A is indefinite, and not dominant: the pivot-free methods must
// refuse it.
template <class T>
System<T> nearly_singular_indefinite_system(std::ptrdiff_t n, std::uint64_t seed) {
  stability::Draw draw(seed);
  std::vector<long double> c(n, 0), v(n), b(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    c[i] = i + 1 < n ? draw.uniform(-1, 1) : 0;
    v[i] = draw.signed_magnitude(0.5, 1);
  }
  long double norm = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const long double left = i > 0 ? c[i - 1] * v[i - 1] : 0;  // a_i = c_{i-1}
    const long double right = i + 1 < n ? c[i] * v[i + 1] : 0;
    b[i] = -(left + right) / v[i];
    norm = std::max(norm, (i > 0 ? std::abs(c[i - 1]) : 0) + std::abs(b[i]) + std::abs(c[i]));
  }
  const long double sigma = nearly_singular_sigma<T>(norm);
  auto s = stability::zero_system<T>(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    s.a[i] = i > 0 ? static_cast<T>(c[i - 1]) : T(0);
    s.b[i] = static_cast<T>(b[i] + sigma);
    s.c[i] = static_cast<T>(c[i]);
    s.d[i] = static_cast<T>(draw.uniform(-1, 1));
  }
  return s;
}

// Row scaling: a strictly dominant system (dominant_at_scale, magnitudes in [1/2, 3]) with its
// rows (and their right-hand sides) multiplied by factors drawn from {low, high}. Row scaling
// leaves x and row dominance unchanged, so every method must still accept and solve it, but
// ||A|| ||A^{-1}|| grows by high / low and so does every quotient of entries from neighbouring
// rows (the multipliers of cyclic reduction, a[i]/b[i-1]; those of partial pivoting). Thomas
// is invariant under row scaling; partial pivoting (Pivoting, LAPACK ?gtsv) is not: its
// row interchanges follow the scaling, and its forward error grows with it (in float at
// n = 65537: ~0.1-0.6 against 2e-7 for Thomas, see the stability table).
template <class T>
System<T> row_scaled(System<T> s, std::uint64_t seed, long double low, long double high) {
  stability::Draw draw(seed ^ 0x5ca1ab1eULL);
  for (std::ptrdiff_t i = 0; i < s.n(); ++i) {
    const long double factor = draw.coin() ? high : low;
    for (auto* entry : {&s.a[i], &s.b[i], &s.c[i], &s.d[i]})
      *entry = static_cast<T>(static_cast<long double>(*entry) * factor);
  }
  return s;
}

// Half of the rows (at random) times 1e+30. Representable in float (FLT_MAX ~ 3.4e38); every
// neighbour ratio is 1, 1e30 or 1e-30, also representable.
template <class T>
System<T> rows_scaled_up_system(std::ptrdiff_t n, std::uint64_t seed) {
  return row_scaled(stability::dominant_at_scale<T>(n, seed, 1), seed, 1, 1e30L);
}

// Half of the rows (at random) times 1e-30. In float the smallest entries, 1e-30 / 2, stay far
// from the subnormal range (FLT_MIN ~ 1.2e-38).
template <class T>
System<T> rows_scaled_down_system(std::ptrdiff_t n, std::uint64_t seed) {
  return row_scaled(stability::dominant_at_scale<T>(n, seed, 1), seed, 1e-30L, 1);
}

// Every row times 1e+30 or 1e-30 (at random): every entry is representable in float, but the
// ratio of neighbouring rows is up to 1e60, which is not (FLT_MAX ~ 3.4e38, and 1e-60 is below
// the smallest subnormal, 1.4e-45). Quotients across rows therefore overflow to inf or
// underflow to 0 in float, and what happens there (measured):
//  - Thomas, and so Auto, never form them (each multiplier is a quotient within one row) and
//    solve it to float accuracy;
//  - CR, PCR and the hybrid: a[i]/b[i-1] overflows, the reduced pivot becomes inf or NaN and
//    the vanishing-pivot check throws NumericalError ("zero or vanishing pivot ... singular");
//  - partial pivoting (Pivoting and LAPACK sgtsv alike): the multiplier b[i]/a[i+1] of an
//    interchange underflows to 0, so the row moved down loses what it should have received
//    and becomes zero; the zero row travels down with each interchange and the last pivot is
//    exactly zero: sgtsv returns info = n, Pivoting throws NumericalError (singular).
// No method returns a non-finite x. In double every quotient is representable and every method
// solves it. The matrix is well posed in both precisions (a row-scaled dominant matrix).
template <class T>
System<T> rows_scaled_mixed_system(std::ptrdiff_t n, std::uint64_t seed) {
  return row_scaled(stability::dominant_at_scale<T>(n, seed, 1), seed, 1e-30L, 1e30L);
}

// Entries near the top of T's range: dominant_at_scale with scale 10^(max_exponent10 - 1),
// 1e37 in float (FLT_MAX ~ 3.4e38), 1e307 in double; the largest entries are ~3 scale, about
// FLT_MAX / 10, so one product of two entries, or a sum of a dozen, overflows. The
// right-hand side has the same scale, so x is O(1).
template <class T>
System<T> near_overflow_system(std::ptrdiff_t n, std::uint64_t seed) {
  const long double scale = std::pow(10.0L, std::numeric_limits<T>::max_exponent10 - 1);
  return stability::dominant_at_scale<T>(n, seed, scale);
}

// Entries near the bottom of T's normal range: dominant_at_scale with scale
// 10^min_exponent10, 1e-37 in float, 1e-307 in double; the smallest entries are ~scale / 2,
// above the smallest normal (FLT_MIN ~ 1.2e-38, DBL_MIN ~ 2.2e-308), but any product of two
// entries underflows to 0. The right-hand side has the same scale, so x is O(1).
template <class T>
System<T> near_underflow_system(std::ptrdiff_t n, std::uint64_t seed) {
  const long double scale = std::pow(10.0L, std::numeric_limits<T>::min_exponent10);
  return stability::dominant_at_scale<T>(n, seed, scale);
}

// Half of the rows (at random) times 10^(max_exponent10 - 2), 1e36 in float, 1e306 in double:
// those rows' entries reach ~3e36 (float), a tenth of the way to FLT_MAX / 10, while their
// neighbours are O(1). Quotients across rows are 1e36 or 1e-36: representable in float, but
// a product of two of them is not.
template <class T>
System<T> rows_near_overflow_system(std::ptrdiff_t n, std::uint64_t seed) {
  const long double high = std::pow(10.0L, std::numeric_limits<T>::max_exponent10 - 2);
  return row_scaled(stability::dominant_at_scale<T>(n, seed, 1), seed, 1, high);
}

// Half of the rows (at random) times 10^min_exponent10, 1e-37 in float, 1e-307 in double:
// those rows' smallest entries, ~5e-38 in float, are just above the smallest normal number
// (FLT_MIN ~ 1.2e-38), so any product with them, or a quotient by a neighbour, is subnormal.
template <class T>
System<T> rows_near_underflow_system(std::ptrdiff_t n, std::uint64_t seed) {
  const long double low = std::pow(10.0L, std::numeric_limits<T>::min_exponent10);
  return row_scaled(stability::dominant_at_scale<T>(n, seed, 1), seed, low, 1);
}

// gallery('dorr', n, theta) of MATLAB (Higham's Test Matrix Toolbox; F. W. Dorr, Math. Comp.
// 25 (1971) 271-283): with h = 1/(n+1) and m = floor((n+1)/2), rows i = 1..n (1-based) have
//   i <= m:  sub = -theta/h^2,              super = sub - (1/2 - i h)/h,
//   i >  m:  super = -theta/h^2,            sub = super + (1/2 - i h)/h,
// and diag = -(sub + super): an upwind scheme for a singularly perturbed two-point problem.
// An M-matrix, row diagonally dominant (strictly only in the first and the last row, by
// theta (n+1)^2), and ill conditioned for small theta: the columns of A^-1 vary greatly in
// norm. PCR and the hybrid lost every digit on it (backward error 0.5 in double at n = 512,
// theta = 1e-4) while each of their levels passed the vanishing-pivot test. Computed in long
// double, rounded once (each row stays dominant within the library's 4 eps slack). Random rhs.
template <class T>
System<T> dorr_system(std::ptrdiff_t n, std::uint64_t seed, long double theta) {
  stability::Draw draw(seed);
  const long double h = 1.0L / static_cast<long double>(n + 1), term = theta / (h * h);
  const std::ptrdiff_t m = (n + 1) / 2;
  auto s = stability::zero_system<T>(n);
  for (std::ptrdiff_t k = 1; k <= n; ++k) {
    const long double drift = (0.5L - static_cast<long double>(k) * h) / h;
    const long double sub = k <= m ? -term : -term + drift;
    const long double super = k <= m ? -term - drift : -term;
    const std::ptrdiff_t i = k - 1;
    s.a[i] = i > 0 ? static_cast<T>(sub) : T(0);
    s.c[i] = i + 1 < n ? static_cast<T>(super) : T(0);
    s.b[i] = static_cast<T>(-(sub + super));
    s.d[i] = static_cast<T>(draw.uniform(-1, 1));
  }
  return s;
}

// theta = 0.01 (MATLAB's default). dgtcon's kappa_1 at the table's seeds: 5e4, 9e9, 5e13 for
// n = 16, 1000, 65537: forward errors mean something in double, in float only at small n.
template <class T>
System<T> dorr_1e2_system(std::ptrdiff_t n, std::uint64_t seed) {
  return dorr_system<T>(n, seed, 1e-2L);
}

// theta = 1e-4, the case where PCR lost every digit. dgtcon's kappa_1: 5e18, 8e20, 2e20 for
// n = 16, 1000, 65537 (kappa u >> 1 in both precisions): only backward errors mean anything.
// Thomas overflows at n = 65537 in both; Auto then pivots.
template <class T>
System<T> dorr_1e4_system(std::ptrdiff_t n, std::uint64_t seed) {
  return dorr_system<T>(n, seed, 1e-4L);
}

// gallery('clement', n) of MATLAB (Clement 1959; Higham's Test Matrix Toolbox): zero diagonal,
// sub-diagonal n-1, n-2, ..., 1, super-diagonal 1, 2, ..., n-1 (entry (i+1, i) is n - i and
// (i, i+1) is i, 1-based). Its eigenvalues are the integers +-(n-1), +-(n-3), ...; for odd n
// one of them is 0, so for odd n the class is the Clement matrix of order n - 1 with a last
// row and column of the identity, nonsingular. Not dominant (the diagonal is zero): every
// step of pivoting interchanges rows; the pivot-free methods must refuse it. Far from normal:
// dgtcon's kappa_1 is 9e2 at n = 16 and 9e151 at n = 1000, and partial pivoting meets an
// exactly zero pivot (underflow) from n = 1000 in float and at 65537 in double, ?gtsv at the
// same row; Eigen's sparse LU in long double does too at 65537 (no reference there).
template <class T>
System<T> clement_system(std::ptrdiff_t n, std::uint64_t seed) {
  stability::Draw draw(seed);
  const std::ptrdiff_t order = n % 2 == 0 ? n : n - 1;
  auto s = stability::zero_system<T>(n);
  for (std::ptrdiff_t i = 0; i < order; ++i) {
    s.a[i] = i > 0 ? static_cast<T>(order - i) : T(0);
    s.c[i] = i + 1 < order ? static_cast<T>(i + 1) : T(0);
  }
  if (order < n) s.b[n - 1] = T(1);
  for (std::ptrdiff_t i = 0; i < n; ++i) s.d[i] = static_cast<T>(draw.uniform(-1, 1));
  return s;
}

// Kahan-type graded rows: gallery('kahan', n, 1.2) is diag(1, s, ..., s^(n-1)) times the unit
// upper triangle with -c above the diagonal (s = sin 1.2, c = cos 1.2); its tridiagonal
// counterpart here is diag(r^i) tridiag(-c, 1, -c), row i graded by r^i with
// r = max(s, 1e-30^(1/(n-1))) so that the last rows stay far from underflow in float. Dominant
// by rows (2c = 0.72 < 1) but not by columns once r < 0.5 (small n): a column meets c r^(i-1)
// from the row above, up to 1/r times its own diagonal. Quotients of neighbouring rows are
// 1/r; row scaling leaves Thomas unchanged but not the multipliers of CR and of pivoting.
// The rhs is graded with its row, so x is O(1).
template <class T>
System<T> kahan_tridiagonal_system(std::ptrdiff_t n, std::uint64_t seed) {
  stability::Draw draw(seed);
  const long double sine = std::sin(1.2L), cosine = std::cos(1.2L);
  const long double ratio =
      n > 1 ? std::max(sine, std::pow(1e-30L, 1.0L / static_cast<long double>(n - 1))) : 1;
  auto s = stability::zero_system<T>(n);
  long double grade = 1;
  for (std::ptrdiff_t i = 0; i < n; ++i, grade *= ratio) {
    s.a[i] = i > 0 ? static_cast<T>(-cosine * grade) : T(0);
    s.b[i] = static_cast<T>(grade);
    s.c[i] = i + 1 < n ? static_cast<T>(-cosine * grade) : T(0);
    s.d[i] = static_cast<T>(draw.uniform(-1, 1) * grade);
  }
  return s;
}

// One class of matrices: a name for tables and test traces, what it is, whether the
// pivot-free methods may accept it, and its generator for each precision.
struct MatrixClass {
  std::string_view name;
  std::string_view description;
  Dominance dominance;
  System<float> (*make_float)(std::ptrdiff_t n, std::uint64_t seed);
  System<double> (*make_double)(std::ptrdiff_t n, std::uint64_t seed);

  template <class T>
  System<T> make(std::ptrdiff_t n, std::uint64_t seed) const {
    static_assert(std::is_same_v<T, float> || std::is_same_v<T, double>,
                  "the stability classes are defined for float and double");
    if constexpr (std::is_same_v<T, float>)
      return make_float(n, seed);
    else
      return make_double(n, seed);
  }
};

#define TRIDIFF_STABILITY_CLASS(name, description, dominance, generator) \
  MatrixClass { name, description, dominance, &generator<float>, &generator<double> }

// Every class, in table order.
inline const MatrixClass kStabilityClasses[] = {
    TRIDIFF_STABILITY_CLASS("strictly_dominant", "|b| >= |a| + |c| + 1, entries uniform",
                            Dominance::Dominant, strictly_dominant_system),
    TRIDIFF_STABILITY_CLASS("weakly_dominant", "|b| = |a| + |c| in every row but one, random signs",
                            Dominance::Dominant, weakly_dominant_system),
    TRIDIFF_STABILITY_CLASS("poisson", "tridiag(-1, 2, -1), kappa ~ 0.4 n^2", Dominance::Dominant,
                            poisson_system),
    TRIDIFF_STABILITY_CLASS("random_nondominant", "every entry uniform in [-1, 1]",
                            Dominance::NotDominant, random_nondominant_system),
    TRIDIFF_STABILITY_CLASS("nearly_singular_spd",
                            "Poisson shifted: sigma_min = 1000 eps ||A||_inf exactly",
                            Dominance::Varies, nearly_singular_spd_system),
    TRIDIFF_STABILITY_CLASS("nearly_singular_indefinite",
                            "symmetric, planted null vector, + 1000 eps ||A|| I",
                            Dominance::NotDominant, nearly_singular_indefinite_system),
    TRIDIFF_STABILITY_CLASS("rows_scaled_1e+30", "strictly dominant, half the rows x 1e+30",
                            Dominance::Dominant, rows_scaled_up_system),
    TRIDIFF_STABILITY_CLASS("rows_scaled_1e-30", "strictly dominant, half the rows x 1e-30",
                            Dominance::Dominant, rows_scaled_down_system),
    TRIDIFF_STABILITY_CLASS("rows_scaled_1e+-30",
                            "strictly dominant, rows x 1e+30 or 1e-30 (ratios 1e60)",
                            Dominance::Dominant, rows_scaled_mixed_system),
    TRIDIFF_STABILITY_CLASS("near_overflow", "dominant, entries ~ 10^(max_exponent10 - 1)",
                            Dominance::Dominant, near_overflow_system),
    TRIDIFF_STABILITY_CLASS("near_underflow", "dominant, entries ~ 10^min_exponent10, normal",
                            Dominance::Dominant, near_underflow_system),
    TRIDIFF_STABILITY_CLASS("rows_near_overflow",
                            "strictly dominant, half the rows x 10^(max_exponent10 - 2)",
                            Dominance::Dominant, rows_near_overflow_system),
    TRIDIFF_STABILITY_CLASS("rows_near_underflow",
                            "strictly dominant, half the rows x 10^min_exponent10",
                            Dominance::Dominant, rows_near_underflow_system),
    TRIDIFF_STABILITY_CLASS("dorr_1e-2", "gallery('dorr', n, 0.01): weakly dominant M-matrix",
                            Dominance::Dominant, dorr_1e2_system),
    TRIDIFF_STABILITY_CLASS("dorr_1e-4", "gallery('dorr', n, 1e-4): kappa_1 ~ 1e20, backward only",
                            Dominance::Dominant, dorr_1e4_system),
    TRIDIFF_STABILITY_CLASS("clement", "gallery('clement', n): zero diagonal, integer entries",
                            Dominance::NotDominant, clement_system),
    TRIDIFF_STABILITY_CLASS("kahan_tridiagonal", "diag(r^i) tridiag(-cos 1.2, 1, -cos 1.2)",
                            Dominance::Dominant, kahan_tridiagonal_system),
};

#undef TRIDIFF_STABILITY_CLASS

}  // namespace tridiff::test
