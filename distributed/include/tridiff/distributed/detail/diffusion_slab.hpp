// The diffusion form's two local steps on one rank's slab, W systems at a time (one SIMD lane
// each), without a subtraction. The general form's steps (slab_lanes.hpp) eliminate the
// expanded diagonal 1 + beta + beta' and lose its 1 as beta grows: their error grew like
// beta * epsilon (float: 2.4e-3 at beta 1e5, 6e-2 at 1e7; x left the range of the rhs).
//
// Instead each slab is a part of the in-process partitioned diffusion solve
// (tridiff/solvers/detail/partitioned_diffusion.hpp, whose header derives the algebra): the
// slab's last row is a separator, the rows before it the part's interior, and
//  1. reduce: one forward sweep of the diffusion kernel per system (diffusion_reduce_row) gives
//     the nine numbers that separator k's row needs of this slab (DiffusionPartEnds), and keeps
//     each interior row as x_i = y_i + l_i x_left + f_i x_{i+1} (y: the eliminated rhs, l: the
//     response to the previous rank's separator x_left, f: the multiplier; all >= 0);
//  2. the owner of a system solves its separators, one per rank, an M-matrix in leak form
//     (open, or a ring when periodic: solve_separators), and sends each rank back x_left and
//     its own separator;
//  3. finish: back substitution through the kept rows, every term >= 0.
// x is then a convex combination of the rhs, as in tridiff::solve_diffusion. A slab of one
// row has an empty interior: its row is its separator.
#pragma once

#include <algorithm>
#include <cstddef>

#include "tridiff/solvers/detail/partitioned_diffusion.hpp"
#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::distributed::detail {

using tridiff::detail::DiffusionPartEnds;

// What step 1 leaves of W systems' slabs: separator k's inputs (see DiffusionPartEnds).
template <class T, int W>
struct SlabEnds {
  using R = real_t<T>;
  T u_first[W], u_last[W], separator_d[W];
  R w_first[W], r_first[W], w_last[W], l_last[W], beta_right[W], separator_beta[W];

  // Lane l's nine numbers, in the order of DiffusionPartEnds' arrays (the message's layout).
  static constexpr int kValues = DiffusionPartEnds<T>::kArrays;
  void pack(int l, T* out) const {
    const T values[kValues] = {u_first[l],       T(w_first[l]),        T(r_first[l]),
                               u_last[l],        T(w_last[l]),         T(l_last[l]),
                               T(beta_right[l]), T(separator_beta[l]), separator_d[l]};
    for (int v = 0; v < kValues; ++v) out[v] = values[v];
  }
};

// The owner's side of SlabEnds::pack: rank q's nine numbers into entry q of `ends`.
template <class T>
void unpack_slab_ends(const T* in, std::ptrdiff_t q, const DiffusionPartEnds<T>& ends) {
  auto real = [](const T& v) {
    if constexpr (is_complex_v<T>)
      return v.real();
    else
      return v;
  };
  ends.u_first[q] = in[0];
  ends.w_first[q] = real(in[1]);
  ends.r_first[q] = real(in[2]);
  ends.u_last[q] = in[3];
  ends.w_last[q] = real(in[4]);
  ends.l_last[q] = real(in[5]);
  ends.beta_right[q] = real(in[6]);
  ends.separator_beta[q] = real(in[7]);
  ends.separator_d[q] = in[8];
}

// Step 1 on a slab of m >= 1 rows of W systems (`rows`: DiffusionRows). Row i < m-1 is kept
// at i * pitch + l in y, l and f. probe[l] stays 0 unless a beta is negative or a value is not
// finite (or a pivot overflowed: links above max() / 2) in lane l; largest[l] receives the
// largest link of lane l (the one into the slab and the separator's included).
template <class T, int W, class Rows>
void reduce_diffusion_lanes(std::ptrdiff_t m, const Rows& rows_in, T* y, real_t<T>* l_kept,
                            real_t<T>* f, std::ptrdiff_t pitch, SlabEnds<T, W>& ends,
                            real_t<T>* probe, real_t<T>* largest) {
  using R = real_t<T>;
  const Rows rows = rows_in;  // a local copy, as in reduce_lanes (slab_lanes.hpp)
  R beta_left[W], beta_before[W], e_before[W], y_w[W], y_l[W], product[W], w_first[W];
  R flaws[W];  // a local, not probe, which the stores of the kept rows could alias
  T y_u[W], u_first[W];
  for (int l = 0; l < W; ++l) {
    flaws[l] = 0;
    beta_left[l] = beta_before[l] = rows.link(-1, l);  // the previous rank's separator link
    largest[l] = beta_left[l];
    e_before[l] = 1;
    y_u[l] = u_first[l] = T(0);
    y_w[l] = w_first[l] = 0;
    y_l[l] = 1;  // so that row 0 gets beta_left * 1 carried in: the response to x_left
    product[l] = 1;
  }
  for (std::ptrdiff_t i = 0; i + 1 < m; ++i) {
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const R link = rows.link(i, l);
      largest[l] = std::max(largest[l], link);
      f[i * pitch + l] = tridiff::detail::diffusion_reduce_row(
          link, rows.rhs(i, l), beta_left[l], beta_before[l], e_before[l], y_u[l], y_w[l], y_l[l],
          product[l], u_first[l], w_first[l], flaws[l]);
      y[i * pitch + l] = y_u[l];
      l_kept[i * pitch + l] = y_l[l];
    }
  }
  for (int l = 0; l < W; ++l) {
    const R separator_beta = rows.link(m - 1, l);
    const T separator_d = rows.rhs(m - 1, l);
    largest[l] = std::max(largest[l], separator_beta);
    probe[l] += flaws[l] + tridiff::detail::zero_if_finite(separator_beta) + rows.flaw(m - 1, l) +
                tridiff::detail::zero_if_finite(separator_d);
    ends.u_first[l] = u_first[l];
    ends.w_first[l] = w_first[l];
    ends.r_first[l] = product[l];  // the response at row 0 to the own separator
    ends.u_last[l] = y_u[l];
    ends.w_last[l] = y_w[l];
    ends.l_last[l] = y_l[l];
    ends.beta_right[l] = beta_before[l];
    ends.separator_beta[l] = separator_beta;
    ends.separator_d[l] = separator_d;
  }
}

// Step 3: row m-1 is the separator (own[l]), rows m-2 .. 0 follow by back substitution from the
// kept rows and the previous rank's separator (left[l]). `store(i, l, value)` writes the
// solution; probe[l] stays 0 if it is finite.
template <class T, int W, class Store>
void finish_diffusion_lanes(std::ptrdiff_t m, const T* y, const real_t<T>* l_kept,
                            const real_t<T>* f, std::ptrdiff_t pitch, const T* left, const T* own,
                            Store&& store, real_t<T>* probe) {
  // Locals, not the caller's arrays, which the stores through `store` could alias.
  T below[W], x_left[W];
  real_t<T> finite[W];
  for (int l = 0; l < W; ++l) {
    below[l] = own[l];
    x_left[l] = left[l];
    finite[l] = tridiff::detail::zero_if_finite(own[l]);
    store(m - 1, l, own[l]);
  }
  for (std::ptrdiff_t i = m - 2; i >= 0; --i) {
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const std::ptrdiff_t at = i * pitch + l;
      below[l] = y[at] + l_kept[at] * x_left[l] + f[at] * below[l];
      store(i, l, below[l]);
      finite[l] += tridiff::detail::zero_if_finite(below[l]);
    }
  }
  for (int l = 0; l < W; ++l) probe[l] += finite[l];
}

}  // namespace tridiff::distributed::detail
