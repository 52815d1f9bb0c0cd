// The LU factors of tridiagonal systems stored one SIMD lane per system, how they are computed
// (one system at a time, the plain reference) and how they solve (W systems at once, or one
// lane alone with the same code). Two kinds:
//   - no pivoting (diagonally dominant systems): A = L U with L lower bidiagonal (diagonal
//     u_i, sub-diagonal a_i, the matrix's own) and U unit upper bidiagonal (w_i = c_i / u_i),
//     the factors of Thomas's algorithm; stored as a_i, 1/u_i, w_i;
//   - partial pivoting, the factorization of LAPACK ?gttrf (Higham §9.5): P A = L U with L
//     unit lower bidiagonal (multipliers dl_i) and U upper with two super-diagonals (d_i, du_i,
//     du2_i); a row interchange at step i is a flag; stored as dl_i, 1/d_i, du_i, du2_i, flag.
// Pivots are stored inverted: the solves then multiply, and a batch solve has no division.
#pragma once

#include <complex>
#include <cstddef>

#include "tridiff/solvers/detail/scalar.hpp"

namespace tridiff::detail {

enum class FactorKind : unsigned char { NoPivoting, Pivoting };

// Which system a solve applies: A, A^T, or A^H (the conjugate transpose; A^T for real data).
enum class Apply : unsigned char { Matrix, Transpose, Adjoint };

// The factors of one chunk of W systems: element (i, l) of every array at [i * W + l].
template <class T>
struct ChunkFactors {
  FactorKind kind;
  const T* lower;                // a_i (no pivoting, a_0 = 0) or dl_i (pivoting, dl_{n-1} = 0)
  const T* inverse_pivot;        // 1/u_i or 1/d_i
  const T* upper;                // w_i (w_{n-1} = 0) or du_i (du_{n-1} = 0)
  const T* upper2;               // du2_i (pivoting only; zero in the last two rows)
  const unsigned char* swapped;  // pivoting only: rows i and i+1 were interchanged at step i
};

template <class T>
inline T conjugate_if(const T& value, bool conjugate) {
  if constexpr (is_complex_v<T>)
    return conjugate ? std::conj(value) : value;
  else
    return value;
}

// Factors system `b` (diagonal), `a` (sub, a[0] unread), `c` (super, c[n-1] unread) without
// pivoting into the strided outputs. Returns -1, or the row whose pivot vanished (the same test
// as detail::thomas: the pivot is rounding noise next to the terms it came from).
template <class T>
std::ptrdiff_t factor_no_pivoting(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b,
                                  Strided<const T> c, Strided<T> lower, Strided<T> inverse_pivot,
                                  Strided<T> upper) {
  T pivot = b[0];
  if (vanishes(pivot, magnitude(b[0]))) return 0;
  for (std::ptrdiff_t i = 0;; ++i) {
    lower[i] = i == 0 ? T(0) : a[i];
    inverse_pivot[i] = T(1) / pivot;
    if (i == n - 1) break;
    upper[i] = c[i] * inverse_pivot[i];
    const T eliminated = a[i + 1] * upper[i];
    pivot = b[i + 1] - eliminated;
    if (vanishes(pivot, magnitude(b[i + 1]) + magnitude(eliminated))) return i + 1;
  }
  upper[n - 1] = T(0);
  return -1;
}

// LAPACK ?gttrf step for step (the same choices, so the same factors), pivots then inverted.
// Returns -1, or the first row whose pivot d_i is exactly zero (LAPACK's INFO - 1).
template <class T>
std::ptrdiff_t factor_pivoting(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b,
                               Strided<const T> c, Strided<T> dl, Strided<T> d, Strided<T> du,
                               Strided<T> du2, Strided<unsigned char> swapped) {
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    dl[i] = i + 1 < n ? a[i + 1] : T(0);
    d[i] = b[i];
    du[i] = i + 1 < n ? c[i] : T(0);
    du2[i] = T(0);
    swapped[i] = 0;
  }
  for (std::ptrdiff_t i = 0; i + 1 < n; ++i) {
    if (magnitude(d[i]) >= magnitude(dl[i])) {
      if (d[i] != T(0)) {  // otherwise column i is zero from row i down: INFO below
        const T factor = dl[i] / d[i];
        dl[i] = factor;
        d[i + 1] -= factor * du[i];
      }
    } else {
      const T factor = d[i] / dl[i];
      d[i] = dl[i];
      dl[i] = factor;
      const T above = du[i];
      du[i] = d[i + 1];
      d[i + 1] = above - factor * d[i + 1];
      if (i + 2 < n) {
        du2[i] = du[i + 1];
        du[i + 1] = -factor * du[i + 1];
      }
      swapped[i] = 1;
    }
  }
  for (std::ptrdiff_t i = 0; i < n; ++i)
    if (d[i] == T(0)) return i;
  for (std::ptrdiff_t i = 0; i < n; ++i) d[i] = T(1) / d[i];
  return -1;
}

// Rows [begin, end) of L z = b without pivoting: z_i = (b_i - a_i z_{i-1}) / u_i, reading b
// from `in` and writing z to `y` (which may be `in`); row begin - 1 of y is already done. The
// blocked drivers call it a block of rows at a time, while the block is in L1.
template <class T, int W, int Lanes>
void forward_no_pivoting(const ChunkFactors<T>& f, std::ptrdiff_t begin, std::ptrdiff_t end,
                         const T* in, std::ptrdiff_t in_stride, T* y, std::ptrdiff_t y_stride) {
  for (std::ptrdiff_t i = begin; i < end; ++i) {
    const T* bi = in + i * in_stride;
    T* yi = y + i * y_stride;
    const T* previous = i > 0 ? yi - y_stride : bi;  // a_0 = 0: row -1 is never used
#pragma omp simd
    for (int l = 0; l < Lanes; ++l)
      yi[l] = (bi[l] - f.lower[i * W + l] * previous[l]) * f.inverse_pivot[i * W + l];
  }
}

// Rows end - 1 down to begin of U x = z (unit upper: x_i = z_i - w_i x_{i+1}) in place; row
// `end` is already done. probe[l] += |x_i| * 0 over the rows: NaN iff some x_i is not finite.
template <class T, int W, int Lanes>
void backward_no_pivoting(const ChunkFactors<T>& f, std::ptrdiff_t n, std::ptrdiff_t begin,
                          std::ptrdiff_t end, T* y, std::ptrdiff_t y_stride, real_t<T>* probe) {
  for (int l = 0; l < Lanes; ++l) probe[l] = 0;
  for (std::ptrdiff_t i = end - 1; i >= begin; --i) {
    T* yi = y + i * y_stride;
    const T* next = i + 1 < n ? yi + y_stride : yi;  // w_{n-1} = 0
#pragma omp simd
    for (int l = 0; l < Lanes; ++l) {
      yi[l] -= f.upper[i * W + l] * next[l];
      probe[l] += magnitude(yi[l]) * 0;
    }
  }
}

// Solves op(A) y = y in place for the `Lanes` systems of one chunk, y's element (i, l) at
// y[i * y_stride + l] and the factors' at [i * W + l] (W >= Lanes; pass the factor pointers of
// lane l and Lanes = 1 to solve one system). Every step is a vector operation across lanes;
// the pivoting kind selects per lane between the swapped and the plain update.
template <class T, int W, int Lanes>
void solve_factored(const ChunkFactors<T>& f, Apply apply, std::ptrdiff_t n, T* y,
                    std::ptrdiff_t y_stride) {
  const bool conj = apply == Apply::Adjoint;
  auto at = [&](const T* p, std::ptrdiff_t i, int l) { return conjugate_if(p[i * W + l], conj); };
  auto row = [&](std::ptrdiff_t i) { return y + i * y_stride; };
  if (f.kind == FactorKind::NoPivoting && apply == Apply::Matrix) {
    forward_no_pivoting<T, W, Lanes>(f, 0, n, y, y_stride, y, y_stride);
    real_t<T> unused[Lanes];
    backward_no_pivoting<T, W, Lanes>(f, n, 0, n, y, y_stride, unused);
    return;
  }
  if (f.kind == FactorKind::NoPivoting) {  // A^T = U^T L^T
    for (std::ptrdiff_t i = 1; i < n; ++i) {
      T* yi = row(i);
      const T* previous = row(i - 1);
#pragma omp simd
      for (int l = 0; l < Lanes; ++l) yi[l] -= at(f.upper, i - 1, l) * previous[l];
    }
    for (std::ptrdiff_t i = n - 1; i >= 0; --i) {
      T* yi = row(i);
      const T* next = i + 1 < n ? row(i + 1) : yi;
      const bool last = i + 1 == n;
#pragma omp simd
      for (int l = 0; l < Lanes; ++l) {
        const T coupling = last ? T(0) : at(f.lower, i + 1, l) * next[l];
        yi[l] = (yi[l] - coupling) * at(f.inverse_pivot, i, l);
      }
    }
    return;
  }
  if (apply == Apply::Matrix) {  // P A = L U: apply the interchanges and L, then U (?gtts2)
    for (std::ptrdiff_t i = 0; i + 1 < n; ++i) {
      T* yi = row(i);
      T* next = row(i + 1);
#pragma omp simd
      for (int l = 0; l < Lanes; ++l) {
        const bool swap = f.swapped[i * W + l] != 0;
        const T kept = swap ? next[l] : yi[l];
        const T other = swap ? yi[l] : next[l];
        yi[l] = kept;
        next[l] = other - f.lower[i * W + l] * kept;
      }
    }
    for (std::ptrdiff_t i = n - 1; i >= 0; --i) {
      T* yi = row(i);
      const T* next = i + 1 < n ? row(i + 1) : yi;
      const T* after = i + 2 < n ? row(i + 2) : yi;
      const bool has_next = i + 1 < n, has_after = i + 2 < n;
#pragma omp simd
      for (int l = 0; l < Lanes; ++l) {
        T value = yi[l];
        if (has_next) value -= f.upper[i * W + l] * next[l];
        if (has_after) value -= f.upper2[i * W + l] * after[l];
        yi[l] = value * f.inverse_pivot[i * W + l];
      }
    }
    return;
  }
  // A^T = U^T L^T P: U^T forwards, then L^T and the interchanges backwards.
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    T* yi = row(i);
    const T* previous = i > 0 ? row(i - 1) : yi;
    const T* before = i > 1 ? row(i - 2) : yi;
    const bool has_previous = i > 0, has_before = i > 1;
#pragma omp simd
    for (int l = 0; l < Lanes; ++l) {
      T value = yi[l];
      if (has_previous) value -= at(f.upper, i - 1, l) * previous[l];
      if (has_before) value -= at(f.upper2, i - 2, l) * before[l];
      yi[l] = value * at(f.inverse_pivot, i, l);
    }
  }
  for (std::ptrdiff_t i = n - 2; i >= 0; --i) {
    T* yi = row(i);
    T* next = row(i + 1);
#pragma omp simd
    for (int l = 0; l < Lanes; ++l) {
      const bool swap = f.swapped[i * W + l] != 0;
      const T eliminated = yi[l] - at(f.lower, i, l) * next[l];
      yi[l] = swap ? next[l] : eliminated;
      next[l] = swap ? eliminated : next[l];
    }
  }
}

// The factors of lane l of a chunk, as a chunk of one (for solve_factored<T, W, 1>).
template <class T, int W>
ChunkFactors<T> lane_of(const ChunkFactors<T>& f, int l) {
  ChunkFactors<T> lane = f;
  lane.lower += l;
  lane.inverse_pivot += l;
  lane.upper += l;
  if (f.kind == FactorKind::Pivoting) {
    lane.upper2 += l;
    lane.swapped += l;
  }
  return lane;
}

}  // namespace tridiff::detail
