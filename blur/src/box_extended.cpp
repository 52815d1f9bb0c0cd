// The extended box (Gwosdek, Grewenig, Bruhn, Weickert 2011, "Theoretical foundations of
// Gaussian convolution by extended box filtering"): a plain box of odd width 2r + 1 can only
// reach the variances r (r + 1) / 3, so n plain boxes miss most target sigmas (and odd widths
// mixed to get near them make the kernel less Gaussian). Adding weight alpha in [0, 1) at
// +-(r + 1) interpolates continuously between the boxes of radius r and r + 1: the variance
//   (r (r + 1) (2r + 1) / 3 + 2 alpha (r + 1)^2) / (2r + 1 + 2 alpha)
// equals sigma^2 / n for
//   alpha = (2r + 1) (sigma^2 / n - r (r + 1) / 3) / (2 ((r + 1)^2 - sigma^2 / n)).
// Each pass costs the same O(1) running sum as a plain box, plus the two end samples.
#include <cmath>

#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/box.hpp"

namespace tridiff {

double ExtendedBox::variance() const {
  const double r = static_cast<double>(radius);
  return (r * (r + 1) * (2 * r + 1) / 3 + 2 * alpha * (r + 1) * (r + 1)) / (2 * r + 1 + 2 * alpha);
}

ExtendedBox extended_box(double sigma, int passes) {
  if (!std::isfinite(sigma) || sigma < 0) throw InvalidArgument("sigma", "must be finite and >= 0");
  if (passes < 1) throw InvalidArgument("passes", "must be >= 1");
  const double v = sigma * sigma / passes;  // the variance each pass must add
  const auto plain_variance = [](double r) { return r * (r + 1) / 3; };
  auto r = static_cast<std::ptrdiff_t>(std::floor(0.5 * std::sqrt(12 * v + 1) - 0.5));
  // Guard the floor against rounding: r is the largest radius with plain_variance(r) <= v.
  while (plain_variance(double(r + 1)) <= v) ++r;
  while (r > 0 && plain_variance(double(r)) > v) --r;
  const double rd = static_cast<double>(r);
  const double alpha = (2 * rd + 1) * (v - plain_variance(rd)) / (2 * ((rd + 1) * (rd + 1) - v));
  return {r, alpha};
}

namespace blur_detail {

void run_box_extended(Plane out, ConstPlane in, const BlurOptions& options) {
  const ExtendedBox box = extended_box(options.sigma, kDefaultBoxPasses);
  const std::vector<BoxPass> passes(kDefaultBoxPasses, BoxPass{box.radius, box.alpha});
  box_passes(out, in, passes, resolve_threads(options.threads));
}

}  // namespace blur_detail

}  // namespace tridiff
