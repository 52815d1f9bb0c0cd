// Thomas for the implicit diffusion system of seed 000 eq. 3.10:
//   a_i = -beta_{i-1},  c_i = -beta_i,  b_i = 1 + beta_{i-1} + beta_i,  beta_{-1} = beta_{n-1} = 0,
// stored as beta alone (one coefficient array instead of three).
//
// With beta >= 0 the matrix is strictly diagonally dominant, every pivot is >= 1 and the solve
// is stable for any beta. The elimination is written without subtractions: with
//   g_i = 1 + beta_{i-1} * e_{i-1},  m_i = g_i + beta_i,  e_i = g_i / m_i  (= 1 + c'_i),
// all terms are non-negative, so even beta ~ 1e6 in float loses no digits to cancellation, and
// the solution is a convex combination of the right-hand side (no new extrema).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <type_traits>

#include "tridiff/solvers/detail/scalar.hpp"
#include "tridiff/solvers/detail/transpose.hpp"

namespace tridiff::detail {

// One system; x may alias d. beta[n-1] is never read. `work` holds n reals.
template <class T>
void diffusion_thomas(std::ptrdiff_t n, Strided<const real_t<T>> beta, Strided<const T> d,
                      Strided<T> x, real_t<T>* work) {
  using R = real_t<T>;
  R beta_before = 0, e_before = 1;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const R beta_here = i + 1 < n ? beta[i] : R(0);
    const R g = 1 + beta_before * e_before;
    const R inverse = 1 / (g + beta_here);
    x[i] = (d[i] + (i == 0 ? T(0) : beta_before * x[i - 1])) * inverse;
    work[i] = beta_here * inverse;  // -c'_i
    e_before = g * inverse;
    beta_before = beta_here;
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) x[i] += work[i] * x[i + 1];
}

// A row of an M-matrix written by what makes it one: its leak (row sum) and its two links,
//   (leak + before + after) x_k - before x_{k-1} - after x_{k+1} = rhs,   all three >= 0.
// The diffusion form is leak 1, before beta_{k-1}, after beta_k; the reduced systems of the
// diffusion form's parts (partitioned_diffusion.hpp, the distributed solve) have other leaks.
// Eliminating with the leak carried, instead of the diagonal, needs no subtraction: every
// pivot is leak + after + (a share of before), x a convex combination of rhs / leak.
template <class T>
struct LeakRow {
  real_t<T> leak, before, after;
  T rhs;
};

// The pivot's inverse, taken in halves where the pivot overflows (two links above max() / 2):
// 1 / inf would be a silent 0. `probe` counts a pivot that not even that keeps finite.
template <class R>
inline R leak_pivot_inverse(R g, R after, R& probe) {
  const R pivot = g + after;
  if (std::isfinite(pivot)) return 1 / pivot;
  const R half = R(0.5) * g + R(0.5) * after;
  probe += std::isfinite(half) ? R(0) : R(1);
  return R(0.5) / half;
}

// The open chain of `n` leak rows (row(k, r) sets r to row k; row 0's before and row n-1's after
// couple to nothing and are not used). x may be the storage row() reads, as row k is read
// before x[k] is written; `work` holds n reals. Returns false if a pivot or x is not finite.
template <class T, class Row>
bool leak_elimination(std::ptrdiff_t n, Row&& row, Strided<T> x, real_t<T>* work) {
  using R = real_t<T>;
  R e_before = 1, probe = 0;
  T carry = T(0);
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    LeakRow<T> r;
    row(k, r);
    const R link_before = k > 0 ? r.before : R(0), after = k + 1 < n ? r.after : R(0);
    const R g = r.leak + link_before * e_before;
    const R inverse = leak_pivot_inverse(g, after, probe);
    carry = (r.rhs + link_before * carry) * inverse;
    x[k] = carry;
    work[k] = after * inverse;
    e_before = g * inverse;
  }
  for (std::ptrdiff_t k = n - 2; k >= 0; --k) x[k] += work[k] * x[k + 1];
  for (std::ptrdiff_t k = 0; k < n; ++k) probe += is_finite(x[k]) ? R(0) : R(1);
  return probe == 0;
}

// The ring of `n` leak rows (row 0's before links it to row n-1, row n-1's after to row 0),
// as subtraction-free as the open chain: the ring is cut at row 0. Rows 1 .. n-1 form an open
// chain whose ends couple to x_0 (through row 1's before and row n-1's after), so by linearity
// x_k = u_k + v_k x_0, with u the chain's solution for rhs and v its response to x_0. The
// chain's rows sum to their leaks apart from those two links, so its response to the leaks,
// w, satisfies w + v = 1: row 0 then reads
//   (leak_0 + before_0 w_{n-1} + after_0 w_1) x_0 = rhs_0 + before_0 u_{n-1} + after_0 u_1,
// every term >= 0 (the textbook route, Sherman-Morrison on the expanded matrix, subtracts, and
// its error grows like beta * epsilon). x may be the storage row() reads; `work` holds 3n
// reals. Returns false if a pivot or x is not finite.
template <class T, class Row>
bool ring_leak_elimination(std::ptrdiff_t n, Row&& row, Strided<T> x, real_t<T>* work) {
  using R = real_t<T>;
  LeakRow<T> first;  // x may be rhs: row 0 is overwritten last, but read it first
  row(0, first);
  if (n == 1) {  // the row's links join x_0 to itself
    x[0] = first.rhs / first.leak;
    return is_finite(x[0]);
  }
  R* const multiplier = work;  // row k: x_k = y_k + multiplier_k x_{k+1} (k < n-1)
  R* const w = work + n;       // the chain's response to its leaks
  R* const v = work + 2 * n;   // and to x_0
  R e_before = 1, carry_w = 0, carry_v = 1, probe = 0;
  T carry_u = T(0);
  for (std::ptrdiff_t k = 1; k < n; ++k) {
    LeakRow<T> r;  // row n-1's after is the link back to x_0
    row(k, r);
    // g carries the link to x_0 at full size in row 1 (e_before = 1).
    const R g = r.leak + r.before * e_before;
    const R inverse = leak_pivot_inverse(g, r.after, probe);
    carry_u = (r.rhs + r.before * carry_u) * inverse;
    carry_w = (r.leak + r.before * carry_w) * inverse;
    carry_v = r.before * carry_v * inverse;
    x[k] = carry_u;
    w[k] = carry_w;
    v[k] = carry_v;
    multiplier[k] = r.after * inverse;
    e_before = g * inverse;
  }
  v[n - 1] += multiplier[n - 1];  // the last row's own link to x_0
  for (std::ptrdiff_t k = n - 2; k >= 1; --k) {
    x[k] += multiplier[k] * x[k + 1];
    w[k] += multiplier[k] * w[k + 1];
    v[k] += multiplier[k] * v[k + 1];
  }
  const T x0 = (first.rhs + first.before * x[n - 1] + first.after * x[1]) /
               (first.leak + first.before * w[n - 1] + first.after * w[1]);
  x[0] = x0;
  for (std::ptrdiff_t k = 1; k < n; ++k) x[k] += v[k] * x0;
  for (std::ptrdiff_t k = 0; k < n; ++k) probe += is_finite(x[k]) ? R(0) : R(1);
  return probe == 0;
}

// The periodic diffusion system (beta[n-1] links x[n-1] to x[0]): the ring of leak rows
// (1, beta[k-1], beta[k]). x may alias d; `work` holds 3n reals.
template <class T>
void periodic_diffusion_thomas(std::ptrdiff_t n, Strided<const real_t<T>> beta, Strided<const T> d,
                               Strided<T> x, real_t<T>* work) {
  using R = real_t<T>;
  ring_leak_elimination(
      n,
      [&](std::ptrdiff_t k, LeakRow<T>& row) {
        row = {R(1), beta[k > 0 ? k - 1 : n - 1], beta[k], d[k]};
      },
      x, work);
}

// Reals of workspace DiffusionLanes<T, W, rhs> needs.
template <class T>
constexpr std::ptrdiff_t diffusion_lanes_workspace(std::ptrdiff_t n, int lanes, int rhs = 1) {
  return n * lanes * (1 + rhs * std::ptrdiff_t(sizeof(T) / sizeof(real_t<T>)));
}

// The same elimination on W systems at once, one SIMD lane each, fed block by block so that a
// driver can transpose image rows into lanes a few columns at a time (all in L1). Each system
// has `Rhs` right-hand sides (LAPACK's NRHS: the colour planes of one image) that share the
// factorisation, so its division and its beta are paid once for all of them.
// The forward sweep keeps its results in `work` (the eliminated right-hand sides and the
// multipliers), so x is written once, by the backward sweep, and only after the forward sweep
// found beta >= 0 and finite and the eliminated rhs finite; x is then a convex combination
// of the rhs and cannot overflow. In-place solves (x == d) are therefore safe.
template <class T, int W, int Rhs = 1>
class DiffusionLanes {
  using R = real_t<T>;
  static_assert(!is_complex_v<T> || sizeof(T) == 2 * sizeof(R));

 public:
  DiffusionLanes(std::ptrdiff_t n, R* work)
      : n_(n), multipliers_(work), eliminated_(reinterpret_cast<T*>(work + n * W)) {
    for (int l = 0; l < W; ++l) {
      beta_before_[l] = 0;
      e_before_[l] = 1;
      probe_[l] = 0;
      for (int c = 0; c < Rhs; ++c) carry_[c][l] = T(0);
    }
  }

  // Rows [begin, end) in increasing order. Row i's beta is at (i - begin) * beta_stride + lane,
  // its right-hand side c at (i - begin) * stride + c * plane_stride + lane.
  void forward(std::ptrdiff_t begin, std::ptrdiff_t end, const R* beta, std::ptrdiff_t beta_stride,
               const T* d, std::ptrdiff_t stride, std::ptrdiff_t plane_stride) {
    forward_to(begin, end, beta, beta_stride, d, stride, plane_stride,
               eliminated_ + begin * Rhs * W, Rhs * W, W);
  }

  // forward, with the eliminated right-hand sides of row i stored by the caller, at
  // e + (i - begin) * e_stride + c * e_plane_stride + lane (only n * W reals of workspace are
  // then used). A driver can keep them in the rows the solution will overwrite, which halves
  // what a long system keeps in cache between the sweeps.
  void forward_to(std::ptrdiff_t begin, std::ptrdiff_t end, const R* beta,
                  std::ptrdiff_t beta_stride, const T* d, std::ptrdiff_t stride,
                  std::ptrdiff_t plane_stride, T* e_out, std::ptrdiff_t e_stride,
                  std::ptrdiff_t e_plane_stride) {
#if defined(__AVX512F__)
    if constexpr (std::is_same_v<T, float> && W % 16 == 0 && Rhs > 1) {
      forward_to_avx512(begin, end, beta, beta_stride, d, stride, plane_stride, e_out, e_stride,
                        e_plane_stride);
      return;
    }
#endif
    // Work on local copies of the state: the compiler then keeps it in registers, as it
    // cannot prove that the stores through w and e leave the members alone.
    R beta_before[W], e_before[W], probe[W];
    T carry[Rhs][W];
    load_state(beta_before, e_before, probe, carry);
    for (std::ptrdiff_t i = begin; i < end; ++i) {
      const R* b = beta + (i - begin) * beta_stride;
      const T* rhs = d + (i - begin) * stride;
      const bool has_link = i + 1 < n_;  // beta[n-1] is not part of the system
      R* w = multipliers_ + i * W;
      T* e = e_out + (i - begin) * e_stride;
#pragma omp simd simdlen(kLoopWidth <T, W>)
      for (int l = 0; l < W; ++l) {
        const R beta_here = has_link ? b[l] : R(0);
        const R g = 1 + beta_before[l] * e_before[l];
        const R inverse = 1 / (g + beta_here);
        R zero_if_finite = 0;
        for (int c = 0; c < Rhs; ++c) {
          const T value = (rhs[c * plane_stride + l] + beta_before[l] * carry[c][l]) * inverse;
          e[c * e_plane_stride + l] = value;
          carry[c][l] = value;
          zero_if_finite += magnitude(value) * 0;
        }
        w[l] = beta_here * inverse;
        e_before[l] = g * inverse;
        beta_before[l] = beta_here;
        // Zero while beta and the values are finite and beta >= 0 (one accumulator, not two:
        // with three right-hand sides of 4 vectors each, registers are short).
        probe[l] += beta_here * 0 + zero_if_finite + (beta_here < 0 ? R(1) : R(0));
      }
    }
    store_state(beta_before, e_before, probe, carry);
  }

  // One right-hand side, beta and rhs of row i at (i - begin) * stride + lane.
  void forward(std::ptrdiff_t begin, std::ptrdiff_t end, const R* beta, const T* d,
               std::ptrdiff_t stride) {
    static_assert(Rhs == 1);
    forward(begin, end, beta, stride, d, stride, 0);
  }

  // After the whole forward sweep: were beta and the rhs valid in every lane?
  bool healthy() const {
    bool ok = true;
    for (int l = 0; l < W; ++l) ok = ok && probe_[l] == 0;
    return ok;
  }

  // Rows [begin, end) in decreasing order, called from the last block to the first; solution c
  // of row i goes to x + (i - begin) * stride + c * plane_stride + lane.
  void backward(std::ptrdiff_t begin, std::ptrdiff_t end, T* x, std::ptrdiff_t stride,
                std::ptrdiff_t plane_stride = 0) {
    backward_from(begin, end, eliminated_ + begin * Rhs * W, Rhs * W, W, x, stride, plane_stride);
  }

  // backward, reading the eliminated right-hand sides where forward_to put them (e may be x).
  void backward_from(std::ptrdiff_t begin, std::ptrdiff_t end, const T* e_in,
                     std::ptrdiff_t e_stride, std::ptrdiff_t e_plane_stride, T* x,
                     std::ptrdiff_t stride, std::ptrdiff_t plane_stride) {
#if defined(__AVX512F__)
    if constexpr (std::is_same_v<T, float> && W % 16 == 0 && Rhs > 1) {
      backward_from_avx512(begin, end, e_in, e_stride, e_plane_stride, x, stride, plane_stride);
      return;
    }
#endif
    T carry[Rhs][W];
    for (int c = 0; c < Rhs; ++c)
      for (int l = 0; l < W; ++l) carry[c][l] = carry_[c][l];
    for (std::ptrdiff_t i = end - 1; i >= begin; --i) {
      const R* w = multipliers_ + i * W;
      const T* e = e_in + (i - begin) * e_stride;
      T* out = x + (i - begin) * stride;
      const bool last = i == n_ - 1;
#pragma omp simd simdlen(kLoopWidth <T, W>)
      for (int l = 0; l < W; ++l)
        for (int c = 0; c < Rhs; ++c) {
          carry[c][l] =
              last ? e[c * e_plane_stride + l] : e[c * e_plane_stride + l] + w[l] * carry[c][l];
          out[c * plane_stride + l] = carry[c][l];
        }
    }
    for (int c = 0; c < Rhs; ++c)
      for (int l = 0; l < W; ++l) carry_[c][l] = carry[c][l];
  }

 private:
#if defined(__AVX512F__)
  // The sweeps of float lanes with several right-hand sides, written with AVX-512 intrinsics:
  // the solution's operations in the order of the portable loops (with the multiply-adds GCC
  // forms there), the validity probe in its own order, and the state in registers. GCC 12 kept the portable loops' state arrays on the stack when Rhs > 1,
  // so that each step's recurrence went through a store and a load. Measured on one core, in
  // L1/L2, three right-hand sides, per 16 lanes: W = 32 35.6 -> 22 cycles, W = 64 35 -> 26;
  // the ADI DOF passes at 3840 x 2160 RGB, 2 threads: rows 7.7 -> 6.8 ms, columns 7.3 -> 6.7.
  // (With one right-hand side GCC keeps the state in registers itself, and is as fast.)
  static constexpr int kVectors = W / 16;

  void forward_to_avx512(std::ptrdiff_t begin, std::ptrdiff_t end, const float* beta,
                         std::ptrdiff_t beta_stride, const float* d, std::ptrdiff_t stride,
                         std::ptrdiff_t plane_stride, float* e_out, std::ptrdiff_t e_stride,
                         std::ptrdiff_t e_plane_stride) {
    const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.f);
    __m512 beta_before[kVectors], e_before[kVectors], probe[kVectors], carry[Rhs][kVectors];
    for (int v = 0; v < kVectors; ++v) {
      beta_before[v] = _mm512_loadu_ps(beta_before_ + 16 * v);
      e_before[v] = _mm512_loadu_ps(e_before_ + 16 * v);
      probe[v] = _mm512_loadu_ps(probe_ + 16 * v);
      for (int c = 0; c < Rhs; ++c) carry[c][v] = _mm512_loadu_ps(carry_[c] + 16 * v);
    }
    for (std::ptrdiff_t i = begin; i < end; ++i) {
      const float* b = beta + (i - begin) * beta_stride;
      const float* rhs = d + (i - begin) * stride;
      const bool has_link = i + 1 < n_;  // beta[n-1] is not part of the system
      float* w = multipliers_ + i * W;
      float* e = e_out + (i - begin) * e_stride;
      for (int v = 0; v < kVectors; ++v) {
        const __m512 beta_here = has_link ? _mm512_loadu_ps(b + 16 * v) : zero;
        const __m512 g = _mm512_fmadd_ps(beta_before[v], e_before[v], one);
        const __m512 inverse = _mm512_div_ps(one, _mm512_add_ps(g, beta_here));
        __m512 zero_if_finite = _mm512_mul_ps(beta_here, zero);
        for (int c = 0; c < Rhs; ++c) {
          const __m512 value =
              _mm512_mul_ps(_mm512_fmadd_ps(beta_before[v], carry[c][v],
                                            _mm512_loadu_ps(rhs + c * plane_stride + 16 * v)),
                            inverse);
          _mm512_storeu_ps(e + c * e_plane_stride + 16 * v, value);
          carry[c][v] = value;
          zero_if_finite = _mm512_fmadd_ps(value, zero, zero_if_finite);
        }
        _mm512_storeu_ps(w + 16 * v, _mm512_mul_ps(beta_here, inverse));
        e_before[v] = _mm512_mul_ps(g, inverse);
        beta_before[v] = beta_here;
        // Zero while beta and the values are finite and beta >= 0.
        const __mmask16 negative = _mm512_cmp_ps_mask(beta_here, zero, _CMP_LT_OQ);
        const __m512 sum = _mm512_add_ps(probe[v], zero_if_finite);
        probe[v] = _mm512_mask_add_ps(sum, negative, sum, one);
      }
    }
    for (int v = 0; v < kVectors; ++v) {
      _mm512_storeu_ps(beta_before_ + 16 * v, beta_before[v]);
      _mm512_storeu_ps(e_before_ + 16 * v, e_before[v]);
      _mm512_storeu_ps(probe_ + 16 * v, probe[v]);
      for (int c = 0; c < Rhs; ++c) _mm512_storeu_ps(carry_[c] + 16 * v, carry[c][v]);
    }
  }

  void backward_from_avx512(std::ptrdiff_t begin, std::ptrdiff_t end, const float* e_in,
                            std::ptrdiff_t e_stride, std::ptrdiff_t e_plane_stride, float* x,
                            std::ptrdiff_t stride, std::ptrdiff_t plane_stride) {
    __m512 carry[Rhs][kVectors];
    for (int v = 0; v < kVectors; ++v)
      for (int c = 0; c < Rhs; ++c) carry[c][v] = _mm512_loadu_ps(carry_[c] + 16 * v);
    for (std::ptrdiff_t i = end - 1; i >= begin; --i) {
      const float* w = multipliers_ + i * W;
      const float* e = e_in + (i - begin) * e_stride;
      float* out = x + (i - begin) * stride;
      const bool last = i == n_ - 1;
      for (int v = 0; v < kVectors; ++v) {
        const __m512 multiplier = _mm512_loadu_ps(w + 16 * v);
        for (int c = 0; c < Rhs; ++c) {
          const __m512 eliminated = _mm512_loadu_ps(e + c * e_plane_stride + 16 * v);
          carry[c][v] = last ? eliminated : _mm512_fmadd_ps(multiplier, carry[c][v], eliminated);
          _mm512_storeu_ps(out + c * plane_stride + 16 * v, carry[c][v]);
        }
      }
    }
    for (int v = 0; v < kVectors; ++v)
      for (int c = 0; c < Rhs; ++c) _mm512_storeu_ps(carry_[c] + 16 * v, carry[c][v]);
  }
#endif

  void load_state(R* beta_before, R* e_before, R* probe, T (*carry)[W]) const {
    for (int l = 0; l < W; ++l) {
      beta_before[l] = beta_before_[l];
      e_before[l] = e_before_[l];
      probe[l] = probe_[l];
      for (int c = 0; c < Rhs; ++c) carry[c][l] = carry_[c][l];
    }
  }
  void store_state(const R* beta_before, const R* e_before, const R* probe, const T (*carry)[W]) {
    for (int l = 0; l < W; ++l) {
      beta_before_[l] = beta_before[l];
      e_before_[l] = e_before[l];
      probe_[l] = probe[l];
      for (int c = 0; c < Rhs; ++c) carry_[c][l] = carry[c][l];
    }
  }

  std::ptrdiff_t n_;
  R* multipliers_;  // beta_i / m_i  (= -c'_i)
  T* eliminated_;   // d'_i, the Rhs right-hand sides of row i side by side
  R beta_before_[W], e_before_[W], probe_[W];
  T carry_[Rhs][W];  // forward: d'_{i-1}; backward: x_{i+1}
};

// Lane-contiguous systems (equation i of lane l at i * row_stride + l). Returns false, with x
// untouched, if some beta is negative or not finite or the rhs is not finite.
// Image columns put every row of the W lanes in a page of its own (row_stride 4096 floats is
// 16 KiB), and the hardware prefetchers do not cross pages: each row would wait for DRAM. So
// the sweeps go in blocks of kAhead rows and ask for the next block's rows first (4096 x 4096
// columns on 1 thread: float 53-60 -> 42-48 ms, double 122-126 -> 99-107 ms; 32 rows ahead
// gained nothing more).
template <class T, int W>
bool diffusion_thomas_lanes(std::ptrdiff_t n, const real_t<T>* beta, const T* d, T* x,
                            std::ptrdiff_t row_stride, real_t<T>* work) {
  constexpr std::ptrdiff_t kAhead = 16;
  DiffusionLanes<T, W> sweep(n, work);
  for (std::ptrdiff_t begin = 0; begin < n; begin += kAhead) {
    const std::ptrdiff_t end = std::min(n, begin + kAhead);
    for (std::ptrdiff_t i = end; i < std::min(n, end + kAhead); ++i) {
      prefetch_values(beta + i * row_stride, W);
      prefetch_values(d + i * row_stride, W);
    }
    sweep.forward(begin, end, beta + begin * row_stride, row_stride, d + begin * row_stride,
                  row_stride, 0);
  }
  if (!sweep.healthy()) return false;
  for (std::ptrdiff_t begin = (n - 1) / kAhead * kAhead; begin >= 0; begin -= kAhead) {
    for (std::ptrdiff_t i = std::max<std::ptrdiff_t>(0, begin - kAhead); i < begin; ++i)
      prefetch_values(x + i * row_stride, W, true);
    sweep.backward(begin, std::min(n, begin + kAhead), x + begin * row_stride, row_stride);
  }
  return true;
}

// Pitch of the staging copy of W rows: a multiple of 16 elements (aligned rows) that is not a
// multiple of 4 KiB, so the W rows of a transposed block do not fall into one cache set.
inline std::ptrdiff_t staging_pitch(std::ptrdiff_t n) { return (n + 15) / 16 * 16 + 16; }

// Reals of workspace diffusion_thomas_rows needs.
template <class T>
std::ptrdiff_t diffusion_rows_workspace(std::ptrdiff_t n, int lanes) {
  const std::ptrdiff_t per_value = std::ptrdiff_t(sizeof(T) / sizeof(real_t<T>));
  return diffusion_lanes_workspace<T>(n, lanes) + lanes * staging_pitch(n) * (1 + per_value) +
         kTransposeBlock * lanes * (1 + per_value);
}

// Contiguous systems (image rows: equation i of system l at l * pitch + i), W at a time.
// The W rows are first copied one after another into a staging area (one sequential stream
// at a time: W rows read side by side are more streams than DRAM and the prefetchers serve
// well, and a power-of-two pitch puts them all in one cache set). Blocks of kTransposeBlock
// columns are then transposed into lanes in L1; the solution goes back the same way.
template <class T, int W>
bool diffusion_thomas_rows(std::ptrdiff_t n, const real_t<T>* beta, const T* d, T* x,
                           std::ptrdiff_t pitch, real_t<T>* work) {
  using R = real_t<T>;
  constexpr std::ptrdiff_t kBlock = kTransposeBlock;
  const std::ptrdiff_t staged = staging_pitch(n);
  DiffusionLanes<T, W> sweep(n, work);
  R* staged_beta = work + diffusion_lanes_workspace<T>(n, W);
  T* staged_values = reinterpret_cast<T*>(staged_beta + W * staged);
  R* block_beta = reinterpret_cast<R*>(staged_values + W * staged);
  T* block_values = reinterpret_cast<T*>(block_beta + kBlock * W);
  for (int l = 0; l < W; ++l) {
    std::copy(beta + l * pitch, beta + l * pitch + n, staged_beta + l * staged);
    std::copy(d + l * pitch, d + l * pitch + n, staged_values + l * staged);
  }
  for (std::ptrdiff_t begin = 0; begin < n; begin += kBlock) {
    const std::ptrdiff_t end = std::min(n, begin + kBlock);
    transpose_into_lanes<R, W>(staged_beta + begin, staged, end - begin, block_beta);
    transpose_into_lanes<T, W>(staged_values + begin, staged, end - begin, block_values);
    sweep.forward(begin, end, block_beta, block_values, W);
  }
  if (!sweep.healthy()) return false;
  for (std::ptrdiff_t begin = (n - 1) / kBlock * kBlock; begin >= 0; begin -= kBlock) {
    const std::ptrdiff_t end = std::min(n, begin + kBlock);
    sweep.backward(begin, end, block_values, W);
    transpose_from_lanes<T, W>(block_values, end - begin, staged_values + begin, staged);
  }
  for (int l = 0; l < W; ++l)
    std::copy(staged_values + l * staged, staged_values + l * staged + n, x + l * pitch);
  return true;
}

}  // namespace tridiff::detail
