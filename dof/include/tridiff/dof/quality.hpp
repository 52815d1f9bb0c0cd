// The DOF error harness: how far a method's output is from the `scatter` reference, overall
// and in the two places where depth of field goes visibly wrong — sharp regions that a method
// blurs although the reference leaves them alone, and the halo where a sharp foreground's colour
// leaks into the blurred background behind it (seed 000 §6, fig. 6.2; seed 002 §28.3).
#pragma once

#include <cstddef>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff {

struct DofError {
  // Over every pixel and channel, on the linear values as they are (highlights above 1
  // included): the physical error.
  double rmse = 0;
  double max_abs = 0;
  // On the values clipped to [0, 1], peak 1: what a display shows. Unclipped, one highlight of
  // 12 blurred slightly differently would outweigh every visible error, and PSNR with peak 1
  // assumes the signal range is [0, 1]. +inf when the clipped images are equal.
  double psnr = 0;
  // Mean SSIM (Wang et al. 2004; Gaussian window sigma 1.5, K1 0.01, K2 0.03, L 1, replicate
  // border) of the clipped images, per channel, averaged over the channels. 1 when equal.
  double ssim = 0;
  // In focus: the pixels that are sharp (|c| < max(1, in_focus_coc_px)) and that the
  // reference leaves exactly unchanged (every channel equal to the input's bit for bit), where
  // the truth is the input. max and RMSE of |out - input| over them (0 when there are none).
  double in_focus_max = 0;
  double in_focus_rmse = 0;
  std::ptrdiff_t in_focus_pixels = 0;
  // Leakage: RMSE of out - reference over the halo pixels (0 when there are none). A halo
  // pixel is out of focus behind the focus (c >= max(1, in_focus_coc_px)) and lies within its
  // own blur radius c / 2 (Euclidean distance between pixel centres) of a sharp pixel. That
  // sharp pixel is nearer than it (its CoC is smaller), so the halo pixel's disc overlaps a
  // sharp foreground: a gather that does not test depth pulls the foreground's colour in here.
  double leakage = 0;
  std::ptrdiff_t leakage_pixels = 0;
};

// `out` and `reference` against each other, with `input` the colour both were computed from and
// `coc` its signed CoC map. Every image the same size and channel count, `coc` the same size
// (InvalidArgument naming the argument otherwise); values finite.
DofError dof_error(const Image& out, const Image& reference, const Image& input, ConstPlane coc,
                   float in_focus_coc_px);

// The two masks behind DofError, one byte per pixel in raster order (1: in the region).
struct DofRegions {
  std::vector<unsigned char> in_focus, leakage;
};
DofRegions dof_regions(const Image& reference, const Image& input, ConstPlane coc,
                       float in_focus_coc_px);

// A method's output against the thin-lens truth (truth.hpp), on what a display shows: linear
// values clipped to [0, 1], then sRGB-encoded (the eye's error, not a highlight's), PSNR with
// peak 1 (+inf when equal) and mean SSIM (as DofError::ssim, on the encoded values). Overall
// and over three regions that partition the frame (TruthRegions); NaN for an empty region.
struct TruthScore {
  double psnr = 0, ssim = 0;
  double psnr_in_focus = 0, ssim_in_focus = 0;
  double psnr_defocused = 0, ssim_defocused = 0;
  double psnr_edges = 0, ssim_edges = 0;
  std::ptrdiff_t in_focus_pixels = 0, defocused_pixels = 0, edge_pixels = 0;
};

// One byte per pixel in raster order, each pixel in exactly one region. Edges: within
// max(kTruthEdgeMarginPx, r + kTruthEdgeMarginPx) of a depth edge (Euclidean, pixel centres),
// r the larger blur radius |c| / 2 of the edge's two sides; a depth edge lies between two
// 4-neighbours whose CoC differ by more than kTruthEdgeJumpPx. There a blur crosses from one
// surface over another, and what the near one hides decides the result: where a post-process
// cannot see behind a foreground and leaks colour across. In focus: the other pixels with
// |c| < 1 px; defocused: the rest.
struct TruthRegions {
  std::vector<unsigned char> in_focus, defocused, edges;
};
// A continuous surface's CoC changes by far less than a pixel from one pixel to the next
// (except at grazing angles); a jump of more is another surface, an occlusion.
inline constexpr float kTruthEdgeJumpPx = 1.f;
// The SSIM window (sigma 1.5 px) and pixel sampling reach this far past the blur itself.
inline constexpr float kTruthEdgeMarginPx = 3.f;
TruthRegions truth_regions(ConstPlane coc);

// `out` against `truth` (same size, 3 channels or more: the first 3 are scored), `coc` the
// signed CoC map the methods were given (same size; InvalidArgument naming the argument).
TruthScore score_against_truth(const Image& out, const Image& truth, ConstPlane coc);

}  // namespace tridiff
