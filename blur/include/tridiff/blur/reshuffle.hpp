// Reshuffling (Porikli 2008; seed 001 §3.7), the single-output algorithm, for arbitrary
// kernels. A kernel is preprocessed once into its list of unique weights w_i and, for each, a
// linkage set: the offsets of the input pixels that carry that weight. Each output pixel is
// then sum_i w_i (sum over the linkage set of input pixels): one multiplication per unique
// weight instead of one per tap (Algorithm 3.2).
//
// Cost per output pixel: one addition per nonzero tap plus one multiplication per unique
// weight. A sampled Gaussian has few repeats (by symmetry: 2 per weight in 1D, 4 to 8 and more
// on circles x^2 + y^2 = c in 2D), so the saving is at most 2x in 1D, ~8x in 2D.
//
// Error: none of its own. Reshuffling regroups the convolution sum exactly, so with exact
// unique weights the result is the convolution with the given kernel up to float rounding.
// The seed does not quantise; Porikli's savings grow when many taps share a weight, which
// `levels` forces by rounding every weight to a multiple of max|w| / levels. That rounding is
// then the only approximation: each tap moves by at most max|w| / (2 levels) (taps rounding to
// zero are dropped), so the realised kernel is within taps * max|w| / (2 levels) in l1.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct ReshuffledKernel {
  struct Link {
    std::ptrdiff_t dx, dy;  // the input pixel (x + dx, y + dy) feeds output (x, y)
  };
  std::vector<double> weights;                // the unique nonzero weights
  std::vector<std::vector<Link>> links;       // links[i]: the linkage set of weights[i]
  std::ptrdiff_t radius_x = 0, radius_y = 0;  // the kernel's half-sizes

  std::ptrdiff_t taps() const;  // the number of links, i.e. of nonzero taps
};

// Preprocesses a width x height kernel (row-major, both sizes odd, centred on the middle
// element; a 1D kernel is height 1). Convolution convention: the impulse response of
// reshuffle_filter is the kernel itself, i.e. out(x, y) = sum k(i, j) in(x - i + cx, y - j + cy).
// levels = 0 keeps the exact weights (taps are linked when their weights are equal as doubles);
// levels > 0 quantises first (see above). InvalidArgument naming "kernel", "width", "height" or
// "levels" for an empty or even-sized kernel, a size that does not match, a non-finite weight,
// an all-zero kernel or levels < 0.
ReshuffledKernel reshuffle_kernel(std::span<const double> kernel, std::ptrdiff_t width,
                                  std::ptrdiff_t height, int levels = 0);

// out = in convolved with the 2D kernel (Algorithm 3.2, every output written once). Any
// border; out must not overlap in. O(pixels * taps).
void reshuffle_filter(Plane out, ConstPlane in, const ReshuffledKernel& kernel, Border border,
                      int threads = 0);

// out = in convolved with the 1D kernel (height 1) along rows, then along columns: the
// separable use of a 1D kernel k, the 2D kernel being k(x) k(y). O(pixels * 2 taps).
// InvalidArgument("kernel") unless the kernel is 1D.
void reshuffle_filter_separable(Plane out, ConstPlane in, const ReshuffledKernel& kernel,
                                Border border, int threads = 0);

}  // namespace tridiff
