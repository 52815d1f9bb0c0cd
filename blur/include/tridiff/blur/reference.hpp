// The exact reference every blur is measured against: convolution with the sampled, normalised
// Gaussian in double precision, with support +-6 sigma (the truncated tail weighs < 2e-9).
#pragma once

#include <cstddef>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

// A plane of doubles (no padding): the reference's output and the harness's scratch.
struct DoublePlane {
  std::ptrdiff_t width = 0, height = 0;
  std::vector<double> values;

  DoublePlane() = default;
  DoublePlane(std::ptrdiff_t w, std::ptrdiff_t h) : width(w), height(h), values(w * h, 0.0) {}
  double& operator()(std::ptrdiff_t x, std::ptrdiff_t y) { return values[y * width + x]; }
  double operator()(std::ptrdiff_t x, std::ptrdiff_t y) const { return values[y * width + x]; }
};

DoublePlane to_double(ConstPlane plane);

// Half-width of the reference kernel: ceil(6 sigma), at least 1.
std::ptrdiff_t reference_radius(double sigma);

// The sampled Gaussian exp(-k^2 / (2 sigma^2)) for k in [-radius, radius], normalised to sum 1
// (index k + radius).
std::vector<double> sampled_gaussian(double sigma, std::ptrdiff_t radius);

// Separable convolution with sampled_gaussian(sigma, reference_radius(sigma)) in double, with
// the given border. InvalidArgument unless sigma is finite and > 0.
DoublePlane reference_gaussian(ConstPlane in, double sigma, Border border, int threads = 0);
DoublePlane reference_gaussian(const DoublePlane& in, double sigma, Border border, int threads = 0);

}  // namespace tridiff
