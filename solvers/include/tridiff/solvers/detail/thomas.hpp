// The Thomas algorithm (Gaussian elimination without pivoting on a tridiagonal matrix): a
// plain single-system reference, and a kernel that runs W systems at once, one per SIMD lane.
// Both are stable when the matrix is diagonally dominant by rows or columns (Higham, "Accuracy
// and Stability of Numerical Algorithms", §9.5); the caller checks that.
#pragma once

#include <algorithm>
#include <cstddef>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

// Solves one system; x may alias d (in place). a[0] and c[n-1] are never read.
// `work` holds n scalars. Returns -1, or the row whose pivot vanished.
template <class T>
std::ptrdiff_t thomas(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b, Strided<const T> c,
                      Strided<const T> d, Strided<T> x, T* work) {
  T pivot = b[0];
  if (vanishes(pivot, magnitude(b[0]))) return 0;
  // The previous row's values travel in registers, off the memory round trip.
  T previous_x = T(0), previous_c = T(0);
  for (std::ptrdiff_t i = 0;; ++i) {
    const T inverse = T(1) / pivot;
    previous_x = (i == 0 ? d[0] : d[i] - a[i] * previous_x) * inverse;
    x[i] = previous_x;
    if (i == n - 1) break;
    previous_c = c[i] * inverse;  // the super-diagonal of the unit upper factor
    work[i] = previous_c;
    const T eliminated = a[i + 1] * previous_c;
    pivot = b[i + 1] - eliminated;
    if (vanishes(pivot, magnitude(b[i + 1]) + magnitude(eliminated))) return i + 1;
  }
  T next = previous_x;
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) {
    next = x[i] - work[i] * next;
    x[i] = next;
  }
  return -1;
}

// The same algorithm on W systems whose equation i lies at `p + i * row_stride + lane`
// (lane-contiguous, so every step loads one vector per array). `work` holds n * W scalars.
// Returns false if any lane met a vanishing pivot or produced a non-finite value; the caller
// then re-solves the lanes one by one with `thomas` to name the culprit.
template <class T, int W>
bool thomas_lanes(std::ptrdiff_t n, const T* a, const T* b, const T* c, const T* d, T* x,
                  std::ptrdiff_t row_stride, T* work) {
  using R = real_t<T>;
  const R tolerance = kVanishingPivot * epsilon<T>;
  T inverse[W], previous_x[W];
  R margin[W];  // min over rows of |pivot| - tolerance * scale: must stay positive
  R probe[W];   // sum of value * 0 over everything produced: NaN iff something is not finite
  for (int l = 0; l < W; ++l) {
    margin[l] = magnitude(b[l]) * (1 - tolerance);
    inverse[l] = T(1) / b[l];
    previous_x[l] = T(0);
    probe[l] = magnitude(b[l]) * 0;  // an infinite first pivot would pass unseen otherwise
  }
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::ptrdiff_t row = i * row_stride;
    const std::ptrdiff_t next = row + row_stride;
    T* w = work + i * W;
    const bool last = i == n - 1;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const T xi = (d[row + l] - (i == 0 ? T(0) : a[row + l] * previous_x[l])) * inverse[l];
      x[row + l] = xi;
      previous_x[l] = xi;
      probe[l] += magnitude(xi) * 0;
    }
    if (last) break;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      w[l] = c[row + l] * inverse[l];
      const T eliminated = a[next + l] * w[l];
      const T pivot = b[next + l] - eliminated;
      const R scale = magnitude(b[next + l]) + magnitude(eliminated);
      margin[l] = std::min(margin[l], magnitude(pivot) - tolerance * scale);
      probe[l] += scale * 0;
      inverse[l] = T(1) / pivot;
    }
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) {
    const std::ptrdiff_t row = i * row_stride;
    const T* w = work + i * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const T xi = x[row + l] - w[l] * x[row + row_stride + l];
      x[row + l] = xi;
      probe[l] += magnitude(xi) * 0;
    }
  }
  bool healthy = true;
  for (int l = 0; l < W; ++l) healthy = healthy && margin[l] > 0 && probe[l] == 0;
  return healthy;
}

}  // namespace tridiff::detail
