// Gaussian elimination with partial pivoting for a tridiagonal system: the algorithm of LAPACK
// ?gtsv. At step i it keeps row i or swaps it with row i+1, whichever has the larger entry in
// column i; a swap fills a second super-diagonal. Backward stable with growth at most 2 per step
// in the worst case (Higham §9.5), so it serves systems that are not diagonally dominant.
#pragma once

#include <cstddef>
#include <utility>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

inline std::ptrdiff_t pivoting_workspace(std::ptrdiff_t n) { return 4 * n; }

// Solves one strided system; x may alias d. a[0] and c[n-1] are never read.
// `work` holds pivoting_workspace(n) scalars. Returns -1, or the row of a zero pivot
// (exactly zero, as LAPACK's INFO: the matrix is singular).
template <class T>
std::ptrdiff_t pivoting(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b,
                        Strided<const T> c, Strided<const T> d, Strided<T> x, T* work) {
  // lower[i]: entry (i+1, i); upper[i]: (i, i+1); upper2[i]: (i, i+2) after a swap.
  T* lower = work;
  T* diag = work + n;
  T* upper = work + 2 * n;
  T* upper2 = work + 3 * n;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    diag[i] = b[i];
    x[i] = d[i];
    if (i + 1 < n) {
      lower[i] = a[i + 1];
      upper[i] = c[i];
    }
    upper2[i] = T(0);
  }
  for (std::ptrdiff_t i = 0; i + 1 < n; ++i) {
    if (magnitude(diag[i]) >= magnitude(lower[i])) {
      if (diag[i] == T(0)) return i;  // column i is zero below the diagonal as well
      const T factor = lower[i] / diag[i];
      diag[i + 1] -= factor * upper[i];
      x[i + 1] -= factor * x[i];
    } else {  // swap rows i and i + 1
      const T factor = diag[i] / lower[i];
      diag[i] = lower[i];
      const T old_diag = diag[i + 1];
      diag[i + 1] = upper[i] - factor * old_diag;
      if (i + 2 < n) {
        upper2[i] = upper[i + 1];
        upper[i + 1] = -factor * upper2[i];
      }
      upper[i] = old_diag;
      const T old_x = x[i];
      x[i] = x[i + 1];
      x[i + 1] = old_x - factor * x[i + 1];
    }
  }
  if (diag[n - 1] == T(0)) return n - 1;
  x[n - 1] /= diag[n - 1];
  if (n > 1) x[n - 2] = (x[n - 2] - upper[n - 2] * x[n - 1]) / diag[n - 2];
  for (std::ptrdiff_t i = n - 3; i >= 0; --i)
    x[i] = (x[i] - upper[i] * x[i + 1] - upper2[i] * x[i + 2]) / diag[i];
  return -1;
}

}  // namespace tridiff::detail
