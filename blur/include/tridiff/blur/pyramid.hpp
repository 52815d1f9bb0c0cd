// Pyramid blur (seed 001 §3.5, after Burt 1981, Strengert et al. and Kraus): the image is
// down-sampled by 2 per level with an analysis filter (2x2 box, 4x4 box, or Kraus's
// quasi-convolution filter of eq. 3.15), then up-sampled back level by level with the
// biquadratic B-spline synthesis filter. Each level roughly doubles the blur, so the levels
// alone give sigmas about 1.5, 3, 6, 12, 25 px; a small separable smoothing at the coarsest
// level fills the gaps in between (see pyramid_plan).
//
// Geometry. Pixel j of level l + 1 sits at the centre of pixels 2j and 2j + 1 of level l
// (as GL texel centres do): the grid is anchored at the top-left pixel, and a blur of sizes
// divisible by 2^levels is symmetric and unshifted.
//
// Borders and sizes. The result is the pyramid blur of the replicate-extended (infinite)
// image, sampled on the input's pixels: exactly, not by clamping each level at its own edge
// (GL_CLAMP_TO_EDGE on every level, as the seed's GPU version does, makes a bright corner
// pixel vanish where the replicate Gaussian spreads it over a whole quadrant: errors up to
// 0.25). Beyond a few pixels from its edge every level of the extended image is constant
// along the edge normal, so each level stores its pixels plus a margin of 2 to 3 pixels a
// side and clamps to that margin, which is exact. Any size works, 1 x 1 and odd sizes
// included, with nothing special for odd sizes: a level of n pixels has about n / 2 + 3.
// Since the grid is anchored at the first pixel, the blur of an image whose size is not a
// multiple of 2^levels is not exactly mirror-symmetric (pyramids are not shift-invariant).
// Only Border::replicate is supported.
//
// Weights are non-negative and sum to 1 at every step, so the result lies within [min, max]
// of the input and a constant stays constant; every analysis filter gives each fine pixel a
// total weight of 1/2 and the B-spline gives each coarse pixel a total weight of 2, so the
// mass of anything far enough from the edges is conserved.
#pragma once

#include <string_view>

#include "tridiff/blur/blur.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

enum class PyramidFilter {
  box2,   // mean of 2 x 2 fine pixels (mipmaps)
  box4,   // mean of 4 x 4 fine pixels (two shifted 2 x 2 boxes, eq. 3.16)
  quasi,  // Kraus's quasi-convolution filter, [13 19 19 13] / 64 per axis (eq. 3.15)
};

std::string_view pyramid_filter_name(PyramidFilter filter);

// The pyramid blur of `levels` levels (0: a copy), plus an optional smoothing of
// `coarse_sigma` coarse pixels at the coarsest level (0: none; see pyramid_plan). `in` and `out`
// have the same size and do not overlap. InvalidArgument on bad sizes, levels outside [0, 30],
// coarse_sigma < 0 or not finite, a border other than replicate, threads < 0 (0: all cores).
void pyramid_blur(Plane out, ConstPlane in, PyramidFilter filter, int levels,
                  Border border = Border::replicate, int threads = 0);
void pyramid_blur(Plane out, ConstPlane in, PyramidFilter filter, int levels, double coarse_sigma,
                  Border border, int threads);

// The effective sigma of `levels` levels (>= 1) of `filter`, in input pixels: the sigma of the
// Gaussian nearest to it in mean absolute difference (seed 001 §4.1.2), measured with
// effective_sigma() on quality_test_set(1024) for levels 1-5 (tests/blur_pyramid_test.cpp
// checks them against seed 001 Tables A.1-A.3). Beyond 5 levels the blur's variance grows
// as (4^levels - 1), so the measured sigma of 5 levels is scaled by
// sqrt((4^levels - 1) / (4^5 - 1)) (about 2 per level).
double pyramid_sigma(PyramidFilter filter, int levels);

// How to reach a target sigma with a pyramid: the most levels whose sigma does not exceed
// the target, and a smoothing at that coarsest level that adds the missing variance:
// coarse_sigma^2 = (sigma^2 - pyramid_sigma(levels)^2) / 4^levels (a coarse pixel is
// 2^levels input pixels wide, and variances add). The smoothing is a few passes of the
// 3-tap [a, 1 - 2a, a] (a <= 1/4) per axis, on an image 4^levels times smaller than the
// input, so it costs almost nothing; between two levels the effective sigma then follows the
// target to within a few percent instead of being off by up to a factor sqrt(2) as the
// nearest level would be. InvalidArgument unless sigma >= pyramid_sigma(filter, 1).
struct PyramidPlan {
  int levels = 1;
  double coarse_sigma = 0;
};
PyramidPlan pyramid_plan(PyramidFilter filter, double sigma);

// pyramid_blur at pyramid_plan(filter, sigma): the registered methods "pyramid-box2",
// "pyramid-box4" and "pyramid-quasi".
void pyramid_blur_sigma(Plane out, ConstPlane in, PyramidFilter filter, double sigma,
                        Border border = Border::replicate, int threads = 0);

}  // namespace tridiff
