// One long system as many short parts side by side in SIMD lanes: the partitioned method
// (Laszlo, Giles & Appleyard 2016; PaScaL_TDMA) with W parts per vector, so that all lanes
// advance in lockstep and the division chain of one part hides behind the others. In three
// steps:
//  1. reduce: each group of W parts is transposed into lanes a block of rows at a time and
//     eliminated by the modified Thomas steps of modified_thomas.hpp (the distributed solve
//     runs the same steps on a rank's slab); only the part's first and last rows are kept, as
//        sub x_{s-1} + x_s + super x_{e-1} = rhs   and   sub x_s + x_{e-1} + super x_e = rhs;
//  2. those 2P rows form a tridiagonal system, solved serially (it is small: P = n / rows);
//  3. finish: with x_s and x_{e-1} known, each part's interior is a plain Thomas solve, run
//     again from the inputs (re-reading four arrays costs less than storing three in step 1
//     and reading them back), and transposed back into x.
// A group's intermediate values stay in L2: the arrays are read twice and x written once.
// Stable for matrices diagonally dominant by rows or by columns, as Thomas: every part is a
// principal submatrix and the reduced system a Schur complement, both dominant again.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

#include "tridiff/solvers/detail/checks.hpp"
#include "tridiff/solvers/detail/modified_thomas.hpp"
#include "tridiff/solvers/detail/scalar.hpp"
#include "tridiff/solvers/detail/subnormals.hpp"
#include "tridiff/solvers/detail/thomas.hpp"
#include "tridiff/solvers/detail/transpose.hpp"
#include "tridiff/solvers/detail/workspace.hpp"

namespace tridiff::detail {

// Parts side by side: two 64-byte vectors of scalars.
template <class T>
inline constexpr int kPartLanes = static_cast<int>(128 / sizeof(T) >= 2 ? 128 / sizeof(T) : 2);

// How a system of n rows is cut: `parts` = groups * W parts of `rows` rows each. The last
// parts may run past row n-1; the rows past it are identity rows (x = 0) that couple to
// nothing, so every lane of every group holds a whole part.
struct PartLayout {
  std::ptrdiff_t n = 0, rows = 0, parts = 0, groups = 0;
};

// Rows per part aimed at: a group's intermediates (3 * rows * W scalars) stay well inside
// L2, and the reduced system (2 rows per part) stays small next to n.
inline constexpr std::ptrdiff_t kPartRowsTarget = 512;

// Rows per part are an odd number of 64-byte lines: each part then starts on a line (aligned
// streaming stores), and the W parts read side by side fall into different cache sets (with
// 512 floats per part, 2 KiB apart, all W streams of an array share two sets of the L1, and
// the in-cache speed halves).
template <class T, int W>
PartLayout make_part_layout(std::ptrdiff_t n, int threads) {
  constexpr std::ptrdiff_t line = 64 / sizeof(T) > 0 ? 64 / sizeof(T) : 1;
  const std::ptrdiff_t per_group = W * kPartRowsTarget;
  // Enough groups for every thread, and as many as the target part length asks for.
  std::ptrdiff_t groups = std::max<std::ptrdiff_t>((n + per_group - 1) / per_group, 1);
  groups = std::max<std::ptrdiff_t>(groups, std::min<std::ptrdiff_t>(threads, n / (W * 64)));
  const std::ptrdiff_t rows_needed = (n + groups * W - 1) / (groups * W);
  std::ptrdiff_t lines = (rows_needed + line - 1) / line;
  lines += 1 - lines % 2;
  const std::ptrdiff_t rows = lines * line;
  const std::ptrdiff_t used = (n + rows - 1) / rows;  // parts holding a row of the system
  groups = (used + W - 1) / W;
  return {n, rows, groups * W, groups};
}

// Scalars of per-thread workspace for one group: the L2 intermediates, a padded staging copy
// of a group's four inputs and its solution, and the transposed blocks.
template <class T, int W>
std::ptrdiff_t part_group_workspace(const PartLayout& layout) {
  return 3 * layout.rows * W + 5 * layout.rows * W + 5 * kTransposeBlock * W;
}

// Where W parts' rows are: row j of lane l of input k (a, b, c, d) at in[k][l][j], and of the
// solution at out[l][j]. Either pointers into the caller's arrays or into the staging copy.
template <class T, int W>
struct PartGroup {
  const T* in[4][W];
  T* out[W];
  std::ptrdiff_t first_part = 0;
  // The lane and local row of the system's last row, if it lies in this group (else lane -1):
  // its super-diagonal is not part of the system and is read as 0.
  int last_lane = -1;
  std::ptrdiff_t last_row = 0;
  bool has_first_row = false;  // lane 0, row 0 is the system's row 0 (its sub is read as 0)
};

// The reduced system's rows (step 1's output, step 2's input): row 2p is part p's first row,
// row 2p+1 its last; sub, super and rhs, unit diagonal.
template <class T>
struct ReducedRows {
  T* sub;
  T* super;
  T* rhs;
};

// Transposes rows [j0, j0 + count) of the group's four inputs into lane blocks
// block[k][j * W + l], and reads the entries outside the system (a_0, c_{n-1}) as 0.
template <class T, int W>
void load_part_block(const PartGroup<T, W>& group, std::ptrdiff_t rows, std::ptrdiff_t j0,
                     std::ptrdiff_t count, T* const block[4]) {
  for (int k = 0; k < 4; ++k) gather_into_lanes<T, W>(group.in[k], j0, count, block[k], rows);
  if (group.has_first_row && j0 == 0) block[0][0] = T(0);
  if (group.last_lane >= 0 && group.last_row >= j0 && group.last_row < j0 + count)
    block[2][(group.last_row - j0) * W + group.last_lane] = T(0);
}

// 0 for a finite value, NaN otherwise: summed over a sweep, a test of everything at once
// (separate terms: a sum of large finite values could overflow).
template <class T>
inline real_t<T> zero_if_finite(const T& value) {
  return magnitude(value) * 0;
}

// Whether every lane stayed healthy: each pivot's margin above the vanishing threshold
// positive, and the probe (a sum of zero_if_finite terms) zero.
template <class R, int W>
bool lanes_healthy(const R* margin, const R* probe) {
  bool healthy = true;
  for (int l = 0; l < W; ++l) healthy = healthy && margin[l] > 0 && probe[l] == 0;
  return healthy;
}

// What the check fused into step 1 found in a group: whether every row it saw is dominant, and
// every column whose neighbours lie in the same part (the columns at the parts' ends are
// judged by part_ends_dominant, which reads the neighbouring part).
struct PartDominance {
  bool rows = true, columns = true;
};

// Step 1 on one group: writes its parts' two reduced rows. `work` holds 3 * rows * W
// scalars (the eliminated rows, in L2) and `block` 4 * kTransposeBlock * W. With Check, also
// tests every coefficient for a finite value and the rows and inner columns for dominance
// (conservatively, without the slack of dominance_by_row: a failure sends the caller to that
// exact test), into `dominance`; the inputs are then read once for both.
template <class T, int W, bool Check = false>
bool reduce_part_group(const PartGroup<T, W>& group, std::ptrdiff_t rows, T* work, T* block_memory,
                       ReducedRows<T> reduced, PartDominance* dominance = nullptr) {
  using R = real_t<T>;
  const R tolerance = kVanishingPivot * epsilon<T>;
  // Per lane: 1 once a row (column) failed; the previous row's |b| and |c| and the |c| before
  // it, for the column test of row j - 1, finished when row j's |a| is read.
  R row_failure[W], column_failure[W], diagonal_before[W], super_before[W], super_before2[W];
  T* const block[4] = {block_memory, block_memory + kTransposeBlock * W,
                       block_memory + 2 * kTransposeBlock * W,
                       block_memory + 3 * kTransposeBlock * W};
  T* const kept_a = work;  // row j: a'_j x_s + x_j + c'_j x_{j+1} = d'_j
  T* const kept_c = work + rows * W;
  T* const kept_d = work + 2 * rows * W;
  // Locals, not a struct's members: GCC then keeps them in registers.
  R margin[W], probe[W];
  // Row 0, normalised: first_a x_{s-1} + x_s + first_c x_{s+1} = first_d.
  T first_a[W], first_c[W], first_d[W];
  // The row before, eliminated; before row 1 it is "x_s = 0 - (-1) x_s", so that row 1 takes
  // the general step.
  T previous_a[W], previous_c[W], previous_d[W];
  for (std::ptrdiff_t j0 = 0; j0 < rows; j0 += kTransposeBlock) {
    const std::ptrdiff_t count = std::min(kTransposeBlock, rows - j0);
    load_part_block(group, rows, j0, count, block);
    for (std::ptrdiff_t j = j0; j < j0 + count; ++j) {
      const T* a = block[0] + (j - j0) * W;
      const T* b = block[1] + (j - j0) * W;
      const T* c = block[2] + (j - j0) * W;
      const T* d = block[3] + (j - j0) * W;
      if (j == 0) {
#pragma omp simd simdlen(kLoopWidth <T, W>)
        for (int l = 0; l < W; ++l) {
          modified_first_row(a[l], b[l], c[l], d[l], first_a[l], first_c[l], first_d[l]);
          margin[l] = magnitude(b[l]) * (1 - tolerance);
          probe[l] =
              zero_if_finite(first_a[l]) + zero_if_finite(first_c[l]) + zero_if_finite(first_d[l]);
          modified_forward_start(previous_a[l], previous_c[l], previous_d[l]);
          if constexpr (Check) {
            const R diagonal = modulus(b[l]), sub = modulus(a[l]), super = modulus(c[l]);
            row_failure[l] = R(diagonal < sub + super);
            column_failure[l] = 0;  // column 0 of the part: part_ends_dominant
            probe[l] += (diagonal + sub + super) * 0;
            diagonal_before[l] = diagonal;
            super_before[l] = super;
            super_before2[l] = 0;
          }
        }
        continue;
      }
      T* ka = kept_a + j * W;
      T* kc = kept_c + j * W;
      T* kd = kept_d + j * W;
#pragma omp simd simdlen(kLoopWidth <T, W>)
      for (int l = 0; l < W; ++l) {
        T eliminated;
        const T pivot = modified_forward_row(a[l], b[l], c[l], d[l], previous_a[l], previous_c[l],
                                             previous_d[l], eliminated);
        const R scale = magnitude(b[l]) + magnitude(eliminated);
        margin[l] = std::min(margin[l], magnitude(pivot) - tolerance * scale);
        ka[l] = previous_a[l];
        kc[l] = previous_c[l];
        kd[l] = previous_d[l];
        probe[l] += zero_if_finite(previous_d[l]) + zero_if_finite(previous_a[l]) +
                    zero_if_finite(b[l]) + zero_if_finite(eliminated);
        if constexpr (Check) {
          const R diagonal = modulus(b[l]), sub = modulus(a[l]), super = modulus(c[l]);
          row_failure[l] = std::max(row_failure[l], R(diagonal < sub + super));
          // Column j - 1 (c_{j-2} above, a_j below); column 0 is left to part_ends_dominant.
          if (j >= 2)
            column_failure[l] =
                std::max(column_failure[l], R(diagonal_before[l] < super_before2[l] + sub));
          probe[l] += (diagonal + sub + super) * 0;
          super_before2[l] = super_before[l];
          super_before[l] = super;
          diagonal_before[l] = diagonal;
        }
      }
    }
  }
  if constexpr (Check) {  // the part's last column is left to part_ends_dominant
    for (int l = 0; l < W; ++l) {
      dominance->rows = dominance->rows && row_failure[l] == 0;
      dominance->columns = dominance->columns && column_failure[l] == 0;
    }
  }
  // Backward through the kept rows: row j as next_a x_s + x_j + next_c x_{e-1} = next_d,
  // starting from row m-1, which is x_{e-1} itself.
  T next_a[W], next_c[W], next_d[W];
  for (int l = 0; l < W; ++l) modified_backward_start(next_a[l], next_c[l], next_d[l]);
  for (std::ptrdiff_t j = rows - 2; j >= 1; --j) {
    const T* ka = kept_a + j * W;
    const T* kc = kept_c + j * W;
    const T* kd = kept_d + j * W;
#pragma omp simd simdlen(kLoopWidth <T, W>)
    for (int l = 0; l < W; ++l)
      modified_backward_row(ka[l], kc[l], kd[l], next_a[l], next_c[l], next_d[l]);
  }
  const std::ptrdiff_t base = 2 * group.first_part;
#pragma omp simd simdlen(kLoopWidth <T, W>)
  for (int l = 0; l < W; ++l) {
    // Row 0 with x_{s+1} substituted from row 1.
    T coupling;
    const T pivot = modified_close_first_row(next_a[l], next_c[l], next_d[l], first_a[l],
                                             first_c[l], first_d[l], coupling);
    margin[l] = std::min(margin[l], magnitude(pivot) - tolerance * (1 + magnitude(coupling)));
    reduced.sub[base + 2 * l] = first_a[l];
    reduced.super[base + 2 * l] = first_c[l];
    reduced.rhs[base + 2 * l] = first_d[l];
    // Row m-1 as the forward sweep left it.
    reduced.sub[base + 2 * l + 1] = previous_a[l];
    reduced.super[base + 2 * l + 1] = previous_c[l];
    reduced.rhs[base + 2 * l + 1] = previous_d[l];
    probe[l] += zero_if_finite(reduced.rhs[base + 2 * l]) +
                zero_if_finite(reduced.sub[base + 2 * l]) +
                zero_if_finite(reduced.super[base + 2 * l]);
  }
  return lanes_healthy<R, W>(margin, probe);
}

// Step 2: solves the reduced system in place (its solution replaces `rhs`). `work` holds 2P
// scalars. Returns false if a pivot vanished.
template <class T>
bool solve_reduced_rows(std::ptrdiff_t parts, ReducedRows<T> reduced, T* diagonal, T* work) {
  const std::ptrdiff_t m = 2 * parts;
  std::fill(diagonal, diagonal + m, T(1));
  return thomas(m, Strided<const T>{reduced.sub, 1}, Strided<const T>{diagonal, 1},
                Strided<const T>{reduced.super, 1}, Strided<const T>{reduced.rhs, 1},
                Strided<T>{reduced.rhs, 1}, work) < 0;
}

// Step 3 on one group: with each part's first and last unknowns from the reduced solution,
// Thomas on the rows between them (the end rows become identity rows), into group.out.
// `work` holds 2 * rows * W scalars and `block` 5 * kTransposeBlock * W.
template <class T, int W>
bool finish_part_group(const PartGroup<T, W>& group, std::ptrdiff_t rows, T* work, T* block_memory,
                       const T* boundary, bool streaming) {
  using R = real_t<T>;
  T* const block[4] = {block_memory, block_memory + kTransposeBlock * W,
                       block_memory + 2 * kTransposeBlock * W,
                       block_memory + 3 * kTransposeBlock * W};
  T* const solution = block_memory + 4 * kTransposeBlock * W;
  T* const kept_c = work;  // row j: x_j + c'_j x_{j+1} = d'_j
  T* const kept_d = work + rows * W;
  const T* first = boundary + 2 * group.first_part;  // x_s of lane l at first[2 l]
  R probe[W];
  T previous_c[W], previous_d[W];
  for (int l = 0; l < W; ++l) {
    probe[l] = 0;
    previous_c[l] = previous_d[l] = T(0);
  }
  for (std::ptrdiff_t j0 = 0; j0 < rows; j0 += kTransposeBlock) {
    const std::ptrdiff_t count = std::min(kTransposeBlock, rows - j0);
    load_part_block(group, rows, j0, count, block);
    // The end rows read x = the known boundary value.
    for (std::ptrdiff_t end : {std::ptrdiff_t(0), rows - 1}) {
      if (end < j0 || end >= j0 + count) continue;
      const std::ptrdiff_t at = (end - j0) * W;
      for (int l = 0; l < W; ++l) {
        block[0][at + l] = block[2][at + l] = T(0);
        block[1][at + l] = T(1);
        block[3][at + l] = first[2 * l + (end == 0 ? 0 : 1)];
      }
    }
    for (std::ptrdiff_t j = j0; j < j0 + count; ++j) {
      const T* a = block[0] + (j - j0) * W;
      const T* b = block[1] + (j - j0) * W;
      const T* c = block[2] + (j - j0) * W;
      const T* d = block[3] + (j - j0) * W;
      T* kc = kept_c + j * W;
      T* kd = kept_d + j * W;
      // The pivots are those of step 1 (the same elimination from row 1), already checked.
#pragma omp simd simdlen(kLoopWidth <T, W>)
      for (int l = 0; l < W; ++l) {
        const T inverse = T(1) / (b[l] - a[l] * previous_c[l]);
        previous_c[l] = c[l] * inverse;
        previous_d[l] = (d[l] - a[l] * previous_d[l]) * inverse;
        kc[l] = previous_c[l];
        kd[l] = previous_d[l];
      }
    }
  }
  T next[W];
  for (int l = 0; l < W; ++l) next[l] = T(0);
  for (std::ptrdiff_t j0 = (rows - 1) / kTransposeBlock * kTransposeBlock; j0 >= 0;
       j0 -= kTransposeBlock) {
    const std::ptrdiff_t count = std::min(kTransposeBlock, rows - j0);
    for (std::ptrdiff_t j = j0 + count - 1; j >= j0; --j) {
      const T* kc = kept_c + j * W;
      const T* kd = kept_d + j * W;
      T* out = solution + (j - j0) * W;
#pragma omp simd simdlen(kLoopWidth <T, W>)
      for (int l = 0; l < W; ++l) {
        next[l] = kd[l] - kc[l] * next[l];
        out[l] = next[l];
        probe[l] += zero_if_finite(next[l]);
      }
    }
    scatter_from_lanes<T, W>(solution, count, group.out, j0, streaming);
  }
  bool finite = true;
  for (int l = 0; l < W; ++l) finite = finite && probe[l] == 0;
  return finite;
}

// The group's pointers: straight into the caller's arrays where its rows are contiguous and
// inside the system, otherwise into `staging` (5 * rows * W scalars), which then receives a
// copy padded with identity rows. The solution goes to `out` (a contiguous array of
// layout.parts * layout.rows if `out_padded`, of n otherwise: a group reaching past row n-1
// then writes to the staging area, and copy_staged_solution moves its rows).
template <class T, int W>
PartGroup<T, W> part_group(const SystemView<T>& s, const PartLayout& layout, std::ptrdiff_t g,
                           T* out, bool out_padded, T* staging) {
  const std::ptrdiff_t rows = layout.rows, first = g * W * rows, span = W * rows;
  const bool inside = first + span <= layout.n;
  const bool contiguous = s.a.stride == 1 && s.b.stride == 1 && s.c.stride == 1 && s.d.stride == 1;
  PartGroup<T, W> group;
  group.first_part = g * W;
  group.has_first_row = g == 0;
  const std::ptrdiff_t last = layout.n - 1 - first;
  if (last >= 0 && last < span) {
    group.last_lane = static_cast<int>(last / rows);
    group.last_row = last % rows;
  }
  const Strided<const T> inputs[4] = {s.a, s.b, s.c, s.d};
  for (int k = 0; k < 4; ++k) {
    T* copy = staging + k * span;
    if (!(inside && contiguous)) {
      const std::ptrdiff_t valid = std::clamp<std::ptrdiff_t>(layout.n - first, 0, span);
      for (std::ptrdiff_t i = 0; i < valid; ++i) copy[i] = inputs[k][first + i];
      std::fill(copy + valid, copy + span, k == 1 ? T(1) : T(0));
    }
    for (int l = 0; l < W; ++l)
      group.in[k][l] = inside && contiguous ? inputs[k].data + first + l * rows : copy + l * rows;
  }
  T* target = inside || out_padded ? out + first : staging + 4 * span;
  for (int l = 0; l < W; ++l) group.out[l] = target + l * rows;
  return group;
}

// Whether the columns at the ends of group g's parts (their first and last rows, whose
// neighbours in the column lie in the next or previous part) are dominant, in the conservative
// test of reduce_part_group<..., true>.
template <class T, int W>
bool part_ends_dominant(const SystemView<T>& s, const PartLayout& layout, std::ptrdiff_t g) {
  using R = real_t<T>;
  bool dominant = true;
  for (std::ptrdiff_t p = g * W; p < (g + 1) * W; ++p)
    for (const std::ptrdiff_t i : {p * layout.rows, p * layout.rows + layout.rows - 1}) {
      if (i >= s.n) continue;
      const R above = i > 0 ? modulus(s.c[i - 1]) : R(0);
      const R below = i + 1 < s.n ? modulus(s.a[i + 1]) : R(0);
      dominant = dominant && !(modulus(s.b[i]) < above + below);
    }
  return dominant;
}

// What partitioned_lanes did.
enum class PartOutcome {
  Solved,
  NotChecked,  // the fused check did not pass (not finite, not dominant, or a pivot vanished
               // in step 1): nothing written; the caller runs the exact check
  BrokeDown,   // a pivot vanished or the solution is not finite; rhs untouched
};

// Above this size the solution is written with non-temporal stores: it cannot stay in cache.
inline constexpr std::ptrdiff_t kStreamingBytes = std::ptrdiff_t(16) << 20;

// Solves one system by parts in lanes, groups of parts shared by `threads` threads; x may be
// s.d (in place). Unless Solved, rhs is left as it was. a_0 and c_{n-1} are not read. With
// `check`, step 1 also tests the matrix for finite values and dominance by rows or by columns
// (what check_system does in two more passes over a, b and c).
template <class T>
PartOutcome partitioned_lanes(const SystemView<T>& s, Strided<T> x, int threads,
                              bool check = false) {
  constexpr int W = kPartLanes<T>;
  const PartLayout layout = make_part_layout<T, W>(s.n, threads);
  const std::ptrdiff_t rows = layout.rows, m = 2 * layout.parts;
  const bool in_place = x.data == s.d.data;
  const bool direct = x.stride == 1 && !in_place;  // the solution goes straight into x
  const std::ptrdiff_t padded = layout.parts * rows;
  static thread_local AlignedBuffer<T> shared;
  shared.resize(5 * m + (direct ? 0 : padded));
  T* const storage = shared.data();  // `shared` names another buffer on the team's threads
  const ReducedRows<T> reduced{storage, storage + m, storage + 2 * m};
  T* out = direct ? x.data : storage + 5 * m;
  const bool streaming = direct && s.n * std::ptrdiff_t(sizeof(T)) >= kStreamingBytes;
  const int team = static_cast<int>(std::min<std::ptrdiff_t>(threads, layout.groups));
  // reduced_ok: step 1 healthy on every group; solved_reduced: step 2; finished_ok: step 3.
  bool reduced_ok = true, solved_reduced = true, finished_ok = true;
  bool rows_dominant = true, columns_dominant = true;  // the fused check's verdicts
  const SubnormalsKept gradual_underflow;              // for the serial steps; see subnormals.hpp
#pragma omp parallel num_threads(team) if (team > 1)
  {
    const SubnormalsKept team_gradual_underflow;  // each thread has its own MXCSR
    static thread_local AlignedBuffer<T> local;
    local.resize(part_group_workspace<T, W>(layout));
    T* work = local.data();
    T* staging = work + 3 * rows * W;
    T* blocks = staging + 5 * rows * W;
    bool ok = true;
    PartDominance dominance;
#pragma omp for schedule(static)
    for (std::ptrdiff_t g = 0; g < layout.groups; ++g) {
      const auto group = part_group<T, W>(s, layout, g, out, !direct, staging);
      if (check) {
        ok = reduce_part_group<T, W, true>(group, rows, work, blocks, reduced, &dominance) && ok;
        dominance.columns = dominance.columns && part_ends_dominant<T, W>(s, layout, g);
      } else {
        ok = reduce_part_group<T, W>(group, rows, work, blocks, reduced) && ok;
      }
    }
    if (!ok) {
#pragma omp atomic write
      reduced_ok = false;
    }
    if (!dominance.rows) {
#pragma omp atomic write
      rows_dominant = false;
    }
    if (!dominance.columns) {
#pragma omp atomic write
      columns_dominant = false;
    }
#pragma omp barrier
    // Step 1 healthy on every group and, when checked, the matrix dominant by rows or by
    // columns as a whole: the same verdict on every thread.
    const bool accepted = reduced_ok && (rows_dominant || columns_dominant);
#pragma omp single
    if (accepted)
      solved_reduced = solve_reduced_rows(layout.parts, reduced, storage + 3 * m, storage + 4 * m);
    if (accepted && solved_reduced) {
#pragma omp for schedule(static)
      for (std::ptrdiff_t g = 0; g < layout.groups; ++g) {
        const auto group = part_group<T, W>(s, layout, g, out, !direct, staging);
        ok = finish_part_group<T, W>(group, rows, work, blocks, reduced.rhs, streaming) && ok;
        const std::ptrdiff_t first = g * W * rows;
        if (direct && first + W * rows > s.n && first < s.n)  // staged: the rows of the system
          std::copy(staging + 4 * W * rows, staging + 4 * W * rows + (s.n - first), out + first);
      }
      finish_streaming_stores();
      if (!ok) {
#pragma omp atomic write
        finished_ok = false;
      }
    }
  }
  PartOutcome outcome = PartOutcome::Solved;
  if (!reduced_ok || !(rows_dominant || columns_dominant))
    outcome = check ? PartOutcome::NotChecked : PartOutcome::BrokeDown;
  else if (!solved_reduced || !finished_ok)
    outcome = PartOutcome::BrokeDown;
  if (outcome == PartOutcome::Solved && !direct) {
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && s.n > (1 << 16))
    for (std::ptrdiff_t i = 0; i < s.n; ++i) x[i] = out[i];
  }
  if (shared.size() * std::ptrdiff_t(sizeof(T)) > (std::ptrdiff_t(256) << 20)) shared = {};
  return outcome;
}

}  // namespace tridiff::detail
