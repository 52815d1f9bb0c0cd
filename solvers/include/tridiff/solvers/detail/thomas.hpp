// The Thomas algorithm (Gaussian elimination without pivoting on a tridiagonal matrix): a
// plain single-system reference, and a kernel that runs W systems at once, one per SIMD lane.
// Both are stable when the matrix is diagonally dominant by rows or columns (Higham, "Accuracy
// and Stability of Numerical Algorithms", §9.5); the caller checks that.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

#include "tridiff/solvers/detail/scalar.hpp"
#include "tridiff/solvers/detail/transpose.hpp"

namespace tridiff::detail {

// Scalars of workspace `thomas` needs for a system of n rows.
inline std::ptrdiff_t thomas_workspace(std::ptrdiff_t n) { return n; }

// Solves one system; x may alias d (in place). a[0] and c[n-1] are never read.
// `work` holds thomas_workspace(n) scalars. Returns -1, or the row whose pivot vanished.
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
// then re-solves the lanes one by one with `thomas` to name the culprit. x is written even
// then: x may be d only where d is a copy.
// With Check, the sweep also tests a, b and c for finite values and every lane for dominance
// by rows or by columns, and a refused lane returns false as well. (That test was a pass of
// its own, which walked image columns, a page per row, once more: 4096 x 4096 float columns
// on 2 threads of an Intel Xeon spent 52 of 89 ms in it.)
// Each row of the lanes lies in a page of its own when the systems are image columns, and the
// hardware prefetchers do not cross pages: the forward sweep asks for the inputs' row kAhead
// rows down, the backward sweep for x's row kAhead rows up (diffusion_thomas_lanes asks for a
// block of kAhead rows at a time instead). On a lane-contiguous copy (stride W) these requests
// are redundant and cheap.
template <class T, int W, bool Check = false>
bool thomas_lanes(std::ptrdiff_t n, const T* a, const T* b, const T* c, const T* d, T* x,
                  std::ptrdiff_t row_stride, T* work) {
  using R = real_t<T>;
  constexpr std::ptrdiff_t kAhead = 16;
  const R tolerance = kVanishingPivot * epsilon<T>;
  T inverse[W], previous_x[W];
  R margin[W];  // min over rows of |pivot| - tolerance * scale: must stay positive
  R probe[W];   // sum of value * 0 over everything produced: NaN iff something is not finite
  R row_failure[W], column_failure[W];  // with Check: 1 once a row (column) is not dominant
  for (int l = 0; l < W; ++l) {
    margin[l] = magnitude(b[l]) * (1 - tolerance);
    inverse[l] = T(1) / b[l];
    previous_x[l] = T(0);
    probe[l] = magnitude(b[l]) * 0;  // an infinite first pivot would pass unseen otherwise
    if constexpr (Check) row_failure[l] = column_failure[l] = 0;
  }
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::ptrdiff_t row = i * row_stride;
    const std::ptrdiff_t next = row + row_stride;
    if (i + kAhead < n) {
      const std::ptrdiff_t ahead = row + kAhead * row_stride;
      for (const T* array : {a, b, c, d}) prefetch_values(array + ahead, W);
    }
    T* w = work + i * W;
    const bool last = i == n - 1;
#pragma omp simd simdlen(kLoopWidth <T, W>)
    for (int l = 0; l < W; ++l) {
      const T xi = (d[row + l] - (i == 0 ? T(0) : a[row + l] * previous_x[l])) * inverse[l];
      x[row + l] = xi;
      previous_x[l] = xi;
      probe[l] += magnitude(xi) * 0;
    }
    if (last) break;
#pragma omp simd simdlen(kLoopWidth <T, W>)
    for (int l = 0; l < W; ++l) {
      w[l] = c[row + l] * inverse[l];
      const T eliminated = a[next + l] * w[l];
      const T pivot = b[next + l] - eliminated;
      const R scale = magnitude(b[next + l]) + magnitude(eliminated);
      margin[l] = std::min(margin[l], magnitude(pivot) - tolerance * scale);
      probe[l] += scale * 0;
      inverse[l] = T(1) / pivot;
      if constexpr (Check) {  // row i and column i (rows i - 1 and i + 1 are in L1)
        const R diagonal = modulus(b[row + l]), super = modulus(c[row + l]);
        const R sub = i > 0 ? modulus(a[row + l]) : R(0);
        const R above = i > 0 ? modulus(c[row - row_stride + l]) : R(0);
        const R below = modulus(a[next + l]);
        row_failure[l] = std::max(row_failure[l], R(diagonal < sub + super));
        column_failure[l] = std::max(column_failure[l], R(diagonal < above + below));
        probe[l] += (super + below) * 0;
      }
    }
  }
  if constexpr (Check) {  // row n-1 and column n-1 (nothing to their right and below)
    const std::ptrdiff_t row = (n - 1) * row_stride;
    for (int l = 0; l < W; ++l) {
      const R diagonal = modulus(b[row + l]);
      const R sub = n > 1 ? modulus(a[row + l]) : R(0);
      const R above = n > 1 ? modulus(c[row - row_stride + l]) : R(0);
      row_failure[l] = std::max(row_failure[l], R(diagonal < sub));
      column_failure[l] = std::max(column_failure[l], R(diagonal < above));
      probe[l] += (sub + above) * 0;
    }
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) {
    const std::ptrdiff_t row = i * row_stride;
    if (i >= kAhead) prefetch_values(x + row - kAhead * row_stride, W, true);
    const T* w = work + i * W;
#pragma omp simd simdlen(kLoopWidth <T, W>)
    for (int l = 0; l < W; ++l) {
      const T xi = x[row + l] - w[l] * x[row + row_stride + l];
      x[row + l] = xi;
      probe[l] += magnitude(xi) * 0;
    }
  }
  bool healthy = true;
  for (int l = 0; l < W; ++l) healthy = healthy && margin[l] > 0 && probe[l] == 0;
  if constexpr (Check)
    for (int l = 0; l < W; ++l)
      healthy = healthy && (row_failure[l] == 0 || column_failure[l] == 0);
  return healthy;
}

// Scalars of workspace thomas_rows needs.
template <class T>
constexpr std::ptrdiff_t thomas_rows_workspace(std::ptrdiff_t n, int lanes) {
  return 2 * n * lanes + 4 * kTransposeBlock * lanes;
}

// thomas_lanes on W contiguous systems (image rows: equation i of system l at l * pitch + i),
// the rows transposed into lanes kTransposeBlock columns at a time (in L1) as the forward sweep
// reaches them: a, b, c and d are read once, from memory, and x written once. Transposing whole
// rows into a slab first (as for other layouts) moves every array through the caches twice more.
// With Check, a lane must also be diagonally dominant by rows or by columns, tested in the
// forward sweep as thomas_lanes does.
// The solution stays in `work` until both sweeps found every lane healthy, so x may be d and a
// failed call leaves x untouched. Returns false if some lane failed (the caller re-solves the
// systems one by one).
template <class T, int W, bool Check>
bool thomas_rows(std::ptrdiff_t n, const T* a, const T* b, const T* c, const T* d, T* x,
                 std::ptrdiff_t pitch, T* work) {
  using R = real_t<T>;
  constexpr std::ptrdiff_t kBlock = kTransposeBlock;
  const R tolerance = kVanishingPivot * epsilon<T>;
  T* multipliers = work;       // c'_i = c_i / pivot_i, lane-contiguous
  T* solution = work + n * W;  // d'_i after the forward sweep, x_i after the backward one
  T* block_a = solution + n * W;
  T* block_b = block_a + kBlock * W;
  T* block_c = block_b + kBlock * W;
  T* block_d = block_c + kBlock * W;
  const T *rows_a[W], *rows_b[W], *rows_c[W], *rows_d[W];
  for (int l = 0; l < W; ++l) {
    rows_a[l] = a + l * pitch;
    rows_b[l] = b + l * pitch;
    rows_c[l] = c + l * pitch;
    rows_d[l] = d + l * pitch;
  }
  T previous_x[W], previous_w[W];
  R margin[W];  // min over rows of |pivot| - tolerance * scale: must stay positive
  R probe[W];   // sum of value * 0 over everything read and produced: NaN iff not all finite
  // Dominance: row i is checked at row i; column i - 1 (|b_{i-1}| against |c_{i-2}| + |a_i|)
  // also at row i, from the magnitudes carried over.
  R row_failure[W], column_failure[W], diagonal_before[W], super_before[W], super_before2[W];
  for (int l = 0; l < W; ++l) {
    previous_x[l] = previous_w[l] = T(0);
    margin[l] = std::numeric_limits<R>::max();
    probe[l] = row_failure[l] = column_failure[l] = 0;
    diagonal_before[l] = super_before[l] = super_before2[l] = 0;
  }
  for (std::ptrdiff_t begin = 0; begin < n; begin += kBlock) {
    const std::ptrdiff_t columns = std::min(kBlock, n - begin);
    gather_into_lanes<T, W>(rows_a, begin, columns, block_a, n);
    gather_into_lanes<T, W>(rows_b, begin, columns, block_b, n);
    gather_into_lanes<T, W>(rows_c, begin, columns, block_c, n);
    gather_into_lanes<T, W>(rows_d, begin, columns, block_d, n);
    for (std::ptrdiff_t k = 0; k < columns; ++k) {
      const std::ptrdiff_t i = begin + k;
      const bool first = i == 0, last = i == n - 1;  // a_0 and c_{n-1} are not part of it
      T* w = multipliers + i * W;
      T* y = solution + i * W;
#pragma omp simd
      for (int l = 0; l < W; ++l) {
        // Loaded whatever the row, then selected: a load under a condition is control flow
        // the vectoriser gives up on.
        const T a_read = block_a[k * W + l], c_read = block_c[k * W + l];
        const T ai = first ? T(0) : a_read;
        const T bi = block_b[k * W + l];
        const T ci = last ? T(0) : c_read;
        const T eliminated = ai * previous_w[l];
        const T pivot = bi - eliminated;
        const R scale = magnitude(bi) + magnitude(eliminated);
        margin[l] = std::min(margin[l], magnitude(pivot) - tolerance * scale);
        const T inverse = T(1) / pivot;
        const T yi = (block_d[k * W + l] - ai * previous_x[l]) * inverse;
        const T wi = ci * inverse;
        y[l] = yi;
        w[l] = wi;
        previous_x[l] = yi;
        previous_w[l] = wi;
        probe[l] += (scale + magnitude(yi) + magnitude(ci)) * 0;
        if constexpr (Check) {
          const R diagonal = modulus(bi), sub = modulus(ai), super = modulus(ci);
          row_failure[l] = std::max(row_failure[l], R(diagonal < sub + super));
          // Row 0 has no column before it: diagonal_before is 0 there and the test passes.
          column_failure[l] =
              std::max(column_failure[l], R(diagonal_before[l] < super_before2[l] + sub));
          super_before2[l] = super_before[l];
          super_before[l] = super;
          diagonal_before[l] = diagonal;
        }
      }
    }
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) {
    const T* w = multipliers + i * W;
    T* y = solution + i * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      y[l] -= w[l] * y[W + l];
      probe[l] += magnitude(y[l]) * 0;
    }
  }
  bool healthy = true;
  for (int l = 0; l < W; ++l) {
    if constexpr (Check)  // the last column: |b_{n-1}| against |c_{n-2}|
      column_failure[l] = std::max(column_failure[l], R(diagonal_before[l] < super_before2[l]));
    healthy = healthy && margin[l] > 0 && probe[l] == 0 &&
              (!Check || row_failure[l] == 0 || column_failure[l] == 0);
  }
  if (!healthy) return false;
  T* rows_x[W];
  for (int l = 0; l < W; ++l) rows_x[l] = x + l * pitch;
  for (std::ptrdiff_t begin = 0; begin < n; begin += kBlock)
    scatter_from_lanes<T, W>(solution + begin * W, std::min(kBlock, n - begin), rows_x, begin);
  return true;
}

}  // namespace tridiff::detail
