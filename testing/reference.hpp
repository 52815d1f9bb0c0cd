// Test support: random systems, an independent reference solve (Eigen LU in long double), and
// the forward and backward errors of a computed solution.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <cmath>
#include <complex>
#include <limits>
#include <random>
#include <vector>

#include "tridiff/solvers.hpp"

namespace tridiff::test {

// long double, or std::complex<long double> for complex T.
template <class T>
using Wide = std::conditional_t<is_complex_v<T>, std::complex<long double>, long double>;

template <class T>
long double magnitude(const T& x) {
  return std::abs(static_cast<Wide<T>>(x));
}

// One system: a[0] and c[n-1] are the corner entries when periodic, else unused (zero).
template <class T>
struct System {
  std::vector<T> a, b, c, d;
  bool periodic = false;
  std::ptrdiff_t n() const { return static_cast<std::ptrdiff_t>(b.size()); }
};

template <class T>
T random_scalar(std::mt19937_64& random, real_t<T> low, real_t<T> high) {
  std::uniform_real_distribution<real_t<T>> uniform(low, high);
  if constexpr (is_complex_v<T>)
    return T(uniform(random), uniform(random));
  else
    return uniform(random);
}

// Strictly diagonally dominant by rows, |b_i| >= |a_i| + |c_i| + 1, with random signs.
template <class T>
System<T> random_dominant(std::ptrdiff_t n, std::uint64_t seed, bool periodic = false) {
  std::mt19937_64 random(seed);
  System<T> s;
  s.periodic = periodic;
  s.a.resize(n);
  s.b.resize(n);
  s.c.resize(n);
  s.d.resize(n);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    s.a[i] = (i > 0 || periodic) ? random_scalar<T>(random, -1, 1) : T(0);
    s.c[i] = (i + 1 < n || periodic) ? random_scalar<T>(random, -1, 1) : T(0);
    const T direction = random_scalar<T>(random, -1, 1);
    const real_t<T> size = static_cast<real_t<T>>(magnitude(direction));
    const real_t<T> needed = static_cast<real_t<T>>(magnitude(s.a[i]) + magnitude(s.c[i])) + 1 +
                             std::uniform_real_distribution<real_t<T>>(0, 1)(random);
    s.b[i] = size > 0 ? direction * (needed / size) : T(needed);
    s.d[i] = random_scalar<T>(random, -1, 1);
  }
  return s;
}

template <class T>
using WideVector = Eigen::Matrix<Wide<T>, Eigen::Dynamic, 1>;

template <class T>
Eigen::SparseMatrix<Wide<T>> wide_matrix(const System<T>& s) {
  const std::ptrdiff_t n = s.n();
  std::vector<Eigen::Triplet<Wide<T>>> entries;
  auto add = [&](std::ptrdiff_t i, std::ptrdiff_t j, const T& v) {
    entries.emplace_back(static_cast<int>(i), static_cast<int>(j), static_cast<Wide<T>>(v));
  };
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    add(i, i, s.b[i]);
    if (i > 0) add(i, i - 1, s.a[i]);
    if (i + 1 < n) add(i, i + 1, s.c[i]);
  }
  if (s.periodic) {  // duplicates are summed, which is what n = 1 and n = 2 need
    add(0, n - 1, s.a[0]);
    add(n - 1, 0, s.c[n - 1]);
  }
  Eigen::SparseMatrix<Wide<T>> m(n, n);
  m.setFromTriplets(entries.begin(), entries.end());
  return m;
}

// The solution in long double: dense partial-pivoting LU for small n, sparse LU beyond. Where
// the sparse LU finds a zero pivot (a matrix singular in long double, e.g. gallery('clement')
// at n = 65537) there is no reference: every entry is NaN. (Eigen's solve after a failed
// factorisation frees memory it does not own.)
template <class T>
WideVector<T> reference_solve(const System<T>& s) {
  const auto matrix = wide_matrix(s);
  WideVector<T> rhs(s.n());
  for (std::ptrdiff_t i = 0; i < s.n(); ++i) rhs[i] = static_cast<Wide<T>>(s.d[i]);
  if (s.n() <= 64) {
    Eigen::Matrix<Wide<T>, Eigen::Dynamic, Eigen::Dynamic> dense(matrix);
    return dense.partialPivLu().solve(rhs);
  }
  Eigen::SparseLU<Eigen::SparseMatrix<Wide<T>>> lu;
  lu.compute(matrix);
  if (lu.info() != Eigen::Success)
    return WideVector<T>::Constant(s.n(), Wide<T>(std::numeric_limits<long double>::quiet_NaN()));
  return lu.solve(rhs);
}

// max_i |x_i - ref_i| / max_i |ref_i|
template <class T>
long double forward_error(const std::vector<T>& x, const WideVector<T>& ref) {
  long double worst = 0, scale = 0;
  for (std::ptrdiff_t i = 0; i < ref.size(); ++i) {
    worst = std::max(worst, std::abs(static_cast<Wide<T>>(x[i]) - ref[i]));
    scale = std::max(scale, std::abs(ref[i]));
  }
  return scale > 0 ? worst / scale : worst;
}

// Normwise backward error ||d - A x|| / (||A|| ||x|| + ||d||), infinity norms, in long double.
template <class T>
long double backward_error(const System<T>& s, const std::vector<T>& x) {
  const auto matrix = wide_matrix(s);
  WideVector<T> wx(s.n()), wd(s.n());
  for (std::ptrdiff_t i = 0; i < s.n(); ++i) {
    wx[i] = static_cast<Wide<T>>(x[i]);
    wd[i] = static_cast<Wide<T>>(s.d[i]);
  }
  const WideVector<T> residual = wd - matrix * wx;
  long double norm_a = 0;
  std::vector<long double> row_sums(s.n(), 0);
  for (int k = 0; k < matrix.outerSize(); ++k)
    for (typename Eigen::SparseMatrix<Wide<T>>::InnerIterator it(matrix, k); it; ++it)
      row_sums[it.row()] += std::abs(it.value());
  for (long double r : row_sums) norm_a = std::max(norm_a, r);
  auto inf_norm = [](const WideVector<T>& v) {
    long double m = 0;
    for (std::ptrdiff_t i = 0; i < v.size(); ++i) m = std::max(m, std::abs(v[i]));
    return m;
  };
  const long double denominator = norm_a * inf_norm(wx) + inf_norm(wd);
  return denominator > 0 ? inf_norm(residual) / denominator : inf_norm(residual);
}

// Varah's bound on ||A^{-1}||_inf ||A||_inf for a matrix dominant by rows.
template <class T>
long double condition_bound(const System<T>& s) {
  const std::ptrdiff_t n = s.n();
  long double norm = 0, margin = INFINITY;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const long double off = ((i > 0 || s.periodic) ? magnitude(s.a[i]) : 0) +
                            ((i + 1 < n || s.periodic) ? magnitude(s.c[i]) : 0);
    norm = std::max(norm, magnitude(s.b[i]) + off);
    margin = std::min(margin, magnitude(s.b[i]) - off);
  }
  return norm / margin;
}

template <class T>
long double unit_roundoff() {
  return std::numeric_limits<real_t<T>>::epsilon() / 2;
}

// The normwise backward error every method must meet on a dominant matrix: a small multiple
// of the unit roundoff, times the number of reduction levels for the cyclic-reduction family,
// whose rows pass through log2(n) updates.
template <class T>
long double backward_bound(Method method, std::ptrdiff_t n) {
  const long double levels = std::ceil(std::log2(static_cast<long double>(n) + 1));
  return 16 * unit_roundoff<T>() * (method_row(method).reduction ? 1 + levels : 1);
}

// Solves s with `options`, out of place, and returns x.
template <class T>
std::vector<T> solve_system(const System<T>& s, SolveOptions options) {
  options.periodic = s.periodic;
  std::vector<T> x(s.n());
  solve(s.a.data(), s.b.data(), s.c.data(), s.d.data(), x.data(), BatchLayout::single(s.n()),
        options);
  return x;
}

}  // namespace tridiff::test
