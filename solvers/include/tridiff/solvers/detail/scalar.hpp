// Scalar helpers shared by the kernels: a strided pointer, a cheap magnitude, finiteness.
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <limits>

#include "tridiff/solvers/layout.hpp"

namespace tridiff::detail {

// A pointer that steps `stride` elements per index: one equation of an image row or column.
template <class T>
struct Strided {
  T* data;
  std::ptrdiff_t stride;
  T& operator[](std::ptrdiff_t i) const { return data[i * stride]; }
};

// |x| for reals; |re| + |im| for complex (the CABS1 of LAPACK): cheap, and within a factor
// sqrt(2) of the modulus, which is all that pivot choices and breakdown tests need.
template <class T>
inline real_t<T> magnitude(const T& x) {
  if constexpr (is_complex_v<T>)
    return std::abs(x.real()) + std::abs(x.imag());
  else
    return std::abs(x);
}

// The modulus |x|, what diagonal dominance compares: CABS1 (magnitude) can be sqrt(2) times
// the modulus on one side of the test and equal to it on the other, so a dominance test in
// CABS1 accepts matrices that are not dominant ([[1+i, 2], [2, 2-2i]] is singular). For
// complex, computed as s * sqrt((re/s)^2 + (im/s)^2) with s = max(|re|, |im|): no overflow
// unless the modulus itself overflows, no underflow in the squares, branch-free (it
// vectorises), and NaN for a NaN or infinite part.
template <class T>
inline real_t<T> modulus(const T& x) {
  if constexpr (is_complex_v<T>) {
    const real_t<T> re = std::abs(x.real()), im = std::abs(x.imag()), s = std::max(re, im);
    const real_t<T> p = re / s, q = im / s;
    // s is 0 for x = 0, and may be 0 beside a NaN part (std::max drops a NaN second
    // argument): re + im is 0 or NaN then.
    return s > 0 ? s * std::sqrt(p * p + q * q) : re + im;
  } else {
    return std::abs(x);
  }
}

template <class T>
inline bool is_finite(const T& x) {
  if constexpr (is_complex_v<T>)
    return std::isfinite(x.real()) && std::isfinite(x.imag());
  else
    return std::isfinite(x);
}

// The widest vector the lane loops of the kernels below ask for, in bytes: 64 (AVX-512). A
// program that caps its vector width (GCC's -mprefer-vector-width=256, say) defines it as 32
// too, since `simdlen` overrides that flag.
#ifndef TRIDIFF_VECTOR_BYTES
#define TRIDIFF_VECTOR_BYTES 64
#endif

// Scalars in one such vector: the width a kernel's lane loops ask for with
// `#pragma omp simd simdlen(...)`. GCC 12 with -march=native uses 256-bit vectors on AVX-512
// CPUs unless told otherwise, and a build-wide -mprefer-vector-width=512 slowed the image
// kernels (the DOF default, 4K on 2 threads: 299 -> 358 ms); so only the kernels measured
// faster with 512 bits ask for them (docs/performance.md): the parts of one long system,
// Thomas on columns and the diffusion form's lane kernel.
template <class T>
inline constexpr int kVectorWidth = static_cast<int>(TRIDIFF_VECTOR_BYTES / sizeof(T) > 0
                                                         ? TRIDIFF_VECTOR_BYTES / sizeof(T)
                                                         : 1);

// The width for a loop over W lanes that gains from wide vectors only when W spans several of
// them (measured: the diffusion kernel on 64 lanes of columns 1.23x faster in float, on the
// rows' 16 lanes 0.9x): one whole vector then, else half of it (what GCC 12 picks by itself
// under -march=native).
template <class T, int W>
inline constexpr int kLoopWidth = W > kVectorWidth<T>       ? kVectorWidth<T>
                                  : kVectorWidth<T> / 2 > 0 ? kVectorWidth<T> / 2
                                                            : 1;

template <class T>
inline constexpr real_t<T> epsilon = std::numeric_limits<real_t<T>>::epsilon();

// A pivot p computed as the difference of terms of size `scale` is noise when
// |p| <= kVanishingPivot * eps * scale: its sign and leading digits come from rounding alone.
inline constexpr int kVanishingPivot = 8;

template <class T>
inline bool vanishes(const T& pivot, real_t<T> scale) {
  return !(magnitude(pivot) > kVanishingPivot * epsilon<T> * scale);
}

}  // namespace tridiff::detail
