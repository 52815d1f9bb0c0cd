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
