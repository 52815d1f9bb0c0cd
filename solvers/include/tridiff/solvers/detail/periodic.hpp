// Periodic (cyclic) tridiagonal systems: row 0 also couples to x[n-1] through a[0], and row n-1
// to x[0] through c[n-1]. Solved by Sherman-Morrison: A = T' + u v^T with T' tridiagonal, so
//   x = y - (v.y / (1 + v.z)) z,  T' y = d,  T' z = u,
// with gamma = -b[0], u = (gamma, 0, ..., 0, c[n-1]), v = (1, 0, ..., 0, a[0] / gamma),
// T' = T with b'[0] = b[0] - gamma and b'[n-1] = b[n-1] - c[n-1] a[0] / gamma.
// If A is diagonally dominant by rows, so is T' (weakly in its last row). By the matrix
// determinant lemma 1 + v.z = det A / det T', so it vanishes only when A is singular.
#pragma once

#include <cstddef>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

inline std::ptrdiff_t periodic_workspace(std::ptrdiff_t n, std::ptrdiff_t inner_workspace) {
  return 3 * n + inner_workspace + 8;
}

// `inner(n, a, b, c, d, x, work)` solves a non-periodic strided system and returns -1 or the
// row of a breakdown. x may alias d. Returns -1, or the row at fault (n - 1 when the
// Sherman-Morrison denominator vanishes).
template <class T, class Inner>
std::ptrdiff_t periodic(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b,
                        Strided<const T> c, Strided<const T> d, Strided<T> x, T* work,
                        Inner&& inner) {
  if (n <= 2) {
    // The wrap-around entries land on the ordinary diagonals: row 0 reads x[n-1] through
    // a[0], row n-1 reads x[0] through c[n-1].
    T sub[2]{}, diag[2]{}, super[2]{};
    if (n == 1) {
      diag[0] = a[0] + b[0] + c[0];
    } else {
      diag[0] = b[0];
      diag[1] = b[1];
      super[0] = c[0] + a[0];
      sub[1] = a[1] + c[1];
    }
    return inner(n, Strided<const T>{sub, 1}, Strided<const T>{diag, 1}, Strided<const T>{super, 1},
                 d, x, work);
  }
  const T corner_top = a[0];         // entry (0, n-1)
  const T corner_bottom = c[n - 1];  // entry (n-1, 0)
  const T gamma = b[0] == T(0) ? T(-1) : -b[0];
  T* modified_b = work;
  T* z = work + n;
  T* u = work + 2 * n;
  T* inner_work = work + 3 * n;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    modified_b[i] = b[i];
    u[i] = T(0);
  }
  modified_b[0] = b[0] - gamma;
  modified_b[n - 1] = b[n - 1] - corner_bottom * corner_top / gamma;
  u[0] = gamma;
  u[n - 1] = corner_bottom;
  const Strided<const T> tb{modified_b, 1};
  std::ptrdiff_t bad = inner(n, a, tb, c, d, x, inner_work);
  if (bad >= 0) return bad;
  bad = inner(n, a, tb, c, Strided<const T>{u, 1}, Strided<T>{z, 1}, inner_work);
  if (bad >= 0) return bad;
  const T ratio = corner_top / gamma;
  const T denominator = T(1) + z[0] + ratio * z[n - 1];
  if (vanishes(denominator, real_t<T>(1) + magnitude(z[0]) + magnitude(ratio * z[n - 1])))
    return n - 1;
  const T factor = (x[0] + ratio * x[n - 1]) / denominator;
  for (std::ptrdiff_t i = 0; i < n; ++i) x[i] -= factor * z[i];
  return -1;
}

}  // namespace tridiff::detail
