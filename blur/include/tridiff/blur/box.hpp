// Repeated box filtering (seed 001 §3.8): n passes of a box approximate a Gaussian (central
// limit theorem); the variances of the passes add up. The box widths for a target sigma, the
// extended box of Gwosdek et al. (2011) that matches sigma exactly, and the separable engine
// that runs the passes with running sums (O(1) a pixel a pass whatever the width).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff {

inline constexpr int kDefaultBoxPasses = 3;

// The variance of a box of odd width w: (w^2 - 1) / 12.
double box_variance(std::ptrdiff_t width);

// The odd widths of `passes` boxes whose variances add up to sigma^2 as nearly as odd widths
// allow (Wells 1986; Kovesi's "ideal widths" rule): m boxes of width wl and passes - m of
// wl + 2, wl the largest odd width not above sqrt(12 sigma^2 / passes + 1), m the nearest
// integer to the count that makes the sum exact. sigma >= 0, passes >= 1.
std::vector<std::ptrdiff_t> box_widths(double sigma, int passes = kDefaultBoxPasses);

// The extended box (Gwosdek, Grewenig, Bruhn, Weickert 2011): weight 1 on [-r, r], weight
// alpha in [0, 1) on -(r + 1) and r + 1, normalised to sum 1. r is the largest radius whose
// plain box does not exceed the per-pass variance sigma^2 / passes; alpha makes it exact.
struct ExtendedBox {
  std::ptrdiff_t radius = 0;
  double alpha = 0;
  double variance() const;
};
ExtendedBox extended_box(double sigma, int passes = kDefaultBoxPasses);

// One pass of the separable engine: a plain box of width 2 radius + 1 when end_weight is 0,
// an extended box otherwise.
struct BoxPass {
  std::ptrdiff_t radius = 0;
  double end_weight = 0;
};

// out = the passes applied along columns, then along rows: the convolution of the
// replicate-extended image with the combined kernel (each pass computes past the image edge
// what the later passes read, rather than clamping at every pass). Boxes may be wider than
// the image. `in` and `out` have the same size and may be the same plane, but
// must not otherwise overlap. threads 0: all cores.
void box_passes(Plane out, ConstPlane in, std::span<const BoxPass> passes, int threads = 0);

// The plain box passes for box_widths(sigma, passes).
std::vector<BoxPass> plain_box_passes(double sigma, int passes = kDefaultBoxPasses);

}  // namespace tridiff
