// The quality harness of seed 001 §4.1.2: how far a blur is from the exact Gaussian, and which
// Gaussian it really is (its effective sigma), over a set of test patterns generated in code.
#pragma once

#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/reference.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct BlurError {
  double max_abs = 0;  // max |approx - exact|
  double rmse = 0;
  double psnr = 0;  // 10 log10(1 / mse), peak 1 (images in [0, 1]); +inf when equal
  double ssim = 0;  // mean SSIM (Wang et al. 2004: Gaussian window sigma 1.5, K1 0.01,
                    // K2 0.03, L 1), replicate border
};

BlurError blur_error(ConstPlane approx, const DoublePlane& exact);

// SSIM of a and b (values in [0, 1]) at every pixel, as in BlurError::ssim (whose mean it is):
// for scores over a part of the frame.
DoublePlane ssim_map(const DoublePlane& a, const DoublePlane& b);

// A blur of one plane, for the harness: out = blur(in).
using PlaneBlur = std::function<void(Plane out, ConstPlane in)>;
// One registered method at `options`, as a PlaneBlur.
PlaneBlur plane_blur(const BlurMethod& method, const BlurOptions& options);

// The l-infinity operator norm of (blur - exact Gaussian of sigma), for a linear shift-
// invariant blur: the l1 norm of the difference of their impulse responses, the impulse in the
// middle of a plane wide enough (>= 16 sigma + 64) that borders play no part. It bounds the
// max error on any image in [0, 1] from above (by the norm) for shift-invariant methods.
double operator_norm_error(const PlaneBlur& blur, double sigma);

// Test patterns with values in [0, 1], one channel, size x size: step edges at several angles,
// discs, thin lines, white noise and a 1/f texture. Deterministic for a given seed.
struct TestPattern {
  std::string name;
  Image image;
};
std::vector<TestPattern> quality_test_set(std::ptrdiff_t size, unsigned seed = 1);

// The sigma of the exact Gaussian nearest to `blur` (seed 001 §4.1.2): the s in [lo, hi]
// minimising the mean |blur(p) - G_s(p)| over the patterns, found by golden-section search to
// a relative 1e-4. `border` is the one the reference uses.
double effective_sigma(const PlaneBlur& blur, std::span<const TestPattern> patterns, double lo,
                       double hi, Border border = Border::replicate);

}  // namespace tridiff
