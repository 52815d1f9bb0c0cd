// The `scatter` method: the slow reference depth of field that the other methods are measured
// against (issue 5; the forward-mapped "splatting" DOF of seed 000 §3.3 / §6). Every pixel
// splats its circle of confusion, and the splats are composited by depth.
//
// The disc. A pixel of signed CoC c (pixels; negative in front of the focus) spreads over a disc
// of radius r = |c| / 2 with an anti-aliased edge: the offset (dx, dy) from its centre gets the
// coverage min(1, r + 1/2 - sqrt(dx² + dy²)) when positive — a radial ramp one pixel wide centred
// on the disc's rim, so the support is the open disc of radius r + 1/2. The weights are the
// coverages divided by their sum (area-normalised: a splat's weights sum to 1, so a pixel's
// energy is conserved). A pixel with |c| < max(1, DofOptions::in_focus_coc_px) is a point: it
// keeps its own value with weight exactly 1.
//
// The frame border is a mirror: the part of a disc that leaves the frame is reflected back into
// it (coordinate -1 is 0, -2 is 1, ..., W is W - 1; repeatedly for discs larger than the frame),
// as if the image continued as its mirror image. Every weight therefore lands in the frame.
//
// Compositing by depth. The signed CoC is the depth key (more negative = nearer). Pixels are
// sorted into layers one pixel of CoC wide (layer k holds floor(c) = k) and the layers are taken
// front to back. Within a layer the splats add up premultiplied colour C and coverage A (the sum
// of the weights that reach the output pixel); where A > 1 the layer is normalised (C /= A, A = 1),
// then it goes "over" what lies behind it with alpha = min(A, 1):
//     out += T · C,   T *= 1 - alpha        (T, the transmittance, starts at 1)
// so a blurred near object covers what is behind it while a sharp near object (points of weight
// 1) hides the far splats completely. Finally out /= 1 - T where 1 - T < 1: the far splats are
// normalised by the accumulated coverage (behind a semi-transparent near edge nothing of the
// hidden background is known, so what is known is rescaled).
//
// What holds exactly (up to float rounding):
//  - Uniform CoC (one layer): every output pixel's coverage is 1 — the mirror-folded discs of all
//    pixels tile the frame, because a disc is symmetric under each axis reflection — so out is the
//    sum of the splats, the convolution of the mirror-extended image with the disc, and the total
//    energy per channel equals the input's.
//  - Every pixel in focus: out is the input, bit for bit.
//  - A pixel whose own layer is the first to reach it with coverage >= 1 (a sharp pixel that no
//    nearer splat covers) keeps its value bit for bit.
//  - A constant colour stays constant for any CoC map (the "over" weights telescope to 1 - T).
// With several layers energy is not conserved (occlusion hides some of it, the final
// normalisation rescales), which is the point of depth compositing. Splitting a continuous depth
// into 1-px layers treats the coverages of neighbouring layers as uncorrelated — the usual
// discretisation of layered compositing.
//
// Parallel: each thread owns a band of output rows and, for every layer, splats the part of every
// disc that falls in its band, then composites its band. No two threads write the same pixel and
// every pixel receives its contributions in the same order (sources in raster order within a
// layer), so the result does not depend on the number of threads.
//
// Lens character (issue 26). The disc above is the circular aperture; with DofOptions::aperture
// (blades, rotation, roundness) or aperture_image each pixel's splat takes that footprint
// instead (aperture_footprint.hpp: the polygon's anti-aliased rim is the same ramp on the signed
// distance to the rim along the ray; a kernel image is box-filtered or bilinearly resampled to
// the CoC diameter), area-normalised the same way; the circle keeps the code above, bit for bit.
// Highlights (DofOptions::highlight_threshold, highlight_gain): an out-of-focus pixel whose
// largest channel m exceeds the threshold t is scaled by (t + gain · (m - t)) / m before it is
// splatted (HighlightBoost: the hue is kept). A sharp pixel is not boosted: it is not spread,
// and the method keeps it bit for bit.
//
// Skipping (DofOptions::skip_in_focus): 32 x 32 tiles that no disc reaches (after the mirror
// fold) hold only points, whose output is their input; they are copied and left out of the layer
// passes. This changes no bit.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"
#include "tridiff/threads.hpp"
#include "aperture_footprint.hpp"
#include "stage_clock.hpp"
#include "frame.hpp"
#include "row_bands.hpp"
#include "tiled_gather.hpp"  // Stages

namespace tridiff {
namespace {

using dof_detail::ApertureFootprint;
using dof_detail::fold;
using dof_detail::HighlightBoost;
using dof_detail::largest_channel;
using dof_detail::Stages;

constexpr std::ptrdiff_t kTile = 32;
constexpr float kMaxDiameter = 16384.f;  // px

// A range [lo, hi] that contains fold(x) for every x in [a, b], where a < n and b >= 0.
std::pair<std::ptrdiff_t, std::ptrdiff_t> folded_range(std::ptrdiff_t a, std::ptrdiff_t b,
                                                       std::ptrdiff_t n) {
  if (a < -n || b >= 2 * n) return {0, n - 1};
  std::ptrdiff_t lo = std::max<std::ptrdiff_t>(a, 0), hi = std::min(b, n - 1);
  if (a < 0) hi = std::max(hi, std::min(n - 1, -1 - a));
  if (b >= n) lo = std::min(lo, std::max<std::ptrdiff_t>(0, 2 * n - 1 - b));
  return {lo, hi};
}

// The disc of one pixel: outer = r + 1/2 bounds the support, reach the largest |dy| (and |dx|)
// with a positive coverage, inv_sum 1 / (sum of the coverages). A point has reach -1.
struct Disc {
  double inv_sum = 1;
  float outer = 0;
  std::int32_t reach = -1;
};

inline double coverage(double outer, std::ptrdiff_t dx, std::ptrdiff_t dy) {
  return std::min(1.0, outer - std::sqrt(double(dx * dx + dy * dy)));
}

Disc make_disc(float coc, FocusTest focus) {
  Disc disc;
  const double diameter = std::fabs(double(coc));
  if (focus.is_sharp(coc)) return disc;
  disc.outer = static_cast<float>(0.5 * diameter + 0.5);
  disc.reach = static_cast<std::int32_t>(std::ceil(disc.outer)) - 1;
  // The sum of the coverages over one quadrant, by symmetry: the centre once, the axes twice
  // (two half-axes each), the rest four times.
  double sum = 0;
  for (std::ptrdiff_t dy = 0; dy <= disc.reach; ++dy) {
    const std::ptrdiff_t hx = dof_detail::footprint_row_half_width(disc.outer, dy);
    for (std::ptrdiff_t dx = 0; dx <= hx; ++dx) {
      const double c = coverage(disc.outer, dx, dy);
      if (c > 0) sum += c * ((dx == 0 ? 1 : 2) * (dy == 0 ? 1 : 2));
    }
  }
  disc.inv_sum = 1.0 / sum;  // sum >= 1: the centre's coverage is 1 for a diameter >= 1
  return disc;
}

// The same for a shaped aperture; a kernel image whose resampled weights vanish (a tiny CoC
// falling between its bright cells) leaves a point.
Disc make_shaped_disc(float coc, FocusTest focus, const ApertureFootprint& footprint) {
  Disc disc;
  const double diameter = std::fabs(double(coc));
  if (focus.is_sharp(coc)) return disc;
  const double sum = footprint.sum(diameter);
  if (!(sum > 0)) return disc;
  disc.outer = footprint.outer(diameter);
  disc.reach = static_cast<std::int32_t>(dof_detail::footprint_reach(disc.outer));
  disc.inv_sum = 1.0 / sum;
  return disc;
}

// The depth layer of a signed CoC: floor(c), more negative = nearer.
inline std::int32_t layer_key(float coc) {
  return static_cast<std::int32_t>(std::floor(std::clamp(double(coc), -1e9, 1e9)));
}

struct Box {
  std::ptrdiff_t x0, y0, x1, y1;  // [x0, x1) x [y0, y1); empty when x0 >= x1
  void add(std::ptrdiff_t x, std::ptrdiff_t y) {
    x0 = std::min(x0, x);
    x1 = std::max(x1, x + 1);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y + 1);
  }
};

// A disc beyond kMaxDiameter px, or splats adding up to more than kMaxSplatWeights (SplatWork),
// would take hours: refused rather than clamped silently, naming the pixel.
void refuse_what_takes_too_long(const DofFrame& frame) {
  if (frame.width() * frame.height() > std::numeric_limits<std::int32_t>::max())
    throw InvalidArgument("color", "has more than 2^31 pixels");
  const ConstPlane coc = frame.coc();
  if (frame.max_abs_coc() > kMaxDiameter)
    for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
      for (std::ptrdiff_t x = 0; x < coc.width(); ++x)
        if (std::fabs(coc(x, y)) > kMaxDiameter)
          throw InvalidArgument("coc", "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                           ") has |CoC| " + std::to_string(std::fabs(coc(x, y))) +
                                           " px; the scatter reference takes at most " +
                                           std::to_string(int(kMaxDiameter)) + " px");
  // Every pixel at the largest CoC: a bound that mostly settles it without a pass.
  const double bound =
      dof_detail::splat_weights(frame.max_abs_coc()) * double(frame.width() * frame.height());
  if (bound > dof_detail::kMaxSplatWeights) {
    const FocusTest focus = frame.focus();
    dof_detail::SplatWork work;
    for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
      for (std::ptrdiff_t x = 0; x < coc.width(); ++x)
        if (!focus.is_sharp(coc(x, y))) work.add(coc(x, y), x, y);
    work.require_within_budget("the scatter reference's splats",
                               "lower the CoC, or use a method whose cost does not grow with it "
                               "(adi, sat, pyramid-layers; bokeh splats only the highlights)");
  }
}

// 1. Every pixel's disc (its normaliser: a sum over the whole disc, computed once).
std::vector<Disc> make_discs(const DofFrame& frame, const ApertureFootprint& footprint) {
  const ConstPlane coc = frame.coc();
  const std::ptrdiff_t width = frame.width(), height = frame.height();
  const FocusTest focus = frame.focus();
  std::vector<Disc> discs(std::size_t(width * height));
#pragma omp parallel for num_threads(frame.threads()) schedule(static)
  for (std::ptrdiff_t y = 0; y < height; ++y) {
    const auto disc_of = [&](float c) {
      return footprint.is_circle() ? make_disc(c, focus) : make_shaped_disc(c, focus, footprint);
    };
    float last_coc = 0;
    Disc last = disc_of(0.f);
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const float c = std::fabs(coc(x, y));
      if (c != last_coc) {
        last = disc_of(c);
        last_coc = c;
      }
      discs[std::size_t(y * width + x)] = last;
    }
  }
  return discs;
}

// 2. The kTile squares that some disc reaches after the mirror fold (all of them without
// skipping), and the pixels of the others.
struct WorkedTiles {
  std::ptrdiff_t tiles_x = 0;
  std::vector<char> worked;
  std::ptrdiff_t skipped = 0;
  bool at(std::ptrdiff_t x, std::ptrdiff_t y) const {
    return worked[std::size_t(y / kTile * tiles_x + x / kTile)] != 0;
  }
};

WorkedTiles worked_tiles(const DofFrame& frame, const std::vector<Disc>& discs, bool skip) {
  const std::ptrdiff_t width = frame.width(), height = frame.height();
  WorkedTiles tiles;
  tiles.tiles_x = (width + kTile - 1) / kTile;
  const std::ptrdiff_t tiles_x = tiles.tiles_x, tiles_y = (height + kTile - 1) / kTile;
  std::vector<char>& worked = tiles.worked;
  worked.assign(std::size_t(tiles_x * tiles_y), skip ? 0 : 1);
  if (skip) {
    std::vector<std::ptrdiff_t> tile_reach(worked.size(), -1);
#pragma omp parallel for num_threads(frame.threads()) schedule(static)
    for (std::ptrdiff_t t = 0; t < tiles_x * tiles_y; ++t) {
      const std::ptrdiff_t tx = t % tiles_x * kTile, ty = t / tiles_x * kTile;
      for (std::ptrdiff_t y = ty; y < std::min(ty + kTile, height); ++y)
        for (std::ptrdiff_t x = tx; x < std::min(tx + kTile, width); ++x)
          tile_reach[t] =
              std::max<std::ptrdiff_t>(tile_reach[t], discs[std::size_t(y * width + x)].reach);
    }
    for (std::ptrdiff_t t = 0; t < tiles_x * tiles_y; ++t) {
      const std::ptrdiff_t reach = tile_reach[t];
      if (reach < 0) continue;
      const std::ptrdiff_t tx = t % tiles_x * kTile, ty = t / tiles_x * kTile;
      const auto [x0, x1] =
          folded_range(tx - reach, std::min(tx + kTile, width) - 1 + reach, width);
      const auto [y0, y1] =
          folded_range(ty - reach, std::min(ty + kTile, height) - 1 + reach, height);
      for (std::ptrdiff_t j = y0 / kTile; j <= y1 / kTile; ++j)
        for (std::ptrdiff_t i = x0 / kTile; i <= x1 / kTile; ++i) worked[j * tiles_x + i] = 1;
    }
  }
  for (std::ptrdiff_t t = 0; t < tiles_x * tiles_y; ++t)
    if (!worked[t])
      tiles.skipped += (std::min(t % tiles_x * kTile + kTile, width) - t % tiles_x * kTile) *
                       (std::min(t / tiles_x * kTile + kTile, height) - t / tiles_x * kTile);
  return tiles;
}

// 3. The sources of the worked tiles sorted into depth layers, raster order within a layer:
// layer l is sources[start[l] ... start[l + 1]).
struct DepthLayers {
  std::vector<std::pair<std::int32_t, std::int32_t>> sources;  // (layer key, pixel index)
  std::vector<std::size_t> start;
  std::size_t count() const { return start.size() - 1; }
};

DepthLayers sort_into_layers(const DofFrame& frame, const WorkedTiles& tiles) {
  const ConstPlane coc = frame.coc();
  const std::ptrdiff_t width = frame.width(), height = frame.height();
  DepthLayers layers;
  auto& sources = layers.sources;
  sources.reserve(std::size_t(width * height - tiles.skipped));
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x)
      if (tiles.at(x, y)) sources.emplace_back(layer_key(coc(x, y)), std::int32_t(y * width + x));
  std::sort(sources.begin(), sources.end());
  for (std::size_t i = 0; i < sources.size(); ++i)
    if (i == 0 || sources[i].first != sources[i - 1].first) layers.start.push_back(i);
  layers.start.push_back(sources.size());
  return layers;
}

// One depth layer being splatted: premultiplied colour (channels planes), then coverage, in
// double — thousands of similar small weights added to a float drift by a systematic rounding
// (1e-4 for D = 130).
struct LayerSums {
  std::ptrdiff_t width;
  std::size_t plane_size;
  std::vector<double> values;
  double* cover;

  LayerSums(std::ptrdiff_t w, std::ptrdiff_t h, int channels)
      : width(w),
        plane_size(std::size_t(w * h)),
        values(plane_size * std::size_t(channels + 1), 0.0),
        cover(values.data() + plane_size * std::size_t(channels)) {}
  std::size_t at(std::ptrdiff_t x, std::ptrdiff_t y) const { return std::size_t(y * width + x); }
};

// Refuses a gain that overflows a float on an out-of-focus pixel (a sharp one is not boosted).
void require_finite_boosts(const DofFrame& frame, const HighlightBoost& boost) {
  if (!boost.active()) return;
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  const FocusTest focus = frame.focus();
  for (std::ptrdiff_t y = 0; y < frame.height(); ++y)
    for (std::ptrdiff_t x = 0; x < frame.width(); ++x) {
      if (!focus.is_sharp(coc(x, y))) boost.require_finite(largest_channel(color, x, y), x, y);
    }
}

// The colour that pixel (x, y), out of focus, spreads: boosted when it is a highlight.
void source_colour(const Image& color, std::ptrdiff_t x, std::ptrdiff_t y,
                   const HighlightBoost& boost, std::vector<double>& lanes) {
  const int channels = color.channels();
  for (int c = 0; c < channels; ++c) lanes[std::size_t(c)] = double(color(x, y, c));
  if (!boost.active()) return;
  const double factor = boost.factor(largest_channel(color, x, y));
  for (int c = 0; c < channels; ++c) lanes[std::size_t(c)] *= factor;
}

// Adds weight w of a source whose colour is `lanes` to pixels [x0, x1] of one row: the fully
// covered run of a circle's row (coverage exactly 1, no fold). The same arithmetic, pixel for
// pixel, as the general loop of splat_band, in a loop that vectorises.
void add_solid_run(double* colour_row, double* cover_row, std::size_t plane_size,
                   const std::vector<double>& lanes, double w, std::ptrdiff_t x0,
                   std::ptrdiff_t x1) {
  for (std::size_t c = 0; c < lanes.size(); ++c) {
    double* values = colour_row + plane_size * c;
    const double add = w * lanes[c];
    for (std::ptrdiff_t x = x0; x <= x1; ++x) values[x] = cover_row[x] == 0 ? add : values[x] + add;
  }
  for (std::ptrdiff_t x = x0; x <= x1; ++x) cover_row[x] += w;
}

// 4a. Splats the part of every disc of layer l that falls in rows [band0, band1); returns the
// box of the pixels it touched. `covers(diameter, outer, dx, dy)` is the footprint's coverage;
// for the circle, the run of each row that it covers fully (ApertureFootprint::solid_half_width)
// is added by add_solid_run.
template <class Covers>
Box splat_band(const DofFrame& frame, const std::vector<Disc>& discs, const DepthLayers& layers,
               std::size_t l, std::ptrdiff_t band0, std::ptrdiff_t band1, LayerSums& sums,
               std::vector<double>& lanes, const HighlightBoost& boost,
               const ApertureFootprint& footprint, Covers covers) {
  const Image& color = frame.color();
  const std::ptrdiff_t width = frame.width(), height = frame.height();
  const int channels = frame.channels();
  const std::size_t plane_size = sums.plane_size;
  double* const cover = sums.cover;
  Box box{width, height, 0, 0};
  for (std::size_t s = layers.start[l]; s < layers.start[l + 1]; ++s) {
    const std::ptrdiff_t index = layers.sources[s].second;
    const std::ptrdiff_t qx = index % width, qy = index / width;
    const Disc& disc = discs[std::size_t(index)];
    if (disc.reach < 0) {  // a point: weight 1 at its own pixel
      if (qy < band0 || qy >= band1) continue;
      const std::size_t i = sums.at(qx, qy);
      const double a = cover[i];
      for (int c = 0; c < channels; ++c) {
        double& v = sums.values[i + plane_size * std::size_t(c)];
        v = a == 0 ? double(color(qx, qy, c)) : v + double(color(qx, qy, c));
      }
      cover[i] = a + 1.0;
      box.add(qx, qy);
      continue;
    }
    const std::ptrdiff_t reach = disc.reach;
    if (qy - reach >= 0 && qy + reach < height && (qy + reach < band0 || qy - reach >= band1))
      continue;  // no fold, and the disc's rows miss the band
    source_colour(color, qx, qy, boost, lanes);
    const double diameter = std::fabs(double(frame.coc()(qx, qy)));
    for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy) {
      const std::ptrdiff_t ty = fold(qy + dy, height);
      if (ty < band0 || ty >= band1) continue;
      const std::ptrdiff_t hx = dof_detail::footprint_row_half_width(disc.outer, dy);
      if (hx < 0) continue;
      const bool inside = qx - hx >= 0 && qx + hx < width;
      double* cover_row = cover + sums.at(0, ty);
      double* colour_row = sums.values.data() + sums.at(0, ty);
      const auto splat_pixels = [&](std::ptrdiff_t from, std::ptrdiff_t to) {
        for (std::ptrdiff_t dx = from; dx <= to; ++dx) {
          const double cov = covers(diameter, disc.outer, dx, dy);
          if (!(cov > 0)) continue;
          const double w = cov * disc.inv_sum;
          const std::ptrdiff_t tx = inside ? qx + dx : fold(qx + dx, width);
          const double a = cover_row[tx];
          for (int c = 0; c < channels; ++c) {
            double& v = colour_row[std::size_t(tx) + plane_size * std::size_t(c)];
            v = a == 0 ? w * lanes[std::size_t(c)] : v + w * lanes[std::size_t(c)];
          }
          cover_row[tx] = a + w;
          box.add(tx, ty);
        }
      };
      // A circle's row without a fold: its rims, and between them the run of coverage 1.
      const std::ptrdiff_t solid = inside ? footprint.solid_half_width(disc.outer, dy) : -1;
      if (solid < 0) {
        splat_pixels(-hx, hx);
        continue;
      }
      splat_pixels(-hx, -solid - 1);
      add_solid_run(colour_row, cover_row, plane_size, lanes, disc.inv_sum, qx - solid, qx + solid);
      box.add(qx - solid, ty);
      box.add(qx + solid, ty);
      splat_pixels(solid + 1, hx);
    }
  }
  return box;
}

// 4b. Composites the splatted layer "over" what is in front of it on `box`, and clears it.
void composite_box(const Box& box, LayerSums& sums, Image& out, Plane trans) {
  const int channels = out.channels();
  const std::size_t plane_size = sums.plane_size;
  for (std::ptrdiff_t y = box.y0; y < box.y1; ++y) {
    double* cover_row = sums.cover + sums.at(0, y);
    double* colour_row = sums.values.data() + sums.at(0, y);
    float* trans_row = trans.row(y);
    for (std::ptrdiff_t x = box.x0; x < box.x1; ++x) {
      const double a = cover_row[x];
      if (a == 0) continue;
      const float t = trans_row[x];
      if (t != 0) {
        for (int c = 0; c < channels; ++c) {
          const double sum = colour_row[std::size_t(x) + plane_size * std::size_t(c)];
          const float v = static_cast<float>(a > 1 ? sum / a : sum);
          out(x, y, c) = t == 1 ? v : out(x, y, c) + t * v;
        }
        trans_row[x] = a >= 1 ? 0.f : static_cast<float>(t * (1.0 - a));
      }
      cover_row[x] = 0;
      for (int c = 0; c < channels; ++c)
        colour_row[std::size_t(x) + plane_size * std::size_t(c)] = 0;
    }
  }
}

// 4c. Normalises rows [band0, band1) by the accumulated coverage; copies the skipped tiles.
void finish_band(const DofFrame& frame, const WorkedTiles& tiles, ConstPlane trans,
                 std::ptrdiff_t band0, std::ptrdiff_t band1, Image& out) {
  const Image& color = frame.color();
  const int channels = frame.channels();
  for (std::ptrdiff_t y = band0; y < band1; ++y)
    for (std::ptrdiff_t x = 0; x < frame.width(); ++x) {
      if (!tiles.at(x, y)) {
        for (int c = 0; c < channels; ++c) out(x, y, c) = color(x, y, c);
        continue;
      }
      const float covered = 1.f - trans(x, y);
      if (covered < 1 && covered > 0)
        for (int c = 0; c < channels; ++c) out(x, y, c) /= covered;
    }
}

}  // namespace

namespace dof_detail {

void run_scatter(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  refuse_what_takes_too_long(frame);
  const std::ptrdiff_t width = frame.width(), height = frame.height();
  const int channels = frame.channels();
  Stages stages(report);
  const ApertureFootprint footprint(settings);
  const HighlightBoost boost{settings.highlight_threshold, settings.highlight_gain};
  require_finite_boosts(frame, boost);
  const std::vector<Disc> discs = make_discs(frame, footprint);
  const WorkedTiles tiles = worked_tiles(frame, discs, settings.skip_in_focus);
  const DepthLayers layers = sort_into_layers(frame, tiles);
  stages.end("discs and layers");

  // 4. Splat and composite, layer by layer, each thread in its band of rows.
  out.reset(width, height, channels);
  LayerSums sums(width, height, channels);
  Image transmit(width, height, 1);
  for (std::ptrdiff_t y = 0; y < height; ++y) std::fill_n(transmit.plane(0).row(y), width, 1.f);
  const Plane trans = transmit.plane(0);
  for_each_row_band(
      height, frame.threads(), [&](std::ptrdiff_t band0, std::ptrdiff_t band1, int thread) {
        std::vector<double> lanes(static_cast<std::size_t>(channels));
        for (std::size_t l = 0; l < layers.count() && band0 < band1; ++l) {
          const Box box =
              footprint.is_circle()
                  ? splat_band(frame, discs, layers, l, band0, band1, sums, lanes, boost, footprint,
                               [](double, float outer, std::ptrdiff_t dx, std::ptrdiff_t dy) {
                                 return coverage(outer, dx, dy);
                               })
                  : splat_band(frame, discs, layers, l, band0, band1, sums, lanes, boost, footprint,
                               [&footprint](double diameter, float outer, std::ptrdiff_t dx,
                                            std::ptrdiff_t dy) {
                                 return footprint.coverage(diameter, outer, dx, dy);
                               });
          composite_box(box, sums, out, trans);
          if (thread == 0 && settings.progress)
            settings.progress(0.99 * double(l + 1) / double(layers.count()));
        }
        finish_band(frame, tiles, trans, band0, band1, out);
      });
  stages.end("splat and composite");
  report.skipped_fraction = double(tiles.skipped) / double(width * height);
  report.notes = std::to_string(layers.count()) + " depth layers of 1 px CoC";
  if (settings.progress) settings.progress(1.0);
}

}  // namespace dof_detail
}  // namespace tridiff
