// One long diffusion system (the matrix of diffusion_form.hpp) cut into parts that run side by
// side in SIMD lanes, as partitioned_lanes.hpp does for the general form, but with no
// subtraction anywhere, so that it keeps the diffusion kernel's guarantees: every pivot >= 1,
// the solution a convex combination of the rhs, no digits lost at beta ~ 1e7 in float. (The
// general form's partitioned steps eliminate the expanded diagonal 1 + beta + beta' and lose
// its 1 for large beta: at beta = 1e7 in float they return 15.5 for an rhs in [0, 1].)
//
// The last row of each part is a separator; the rows before it, the part's interior, couple to
// the rest of the system only through the separators on either side, by beta_left (the link
// from the separator before) and beta_right (the link to the part's own separator). With A the
// interior's matrix (its end rows keep their full diagonals), linearity gives
//     x = u + L x_left + R x_right,   u = A^-1 d,  L = A^-1 (beta_left e_first),
//                                                  R = A^-1 (beta_right e_last),
// and since A's rows sum to 1 except for beta_left and beta_right at its ends,
// 1 = w + L + R with w = A^-1 (1, ..., 1): the "leak", computed directly, never as 1 - L - R.
//  1. reduce: one forward sweep of the diffusion kernel per part, with the right-hand sides d,
//     all ones and beta_left e_first, gives u, w and L at the interior's last row (there the
//     solution is the eliminated rhs). The first row's values come from the back substitution
//     unrolled, x_first = sum_i (f_0 ... f_{i-1}) y_i with f_i the multipliers (all terms >= 0
//     for w and L), so the sweep keeps nothing per row; R at the first row is f_0 ... f_last.
//  2. the separators: separator k's equation with its neighbours substituted reads
//        (s + l + r) x_k - l x_{k-1} - r x_{k+1} = d_k + b_a u_last + b_b u_first',
//        s = 1 + b_a w_last + b_b w_first',  l = b_a L_last,  r = b_b R_first',
//     (b_a, b_b: the separator's links up and down; ' the part after), every term >= 0: an
//     M-matrix with row sums s >= 1, solved serially (one row a part) by the elimination of
//     leak rows (diffusion_form.hpp), as subtraction-free as the diffusion kernel.
//  3. finish: each interior again by the diffusion kernel, the separators as boundary values
//     (they enter as the carried value before the first row and after the last), stored in
//     L2 between the sweeps and transposed back into x.
// The arrays beta and d are read twice and x written once.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

#include "tridiff/solvers/detail/diffusion_form.hpp"
#include "tridiff/solvers/detail/partitioned_lanes.hpp"
#include "tridiff/solvers/detail/scalar.hpp"
#include "tridiff/solvers/detail/subnormals.hpp"
#include "tridiff/solvers/detail/transpose.hpp"
#include "tridiff/solvers/detail/workspace.hpp"

namespace tridiff::detail {

// Where W parts' rows are: row j of lane l at beta[l][j], d[l][j] and out[l][j]. Either
// pointers into the caller's arrays or into a staging copy.
template <class T, int W>
struct DiffusionPartGroup {
  const T* beta[W];
  const T* d[W];
  T* out[W];
  T beta_left[W];  // the link from the separator before each part (0 for the first part)
  std::ptrdiff_t first_part = 0;
};

// What step 1 keeps of each part, and what step 2 needs of it (one entry a part). The
// distributed solve keeps the same of each rank's slab (with complex right-hand sides: u and
// d complex, the rest real).
template <class T>
struct DiffusionPartEnds {
  using R = real_t<T>;
  T* u_first;
  R* w_first;
  R* r_first;
  T* u_last;
  R* w_last;
  R* l_last;
  R* beta_right;      // the link from the interior's last row to the separator
  R* separator_beta;  // the separator's link to the next part's first row
  T* separator_d;

  static constexpr int kArrays = 9;
  // `values`: 3 * parts scalars (u_first, u_last, separator_d); `reals`: 6 * parts.
  DiffusionPartEnds(T* values, R* reals, std::ptrdiff_t parts)
      : u_first(values),
        w_first(reals),
        r_first(reals + parts),
        u_last(values + parts),
        w_last(reals + 2 * parts),
        l_last(reals + 3 * parts),
        beta_right(reals + 4 * parts),
        separator_beta(reals + 5 * parts),
        separator_d(values + 2 * parts) {}
};

// Group g's pointers: straight into beta and d where its rows are contiguous and its last
// part ends before row n-1 (so that beta[n-1], not part of the system, is never read),
// otherwise into `staging` (3 * rows * W values), a copy padded with decoupled rows (beta 0,
// d 0; beta[n-1] read as 0). The solution goes to `out` as in part_group.
template <class T, int W>
DiffusionPartGroup<T, W> diffusion_part_group(Strided<const T> beta, Strided<const T> d,
                                              const PartLayout& layout, std::ptrdiff_t g, T* out,
                                              bool out_padded, T* staging) {
  const std::ptrdiff_t rows = layout.rows, n = layout.n, first = g * W * rows, span = W * rows;
  const bool inside = first + span <= n - 1;
  const bool contiguous = beta.stride == 1 && d.stride == 1;
  DiffusionPartGroup<T, W> group;
  group.first_part = g * W;
  const Strided<const T> inputs[2] = {beta, d};
  // Valid rows of each input: beta's row n-1 is not part of the system.
  const std::ptrdiff_t ends[2] = {n - 1, n};
  for (int k = 0; k < 2; ++k) {
    T* copy = staging + k * span;
    if (!(inside && contiguous)) {
      const std::ptrdiff_t valid = std::clamp<std::ptrdiff_t>(ends[k] - first, 0, span);
      for (std::ptrdiff_t i = 0; i < valid; ++i) copy[i] = inputs[k][first + i];
      std::fill(copy + valid, copy + span, T(0));
    }
    for (int l = 0; l < W; ++l) {
      const T* rows_of = inside && contiguous ? inputs[k].data + first + l * rows : copy + l * rows;
      (k == 0 ? group.beta : group.d)[l] = rows_of;
    }
  }
  for (int l = 0; l < W; ++l) {
    const std::ptrdiff_t before = first + l * rows - 1;  // the previous part's separator
    group.beta_left[l] = before >= 0 && before < n - 1 ? beta[before] : T(0);
  }
  T* target = first + span <= n || out_padded ? out + first : staging + 2 * span;
  for (int l = 0; l < W; ++l) group.out[l] = target + l * rows;
  return group;
}

// L and the product of the multipliers, both in [0, 1], decay geometrically along a part where
// beta is small, and as subnormals every operation on them would cost a microcode assist. So
// they are set to 0 once negligible: once value * weight < min() / epsilon (2^-103 in float,
// 2^-970 in double), where `weight` >= 1 bounds the conductance that multiplies the value
// later (the product ends up multiplied by the link into the part, beta_left; L at row j by
// beta_j, the link it crosses next). The change is then below min() against the rhs and
// below epsilon against the separator's diagonal (>= 1), whatever the size of beta.
template <class T>
inline T flush_negligible(T value, T weight) {
  constexpr T kNegligible = std::numeric_limits<T>::min() / std::numeric_limits<T>::epsilon();
  return value * std::max(T(1), weight) < kNegligible ? T(0) : value;
}

// One row of step 1 (see the header) in one lane: the diffusion kernel's forward step on the
// right-hand sides d (y_u), all ones (y_w) and beta_left e_first (y_l), with the first row's
// u and w summed through the product of the multipliers. Returns the multiplier f (row j:
// x_j = y_j + f x_{j+1}). The pivot g + beta_here overflows only for beta above max() / 2;
// its inverse would then be a silent 0, so the probe counts it.
template <class T, class R>
inline R diffusion_reduce_row(R beta_here, T rhs, R beta_left, R& beta_before, R& e_before, T& y_u,
                              R& y_w, R& y_l, R& product, T& u_first, R& w_first, R& probe) {
  const R g = 1 + beta_before * e_before;
  const R inverse = 1 / (g + beta_here);
  y_u = (rhs + beta_before * y_u) * inverse;
  y_w = (1 + beta_before * y_w) * inverse;
  y_l = flush_negligible(beta_before * y_l * inverse, beta_here);
  u_first += product * y_u;
  w_first += product * y_w;
  const R multiplier = beta_here * inverse;
  product = flush_negligible(product * multiplier, beta_left);
  e_before = g * inverse;
  beta_before = beta_here;
  probe += zero_if_finite(g + beta_here) + zero_if_finite(rhs) + R(beta_here < 0);
  return multiplier;
}

// Step 1 on one group (see the header): fills the group's entries of `ends`. `block` holds
// 2 * kTransposeBlock * W values. Returns false if a value was not finite or a beta negative.
template <class T, int W>
bool reduce_diffusion_group(const DiffusionPartGroup<T, W>& group, std::ptrdiff_t rows,
                            T* block_memory, const DiffusionPartEnds<T>& ends) {
  T* const beta_block = block_memory;
  T* const d_block = block_memory + kTransposeBlock * W;
  // Per lane: the sweep's state (the kernel's beta_before, e_before), the eliminated rhs of
  // d, of all ones and of beta_left e_first (y_u, y_w, y_l), the product of the multipliers so
  // far and the first row's u and w being summed. Locals: GCC keeps them in registers.
  T beta_before[W], e_before[W], y_u[W], y_w[W], y_l[W], product[W], u_first[W], w_first[W];
  T probe[W], separator_beta[W], separator_d[W];
  for (int l = 0; l < W; ++l) {
    beta_before[l] = group.beta_left[l];
    e_before[l] = 1;
    y_u[l] = y_w[l] = 0;
    y_l[l] = 1;  // so that row 0 gets beta_left * 1 carried in: the rhs beta_left e_first
    product[l] = 1;
    u_first[l] = w_first[l] = 0;
    probe[l] = zero_if_finite(group.beta_left[l]) + T(group.beta_left[l] < 0);
  }
  const std::ptrdiff_t interior = rows - 1;
  for (std::ptrdiff_t j0 = 0; j0 < rows; j0 += kTransposeBlock) {
    const std::ptrdiff_t count = std::min(kTransposeBlock, rows - j0);
    gather_into_lanes<T, W>(group.beta, j0, count, beta_block, rows);
    gather_into_lanes<T, W>(group.d, j0, count, d_block, rows);
    const std::ptrdiff_t stop = std::min(j0 + count, interior);
    for (std::ptrdiff_t j = j0; j < stop; ++j) {
      const T* b = beta_block + (j - j0) * W;
      const T* rhs = d_block + (j - j0) * W;
#pragma omp simd
      for (int l = 0; l < W; ++l)
        diffusion_reduce_row(b[l], rhs[l], group.beta_left[l], beta_before[l], e_before[l], y_u[l],
                             y_w[l], y_l[l], product[l], u_first[l], w_first[l], probe[l]);
    }
    if (interior >= j0 && interior < j0 + count)
      for (int l = 0; l < W; ++l) {
        separator_beta[l] = beta_block[(interior - j0) * W + l];
        separator_d[l] = d_block[(interior - j0) * W + l];
      }
  }
  bool healthy = true;
  for (int l = 0; l < W; ++l) {
    const std::ptrdiff_t p = group.first_part + l;
    ends.u_first[p] = u_first[l];
    ends.w_first[p] = w_first[l];
    ends.r_first[p] = product[l];  // f_0 ... f_last: the response at row 0 to beta_right e_last
    ends.u_last[p] = y_u[l];
    ends.w_last[p] = y_w[l];
    ends.l_last[p] = y_l[l];
    ends.beta_right[p] = beta_before[l];
    ends.separator_beta[p] = separator_beta[l];
    ends.separator_d[p] = separator_d[l];
    probe[l] += zero_if_finite(u_first[l]) + zero_if_finite(y_u[l]) +
                zero_if_finite(separator_beta[l]) + zero_if_finite(separator_d[l]) +
                T(separator_beta[l] < 0);
    healthy = healthy && probe[l] == 0;
  }
  return healthy;
}

// Separator k's row (see the header) as a leak row: its neighbours' interiors substituted.
// The part after the last is the first if `periodic` (the distributed solve's ring), else
// nothing (the last part's separator is row n-1 or a padding row).
template <class T>
void separator_row(const DiffusionPartEnds<T>& ends, std::ptrdiff_t k, std::ptrdiff_t parts,
                   bool periodic, LeakRow<T>& row) {
  using R = real_t<T>;
  const std::ptrdiff_t after = k + 1 < parts ? k + 1 : (periodic ? 0 : -1);
  const R up = ends.beta_right[k];
  const R down = after >= 0 ? ends.separator_beta[k] : R(0);
  const R w_after = after >= 0 ? ends.w_first[after] : R(0);
  const R r_after = after >= 0 ? ends.r_first[after] : R(0);
  const T u_after = after >= 0 ? ends.u_first[after] : T(0);
  row = {1 + up * ends.w_last[k] + down * w_after, up * ends.l_last[k], down * r_after,
         ends.separator_d[k] + up * ends.u_last[k] + down * u_after};
}

// Step 2: the separators' values into `x` (one a part). `work` holds a value a part (3 if
// `periodic`). Returns false if the inputs or the solution were not finite.
template <class T>
bool solve_separators(std::ptrdiff_t parts, const DiffusionPartEnds<T>& ends, T* x, real_t<T>* work,
                      bool periodic = false) {
  auto row = [&](std::ptrdiff_t k, LeakRow<T>& r) { separator_row(ends, k, parts, periodic, r); };
  return periodic ? ring_leak_elimination(parts, row, Strided<T>{x, 1}, work)
                  : leak_elimination(parts, row, Strided<T>{x, 1}, work);
}

// Step 3 on one group: each interior by the diffusion kernel with the separators on either
// side as boundary values, into group.out (the separator rows too). `work` holds 2 * rows * W
// values and `block` 3 * kTransposeBlock * W. Returns false if the solution is not finite.
template <class T, int W>
bool finish_diffusion_group(const DiffusionPartGroup<T, W>& group, std::ptrdiff_t rows, T* work,
                            T* block_memory, const T* separators, bool streaming) {
  T* const beta_block = block_memory;
  T* const d_block = block_memory + kTransposeBlock * W;
  T* const solution = block_memory + 2 * kTransposeBlock * W;
  T* const kept_f = work;  // row j: x_j = y_j + f_j x_{j+1}
  T* const kept_y = work + rows * W;
  T beta_before[W], e_before[W], carry[W], below[W], probe[W];
  for (int l = 0; l < W; ++l) {
    const std::ptrdiff_t p = group.first_part + l;
    beta_before[l] = group.beta_left[l];
    e_before[l] = 1;
    carry[l] = p > 0 ? separators[p - 1] : T(0);  // x_left, carried into row 0
    below[l] = separators[p];
    probe[l] = 0;
  }
  const std::ptrdiff_t interior = rows - 1;
  for (std::ptrdiff_t j0 = 0; j0 < interior; j0 += kTransposeBlock) {
    const std::ptrdiff_t count = std::min(kTransposeBlock, interior - j0);
    gather_into_lanes<T, W>(group.beta, j0, count, beta_block, rows);
    gather_into_lanes<T, W>(group.d, j0, count, d_block, rows);
    for (std::ptrdiff_t j = j0; j < j0 + count; ++j) {
      const T* b = beta_block + (j - j0) * W;
      const T* rhs = d_block + (j - j0) * W;
      T* f = kept_f + j * W;
      T* y = kept_y + j * W;
#pragma omp simd
      for (int l = 0; l < W; ++l) {
        const T beta_here = b[l];
        const T g = 1 + beta_before[l] * e_before[l];
        const T inverse = 1 / (g + beta_here);
        carry[l] = (rhs[l] + beta_before[l] * carry[l]) * inverse;
        y[l] = carry[l];
        f[l] = beta_here * inverse;
        e_before[l] = g * inverse;
        beta_before[l] = beta_here;
      }
    }
  }
  // Backward, block by block from the last; row rows-1 is the part's separator.
  for (std::ptrdiff_t j0 = (rows - 1) / kTransposeBlock * kTransposeBlock; j0 >= 0;
       j0 -= kTransposeBlock) {
    const std::ptrdiff_t count = std::min(kTransposeBlock, rows - j0);
    for (std::ptrdiff_t j = j0 + count - 1; j >= j0; --j) {
      T* out = solution + (j - j0) * W;
      if (j == interior) {
        for (int l = 0; l < W; ++l) out[l] = below[l];
        continue;
      }
      const T* f = kept_f + j * W;
      const T* y = kept_y + j * W;
#pragma omp simd
      for (int l = 0; l < W; ++l) {
        below[l] = y[l] + f[l] * below[l];
        out[l] = below[l];
        probe[l] += zero_if_finite(below[l]);
      }
    }
    scatter_from_lanes<T, W>(solution, count, group.out, j0, streaming);
  }
  bool finite = true;
  for (int l = 0; l < W; ++l) finite = finite && probe[l] == 0;
  return finite;
}

// Solves one diffusion system (beta[n-1] not read, not periodic) by parts in lanes, groups of
// parts shared by `threads` threads; x may be d (in place). Returns the number of parts, or 0,
// with d untouched, if beta or d holds a value that is not finite or a negative beta, or if an
// intermediate overflowed (rhs near max()): the caller then solves by the scalar path, which
// names the row or rescales. Real scalars only.
template <class T>
std::ptrdiff_t partitioned_diffusion(Strided<const T> beta, Strided<const T> d, std::ptrdiff_t n,
                                     Strided<T> x, int threads) {
  static_assert(!is_complex_v<T>);
  constexpr int W = kPartLanes<T>;
  const PartLayout layout = make_part_layout<T, W>(n, threads);
  const std::ptrdiff_t rows = layout.rows, parts = layout.parts;
  const bool in_place = x.data == d.data;
  const bool direct = x.stride == 1 && !in_place;  // the solution goes straight into x
  const std::ptrdiff_t padded = parts * rows;
  const std::ptrdiff_t kept = (DiffusionPartEnds<T>::kArrays + 2) * parts;
  static thread_local AlignedBuffer<T> shared;
  shared.resize(kept + (direct ? 0 : padded));
  T* const storage = shared.data();  // `shared` names another buffer on the team's threads
  const DiffusionPartEnds<T> ends(storage, storage + 3 * parts, parts);
  T* const separators = storage + DiffusionPartEnds<T>::kArrays * parts;
  T* const separator_work = separators + parts;  // the open chain needs a value a part
  T* const out = direct ? x.data : storage + kept;
  const bool streaming = direct && n * std::ptrdiff_t(sizeof(T)) >= kStreamingBytes;
  const int team = static_cast<int>(std::min<std::ptrdiff_t>(threads, layout.groups));
  bool reduced_ok = true, separators_ok = true, finished_ok = true;
  const SubnormalsKept gradual_underflow;  // for the serial step; see subnormals.hpp
#pragma omp parallel num_threads(team) if (team > 1)
  {
    const SubnormalsKept team_gradual_underflow;  // each thread has its own MXCSR
    static thread_local AlignedBuffer<T> local;
    local.resize(2 * rows * W + 3 * rows * W + 3 * kTransposeBlock * W);
    T* const work = local.data();
    T* const staging = work + 2 * rows * W;
    T* const blocks = staging + 3 * rows * W;
    bool ok = true;
#pragma omp for schedule(static)
    for (std::ptrdiff_t g = 0; g < layout.groups; ++g) {
      const auto group = diffusion_part_group<T, W>(beta, d, layout, g, out, !direct, staging);
      ok = reduce_diffusion_group<T, W>(group, rows, blocks, ends) && ok;
    }
    if (!ok) {
#pragma omp atomic write
      reduced_ok = false;
    }
#pragma omp barrier
#pragma omp single
    if (reduced_ok) separators_ok = solve_separators(parts, ends, separators, separator_work);
    if (reduced_ok && separators_ok) {
#pragma omp for schedule(static)
      for (std::ptrdiff_t g = 0; g < layout.groups; ++g) {
        const auto group = diffusion_part_group<T, W>(beta, d, layout, g, out, !direct, staging);
        ok = finish_diffusion_group<T, W>(group, rows, work, blocks, separators, streaming) && ok;
        const std::ptrdiff_t first = g * W * rows;
        if (direct && first + W * rows > n && first < n)  // staged: the rows of the system
          std::copy(staging + 2 * W * rows, staging + 2 * W * rows + (n - first), out + first);
      }
      finish_streaming_stores();
      if (!ok) {
#pragma omp atomic write
        finished_ok = false;
      }
    }
  }
  const bool solved = reduced_ok && separators_ok && finished_ok;
  if (solved && !direct) {
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && n > (1 << 16))
    for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = out[i];
  }
  if (shared.size() * std::ptrdiff_t(sizeof(T)) > (std::ptrdiff_t(256) << 20)) shared = {};
  return solved ? parts : 0;
}

}  // namespace tridiff::detail
