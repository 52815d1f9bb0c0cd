// Small transposes between W contiguous rows and lane-contiguous blocks (row k of a block
// holds element k of every row): how image rows become one SIMD lane per system. Rows move 16
// columns at a time; with AVX-512, float blocks are transposed 16 x 16 in registers.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

// GCC 12 reports its own _mm512_undefined_* placeholders inside the AVX-512 intrinsics as
// maybe-uninitialized (GCC bug 105593); nothing here reads an uninitialised value.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif

namespace tridiff::detail {

// Columns per block when a driver streams rows through lanes: 32 keeps three blocks of 64
// lanes of float in half of L1.
inline constexpr std::ptrdiff_t kTransposeBlock = 32;

#if defined(__AVX512F__)
// In-register transpose of 16 rows of 16 floats: interleave pairs of rows, then pairs of
// pairs, then 128-bit quarters twice.
[[gnu::always_inline]] inline void transpose_16x16(__m512 r[16]) {
  __m512 t[16], u[16];
  for (int k = 0; k < 8; ++k) {
    t[2 * k] = _mm512_unpacklo_ps(r[2 * k], r[2 * k + 1]);
    t[2 * k + 1] = _mm512_unpackhi_ps(r[2 * k], r[2 * k + 1]);
  }
  for (int k = 0; k < 4; ++k) {
    const __m512d a = _mm512_castps_pd(t[4 * k]), b = _mm512_castps_pd(t[4 * k + 2]);
    const __m512d c = _mm512_castps_pd(t[4 * k + 1]), d = _mm512_castps_pd(t[4 * k + 3]);
    u[4 * k] = _mm512_castpd_ps(_mm512_unpacklo_pd(a, b));
    u[4 * k + 1] = _mm512_castpd_ps(_mm512_unpackhi_pd(a, b));
    u[4 * k + 2] = _mm512_castpd_ps(_mm512_unpacklo_pd(c, d));
    u[4 * k + 3] = _mm512_castpd_ps(_mm512_unpackhi_pd(c, d));
  }
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 4; ++j) {
      t[8 * k + j] = _mm512_shuffle_f32x4(u[8 * k + j], u[8 * k + 4 + j], 0x88);
      t[8 * k + 4 + j] = _mm512_shuffle_f32x4(u[8 * k + j], u[8 * k + 4 + j], 0xdd);
    }
  for (int j = 0; j < 8; ++j) {
    r[j] = _mm512_shuffle_f32x4(t[j], t[8 + j], 0x88);
    r[8 + j] = _mm512_shuffle_f32x4(t[j], t[8 + j], 0xdd);
  }
}

// The same for 8 rows of 8 doubles: interleave pairs of rows, then pairs of pairs (two-source
// permutes), then 256-bit halves.
[[gnu::always_inline]] inline void transpose_8x8(__m512d r[8]) {
  const __m512i low_pairs = _mm512_setr_epi64(0, 1, 8, 9, 4, 5, 12, 13);
  const __m512i high_pairs = _mm512_setr_epi64(2, 3, 10, 11, 6, 7, 14, 15);
  __m512d t[8], u[8];
  for (int k = 0; k < 4; ++k) {
    t[2 * k] = _mm512_unpacklo_pd(r[2 * k], r[2 * k + 1]);      // columns 0, 2, 4, 6
    t[2 * k + 1] = _mm512_unpackhi_pd(r[2 * k], r[2 * k + 1]);  // columns 1, 3, 5, 7
  }
  for (int h = 0; h < 2; ++h) {  // u[4h + j]: column j, then column j + 4, of rows 4h..4h+3
    u[4 * h] = _mm512_permutex2var_pd(t[4 * h], low_pairs, t[4 * h + 2]);
    u[4 * h + 1] = _mm512_permutex2var_pd(t[4 * h + 1], low_pairs, t[4 * h + 3]);
    u[4 * h + 2] = _mm512_permutex2var_pd(t[4 * h], high_pairs, t[4 * h + 2]);
    u[4 * h + 3] = _mm512_permutex2var_pd(t[4 * h + 1], high_pairs, t[4 * h + 3]);
  }
  for (int j = 0; j < 4; ++j) {
    r[j] = _mm512_shuffle_f64x2(u[j], u[4 + j], 0x44);
    r[4 + j] = _mm512_shuffle_f64x2(u[j], u[4 + j], 0xEE);
  }
}

inline __mmask8 first_columns8(std::ptrdiff_t columns) {
  return columns >= 8 ? __mmask8(0xFF) : __mmask8((1u << columns) - 1);
}

inline __mmask16 first_columns(std::ptrdiff_t columns) {
  return columns >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << columns) - 1);
}

// to[j * stride] = r[j] for j < count, and r[j] = from[j * stride] for j < count (zero above).
// The whole 16 on their own path: with a variable count GCC 12 tests j < count before every
// row, a chain of 16 compares per 16 x 16 transpose (the ADI rows pass, 3840 x 2160 RGB, 2
// threads of an Intel Xeon, 4 alternating runs: 11.6-11.8 -> 10.9-11.5 ms).
[[gnu::always_inline]] inline void store_block_rows(const __m512 r[16], std::ptrdiff_t count,
                                                    float* to, std::ptrdiff_t stride) {
  if (count == 16) {
    for (int j = 0; j < 16; ++j) _mm512_storeu_ps(to + j * stride, r[j]);
    return;
  }
  for (std::ptrdiff_t j = 0; j < count; ++j) _mm512_storeu_ps(to + j * stride, r[j]);
}
[[gnu::always_inline]] inline void load_block_rows(const float* from, std::ptrdiff_t stride,
                                                   std::ptrdiff_t count, __m512 r[16]) {
  if (count == 16) {
    for (int j = 0; j < 16; ++j) r[j] = _mm512_loadu_ps(from + j * stride);
    return;
  }
  for (int j = 0; j < 16; ++j)
    r[j] = j < count ? _mm512_loadu_ps(from + j * stride) : _mm512_setzero_ps();
}
#endif

// Asks for the cache lines of `count` consecutive values at p (for writing if `write`).
template <class V>
inline void prefetch_values(const V* p, std::ptrdiff_t count, bool write = false) {
  constexpr std::ptrdiff_t kLine = 64 / sizeof(V) > 0 ? 64 / sizeof(V) : 1;
  // An if, not a conditional expression of the two calls: clang 14 crashed on that at -O0.
  for (std::ptrdiff_t k = 0; k < count; k += kLine) {
    if (write)
      __builtin_prefetch(p + k, 1);
    else
      __builtin_prefetch(p + k, 0);
  }
}

// block[k * W + l] = rows[l][x + k] for k < columns, l < W: W rows anywhere in memory (a band
// of image rows, with a spare row standing in for rows past the image). W rows read side by
// side, 64 bytes of each at a time, are more streams than the hardware prefetchers follow, so
// each row is fetched four cache lines ahead (measured: the IIR row pass 14 -> 12 ms per
// 4096^2 plane), as far as column `readable` of every row (default: the columns gathered). A
// driver that gathers a long row one short block at a time passes the row's length, or no
// block would ever be fetched ahead (the ADI DOF at 3840 x 2160 RGB, 2 threads, whose rows pass
// gathers 32 columns a block: 23.8 -> 19.7 ms).
template <class T, int W>
inline void gather_into_lanes(const T* const* rows, std::ptrdiff_t x, std::ptrdiff_t columns,
                              T* block, std::ptrdiff_t readable = -1) {
  constexpr std::ptrdiff_t kAhead = 4 * 64 / sizeof(T);
  if (readable < 0) readable = x + columns;
  for (std::ptrdiff_t k = 0; k < columns; k += 16) {
    const std::ptrdiff_t width = std::min<std::ptrdiff_t>(16, columns - k);
    if (x + k + kAhead < readable)  // every cache line of the next 16 columns
      for (int l = 0; l < W; ++l)
        for (std::ptrdiff_t line = 0; line < 16; line += 64 / std::ptrdiff_t(sizeof(T)))
          __builtin_prefetch(rows[l] + x + k + kAhead + line);
#if defined(__AVX512F__)
    if constexpr (std::is_same_v<T, double> && W % 8 == 0) {
      for (std::ptrdiff_t half = 0; half < width; half += 8) {
        const __mmask8 mask = first_columns8(width - half);
        for (int group = 0; group < W; group += 8) {
          __m512d r[8];
          for (int j = 0; j < 8; ++j)
            r[j] = _mm512_maskz_loadu_pd(mask, rows[group + j] + x + k + half);
          transpose_8x8(r);
          for (std::ptrdiff_t j = 0; j < std::min<std::ptrdiff_t>(8, width - half); ++j)
            _mm512_storeu_pd(block + (k + half + j) * W + group, r[j]);
        }
      }
      continue;
    }
    if constexpr (std::is_same_v<T, float> && W % 16 == 0) {
      const __mmask16 mask = first_columns(width);
      for (int group = 0; group < W; group += 16) {
        __m512 r[16];
        for (int j = 0; j < 16; ++j) r[j] = _mm512_maskz_loadu_ps(mask, rows[group + j] + x + k);
        transpose_16x16(r);
        store_block_rows(r, width, block + k * W + group, W);
      }
      continue;
    }
#endif
    for (int l = 0; l < W; ++l)
      for (std::ptrdiff_t j = 0; j < width; ++j) block[(k + j) * W + l] = rows[l][x + k + j];
  }
}

// rows[l][x + k] = block[k * W + l] for k < columns, l < W. With `streaming`, whole aligned
// 64-byte pieces bypass the caches (non-temporal stores): for a result that nothing reads
// again soon, this saves reading every line from memory before it is overwritten (the ADI
// DOF's rows pass, 3840 x 2160 RGB: 19.7 -> 18.5 ms). The caller ends with
// finish_streaming_stores() before another thread may read what was stored.
template <class T, int W>
inline void scatter_from_lanes(const T* block, std::ptrdiff_t columns, T* const* rows,
                               std::ptrdiff_t x, [[maybe_unused]] bool streaming = false) {
  for (std::ptrdiff_t k = 0; k < columns; k += 16) {
    const std::ptrdiff_t width = std::min<std::ptrdiff_t>(16, columns - k);
#if defined(__AVX512F__)
    if constexpr (std::is_same_v<T, double> && W % 8 == 0) {
      for (std::ptrdiff_t half = 0; half < width; half += 8) {
        const std::ptrdiff_t count = std::min<std::ptrdiff_t>(8, width - half);
        const __mmask8 mask = first_columns8(count);
        for (int group = 0; group < W; group += 8) {
          __m512d r[8];
          for (int j = 0; j < 8; ++j)
            r[j] = j < count ? _mm512_loadu_pd(block + (k + half + j) * W + group)
                             : _mm512_setzero_pd();
          transpose_8x8(r);
          for (int j = 0; j < 8; ++j) {
            double* to = rows[group + j] + x + k + half;
            if (streaming && count == 8 && (reinterpret_cast<std::uintptr_t>(to) & 63) == 0)
              _mm512_stream_pd(to, r[j]);
            else
              _mm512_mask_storeu_pd(to, mask, r[j]);
          }
        }
      }
      continue;
    }
    if constexpr (std::is_same_v<T, float> && W % 16 == 0) {
      const __mmask16 mask = first_columns(width);
      for (int group = 0; group < W; group += 16) {
        __m512 r[16];
        load_block_rows(block + k * W + group, W, width, r);
        transpose_16x16(r);
        for (int j = 0; j < 16; ++j) {
          float* to = rows[group + j] + x + k;
          if (streaming && width == 16 && (reinterpret_cast<std::uintptr_t>(to) & 63) == 0)
            _mm512_stream_ps(to, r[j]);
          else
            _mm512_mask_storeu_ps(to, mask, r[j]);
        }
      }
      continue;
    }
#endif
    for (int l = 0; l < W; ++l)
      for (std::ptrdiff_t j = 0; j < width; ++j) rows[l][x + k + j] = block[(k + j) * W + l];
  }
}

// Orders the non-temporal stores of scatter_from_lanes before every later store (they are
// weakly ordered on x86).
inline void finish_streaming_stores() {
#if defined(__AVX512F__)
  _mm_sfence();
#endif
}

// block[k * W + l] = rows[l * pitch + k] for k < columns, l < W.
template <class T, int W>
inline void transpose_into_lanes(const T* rows, std::ptrdiff_t pitch, std::ptrdiff_t columns,
                                 T* block) {
  const T* pointers[W];
  for (int l = 0; l < W; ++l) pointers[l] = rows + l * pitch;
  gather_into_lanes<T, W>(pointers, 0, columns, block);
}

// rows[l * pitch + k] = block[k * W + l] for k < columns, l < W.
template <class T, int W>
inline void transpose_from_lanes(const T* block, std::ptrdiff_t columns, T* rows,
                                 std::ptrdiff_t pitch) {
  T* pointers[W];
  for (int l = 0; l < W; ++l) pointers[l] = rows + l * pitch;
  scatter_from_lanes<T, W>(block, columns, pointers, 0);
}

}  // namespace tridiff::detail

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
