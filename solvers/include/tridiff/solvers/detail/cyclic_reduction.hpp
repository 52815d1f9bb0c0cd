// Odd-even cyclic reduction (CR), parallel cyclic reduction (PCR) and their hybrid, for any n.
//
// Seed 000 §3.5.3 (eqs. 3.12-3.17) states CR for n = 2^k - 1. Here a level of m rows keeps its
// odd rows 1, 3, 5, ... (floor(m/2) of them); a kept row whose right neighbour does not exist
// (m even, last row) simply has gamma = 0. Back substitution recovers the even rows, whose
// missing neighbours are zero. This handles every m >= 1 without padding.
// PCR eliminates both neighbours of every row at distances 1, 2, 4, ... until all rows are
// decoupled. The hybrid reduces with CR until at most `pcr_below` rows remain, then finishes
// with PCR: pure CR is pcr_below = 1, pure PCR is pcr_below >= n.
// Both are stable for diagonally dominant matrices (CR and PCR preserve dominance).
#pragma once

#include <algorithm>
#include <cstddef>
#include <utility>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

// Rows of one reduction level, stored contiguously; a[0] and c[m-1] hold zeros.
template <class T>
struct Level {
  T* a;
  T* b;
  T* c;
  T* d;
};

// Scalars of workspace `cyclic_reduction` needs for a system of n rows.
inline std::ptrdiff_t cyclic_reduction_workspace(std::ptrdiff_t n) {
  // The level copy (4n + n for x), the reduced levels (< 5n in all) and PCR's buffers (4n).
  return 14 * n + 64;
}

// Original row index of row k of the level reached after `depth` halvings.
inline std::ptrdiff_t original_row(std::ptrdiff_t k, int depth) { return ((k + 1) << depth) - 1; }

// PCR on a contiguous level of m rows; `spare` holds 4m scalars; solution into x.
// Returns -1, or the (level) row whose pivot vanished.
template <class T>
std::ptrdiff_t parallel_cyclic_reduction(std::ptrdiff_t m, Level<T> now, T* spare, T* x) {
  Level<T> next{spare, spare + m, spare + 2 * m, spare + 3 * m};
  for (std::ptrdiff_t s = 1; s < m; s *= 2) {
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      const bool left = i - s >= 0, right = i + s < m;
      if (left && now.b[i - s] == T(0)) return i - s;  // name the zero pivot, not its victim
      if (right && now.b[i + s] == T(0)) return i + s;
      const T alpha = left ? -now.a[i] / now.b[i - s] : T(0);
      const T gamma = right ? -now.c[i] / now.b[i + s] : T(0);
      const T from_left = left ? alpha * now.c[i - s] : T(0);
      const T from_right = right ? gamma * now.a[i + s] : T(0);
      next.b[i] = now.b[i] + from_left + from_right;
      if (vanishes(next.b[i], magnitude(now.b[i]) + magnitude(from_left) + magnitude(from_right)))
        return i;
      next.a[i] = left ? alpha * now.a[i - s] : T(0);
      next.c[i] = right ? gamma * now.c[i + s] : T(0);
      next.d[i] =
          now.d[i] + (left ? alpha * now.d[i - s] : T(0)) + (right ? gamma * now.d[i + s] : T(0));
    }
    std::swap(now, next);
  }
  for (std::ptrdiff_t i = 0; i < m; ++i) x[i] = now.d[i] / now.b[i];
  return -1;
}

// CR on a contiguous level of m rows, recursing on the odd rows. `work` is workspace for the
// reduced levels and PCR. Returns -1, or the original row whose pivot vanished.
template <class T>
std::ptrdiff_t reduce_and_solve(std::ptrdiff_t m, Level<T> level, T* x, T* work,
                                std::ptrdiff_t pcr_below, int depth) {
  if (m <= std::max<std::ptrdiff_t>(pcr_below, 1)) {
    const std::ptrdiff_t bad = parallel_cyclic_reduction(m, level, work, x);
    return bad < 0 ? -1 : original_row(bad, depth);
  }
  const std::ptrdiff_t h = m / 2;
  Level<T> reduced{work, work + h, work + 2 * h, work + 3 * h};
  T* reduced_x = work + 4 * h;
  for (std::ptrdiff_t k = 0; k < h; ++k) {
    const std::ptrdiff_t i = 2 * k + 1;
    const bool right = i + 1 < m;
    if (level.b[i - 1] == T(0)) return original_row(i - 1, depth);
    if (right && level.b[i + 1] == T(0)) return original_row(i + 1, depth);
    const T alpha = -level.a[i] / level.b[i - 1];  // seed 000 eq. 3.12
    const T gamma = right ? -level.c[i] / level.b[i + 1] : T(0);
    const T from_left = alpha * level.c[i - 1];  // eq. 3.14
    const T from_right = right ? gamma * level.a[i + 1] : T(0);
    reduced.b[k] = level.b[i] + from_left + from_right;
    if (vanishes(reduced.b[k],
                 magnitude(level.b[i]) + magnitude(from_left) + magnitude(from_right)))
      return original_row(k, depth + 1);
    reduced.a[k] = alpha * level.a[i - 1];  // eq. 3.13 (level.a[0] is zero)
    reduced.c[k] = right ? gamma * level.c[i + 1] : T(0);
    reduced.d[k] =
        level.d[i] + alpha * level.d[i - 1] + (right ? gamma * level.d[i + 1] : T(0));  // eq. 3.15
  }
  const std::ptrdiff_t bad =
      reduce_and_solve(h, reduced, reduced_x, work + 5 * h, pcr_below, depth + 1);
  if (bad >= 0) return bad;
  for (std::ptrdiff_t k = 0; k < h; ++k) x[2 * k + 1] = reduced_x[k];
  for (std::ptrdiff_t i = 0; i < m; i += 2) {  // eq. 3.17
    T sum = level.d[i];
    if (i > 0) sum -= level.a[i] * x[i - 1];
    if (i + 1 < m) sum -= level.c[i] * x[i + 1];
    if (vanishes(level.b[i], magnitude(level.b[i]))) return original_row(i, depth);
    x[i] = sum / level.b[i];
  }
  return -1;
}

// Solves one strided system by CR (pcr_below = 1), PCR (pcr_below >= n) or the hybrid.
// x may alias d. `work` holds cyclic_reduction_workspace(n) scalars.
template <class T>
std::ptrdiff_t cyclic_reduction(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b,
                                Strided<const T> c, Strided<const T> d, Strided<T> x, T* work,
                                std::ptrdiff_t pcr_below) {
  Level<T> level{work, work + n, work + 2 * n, work + 3 * n};
  T* solution = work + 4 * n;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    level.a[i] = i > 0 ? a[i] : T(0);
    level.b[i] = b[i];
    level.c[i] = i + 1 < n ? c[i] : T(0);
    level.d[i] = d[i];
  }
  const std::ptrdiff_t bad = reduce_and_solve(n, level, solution, work + 5 * n, pcr_below, 0);
  if (bad >= 0) return bad;
  for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = solution[i];
  return -1;
}

}  // namespace tridiff::detail
