// The quality harness: error measures, the operator-norm error, test patterns and the
// effective sigma (seed 001 §4.1.2).
#include "tridiff/blur/quality.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace tridiff {

namespace {

void require_same_size(ConstPlane approx, const DoublePlane& exact) {
  if (approx.width() != exact.width || approx.height() != exact.height)
    throw InvalidArgument("exact", "size differs from approx");
}

// Mean SSIM of a and b (values in [0, 1]) with a Gaussian window of sigma 1.5.
double mean_ssim(const DoublePlane& a, const DoublePlane& b) {
  const DoublePlane map = ssim_map(a, b);
  double sum = 0;
  for (const double value : map.values) sum += value;
  return sum / static_cast<double>(a.values.size());
}

}  // namespace

DoublePlane ssim_map(const DoublePlane& a, const DoublePlane& b) {
  if (a.width != b.width || a.height != b.height) throw InvalidArgument("b", "size differs from a");
  constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03, kWindow = 1.5;
  DoublePlane aa(a.width, a.height), bb(a.width, a.height), ab(a.width, a.height);
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    aa.values[i] = a.values[i] * a.values[i];
    bb.values[i] = b.values[i] * b.values[i];
    ab.values[i] = a.values[i] * b.values[i];
  }
  const DoublePlane mu_a = reference_gaussian(a, kWindow, Border::replicate);
  const DoublePlane mu_b = reference_gaussian(b, kWindow, Border::replicate);
  const DoublePlane m_aa = reference_gaussian(aa, kWindow, Border::replicate);
  const DoublePlane m_bb = reference_gaussian(bb, kWindow, Border::replicate);
  const DoublePlane m_ab = reference_gaussian(ab, kWindow, Border::replicate);
  DoublePlane map(a.width, a.height);
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    const double ma = mu_a.values[i], mb = mu_b.values[i];
    const double var_a = m_aa.values[i] - ma * ma, var_b = m_bb.values[i] - mb * mb;
    const double cov = m_ab.values[i] - ma * mb;
    map.values[i] =
        (2 * ma * mb + kC1) * (2 * cov + kC2) / ((ma * ma + mb * mb + kC1) * (var_a + var_b + kC2));
  }
  return map;
}

BlurError blur_error(ConstPlane approx, const DoublePlane& exact) {
  require_same_size(approx, exact);
  BlurError error;
  double sum_sq = 0;
  for (std::ptrdiff_t y = 0; y < exact.height; ++y)
    for (std::ptrdiff_t x = 0; x < exact.width; ++x) {
      const double d = approx(x, y) - exact(x, y);
      error.max_abs = std::max(error.max_abs, std::abs(d));
      sum_sq += d * d;
    }
  const double mse = sum_sq / static_cast<double>(exact.values.size());
  error.rmse = std::sqrt(mse);
  error.psnr = mse > 0 ? -10 * std::log10(mse) : std::numeric_limits<double>::infinity();
  error.ssim = mean_ssim(to_double(approx), exact);
  return error;
}

PlaneBlur plane_blur(const BlurMethod& method, const BlurOptions& options) {
  return [&method, options](Plane out, ConstPlane in) { blur(out, in, method, options); };
}

double operator_norm_error(const PlaneBlur& blur_plane, double sigma) {
  const std::ptrdiff_t n = 2 * (static_cast<std::ptrdiff_t>(std::ceil(8 * sigma)) + 32) + 1;
  const std::ptrdiff_t centre = n / 2;
  Image impulse(n, n, 1), response(n, n, 1);
  impulse(centre, centre, 0) = 1;
  blur_plane(response.plane(0), impulse.plane(0));
  // The exact response is the outer product of the sampled kernel with itself.
  const std::ptrdiff_t r = std::min(reference_radius(sigma), centre);
  const std::vector<double> kernel = sampled_gaussian(sigma, r);
  double norm = 0;
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x) {
      const std::ptrdiff_t dx = x - centre, dy = y - centre;
      const double exact =
          std::abs(dx) <= r && std::abs(dy) <= r ? kernel[dx + r] * kernel[dy + r] : 0.0;
      norm += std::abs(response(x, y, 0) - exact);
    }
  return norm;
}

namespace {

Image pattern_edges(std::ptrdiff_t n) {
  Image image(n, n, 1);
  const double angles[] = {0.0, 0.65, 1.24};  // radians: edges at 0, 37 and 71 degrees
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x) {
      int parity = 0;
      for (double a : angles)
        parity ^= (x - 0.37 * n) * std::cos(a) + (y - 0.55 * n) * std::sin(a) > 0;
      image(x, y, 0) = static_cast<float>(parity);
    }
  return image;
}

Image pattern_discs(std::ptrdiff_t n, std::mt19937& rng) {
  Image image(n, n, 1);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int d = 0; d < 12; ++d) {
    const double cx = unit(rng) * n, cy = unit(rng) * n;
    const double radius = 2 + unit(rng) * n / 6.0;
    const float value = static_cast<float>(0.2 + 0.8 * unit(rng));
    for (std::ptrdiff_t y = 0; y < n; ++y)
      for (std::ptrdiff_t x = 0; x < n; ++x)
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= radius * radius) image(x, y, 0) = value;
  }
  return image;
}

Image pattern_lines(std::ptrdiff_t n) {
  Image image(n, n, 1);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    image(i, n / 3, 0) = 1;            // horizontal
    image(2 * n / 3, i, 0) = 1;        // vertical
    image(i, i, 0) = 1;                // diagonal
    image(i, (n - 1 - i / 2), 0) = 1;  // shallow slope
  }
  return image;
}

Image pattern_noise(std::ptrdiff_t n, std::mt19937& rng) {
  Image image(n, n, 1);
  std::uniform_real_distribution<float> unit(0, 1);
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x) image(x, y, 0) = unit(rng);
  return image;
}

// Octaves of bilinearly interpolated value noise, amplitude proportional to the wavelength:
// an amplitude spectrum close to 1/f, as in natural images. Scaled to [0, 1].
Image pattern_texture(std::ptrdiff_t n, std::mt19937& rng) {
  std::vector<double> sum(n * n, 0.0);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (std::ptrdiff_t spacing = n; spacing >= 2; spacing /= 2) {
    const std::ptrdiff_t cells = n / spacing + 2;
    std::vector<double> grid(cells * cells);
    for (double& g : grid) g = unit(rng);
    for (std::ptrdiff_t y = 0; y < n; ++y)
      for (std::ptrdiff_t x = 0; x < n; ++x) {
        const double gx = static_cast<double>(x) / spacing, gy = static_cast<double>(y) / spacing;
        const std::ptrdiff_t ix = static_cast<std::ptrdiff_t>(gx),
                             iy = static_cast<std::ptrdiff_t>(gy);
        const double fx = gx - ix, fy = gy - iy;
        const double top = grid[iy * cells + ix] * (1 - fx) + grid[iy * cells + ix + 1] * fx;
        const double bottom =
            grid[(iy + 1) * cells + ix] * (1 - fx) + grid[(iy + 1) * cells + ix + 1] * fx;
        sum[y * n + x] += spacing * (top * (1 - fy) + bottom * fy);
      }
  }
  const auto [lo, hi] = std::minmax_element(sum.begin(), sum.end());
  Image image(n, n, 1);
  const double scale = *hi > *lo ? 1 / (*hi - *lo) : 0;
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x)
      image(x, y, 0) = static_cast<float>((sum[y * n + x] - *lo) * scale);
  return image;
}

}  // namespace

std::vector<TestPattern> quality_test_set(std::ptrdiff_t size, unsigned seed) {
  if (size < 8) throw InvalidArgument("size", "must be at least 8");
  std::mt19937 rng(seed);
  std::vector<TestPattern> set;
  set.push_back({"edges", pattern_edges(size)});
  set.push_back({"discs", pattern_discs(size, rng)});
  set.push_back({"lines", pattern_lines(size)});
  set.push_back({"noise", pattern_noise(size, rng)});
  set.push_back({"texture", pattern_texture(size, rng)});
  return set;
}

double effective_sigma(const PlaneBlur& blur_plane, std::span<const TestPattern> patterns,
                       double lo, double hi, Border border) {
  if (patterns.empty()) throw InvalidArgument("patterns", "is empty");
  if (!(lo > 0) || !(hi > lo)) throw InvalidArgument("lo", "need 0 < lo < hi");
  std::vector<DoublePlane> inputs, outputs;
  for (const TestPattern& p : patterns) {
    Image out(p.image.width(), p.image.height(), 1);
    blur_plane(out.plane(0), p.image.plane(0));
    inputs.push_back(to_double(p.image.plane(0)));
    outputs.push_back(to_double(out.plane(0)));
  }
  const auto mismatch = [&](double s) {
    double total = 0;
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      const DoublePlane exact = reference_gaussian(inputs[i], s, border);
      double sum = 0;
      for (std::size_t k = 0; k < exact.values.size(); ++k)
        sum += std::abs(outputs[i].values[k] - exact.values[k]);
      total += sum / static_cast<double>(exact.values.size());
    }
    return total;
  };
  const double inv_phi = (std::sqrt(5.0) - 1) / 2;
  double a = lo, b = hi;
  double c = b - inv_phi * (b - a), d = a + inv_phi * (b - a);
  double fc = mismatch(c), fd = mismatch(d);
  while (b - a > 1e-4 * a) {
    if (fc < fd) {
      b = d, d = c, fd = fc;
      c = b - inv_phi * (b - a), fc = mismatch(c);
    } else {
      a = c, c = d, fc = fd;
      d = a + inv_phi * (b - a), fd = mismatch(d);
    }
  }
  return (a + b) / 2;
}

}  // namespace tridiff
