// The two local steps of the distributed solve (general form) on one rank's slab of rows, W
// systems at a time (one SIMD lane each): the modified Thomas reduction (PaScaL_TDMA; Laszlo,
// Giles & Appleyard 2016) that leaves two boundary rows per system, and the finish from the
// boundary unknowns.
// The row arithmetic is tridiff/solvers/detail/modified_thomas.hpp, shared with the in-process
// partitioned solve (partitioned_lanes.hpp: the parts of one long system in lanes). What is
// this file's own is the slab's layout: W systems of one slab, read where they lie (general or
// diffusion form), that may hold 1 or 2 rows and whose first row couples to the previous rank;
// the eliminated rows are kept in full for the finish, which substitutes back instead of
// eliminating again (partitioned_lanes re-reads its inputs: its parts are sized for L2).
// The diffusion form's rows are read here too (DiffusionRows); its steps are
// diffusion_slab.hpp.
#pragma once

#include <algorithm>
#include <cstddef>

#include "tridiff/solvers/detail/modified_thomas.hpp"
#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::distributed::detail {

using tridiff::detail::epsilon;
using tridiff::detail::kVanishingPivot;
using tridiff::detail::magnitude;

// Element (row i, lane l) of W systems of a slab: lanes are systems `system_stride` apart;
// kUnitLanes says the stride is 1 (systems interleaved: the lanes load as one vector).
template <bool kUnitLanes>
struct Lanes {
  std::ptrdiff_t row_stride, system_stride;
  std::ptrdiff_t at(std::ptrdiff_t i, int l) const {
    return i * row_stride + (kUnitLanes ? l : l * system_stride);
  }
};

// The general form: three diagonals and the rhs. `open_first` / `open_last`: the slab holds
// global row 0 / n-1 of a non-periodic system, whose sub- / super-diagonal entry is not read.
template <class T, bool kUnitLanes>
struct GeneralRows {
  const T *a, *b, *c, *d;
  Lanes<kUnitLanes> lanes;
  std::ptrdiff_t rows;
  bool open_first, open_last;

  T sub(std::ptrdiff_t i, int l) const { return i == 0 && open_first ? T(0) : a[lanes.at(i, l)]; }
  T diag(std::ptrdiff_t i, int l) const { return b[lanes.at(i, l)]; }
  T super(std::ptrdiff_t i, int l) const {
    return i == rows - 1 && open_last ? T(0) : c[lanes.at(i, l)];
  }
  T rhs(std::ptrdiff_t i, int l) const { return d[lanes.at(i, l)]; }
  real_t<T> flaw(std::ptrdiff_t, int) const { return 0; }  // non-finite shows in the results
};

// The diffusion form (seed 000 eq. 3.10): a_i = -beta_{i-1}, b_i = 1 + beta_{i-1} + beta_i,
// c_i = -beta_i, solved without expanding them (diffusion_slab.hpp). The link into the slab's
// first row lives on the previous rank: `ghost[l]` (0 at global row 0 of a non-periodic system).
template <class T, bool kUnitLanes>
struct DiffusionRows {
  using R = real_t<T>;
  const R* beta;
  const T* d;
  const R* ghost;
  Lanes<kUnitLanes> lanes;
  std::ptrdiff_t rows;
  bool open_last;

  R link(std::ptrdiff_t i, int l) const {  // beta_i, the link from row i to row i + 1
    if (i < 0) return ghost[l];
    return i == rows - 1 && open_last ? R(0) : beta[lanes.at(i, l)];
  }
  T rhs(std::ptrdiff_t i, int l) const { return d[lanes.at(i, l)]; }
  // A negative conductance (refused, as by tridiff::solve_diffusion) counts as a flaw.
  R flaw(std::ptrdiff_t i, int l) const { return link(i, l) < 0 ? R(1) : R(0); }
};

// The reduction of a slab of m >= 1 rows, for W lanes. The forward sweep leaves (results at
// i * pitch + l)
//   row i >= 1:  a'_i x_0 + x_i + c'_i x_{i+1} = d'_i     (x_m: the next rank's first unknown)
// and a backward sweep, which only reads them (it carries row i + 1 in registers), expresses
// row 1 through x_0 and x_{m-1} to eliminate x_1 from row 0, which then reads
//   row 0:       a'_0 x_{-1} + x_0 + c'_0 x_{m-1} = d'_0  (x_{-1}: the previous rank's last)
// Rows 0 and m-1 are this slab's two rows of the reduced system (with m = 1, the one row reads
// a' x_{-1} + x_0 + c' x_1 = d'; with m = 2 both rows are only normalised). Keeping the forward
// form of the other rows, and finishing by back substitution (finish_lanes), saves the stores
// of a backward sweep that rewrites every row.
// probe[l] stays 0 unless a pivot vanished or a value is not finite in lane l.
template <class T, int W, class Rows>
void reduce_lanes(std::ptrdiff_t m, const Rows& rows_in, T* dp, T* ap, T* cp, std::ptrdiff_t pitch,
                  real_t<T>* probe) {
  // A local copy, whose pointers the stores below cannot change: through the reference GCC 12
  // left the forward sweep scalar, one lane at a time (2 ranks, 4096 x 4096 floats: a rank's
  // reduction 73-77 -> 67-70 ms).
  const Rows rows = rows_in;
  using R = real_t<T>;
  const R tolerance = kVanishingPivot * epsilon<T>;
  // The forward sweep sums its flaws in a local, not in probe, which the stores of the rows
  // could alias (the compiler would reload it every row).
  R flaws[W] = {};
  // The first two rows are only normalised: neither has a row above it within the slab.
  for (std::ptrdiff_t i = 0; i < std::min<std::ptrdiff_t>(m, 2); ++i) {
    T* d = dp + i * pitch;
    T* a = ap + i * pitch;
    T* c = cp + i * pitch;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const T pivot = rows.diag(i, l);
      tridiff::detail::modified_first_row(rows.sub(i, l), pivot, rows.super(i, l), rows.rhs(i, l),
                                          a[l], c[l], d[l]);
      const bool vanished = !(magnitude(pivot) > R(0));
      flaws[l] += (vanished ? R(1) : R(0)) + magnitude(d[l] + a[l] + c[l]) * 0 + rows.flaw(i, l);
    }
  }
  for (std::ptrdiff_t i = 2; i < m; ++i) {
    T* d = dp + i * pitch;
    T* a = ap + i * pitch;
    T* c = cp + i * pitch;
    const T* d_above = d - pitch;
    const T* a_above = a - pitch;
    const T* c_above = c - pitch;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const T sub = rows.sub(i, l), diag = rows.diag(i, l);
      T row_a = a_above[l], row_c = c_above[l], row_d = d_above[l], eliminated;
      const T pivot = tridiff::detail::modified_forward_row(
          sub, diag, rows.super(i, l), rows.rhs(i, l), row_a, row_c, row_d, eliminated);
      a[l] = row_a;
      c[l] = row_c;
      d[l] = row_d;
      const bool vanished =
          !(magnitude(pivot) > tolerance * (magnitude(diag) + magnitude(eliminated)));
      flaws[l] += (vanished ? R(1) : R(0)) + magnitude(d[l] + a[l] + c[l]) * 0 + rows.flaw(i, l);
    }
  }
  for (int l = 0; l < W; ++l) probe[l] += flaws[l];
  if (m < 3) return;
  // Backward, rows m-3 .. 1: row i + 1 through x_0 and x_{m-1} (row m-2 already reads so).
  T below_d[W], below_a[W], below_c[W];
  for (int l = 0; l < W; ++l) {
    below_d[l] = dp[(m - 2) * pitch + l];
    below_a[l] = ap[(m - 2) * pitch + l];
    below_c[l] = cp[(m - 2) * pitch + l];
  }
  for (std::ptrdiff_t i = m - 3; i >= 1; --i) {
    const T* d = dp + i * pitch;
    const T* a = ap + i * pitch;
    const T* c = cp + i * pitch;
#pragma omp simd
    for (int l = 0; l < W; ++l)
      tridiff::detail::modified_backward_row(a[l], c[l], d[l], below_a[l], below_c[l], below_d[l]);
  }
  // Row 0 drops x_1 for x_{m-1}: its own pivot.
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    T product;
    const T pivot = tridiff::detail::modified_close_first_row(below_a[l], below_c[l], below_d[l],
                                                              ap[l], cp[l], dp[l], product);
    const bool vanished = !(magnitude(pivot) > tolerance * (1 + magnitude(product)));
    probe[l] += (vanished ? R(1) : R(0)) + magnitude(dp[l] + ap[l] + cp[l]) * 0;
  }
}

// The first row whose pivot vanishes in reduce_lanes for one system (lane 0 of `rows`), or 0
// if only the final pivot of row 0 or an overflow is at fault. Replays the forward pivots.
template <class T, class Rows>
std::ptrdiff_t first_vanishing_pivot(std::ptrdiff_t m, const Rows& rows) {
  const real_t<T> tolerance = kVanishingPivot * epsilon<T>;
  T c_above = T(0);
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    const T eliminated = i < 2 ? T(0) : rows.sub(i, 0) * c_above;
    const T pivot = rows.diag(i, 0) - eliminated;
    const auto scale = magnitude(rows.diag(i, 0)) + magnitude(eliminated);
    if (!(magnitude(pivot) > (i < 2 ? real_t<T>(0) : tolerance * scale))) return i;
    c_above = rows.super(i, 0) / pivot;
  }
  return 0;
}

// The finish: x_0 and x_{m-1} are the boundary unknowns (first[l], last[l]); the rows between
// follow by back substitution in their forward form, x_i = d'_i - a'_i x_0 - c'_i x_{i+1}.
// `store(i, l, value)` writes the solution; probe[l] stays 0 if it is finite.
template <class T, int W, class Store>
void finish_lanes(std::ptrdiff_t m, const T* dp, const T* ap, const T* cp, std::ptrdiff_t pitch,
                  const T* first, const T* last, Store&& store, real_t<T>* probe) {
  // Locals, not the caller's arrays: the stores through `store` could alias those, and the
  // compiler would then reload them every row (the finish of 4096 x 4096 floats took 42 ms
  // instead of 25 once the call chain was not inlined).
  T below[W], x0[W];
  real_t<T> finite[W];
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    x0[l] = first[l];
    store(0, l, first[l]);
    store(m - 1, l, last[l]);
    below[l] = last[l];
    finite[l] = magnitude(first[l] + last[l]) * 0;
  }
  for (std::ptrdiff_t i = m - 2; i >= 1; --i) {
    const T* d = dp + i * pitch;
    const T* a = ap + i * pitch;
    const T* c = cp + i * pitch;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      below[l] = d[l] - a[l] * x0[l] - c[l] * below[l];
      store(i, l, below[l]);
      finite[l] += magnitude(below[l]) * 0;
    }
  }
  for (int l = 0; l < W; ++l) probe[l] += finite[l];
}

}  // namespace tridiff::distributed::detail
