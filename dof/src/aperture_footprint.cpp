// The footprint of a defocused point for an aperture shape or kernel image
// (aperture_footprint.hpp).
#include "aperture_footprint.hpp"

#include <cstdio>
#include <numbers>
#include <string>

namespace tridiff::dof_detail {

ApertureFootprint::ApertureFootprint(const DofOptions& options) {
  validate(options.aperture);
  if (options.aperture_image) {
    const Image& kernel = *options.aperture_image;
    validate_aperture_image(kernel);
    kind_ = Kind::image;
    kernel_width_ = kernel.width();
    kernel_height_ = kernel.height();
    kernel_.resize(std::size_t(kernel_width_ * kernel_height_));
    sat_.assign(std::size_t((kernel_width_ + 1) * (kernel_height_ + 1)), 0.0);
    for (std::ptrdiff_t y = 0; y < kernel_height_; ++y) {
      double row_sum = 0;
      for (std::ptrdiff_t x = 0; x < kernel_width_; ++x) {
        kernel_[std::size_t(y * kernel_width_ + x)] = kernel(x, y, 0);
        row_sum += double(kernel(x, y, 0));
        sat_[std::size_t((y + 1) * (kernel_width_ + 1) + x + 1)] =
            sat_[std::size_t(y * (kernel_width_ + 1) + x + 1)] + row_sum;
      }
    }
    return;
  }
  if (options.aperture.is_circle()) return;
  kind_ = Kind::polygon;
  const int blades = options.aperture.blades;
  const double sector = 2 * std::numbers::pi / blades;
  const double rotation = double(options.aperture.rotation_deg) * std::numbers::pi / 180;
  for (int k = 0; k < blades; ++k) {
    // The middle of blade k lies half a sector past corner k, corner 0 straight up
    // (aperture_rim); y is down.
    const double middle = std::numbers::pi / 2 + rotation + sector * (k + 0.5);
    normal_x_.push_back(std::cos(middle));
    normal_y_.push_back(-std::sin(middle));
  }
  roundness_ = options.aperture.roundness;
  apothem_ = std::cos(0.5 * sector);
}

float ApertureFootprint::outer(double diameter) const {
  if (kind_ != Kind::image) return static_cast<float>(0.5 * diameter + 0.5);
  // The kernel's square reaches half its side plus the filter's half-width (a pixel shrunk,
  // a kernel cell enlarged) along each axis; its corners lie sqrt(2) further.
  const double scale = diameter / double(std::max(kernel_width_, kernel_height_));
  const double half = 0.5 * diameter + 0.5 * std::max(1.0, scale);
  return static_cast<float>(half * std::numbers::sqrt2 + 1e-3);
}

double ApertureFootprint::coverage(double diameter, float outer, std::ptrdiff_t dx,
                                   std::ptrdiff_t dy) const {
  switch (kind_) {
    case Kind::circle: return std::min(1.0, double(outer) - std::sqrt(double(dx * dx + dy * dy)));
    case Kind::polygon: return polygon_coverage(diameter, dx, dy);
    case Kind::image: return image_coverage(diameter, dx, dy);
  }
  return 0;
}

std::ptrdiff_t ApertureFootprint::solid_half_width(float outer, std::ptrdiff_t dy) const {
  if (kind_ != Kind::circle) return -1;
  const auto solid = [&](std::ptrdiff_t dx) { return coverage(0, outer, dx, dy) >= 1.0; };
  // The exact-arithmetic guess, then corrected by coverage itself, which is monotone in |dx|.
  const double inner = double(outer) - 1;
  const double room = inner * inner - double(dy * dy);
  std::ptrdiff_t half = room >= 0 ? static_cast<std::ptrdiff_t>(std::sqrt(room)) : -1;
  while (half >= 0 && !solid(half)) --half;
  while (solid(half + 1)) ++half;
  return half;
}

double ApertureFootprint::sum(double diameter) const {
  const float bound = outer(diameter);
  const std::ptrdiff_t reach = footprint_reach(bound);
  double total = 0;
  for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy) {
    const std::ptrdiff_t hx = footprint_row_half_width(bound, dy);
    const std::ptrdiff_t solid = solid_half_width(bound, dy);
    if (solid >= 0) {  // the circle: 1 inside, and the rim the same on both sides
      total += double(2 * solid + 1);
      for (std::ptrdiff_t dx = solid + 1; dx <= hx; ++dx)
        total += 2 * std::max(0.0, coverage(diameter, bound, dx, dy));
      continue;
    }
    for (std::ptrdiff_t dx = -hx; dx <= hx; ++dx) {
      const double c = coverage(diameter, bound, dx, dy);
      if (c > 0) total += c;
    }
  }
  return total;
}

double ApertureFootprint::polygon_coverage(double diameter, std::ptrdiff_t dx,
                                           std::ptrdiff_t dy) const {
  const double radius = 0.5 * diameter;
  const double dist = std::sqrt(double(dx * dx + dy * dy));
  if (dist == 0) return std::min(1.0, radius + 0.5);
  // dist · cos(φ), φ the angle from the nearest blade's middle: the largest projection on the
  // middles (> 0 for 3 or more blades), so rim = cos(π/N) / cos(φ) = apothem · dist / proj.
  double projection = -INFINITY;
  for (std::size_t k = 0; k < normal_x_.size(); ++k)
    projection = std::max(projection, double(dx) * normal_x_[k] + double(dy) * normal_y_[k]);
  const double rim = roundness_ + (1 - roundness_) * apothem_ * dist / projection;
  return std::min(1.0, radius * rim + 0.5 - dist);
}

double ApertureFootprint::image_coverage(double diameter, std::ptrdiff_t dx,
                                         std::ptrdiff_t dy) const {
  // Kernel coordinates: cell edges at integers, the point at the kernel's centre.
  const double scale = diameter / double(std::max(kernel_width_, kernel_height_));
  const double centre_u = 0.5 * double(kernel_width_), centre_v = 0.5 * double(kernel_height_);
  if (scale < 1)
    return scale * scale *
           kernel_integral(
               centre_u + (double(dx) - 0.5) / scale, centre_u + (double(dx) + 0.5) / scale,
               centre_v + (double(dy) - 0.5) / scale, centre_v + (double(dy) + 0.5) / scale);
  return kernel_bilinear(centre_u + double(dx) / scale - 0.5, centre_v + double(dy) / scale - 0.5);
}

// ∫∫ over [u0, u1] x [v0, v1] of the kernel, piecewise constant on its cells (zero outside).
double ApertureFootprint::kernel_integral(double u0, double u1, double v0, double v1) const {
  return sat_at(u1, v1) - sat_at(u0, v1) - sat_at(u1, v0) + sat_at(u0, v0);
}

// ∫∫ over [0, u] x [0, v]: bilinear in the summed-area table, which is exact because the
// integral of a piecewise-constant function is bilinear within each cell.
double ApertureFootprint::sat_at(double u, double v) const {
  u = std::clamp(u, 0.0, double(kernel_width_));
  v = std::clamp(v, 0.0, double(kernel_height_));
  const std::ptrdiff_t i = std::min(static_cast<std::ptrdiff_t>(u), kernel_width_ - 1);
  const std::ptrdiff_t j = std::min(static_cast<std::ptrdiff_t>(v), kernel_height_ - 1);
  const double fu = u - double(i), fv = v - double(j);
  const std::ptrdiff_t pitch = kernel_width_ + 1;
  const auto at = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
    return sat_[std::size_t(y * pitch + x)];
  };
  return (1 - fv) * ((1 - fu) * at(i, j) + fu * at(i + 1, j)) +
         fv * ((1 - fu) * at(i, j + 1) + fu * at(i + 1, j + 1));
}

// The kernel at (u, v) in cell-centre coordinates, bilinear, zero outside the image.
double ApertureFootprint::kernel_bilinear(double u, double v) const {
  const double fu0 = std::floor(u), fv0 = std::floor(v);
  if (fu0 < -1 || fv0 < -1 || fu0 >= double(kernel_width_) || fv0 >= double(kernel_height_))
    return 0;
  const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(fu0), j = static_cast<std::ptrdiff_t>(fv0);
  const double fu = u - fu0, fv = v - fv0;
  const auto at = [&](std::ptrdiff_t x, std::ptrdiff_t y) -> double {
    if (x < 0 || y < 0 || x >= kernel_width_ || y >= kernel_height_) return 0;
    return kernel_[std::size_t(y * kernel_width_ + x)];
  };
  return (1 - fv) * ((1 - fu) * at(i, j) + fu * at(i + 1, j)) +
         fv * ((1 - fu) * at(i, j + 1) + fu * at(i + 1, j + 1));
}

void HighlightBoost::require_finite(float largest, std::ptrdiff_t x, std::ptrdiff_t y) const {
  if (!(largest > threshold) || std::isfinite(threshold + gain * (largest - threshold))) return;
  throw InvalidArgument("highlight_gain",
                        "boosting pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                            "), largest channel " + std::to_string(largest) + ", by " +
                            std::to_string(gain) + " overflows a float: lower the gain");
}

void SplatWork::add(float coc, std::ptrdiff_t x, std::ptrdiff_t y) {
  weights_ += splat_weights(coc);
  ++count_;
  if (std::fabs(coc) > largest_) {
    largest_ = std::fabs(coc);
    x_ = x;
    y_ = y;
  }
}

void SplatWork::require_within_budget(const std::string& splats, const std::string& remedy) const {
  if (weights_ <= kMaxSplatWeights) return;
  char numbers[160];
  std::snprintf(numbers, sizeof numbers,
                " would evaluate %.2g weights (%td splats; the largest |CoC| is %g px, at pixel "
                "(%td, %td)); at most %.0e are splatted: ",
                weights_, count_, double(largest_), x_, y_, kMaxSplatWeights);
  throw InvalidArgument("coc", splats + numbers + remedy);
}

}  // namespace tridiff::dof_detail
