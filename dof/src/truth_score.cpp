// Scores against the thin-lens truth (quality.hpp): sRGB-encoded PSNR and SSIM, overall and over
// the in-focus, defocused and depth-edge regions.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "tridiff/blur/quality.hpp"
#include "tridiff/dof/quality.hpp"
#include "tridiff/image/color.hpp"

namespace tridiff {
namespace {

void require_scorable(const Image& out, const Image& truth, ConstPlane coc) {
  if (truth.channels() < 3) throw InvalidArgument("truth", "needs 3 channels (RGB)");
  if (out.width() != truth.width() || out.height() != truth.height() || out.channels() < 3)
    throw InvalidArgument(
        "out", "is " + std::to_string(out.width()) + " x " + std::to_string(out.height()) + " x " +
                   std::to_string(out.channels()) + ", the truth " + std::to_string(truth.width()) +
                   " x " + std::to_string(truth.height()) + " x 3");
  if (coc.width() != truth.width() || coc.height() != truth.height())
    throw InvalidArgument("coc", "size differs from the truth's");
}

// Marks the disc of radius `reach` around (cx, cy).
void stamp_disc(std::vector<unsigned char>& mask, std::ptrdiff_t width, std::ptrdiff_t height,
                std::ptrdiff_t cx, std::ptrdiff_t cy, float reach) {
  const auto span = std::ptrdiff_t(std::floor(reach));
  for (std::ptrdiff_t y = std::max<std::ptrdiff_t>(0, cy - span);
       y <= std::min(height - 1, cy + span); ++y)
    for (std::ptrdiff_t x = std::max<std::ptrdiff_t>(0, cx - span);
         x <= std::min(width - 1, cx + span); ++x) {
      const float dx = float(x - cx), dy = float(y - cy);
      if (dx * dx + dy * dy <= reach * reach) mask[std::size_t(y * width + x)] = 1;
    }
}

// Both pixels of every depth edge, each stamped with the larger blur radius of the pair.
std::vector<unsigned char> edge_region(ConstPlane coc) {
  const std::ptrdiff_t width = coc.width(), height = coc.height();
  std::vector<unsigned char> edges(std::size_t(width * height), 0);
  auto pair = [&](std::ptrdiff_t x0, std::ptrdiff_t y0, std::ptrdiff_t x1, std::ptrdiff_t y1) {
    const float a = coc(x0, y0), b = coc(x1, y1);
    if (!(std::fabs(a - b) > kTruthEdgeJumpPx)) return;
    const float reach = 0.5f * std::max(std::fabs(a), std::fabs(b)) + kTruthEdgeMarginPx;
    stamp_disc(edges, width, height, x0, y0, reach);
    stamp_disc(edges, width, height, x1, y1, reach);
  };
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      if (x + 1 < width) pair(x, y, x + 1, y);
      if (y + 1 < height) pair(x, y, x, y + 1);
    }
  return edges;
}

// The first three channels clipped to [0, 1] and sRGB-encoded, one DoublePlane each.
std::array<DoublePlane, 3> displayed(const Image& image) {
  std::array<DoublePlane, 3> planes;
  for (int c = 0; c < 3; ++c) {
    planes[std::size_t(c)] = DoublePlane(image.width(), image.height());
    for (std::ptrdiff_t y = 0; y < image.height(); ++y)
      for (std::ptrdiff_t x = 0; x < image.width(); ++x)
        planes[std::size_t(c)](x, y) = linear_to_srgb(std::clamp(image(x, y, c), 0.f, 1.f));
  }
  return planes;
}

struct RegionSums {
  double squared_error = 0, ssim = 0;
  std::ptrdiff_t pixels = 0;
  void scores(double& psnr, double& ssim_mean) const {
    if (pixels == 0) {
      psnr = ssim_mean = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    const double mse = squared_error / double(3 * pixels);
    psnr = mse > 0 ? -10 * std::log10(mse) : std::numeric_limits<double>::infinity();
    ssim_mean = ssim / double(pixels);
  }
};

}  // namespace

TruthRegions truth_regions(ConstPlane coc) {
  TruthRegions regions;
  regions.edges = edge_region(coc);
  regions.in_focus.assign(regions.edges.size(), 0);
  regions.defocused.assign(regions.edges.size(), 0);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
      const std::size_t i = std::size_t(y * coc.width() + x);
      if (regions.edges[i]) continue;
      (std::fabs(coc(x, y)) < 1.f ? regions.in_focus : regions.defocused)[i] = 1;
    }
  return regions;
}

TruthScore score_against_truth(const Image& out, const Image& truth, ConstPlane coc) {
  require_scorable(out, truth, coc);
  const TruthRegions regions = truth_regions(coc);
  const std::array<DoublePlane, 3> shown = displayed(out), expected = displayed(truth);
  std::array<DoublePlane, 3> ssim;
  for (std::size_t c = 0; c < 3; ++c) ssim[c] = ssim_map(shown[c], expected[c]);
  RegionSums all, in_focus, defocused, edges;
  for (std::size_t i = 0; i < regions.edges.size(); ++i) {
    double squared = 0, similarity = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      const double d = shown[c].values[i] - expected[c].values[i];
      squared += d * d;
      similarity += ssim[c].values[i] / 3;
    }
    RegionSums& region = regions.edges[i] ? edges : regions.in_focus[i] ? in_focus : defocused;
    for (RegionSums* sums : {&all, &region}) {
      sums->squared_error += squared;
      sums->ssim += similarity;
      ++sums->pixels;
    }
  }
  TruthScore score;
  all.scores(score.psnr, score.ssim);
  in_focus.scores(score.psnr_in_focus, score.ssim_in_focus);
  defocused.scores(score.psnr_defocused, score.ssim_defocused);
  edges.scores(score.psnr_edges, score.ssim_edges);
  score.in_focus_pixels = in_focus.pixels;
  score.defocused_pixels = defocused.pixels;
  score.edge_pixels = edges.pixels;
  return score;
}

}  // namespace tridiff
