// sRGB transfer functions: images are blurred in linear light (a blur is a weighted average of
// radiance), so encoded inputs are linearised first and encoded again on output.
#pragma once

#include <cmath>

#include "tridiff/image/image.hpp"

namespace tridiff {

// The piecewise sRGB curve (IEC 61966-2-1): linear segment below 0.04045 / 0.0031308.
inline float srgb_to_linear(float encoded) {
  return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}
inline float linear_to_srgb(float linear) {
  if (!(linear > 0.0031308f)) return 12.92f * std::max(linear, 0.f);
  return 1.055f * std::pow(linear, 1.f / 2.4f) - 0.055f;
}

// Applies the curve to the first min(3, channels) planes (alpha, if any, stays linear).
void srgb_to_linear(Image& image, int threads = 0);
void linear_to_srgb(Image& image, int threads = 0);

}  // namespace tridiff
