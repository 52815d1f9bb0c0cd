// Thomas for the implicit diffusion system of seed 000 eq. 3.10:
//   a_i = -beta_{i-1},  c_i = -beta_i,  b_i = 1 + beta_{i-1} + beta_i,  beta_{-1} = beta_{n-1} = 0,
// stored as beta alone (one coefficient array instead of three).
//
// With beta >= 0 the matrix is strictly diagonally dominant, every pivot is >= 1 and the solve
// is stable for any beta. The elimination is written without subtractions: with
//   g_i = 1 + beta_{i-1} * e_{i-1},  m_i = g_i + beta_i,  e_i = g_i / m_i  (= 1 + c'_i),
// all terms are non-negative, so even beta ~ 1e6 in float loses no digits to cancellation, and
// the solution is a convex combination of the right-hand side (no new extrema).
#pragma once

#include <algorithm>
#include <cstddef>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

// One system; x may alias d. beta[n-1] is never read. `work` holds n reals.
template <class T>
void diffusion_thomas(std::ptrdiff_t n, Strided<const real_t<T>> beta, Strided<const T> d,
                      Strided<T> x, real_t<T>* work) {
  using R = real_t<T>;
  R beta_before = 0, e_before = 1;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const R beta_here = i + 1 < n ? beta[i] : R(0);
    const R g = 1 + beta_before * e_before;
    const R inverse = 1 / (g + beta_here);
    x[i] = (d[i] + (i == 0 ? T(0) : beta_before * x[i - 1])) * inverse;
    work[i] = beta_here * inverse;  // -c'_i
    e_before = g * inverse;
    beta_before = beta_here;
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) x[i] += work[i] * x[i + 1];
}

// W systems at once, lane-contiguous as in thomas_lanes. `work` holds n * W reals.
// Returns false if some beta is negative or not finite, or the result is not finite.
template <class T, int W>
bool diffusion_thomas_lanes(std::ptrdiff_t n, const real_t<T>* beta, const T* d, T* x,
                            std::ptrdiff_t row_stride, real_t<T>* work) {
  using R = real_t<T>;
  R beta_before[W], e_before[W], min_beta[W], probe[W];
  T previous_x[W];
  for (int l = 0; l < W; ++l) {
    beta_before[l] = 0;
    e_before[l] = 1;
    min_beta[l] = 0;
    probe[l] = 0;
    previous_x[l] = T(0);
  }
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::ptrdiff_t row = i * row_stride;
    const bool has_link = i + 1 < n;  // beta[n-1] is not part of the system
    R* w = work + i * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const R beta_here = has_link ? beta[row + l] : R(0);
      const R g = 1 + beta_before[l] * e_before[l];
      const R inverse = 1 / (g + beta_here);
      const T xi = (d[row + l] + beta_before[l] * previous_x[l]) * inverse;
      x[row + l] = xi;
      previous_x[l] = xi;
      w[l] = beta_here * inverse;
      e_before[l] = g * inverse;
      beta_before[l] = beta_here;
      min_beta[l] = std::min(min_beta[l], beta_here);
      probe[l] += beta_here * 0 + magnitude(xi) * 0;
    }
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) {
    const std::ptrdiff_t row = i * row_stride;
    const R* w = work + i * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const T xi = x[row + l] + w[l] * x[row + row_stride + l];
      x[row + l] = xi;
      probe[l] += magnitude(xi) * 0;
    }
  }
  bool healthy = true;
  for (int l = 0; l < W; ++l) healthy = healthy && min_beta[l] >= 0 && probe[l] == 0;
  return healthy;
}

}  // namespace tridiff::detail
