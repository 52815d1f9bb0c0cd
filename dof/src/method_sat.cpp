// The `sat` and `sat-layers` methods: depth of field gathered from summed-area tables at half
// resolution (seed 003, "Our Approach"; the tables of seed 001 §2.1, eq. 2.3).
//
// `sat` (seed 003 as written). The colour is averaged over 2 x 2 blocks into a half-resolution
// image h (the last row/column of an odd size averages the edge pixel with itself: the replicate
// border), one SummedAreaTable per channel. A sharp pixel (|c| < max(1, in_focus_coc_px)) keeps
// its value bit for bit. An out-of-focus pixel p of radius R = |c| / 2 gets the mean of three box
// means — half-extents (R, R/2), (3R/4, 3R/4), (R/2, R) full-resolution pixels about p's centre,
// the "R x 0.5R, 0.75R x 0.75R, 0.5R x R" cross that seed 003 (fig. 5) combines into a rounder
// kernel. Its variance per axis is 29/144 R² = 0.201 R², a disc's is R²/4: the kernel is 10 %
// narrower in sigma than the scatter reference's disc (we keep the seed's sizes).
//
// Half resolution, as the sample's bilinear texture reads do: a box is read at fractional
// half-resolution coordinates, [(x + 1/2 - a) / 2, (x + 1/2 + a) / 2] for half-extent a, and the
// table is interpolated bilinearly between its entries. That is exact: T of a piecewise-constant
// image is bilinear inside each cell, so a box mean is the exact integral of h (upsampled by
// pixel replication) over the full-resolution box divided by its area. The output therefore
// varies continuously with the CoC and the position (no 2-pixel steps). replicate_box_sum takes
// whole-pixel rectangles only, so the fractional boxes are evaluated here from table.at() with the
// same replicate extension (a line continues as its edge pixel, also for boxes larger than the
// frame): 16 entries a box. The border is replicate (what the table gives), not the mirror of
// `scatter`. The tables are the double SummedAreaTable: at half resolution 2 bytes a
// full-resolution pixel a channel, one load an entry (the tiled float table costs five), and its
// rounding, about 16 eps_double T_max / box area, is negligible at any frame size.
//
// `sat-layers` (the remedy seed 003 proposes under "Limitations" against leaking). Two sets of
// tables, each premultiplied by a coverage α held in an extra table (seed 003: "use that total
// value instead of the analytic area"): the far layer (c >= the sharp threshold) and the near
// layer (c <= -threshold), each with planes α C, α and α R. Sharp pixels are in neither. Per p:
//  - base: a sharp p is its own colour with coverage 1. Otherwise the far layer's three-box
//    means with radius R_b: B = mean(α C) / mean(α), coverage a = min(mean(α), 1); near and
//    sharp colours do not leak into B. For a far p, R_b is its own radius; behind a near p, the
//    far pixels that would splat onto p are read with R_b = the mean far radius in the square of
//    half-extent TileMap reach_radius about p (from the α R and α tables), so a far layer of
//    small CoC does not show through a near object.
//  - front, only in tiles whose TileMap near reach is > 0: the near radius R_n is the mean near
//    radius in the square of half-extent near_reach_radius about p, then F = three-box mean of
//    α C and A = three-box mean of α with R_n. For a uniform near CoC these are the scatter's
//    near coverage and premultiplied colour exactly (a box-filtered α and α C, as area-normalised
//    splats are).
//  - composite, near over the base and renormalised by the union of the coverages, as `scatter`
//    does: out = (F + (1 - A) a B) / (A + (1 - A) a); without a front, out = B.
// Whether a box holds any coverage is decided exactly by replicate_box_sum over the whole
// half-resolution cells it touches (α is a multiple of 1/4, so those sums are exact in double);
// the fractional read alone would leave rounding residues instead of zero, so a mean coverage
// below kMinCoverage counts as none.
//
// Validity: any finite CoC, any size (1 x 1 up), any channel count; the cost per pixel does not
// depend on the CoC (O(pixels) for any blur). `sat` is a convex combination of the input
// (output within its range up to rounding); so is `sat-layers`.
// Known artifacts: (1) half resolution: a pixel just out of focus (R = 1/2) is already a 2-pixel
// blur, a step next to sharp pixels that keep full resolution; (2) the kernel is a gather with
// the pixel's own CoC, not a scatter: in `sat` sharp and near colours leak into the background
// blur and a blurred near object does not spread over a sharp background (blurs_foreground
// false); `sat-layers` removes both, but its near radius is a neighbourhood mean (wrong where near
// CoCs vary quickly) and it bounds that mean by the per-tile near reach, which can show tile
// edges in the near halo where near CoCs vary (the far radius behind a near pixel likewise);
// (3) box kernels: square-ish bokeh, not discs; (4) far pixels of different depths still mix
// (one far layer, not depth-sorted layers); (5) HDR highlights next to a near edge in `sat`
// bleed into it (the largest error against `scatter`, see tests/dof_sat_test.cpp).
//
// Skipping: TileMap with a margin of 2 px for the half-resolution cells (a box touches a cell up
// to 1.5 px beyond its edge). A tile that nothing reaches holds only sharp pixels, whose output is
// their input, and no near reach, so no foreground: such tiles are copied, which changes no bit.
// The near tables and the foreground pass are left out when the frame has no near pixel (they
// would add exactly zero coverage); the far tables when it has no far pixel and skipping is on.
// All passes split the work so that no result depends on the thread count.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "tridiff/blur/sat.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"
#include "tridiff/threads.hpp"
#include "frame.hpp"
#include "tiled_gather.hpp"

namespace tridiff {
namespace {

// A box touches half-resolution cells up to 1.5 full-resolution pixels beyond its edge.
constexpr std::ptrdiff_t kHalfResMargin = 2;
// Half-extents of the three boxes along x in units of R; along y the same in reverse order.
constexpr std::array<double, 3> kExtent{1.0, 0.75, 0.5};
// A layer's mean coverage below this is taken as none: the fractional table reads leave rounding
// residues of about 16 eps_double x (cells in the frame) / (box area in cells), < 1e-7 up to
// 16k x 16k frames; a true coverage this small weighs its layer by less than 1e-6.
constexpr double kMinCoverage = 1e-6;

// The integral over [lo, hi] of a line of n half-resolution cells (cell i = [i, i + 1)) extended
// by its edge values, as taps of the line's prefix table t(p), p in [-1, n), t(-1) = 0:
// integral = sum weight[k] * t(index[k]). The continuous prefix C(X) is t linearly interpolated
// between cell edges, X t(0) before the line and continued with slope t(n-1) - t(n-2) after it.
struct AxisTaps {
  std::ptrdiff_t index[4];
  double weight[4];
  std::ptrdiff_t first_cell, last_cell;  // the cells [lo, hi] touches, clamped to the line
};

void prefix_taps(double at, std::ptrdiff_t n, double sign, std::ptrdiff_t* index, double* weight) {
  if (at <= 0) {
    index[0] = 0, weight[0] = sign * at;
    index[1] = -1, weight[1] = 0;
  } else if (at < double(n)) {
    const double cell = std::floor(at), f = at - cell;
    index[0] = std::ptrdiff_t(cell) - 1, weight[0] = sign * (1 - f);
    index[1] = std::ptrdiff_t(cell), weight[1] = sign * f;
  } else {
    const double beyond = at - double(n);
    index[0] = n - 1, weight[0] = sign * (1 + beyond);
    index[1] = n - 2, weight[1] = -sign * beyond;  // t(-1) = 0 when n = 1
  }
}

AxisTaps axis_taps(double lo, double hi, std::ptrdiff_t n) {
  AxisTaps taps;
  prefix_taps(hi, n, 1.0, taps.index, taps.weight);
  prefix_taps(lo, n, -1.0, taps.index + 2, taps.weight + 2);
  taps.first_cell = std::clamp<double>(std::floor(lo), 0, double(n - 1));
  taps.last_cell = std::clamp<double>(std::ceil(hi) - 1, 0, double(n - 1));
  return taps;
}

// The taps of the full-resolution interval [p + 1/2 - half_extent, p + 1/2 + half_extent].
AxisTaps full_res_taps(std::ptrdiff_t p, double half_extent, std::ptrdiff_t cells) {
  const double centre = (double(p) + 0.5) * 0.5, half = 0.5 * half_extent;
  return axis_taps(centre - half, centre + half, cells);
}

double box_integral(const SummedAreaTable& table, const AxisTaps& xs, const AxisTaps& ys) {
  double sum = 0;
  for (int j = 0; j < 4; ++j) {
    double row = 0;
    for (int i = 0; i < 4; ++i) row += xs.weight[i] * table.at(xs.index[i], ys.index[j]);
    sum += ys.weight[j] * row;
  }
  return sum;
}

// Whether any cell the box touches holds coverage: exact (coverage sums are multiples of 1/4).
bool any_coverage(const SummedAreaTable& alpha, const AxisTaps& xs, const AxisTaps& ys) {
  return alpha.replicate_box_sum(xs.first_cell, ys.first_cell, xs.last_cell, ys.last_cell) > 0;
}

// The three boxes of radius R about pixel (x, y): box b spans kExtent[b] R along x and
// kExtent[2 - b] R along y.
struct ThreeBoxes {
  AxisTaps xs[3], ys[3];
  double inv_area[3];  // 1 / area in half-resolution cells

  ThreeBoxes() = default;
  ThreeBoxes(std::ptrdiff_t x, std::ptrdiff_t y, double radius, std::ptrdiff_t cells_x,
             std::ptrdiff_t cells_y) {
    for (int b = 0; b < 3; ++b) {
      xs[b] = full_res_taps(x, kExtent[b] * radius, cells_x);
      ys[b] = full_res_taps(y, kExtent[b] * radius, cells_y);
      inv_area[b] = 1.0 / (kExtent[b] * radius * kExtent[2 - b] * radius);
    }
  }
  // The mean of the three box means of `table`'s image.
  double mean(const SummedAreaTable& table) const {
    double sum = 0;
    for (int b = 0; b < 3; ++b) sum += box_integral(table, xs[b], ys[2 - b]) * inv_area[b];
    return sum / 3;
  }
  // Whether any cell of the union's bounding box (xs[0] x ys[0]) holds coverage.
  bool any_coverage(const SummedAreaTable& alpha) const {
    return tridiff::any_coverage(alpha, xs[0], ys[0]);
  }
};

// The mean radius of a layer's pixels in the square of half-extent `reach` about pixel (x, y),
// from its tables: [alpha] = α, [alpha + 1] = α R; clamped to [min_radius, reach]. False when
// the square holds no coverage.
bool layer_radius(const std::vector<SummedAreaTable>& layer, std::size_t alpha, std::ptrdiff_t x,
                  std::ptrdiff_t y, double reach, double min_radius, double& radius) {
  const AxisTaps xs = full_res_taps(x, reach, layer[alpha].width());
  const AxisTaps ys = full_res_taps(y, reach, layer[alpha].height());
  if (!any_coverage(layer[alpha], xs, ys)) return false;
  const double weight = box_integral(layer[alpha], xs, ys);
  if (!(weight / (reach * reach) > kMinCoverage)) return false;
  radius = std::clamp(box_integral(layer[alpha + 1], xs, ys) / weight, min_radius, reach);
  return true;
}

// One table per plane of `planes`.
std::vector<SummedAreaTable> build_tables(const Image& planes, int team) {
  std::vector<SummedAreaTable> tables;
  for (int c = 0; c < planes.channels(); ++c) tables.emplace_back(planes.plane(c), team);
  return tables;
}

// The half-resolution image of `planes` channels, plane k the 2 x 2 mean of value(k, x, y)
// (replicate border for odd sizes).
template <class Value>
Image half_resolution(std::ptrdiff_t width, std::ptrdiff_t height, int planes, int team,
                      const Value& value) {
  Image half((width + 1) / 2, (height + 1) / 2, planes);
#pragma omp parallel for num_threads(team) schedule(static)
  for (std::ptrdiff_t j = 0; j < half.height(); ++j) {
    const std::ptrdiff_t y0 = 2 * j, y1 = std::min(2 * j + 1, height - 1);
    for (std::ptrdiff_t i = 0; i < half.width(); ++i) {
      const std::ptrdiff_t x0 = 2 * i, x1 = std::min(2 * i + 1, width - 1);
      for (int k = 0; k < planes; ++k)
        half(i, j, k) =
            0.25f * ((value(k, x0, y0) + value(k, x1, y0)) + (value(k, x0, y1) + value(k, x1, y1)));
    }
  }
  return half;
}

// The tiles, with a margin for the half-resolution cells, and the output allocated.
TileMap prepare(Image& out, const DofFrame& frame, dof_detail::Stages& stages) {
  TileMap tiles(frame.coc(), frame.sharp_below(), TileMap::kDefaultTile, kHalfResMargin,
                frame.threads());
  out.reset(frame.width(), frame.height(), frame.channels());
  stages.end("classify tiles");
  return tiles;
}

std::string size_note(const Image& color) {
  return "half-resolution tables " + std::to_string((color.width() + 1) / 2) + " x " +
         std::to_string((color.height() + 1) / 2) + ", replicate border, 3 boxes a pixel";
}

// The two layers' tables at half resolution: per layer channels x α C, then α, then α R.
struct LayerTables {
  std::vector<SummedAreaTable> far, near;  // empty: the layer is left out
  std::size_t alpha = 0;                   // the index of α (the channel count)
  std::ptrdiff_t cells_x = 0, cells_y = 0;
};

LayerTables layer_tables(const DofFrame& frame, bool has_far, bool has_near) {
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  const int channels = color.channels(), team = frame.threads();
  const std::ptrdiff_t width = color.width(), height = color.height();
  const FocusTest focus = frame.focus();
  LayerTables tables;
  tables.alpha = std::size_t(channels);
  tables.cells_x = (width + 1) / 2;
  tables.cells_y = (height + 1) / 2;
  if (has_far)
    tables.far = build_tables(half_resolution(width, height, channels + 2, team,
                                              [&](int k, std::ptrdiff_t x, std::ptrdiff_t y) {
                                                const float c = coc(x, y);
                                                if (!focus.is_far(c)) return 0.f;
                                                if (k < channels) return color(x, y, k);
                                                return k == channels ? 1.f : 0.5f * c;
                                              }),
                              team);
  if (has_near)
    tables.near = build_tables(half_resolution(width, height, channels + 2, team,
                                               [&](int k, std::ptrdiff_t x, std::ptrdiff_t y) {
                                                 const float c = coc(x, y);
                                                 if (!focus.is_near(c)) return 0.f;
                                                 if (k < channels) return color(x, y, k);
                                                 return k == channels ? 1.f : -0.5f * c;
                                               }),
                               team);
  return tables;
}

// sat-layers at pixel (x, y) of `tile`: the base (the pixel, or the far layer), the near layer
// over it, renormalised by the union of their coverages.
void composite_pixel(Image& out, const DofFrame& frame, const LayerTables& tables, std::ptrdiff_t x,
                     std::ptrdiff_t y, const TileInfo& tile) {
  const Image& color = frame.color();
  const int channels = color.channels();
  const FocusTest focus = frame.focus();
  const float sharp_below = focus.sharp_below;
  const std::vector<SummedAreaTable>& far = tables.far;
  const std::vector<SummedAreaTable>& near = tables.near;
  const std::size_t alpha = tables.alpha;
  const std::ptrdiff_t cells_x = tables.cells_x, cells_y = tables.cells_y;
  const bool has_near = !near.empty();
  const float c = frame.coc()(x, y);
  const double radius = 0.5 * std::fabs(double(c));
  const bool sharp = focus.is_sharp(c);
  // The base: the pixel itself, or the far layer normalised by its coverage, read with
  // the pixel's radius, or behind a near pixel with the radius of the far pixels around.
  ThreeBoxes back;
  double back_cover = 0;
  if (!sharp && !far.empty()) {
    double back_radius = radius;
    const bool found = c > 0 || layer_radius(far, alpha, x, y, tile.reach_radius,
                                             0.5 * double(sharp_below), back_radius);
    if (found) {
      back = ThreeBoxes(x, y, back_radius, cells_x, cells_y);
      if (back.any_coverage(far[alpha])) back_cover = back.mean(far[alpha]);
    }
  }
  const bool has_base = sharp || back_cover > kMinCoverage;
  // The near layer, in tiles that a near disc reaches.
  ThreeBoxes front;
  double front_cover = 0;
  double front_radius = 0;
  if (has_near && tile.near_reach_radius > 0 &&
      layer_radius(near, alpha, x, y, tile.near_reach_radius, 0.5 * double(sharp_below),
                   front_radius)) {
    front = ThreeBoxes(x, y, front_radius, cells_x, cells_y);
    if (front.any_coverage(near[alpha])) front_cover = std::min(front.mean(near[alpha]), 1.0);
  }
  const bool has_front = front_cover > kMinCoverage;
  // Near over the base with the coverages as alphas, renormalised by their union (what
  // `scatter` does): continuous where the far coverage behind a near edge fades out.
  const double base_alpha = sharp ? 1.0 : has_base ? std::min(back_cover, 1.0) : 0.0;
  const double total = front_cover + (1 - front_cover) * base_alpha;
  for (int ch = 0; ch < channels; ++ch) {
    const std::size_t k = std::size_t(ch);
    double v = sharp ? double(color(x, y, ch)) : 0.0;
    if (!sharp && has_base) v = back.mean(far[k]) / back_cover;
    if (has_front)
      v = (front.mean(near[k]) + (1 - front_cover) * (has_base ? base_alpha * v : 0.0)) / total;
    // Neither layer in reach happens only through rounding: keep the input.
    out(x, y, ch) = has_base || has_front ? static_cast<float>(v) : color(x, y, ch);
  }
}

}  // namespace

namespace dof_detail {

void run_sat(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  const int channels = color.channels(), team = frame.threads();
  Stages stages(report);
  const TileMap tiles = prepare(out, frame, stages);
  const TiledGather gather(tiles, settings.skip_in_focus, team);
  report.skipped_fraction = gather.skipped_fraction();

  std::vector<SummedAreaTable> tables;
  if (tiles.max_radius() > 0 || !gather.skip())
    tables = build_tables(
        half_resolution(color.width(), color.height(), channels, team,
                        [&](int c, std::ptrdiff_t x, std::ptrdiff_t y) { return color(x, y, c); }),
        team);
  stages.end("half-resolution tables");

  const std::ptrdiff_t cells_x = (color.width() + 1) / 2, cells_y = (color.height() + 1) / 2;
  const FocusTest focus = frame.focus();
  gather.for_each_pixel([&](std::ptrdiff_t x, std::ptrdiff_t y, const TileInfo&) {
    const float c = coc(x, y);
    if (focus.is_sharp(c)) {
      for (int ch = 0; ch < channels; ++ch) out(x, y, ch) = color(x, y, ch);
      return;
    }
    const ThreeBoxes boxes(x, y, 0.5 * std::fabs(double(c)), cells_x, cells_y);
    for (int ch = 0; ch < channels; ++ch)
      out(x, y, ch) = static_cast<float>(boxes.mean(tables[std::size_t(ch)]));
  });
  gather.copy_the_rest(out, color);
  stages.end("gather");
  report.layered = false;
  report.notes = size_note(color);
  if (settings.progress) settings.progress(1.0);
}

void run_sat_layers(Image& out, const DofFrame& frame, const DofOptions& settings,
                    DofReport& report) {
  const Image& color = frame.color();
  Stages stages(report);
  const TileMap tiles = prepare(out, frame, stages);
  const TiledGather gather(tiles, settings.skip_in_focus, frame.threads());
  report.skipped_fraction = gather.skipped_fraction();
  const bool has_near = tiles.has_near();
  const LayerTables tables = layer_tables(frame, tiles.has_far() || !gather.skip(), has_near);
  stages.end("half-resolution tables");

  gather.for_each_pixel([&](std::ptrdiff_t x, std::ptrdiff_t y, const TileInfo& tile) {
    composite_pixel(out, frame, tables, x, y, tile);
  });
  gather.copy_the_rest(out, color);
  stages.end("gather and composite");
  report.layered = has_near;
  report.notes = size_note(color) +
                 (has_near ? ", near layer over far layer" : ", no near pixel: far layer only");
  if (settings.progress) settings.progress(1.0);
}

}  // namespace dof_detail
}  // namespace tridiff
