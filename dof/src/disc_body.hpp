// The lens's disc where a diffusion blur is furthest from it: in the far field, away from every
// depth edge, the `bokeh` body takes the exact disc average of its input instead of the
// diffusion's bell (issue 26, "SSIM at least scatter's").
//
// Why. A diffusion blur is a bell; a lens spreads a point over a flat disc. Where the CoC is
// smooth the thin-lens image is, to within its rim, the input convolved with the disc, and a bell
// of any width leaves mid-frequency texture the disc removes (SSIM against the ray-traced truth
// on the procedural scene's wall, CoC 8-16 px: 0.968 for the body, 0.994 for `scatter`).
// Where the CoC jumps (an in-focus edge, a near object over the background) a gather with the
// pixel's own disc would leak across the edge; there the layered diffusion stays.
//
// Which pixels. The frame is cut into kDiscTile squares (TileMap). A tile is "smooth" when
//  - no near pixel's disc reaches it (TileMap::near_reach_radius == 0), and
//  - every pixel within the tile's largest radius R + 1 of it (rounded out to whole tiles) is
//    far with kMinDiscCocPx <= c <= kMaxDiscCocPx (and c >= sharp_below), the CoCs spanning at
//    most kSmoothCocPx.
// Then every disc a smooth pixel gathers covers only far pixels whose own disc, which a scatter
// would spread, differs from the gathering pixel's by at most kSmoothCocPx / 2 in radius: about
// the width of the anti-aliased rim.
//
// The disc. A pixel of radius r = c / 2 averages, over the rows dy = -floor(r + 1/2) ..
// floor(r + 1/2), the input's row y + dy over a span centred on x, as wide as the disc's area in
// the strip [dy - 1/2, dy + 1/2] (exact, through an arcsine polynomial): the rows hold the
// disc's area, a row enters (r = |dy| - 1/2) with width 0, so the average varies continuously
// with r. Both ends of a span are read from the row's prefix sums (in double), interpolated
// linearly: the exact integral of the row (pixels as boxes) over the span, so the ends are
// anti-aliased. The weight is the sum of the strips' areas, pi r². Rows and columns beyond the
// frame fold as a mirror (fold(), as scatter's splats do). The 8 pixels of a tile row are
// gathered together, in vector lanes, with one radius (their spans then start at consecutive
// pixels): the tile's smallest and its largest, each pixel interpolating linearly between the
// two at its own (disc_body.cpp). Cost: per tile row and channel, 2 floor(r + 1/2) + 1 rows of
// four 8-lane reads, once or twice; O(r) a pixel, not O(r²). Per block of 32 x 128 pixels,
// prefix sums over (32 + 2 r) x (128 + 2 r) pixels, which kMaxDiscCocPx bounds. Wide discs
// (kHalfResRadiusPx) are gathered at half resolution and interpolated back.
//
// Precision: the prefix sums are in double; a value above about 1e13 times the others in the
// same block's window (an in-focus pixel in the same rows, not clamped as a highlight) costs
// the small ones their digits.
#pragma once

#include <cstddef>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff::dof_detail {

inline constexpr std::ptrdiff_t kDiscTile = 8;
// The largest CoC spread (px, a diameter) around a smooth tile. Against the ray-traced truth
// (1080p, both scenes) a 0.5 px bound left a third of the gain, 2 px let gathers past lamps
// whose own discs are smaller and cost the lamp scene 0.3 dB.
inline constexpr float kSmoothCocPx = 1.f;

// The smallest CoC (px) the disc gather takes. Below it the rows are too few for their
// centred spans to draw a disc (at 2.5 px the gather is 0.02 from the pixels' true coverage on
// a 1/f² texture in [0, 1], at 7 px 0.003), and the diffusion's bell is as near.
inline constexpr float kMinDiscCocPx = 4.f;
// The largest: the prefix sums of a block cover (32 + c) x (128 + c) pixels and each pixel reads
// c + 1 rows, so a disc of thousands of pixels would cost seconds and gigabytes where the
// diffusion costs the same at any size. 128 px (twice the lens's default clamp): 1.3 MiB of sums
// a block.
inline constexpr float kMaxDiscCocPx = 128.f;

// From this radius (px; the tile's smallest) a tile is gathered at half resolution: the discs
// of the input's 2 x 2 means (radius r / 2, less the blur of the means and of the way back),
// interpolated bilinearly back to the tile's pixels. A quarter of the pixels, each reading
// half the rows: an eighth of the work. Against the exact disc by brute force (1/f² texture in
// [0, 1]) its error is 5-10 times the full resolution's at the same size; at d = 24 px (max
// 5.5e-3, rms 1.3e-3) within the full resolution's at d = 4 (1.2e-2, 2.3e-3; dof_bokeh_test).
inline constexpr double kHalfResRadiusPx = 12;

// The disc averages of the smooth tiles, packed: tile i's channel c is values[offset_i + c *
// area_i ...] in row-major order.
struct DiscTiles {
  std::vector<Rect> tiles;
  std::vector<std::size_t> offsets;
  detail::FloatStorage values;
  int channels = 0;

  std::ptrdiff_t pixels() const;
};

// The tiles of `coc` that are smooth (above), in raster order.
std::vector<Rect> smooth_far_tiles(ConstPlane coc, float sharp_below, int threads);

// The disc average of `input` (same size as coc) on each of `tiles` (tiles of the kDiscTile
// grid, from smooth_far_tiles; those from kHalfResRadiusPx at half resolution). OpenMP over
// blocks of 32 x 128 pixels (of the half frame for those), whose tiles share their prefix
// sums; the result does not depend on the thread count. The tiles come back in another order
// (the full resolution's by block, then the half resolution's).
DiscTiles gather_discs(const Image& input, ConstPlane coc, std::vector<Rect> tiles, int threads);

// The width (px) over which a disc tile blends into a neighbouring tile without the disc: the
// two blurs differ by the texture a bell leaves, and a hard switch drew the tiles' staircase
// along depth edges.
inline constexpr double kBlendPx = 6;

// Writes the gathered values into `out` (the frame's size and channels, holding the diffusion's
// body): at full weight from kBlendPx inside the disc tiles' region, blended linearly with the
// body's nearer its edge.
void paste_discs(Image& out, const DiscTiles& discs, int threads);

}  // namespace tridiff::dof_detail
