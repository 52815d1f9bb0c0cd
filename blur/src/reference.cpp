// The exact Gaussian reference: separable convolution in double with the sampled kernel.
#include "tridiff/blur/reference.hpp"

#include <cmath>
#include <string>

namespace tridiff {

DoublePlane to_double(ConstPlane plane) {
  DoublePlane out(plane.width(), plane.height());
  for (std::ptrdiff_t y = 0; y < plane.height(); ++y)
    for (std::ptrdiff_t x = 0; x < plane.width(); ++x) out(x, y) = plane(x, y);
  return out;
}

std::ptrdiff_t reference_radius(double sigma) {
  return std::max<std::ptrdiff_t>(1, static_cast<std::ptrdiff_t>(std::ceil(6 * sigma)));
}

std::vector<double> sampled_gaussian(double sigma, std::ptrdiff_t radius) {
  if (!(sigma > 0) || !std::isfinite(sigma))
    throw InvalidArgument("sigma", "must be finite and > 0, got " + std::to_string(sigma));
  if (radius < 0) throw InvalidArgument("radius", "must be >= 0");
  std::vector<double> kernel(2 * radius + 1);
  double sum = 0;
  for (std::ptrdiff_t k = -radius; k <= radius; ++k)
    sum += kernel[k + radius] = std::exp(-0.5 * (k / sigma) * (k / sigma));
  for (double& w : kernel) w /= sum;
  return kernel;
}

namespace {

// Rows, then columns; each output row is a weighted sum of whole input rows so that the inner
// loops run over x.
DoublePlane convolve_separable(const DoublePlane& in, const std::vector<double>& kernel,
                               Border border, int threads) {
  const std::ptrdiff_t w = in.width, h = in.height;
  const std::ptrdiff_t r = static_cast<std::ptrdiff_t>(kernel.size() / 2);
  DoublePlane rows(w, h), out(w, h);
#pragma omp parallel num_threads(threads)
  {
    std::vector<double> padded(w + 2 * r);
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      for (std::ptrdiff_t i = -r; i < w + r; ++i) {
        const std::ptrdiff_t j = border_index(i, w, border);
        padded[i + r] = j < 0 ? 0.0 : in(j, y);
      }
      for (std::ptrdiff_t x = 0; x < w; ++x) {
        double sum = 0;
        for (std::ptrdiff_t k = 0; k <= 2 * r; ++k) sum += kernel[k] * padded[x + k];
        rows(x, y) = sum;
      }
    }
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      double* dst = &out(0, y);
      for (std::ptrdiff_t k = 0; k <= 2 * r; ++k) {
        const std::ptrdiff_t j = border_index(y + k - r, h, border);
        if (j < 0) continue;
        const double* src = &rows(0, j);
        const double weight = kernel[k];
        for (std::ptrdiff_t x = 0; x < w; ++x) dst[x] += weight * src[x];
      }
    }
  }
  return out;
}

}  // namespace

DoublePlane reference_gaussian(const DoublePlane& in, double sigma, Border border, int threads) {
  if (in.width < 1 || in.height < 1) throw InvalidArgument("in", "is empty");
  if (threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
  const std::vector<double> kernel = sampled_gaussian(sigma, reference_radius(sigma));
  return convolve_separable(in, kernel, border, resolve_threads(threads));
}

DoublePlane reference_gaussian(ConstPlane in, double sigma, Border border, int threads) {
  return reference_gaussian(to_double(in), sigma, border, threads);
}

}  // namespace tridiff
