// One long system solved by P threads: the partitioned ("modified Thomas") method of
// Laszlo, Giles & Appleyard (2016), as in PaScaL_TDMA and SPIKE. In three steps, so that only
// the exchange of boundary rows changes when distributed ranks replace threads:
//  1. reduce: each part (rows [s, e), at least 3) is eliminated on its own until every row
//     reads  a'_i x_s + x_i + c'_i x_{e-1} = d'_i,  except the first row, which couples to
//     the previous part's last unknown, and the last row, which couples to the next part's
//     first unknown;
//  2. the first and last rows of all parts form a tridiagonal system of 2P unknowns, solved
//     serially;
//  3. finish: each part recovers its interior rows from its two boundary unknowns.
// Stable for diagonally dominant matrices, like Thomas (the reduced system stays dominant).
#pragma once

#include <cstddef>

#include "tridiff/solvers/detail/scalar.hpp"
#include "tridiff/solvers/detail/thomas.hpp"

namespace tridiff::detail {

// A part needs at least 3 rows: its first row must not be its last row's neighbour.
inline constexpr std::ptrdiff_t kMinPartRows = 3;

// Step 1 on rows [s, e) of a system of n rows. The eliminated right-hand side goes to
// `eliminated`, a' and c' to `coupling_a` and `coupling_c` (all indexed like the rows), so that
// x is written only by step 3, once the solve is known to succeed.
// Returns -1, or the row whose pivot vanished.
template <class T>
std::ptrdiff_t partition_reduce(std::ptrdiff_t s, std::ptrdiff_t e, std::ptrdiff_t n,
                                Strided<const T> a, Strided<const T> b, Strided<const T> c,
                                Strided<const T> d, T* x, T* coupling_a, T* coupling_c) {
  auto sub = [&](std::ptrdiff_t i) { return i > 0 ? a[i] : T(0); };
  auto super = [&](std::ptrdiff_t i) { return i + 1 < n ? c[i] : T(0); };
  for (std::ptrdiff_t i = s; i < s + 2; ++i) {  // the first two rows are only normalised
    if (vanishes(b[i], magnitude(b[i]))) return i;
    const T inverse = T(1) / b[i];
    x[i] = d[i] * inverse;
    coupling_a[i] = sub(i) * inverse;
    coupling_c[i] = super(i) * inverse;
  }
  // The previous row's values travel in registers: through memory, the store-to-load
  // round trip would lengthen the dependency chain that bounds this loop.
  T previous_a = coupling_a[s + 1], previous_c = coupling_c[s + 1], previous_x = x[s + 1];
  for (std::ptrdiff_t i = s + 2; i < e; ++i) {
    const T eliminated = a[i] * previous_c;
    const T pivot = b[i] - eliminated;
    if (vanishes(pivot, magnitude(b[i]) + magnitude(eliminated))) return i;
    const T inverse = T(1) / pivot;
    previous_x = (d[i] - a[i] * previous_x) * inverse;
    previous_a = -a[i] * previous_a * inverse;
    previous_c = super(i) * inverse;
    x[i] = previous_x;
    coupling_a[i] = previous_a;
    coupling_c[i] = previous_c;
  }
  T next_x = x[e - 2], next_a = coupling_a[e - 2], next_c = coupling_c[e - 2];
  for (std::ptrdiff_t i = e - 3; i > s; --i) {
    next_x = x[i] - coupling_c[i] * next_x;
    next_a = coupling_a[i] - coupling_c[i] * next_a;
    next_c = -coupling_c[i] * next_c;
    x[i] = next_x;
    coupling_a[i] = next_a;
    coupling_c[i] = next_c;
  }
  const T pivot = T(1) - coupling_c[s] * coupling_a[s + 1];
  if (vanishes(pivot, real_t<T>(1) + magnitude(coupling_c[s] * coupling_a[s + 1]))) return s;
  const T inverse = T(1) / pivot;
  x[s] = (x[s] - coupling_c[s] * x[s + 1]) * inverse;
  coupling_a[s] *= inverse;
  coupling_c[s] = -coupling_c[s] * coupling_c[s + 1] * inverse;
  return -1;
}

inline std::ptrdiff_t partition_reduced_workspace(std::ptrdiff_t parts) { return 10 * parts; }

// Step 2: the boundary rows of the P parts (first, last, first, last, ...) as one tridiagonal
// system with unit diagonal; solves it and writes the 2P boundary unknowns into
// `eliminated` (the x of step 1).
// `bounds` holds P + 1 part boundaries; `work` holds partition_reduced_workspace(P) scalars.
template <class T>
std::ptrdiff_t partition_solve_reduced(std::ptrdiff_t parts, const std::ptrdiff_t* bounds, T* x,
                                       const T* coupling_a, const T* coupling_c, T* work) {
  const std::ptrdiff_t m = 2 * parts;
  T* sub = work;
  T* diag = work + m;
  T* super = work + 2 * m;
  for (std::ptrdiff_t p = 0; p < parts; ++p) {
    const std::ptrdiff_t first = bounds[p], last = bounds[p + 1] - 1;
    sub[2 * p] = coupling_a[first];
    super[2 * p] = coupling_c[first];
    sub[2 * p + 1] = coupling_a[last];
    super[2 * p + 1] = coupling_c[last];
    diag[2 * p] = diag[2 * p + 1] = T(1);
    work[3 * m + 2 * p] = x[first];
    work[3 * m + 2 * p + 1] = x[last];
  }
  T* rhs = work + 3 * m;
  const std::ptrdiff_t bad =
      thomas(m, Strided<const T>{sub, 1}, Strided<const T>{diag, 1}, Strided<const T>{super, 1},
             Strided<const T>{rhs, 1}, Strided<T>{rhs, 1}, work + 4 * m);
  if (bad >= 0) return bad % 2 == 0 ? bounds[bad / 2] : bounds[bad / 2 + 1] - 1;
  for (std::ptrdiff_t p = 0; p < parts; ++p) {
    x[bounds[p]] = rhs[2 * p];
    x[bounds[p + 1] - 1] = rhs[2 * p + 1];
  }
  return -1;
}

// Step 3 on rows [s, e): every row from the part's two boundary unknowns, into x. Returns
// false if the solution is not finite.
template <class T>
bool partition_finish(std::ptrdiff_t s, std::ptrdiff_t e, const T* eliminated, const T* coupling_a,
                      const T* coupling_c, Strided<T> x) {
  const T first = eliminated[s], last = eliminated[e - 1];
  real_t<T> probe = 0;
  for (std::ptrdiff_t i = s; i < e; ++i) {
    const bool boundary = i == s || i == e - 1;
    const T value =
        boundary ? eliminated[i] : eliminated[i] - coupling_a[i] * first - coupling_c[i] * last;
    x[i] = value;
    probe += magnitude(value) * 0;
  }
  return probe == 0;
}

}  // namespace tridiff::detail
