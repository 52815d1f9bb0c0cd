// The 1-norm of a matrix B known only through products B x and B^H x: Hager's estimator with
// Higham's refinements (Higham, "FORTRAN codes for estimating the one-norm of a real or complex
// matrix", ACM TOMS 14, 1988, Algorithm 4.1), as LAPACK ?lacn2 runs it. ?gtcon applies it to
// B = A^{-1} for the condition number, ?gtrfs to |A^{-1}| diag(w) for the forward error bound.
// The estimate is a lower bound, in practice within a factor of 3 and usually exact.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

template <class T>
real_t<T> norm1_of(const std::vector<T>& x) {
  real_t<T> sum = 0;
  for (const T& value : x) sum += modulus(value);
  return sum;
}

// x_i / |x_i| (1 where x_i = 0): the subgradient of the 1-norm at x.
template <class T>
T sign_of(const T& value) {
  const real_t<T> size = modulus(value);
  if constexpr (is_complex_v<T>)
    return size > 0 ? value / size : T(1);
  else
    return value >= 0 ? T(1) : T(-1);
}

template <class T>
std::ptrdiff_t index_of_largest(const std::vector<T>& x) {
  std::ptrdiff_t best = 0;
  for (std::ptrdiff_t i = 1; i < std::ptrdiff_t(x.size()); ++i)
    if (modulus(x[i]) > modulus(x[best])) best = i;
  return best;
}

// ||B||_1 estimated with at most 5 products by B and 5 by B^H; apply(x) overwrites x with B x,
// apply_adjoint(x) with B^H x.
template <class T, class Apply, class ApplyAdjoint>
real_t<T> estimate_norm1(std::ptrdiff_t n, Apply&& apply, ApplyAdjoint&& apply_adjoint) {
  using R = real_t<T>;
  constexpr int kMaxIterations = 5;
  std::vector<T> x(n, T(R(1) / R(n))), signs(n);
  apply(x);
  if (n == 1) return modulus(x[0]);
  R estimate = norm1_of(x);
  for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = signs[i] = sign_of(x[i]);
  apply_adjoint(x);
  std::ptrdiff_t j = index_of_largest(x);
  for (int iteration = 2;; ++iteration) {
    std::fill(x.begin(), x.end(), T(0));
    x[j] = T(1);
    apply(x);
    const R previous = estimate;
    estimate = norm1_of(x);
    bool repeated = !is_complex_v<T>;  // a real sign vector seen before: converged
    for (std::ptrdiff_t i = 0; i < n && repeated; ++i) repeated = sign_of(x[i]) == signs[i];
    if (repeated || estimate <= previous) break;
    for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = signs[i] = sign_of(x[i]);
    apply_adjoint(x);
    const std::ptrdiff_t last = j;
    j = index_of_largest(x);
    if (modulus(x[last]) == modulus(x[j]) || iteration >= kMaxIterations) break;
  }
  // Higham's extra test vector of alternating signs and growing size catches the matrices
  // (some of them tridiagonal) on which the gradient steps stall.
  for (std::ptrdiff_t i = 0; i < n; ++i)
    x[i] = T((i % 2 == 0 ? R(1) : R(-1)) * (1 + R(i) / R(n - 1)));
  apply(x);
  return std::max(estimate, 2 * norm1_of(x) / (3 * R(n)));
}

}  // namespace tridiff::detail
