// What one defocused point of light becomes — its footprint for the aperture of DofOptions
// (circle, bladed polygon or a custom kernel image) — and the highlight boost; shared by the
// `scatter` reference and the `bokeh` sprites so that both draw the same shape. Private to
// dof/src.
//
// The footprint of a point of CoC diameter d (pixels) gives each integer offset (dx, dy) from
// the point a coverage >= 0; the splat's weights are the coverages divided by their sum (area
// normalised: a point's energy is conserved).
//  - Circle: min(1, d/2 + 1/2 - |(dx, dy)|), the radial ramp one pixel wide on the rim.
//  - Polygon (ApertureShape, scaled so that its circumscribed circle is the CoC disc): the same
//    ramp on the signed distance to the rim along the ray, min(1, d/2 · rim(θ) + 1/2 - dist),
//    rim(θ) = aperture_rim. θ is counter-clockwise on the screen (y up), as a viewer reads
//    "rotation". rim(θ)'s cos(φ) is computed without trigonometry: dist · cos(φ) is the largest
//    projection of the offset on the blades' middle directions.
//  - Kernel image (one channel, kw x kh): its longer side spans d pixels, centred on the point,
//    upright as in the file. Shrunk (d < max(kw, kh)): each output pixel takes the exact
//    integral of the piecewise-constant kernel over its square (a box filter, from a
//    summed-area table); enlarged: the bilinear interpolation of the kernel (zero outside).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "tridiff/dof/method.hpp"

namespace tridiff::dof_detail {

class ApertureFootprint {
 public:
  // Checks the aperture (validate) and the kernel image (validate_aperture_image).
  explicit ApertureFootprint(const DofOptions& options);

  bool is_circle() const { return kind_ == Kind::circle; }
  // A radius that bounds the support for CoC diameter d >= 1: every offset of positive coverage
  // has |(dx, dy)| < outer(d).
  float outer(double diameter) const;
  // The unnormalised weight at offset (dx, dy) for CoC diameter d (zero or negative: none).
  double coverage(double diameter, float outer, std::ptrdiff_t dx, std::ptrdiff_t dy) const;
  // The sum of the positive coverages over the offsets with |(dx, dy)| < outer.
  double sum(double diameter) const;
  // For the circle: the largest dx of row dy whose coverage is exactly 1 (every |dx| up to it
  // is covered fully; -1 if none), found with coverage's own arithmetic; -1 for the other
  // shapes. The inside of a large disc is most of it, and needs no square root.
  std::ptrdiff_t solid_half_width(float outer, std::ptrdiff_t dy) const;

 private:
  enum class Kind { circle, polygon, image };
  double polygon_coverage(double diameter, std::ptrdiff_t dx, std::ptrdiff_t dy) const;
  double image_coverage(double diameter, std::ptrdiff_t dx, std::ptrdiff_t dy) const;
  double kernel_integral(double u0, double u1, double v0, double v1) const;
  double kernel_bilinear(double u, double v) const;
  double sat_at(double u, double v) const;

  Kind kind_ = Kind::circle;
  // Polygon: the blades' middle directions (unit, screen coordinates y down) and the rim's
  // constants.
  std::vector<double> normal_x_, normal_y_;
  double roundness_ = 1, apothem_ = 1;  // apothem: cos(pi / blades)
  // Kernel image: its values and summed-area table ((kw + 1) x (kh + 1), double).
  std::ptrdiff_t kernel_width_ = 0, kernel_height_ = 0;
  std::vector<float> kernel_;
  std::vector<double> sat_;
};

// The mirror fold of coordinate x into [0, n): the frame continued as its mirror image, so that
// every weight of a splat lands in the frame (energy is conserved at the border).
inline std::ptrdiff_t fold(std::ptrdiff_t x, std::ptrdiff_t n) {
  if (x >= 0 && x < n) return x;
  const std::ptrdiff_t period = 2 * n;
  std::ptrdiff_t m = x % period;
  if (m < 0) m += period;
  return m < n ? m : period - 1 - m;
}

// The largest |dy| (and |dx|) whose coverage can be positive, for a support bounded by outer.
inline std::ptrdiff_t footprint_reach(float outer) {
  return static_cast<std::ptrdiff_t>(std::ceil(outer)) - 1;
}

// The half-width of row dy of a support bounded by outer (a bound; coverage decides).
inline std::ptrdiff_t footprint_row_half_width(double outer, std::ptrdiff_t dy) {
  const double s = outer * outer - double(dy * dy);
  return s > 0 ? static_cast<std::ptrdiff_t>(std::floor(std::sqrt(s))) : -1;
}

// The largest channel of pixel (x, y): what the highlight threshold and boost look at.
inline float largest_channel(const Image& color, std::ptrdiff_t x, std::ptrdiff_t y) {
  float largest = color(x, y, 0);
  for (int c = 1; c < color.channels(); ++c) largest = std::max(largest, color(x, y, c));
  return largest;
}

// The highlight boost of DofOptions, keeping the hue: a pixel whose largest channel m exceeds
// the threshold t is scaled by (t + gain · (m - t)) / m, so its largest channel becomes
// t + gain · (m - t) and the ratios between its channels stay (a per-channel boost would push
// a coloured lamp towards a different hue). Below the threshold: unchanged.
struct HighlightBoost {
  float threshold = INFINITY;
  float gain = 1;
  bool active() const { return std::isfinite(threshold) && gain != 1; }
  // The factor for a pixel whose largest channel is `largest`.
  float factor(float largest) const {
    return largest > threshold ? (threshold + gain * (largest - threshold)) / largest : 1.f;
  }
  // Refuses (InvalidArgument naming highlight_gain) a boost of pixel (x, y), largest channel
  // `largest`, that overflows a float: every boosted value, and a sprite's excess, is at most
  // t + gain · (m - t), and an infinite one would spread inf (and 0 · inf = NaN) over the frame.
  void require_finite(float largest, std::ptrdiff_t x, std::ptrdiff_t y) const;
};

// The splat methods' guard against a run that would not end. A splat of CoC diameter D px
// evaluates about pi (D/2 + 1/2)^2 weights (its footprint's support; a kernel image's is up to
// twice that), so a frame's cost grows with the square of its CoC: a 128 x 72 frame whose CoC
// reaches 4000 px took `scatter` 14 s (5.4e9 weights, 2.5 ns each on two cores); 1920 x 1080
// at that CoC everywhere would take about 18 hours. Splats adding up to more than
// kMaxSplatWeights (about ten minutes on two cores; 7680 x 4320 at the lens's default clamp
// of 64 px is 1.1e11) are refused with an error naming the largest CoC and its pixel, instead
// of running for hours; the CoC is not clamped silently.
inline constexpr double kMaxSplatWeights = 2.5e11;

// The weights a splat of signed CoC `coc` evaluates, about: pi (|coc|/2 + 1/2)^2.
inline double splat_weights(float coc) {
  const double radius = 0.5 * std::fabs(double(coc)) + 0.5;
  return std::numbers::pi * radius * radius;
}

class SplatWork {
 public:
  // Counts the splat of pixel (x, y), signed CoC `coc`.
  void add(float coc, std::ptrdiff_t x, std::ptrdiff_t y);
  // InvalidArgument naming "coc" when the splats counted exceed kMaxSplatWeights; `splats`
  // says what they are ("the scatter reference's splats"), `remedy` what to do instead.
  void require_within_budget(const std::string& splats, const std::string& remedy) const;

 private:
  double weights_ = 0;
  std::ptrdiff_t count_ = 0, x_ = 0, y_ = 0;
  float largest_ = 0;
};

}  // namespace tridiff::dof_detail
