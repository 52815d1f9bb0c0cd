// Gaussian elimination with partial pivoting for a tridiagonal system: the algorithm of LAPACK
// ?gtsv. At step i it keeps row i or swaps it with row i+1, whichever has the larger entry in
// column i; a swap fills a second super-diagonal. Backward stable with growth at most 2 per step
// in the worst case (Higham §9.5), so it serves systems that are not diagonally dominant.
#pragma once

#include <cstddef>
#include <utility>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

inline std::ptrdiff_t pivoting_workspace(std::ptrdiff_t n) { return 2 * n; }

// Solves one strided system; x may alias d. a[0] and c[n-1] are never read.
// `work` holds pivoting_workspace(n) scalars. Returns -1, or the row of a zero pivot
// (exactly zero, as LAPACK's INFO: the matrix is singular).
//
// One pass eliminates and stores each finished row of U divided by its pivot,
//   x_i + upper[i] x_{i+1} + upper2[i] x_{i+2} = y_i  (y_i in x),
// so that back substitution is one multiply-add on its dependency chain instead of a
// division (?gtsv divides there): the same row choices and the same elimination, with one
// more rounding per entry of U. The row being eliminated travels in registers; the inputs
// are read once, in place of a copy into workspace.
template <class T>
std::ptrdiff_t pivoting(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b,
                        Strided<const T> c, Strided<const T> d, Strided<T> x, T* work) {
  T* upper = work;       // entry (i, i+1) of U / pivot
  T* upper2 = work + n;  // entry (i, i+2) of U / pivot, filled by a swap
  // Row i after steps 0..i-1: pivot candidate, entries in columns i+1 and i+2, rhs.
  T diag = b[0], right = n > 1 ? c[0] : T(0), rhs = d[0];
  for (std::ptrdiff_t i = 0; i + 1 < n; ++i) {
    const T lower = a[i + 1], next_diag = b[i + 1], next_d = d[i + 1];
    const T next_right = i + 2 < n ? c[i + 1] : T(0);
    T pivot, row_right, row_right2, row_rhs;
    if (magnitude(diag) >= magnitude(lower)) {
      if (diag == T(0)) return i;  // column i is zero below the diagonal as well
      const T factor = lower / diag;
      pivot = diag;
      row_right = right;
      row_right2 = T(0);
      row_rhs = rhs;
      diag = next_diag - factor * right;
      right = next_right;
      rhs = next_d - factor * rhs;
    } else {  // swap rows i and i + 1
      const T factor = diag / lower;
      pivot = lower;
      row_right = next_diag;
      row_right2 = next_right;
      row_rhs = next_d;
      diag = right - factor * next_diag;
      right = -factor * next_right;
      rhs = rhs - factor * next_d;
    }
    const T inverse = T(1) / pivot;  // off the elimination's dependency chain
    upper[i] = row_right * inverse;
    upper2[i] = row_right2 * inverse;
    x[i] = row_rhs * inverse;
  }
  if (diag == T(0)) return n - 1;
  T next = rhs / diag, after = T(0);  // x_{i+1}, x_{i+2}
  x[n - 1] = next;
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) {
    // x_{i+2} first: it is known a step earlier, so only one multiply-add waits for x_{i+1}.
    const T value = (x[i] - upper2[i] * after) - upper[i] * next;
    after = next;
    next = value;
    x[i] = value;
  }
  return -1;
}

}  // namespace tridiff::detail
