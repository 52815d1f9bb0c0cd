// The `pyramid-layers` method: layered depth of field, each depth layer blurred uniformly with
// Kraus's quasi-convolution pyramid and the layers composited front to back (seed 001 §2.3, the
// layered methods of Scofield, Schedl and Kraus & Strengert; §3.5, the pyramid; §4.5, the
// quasi-convolution pyramid in a layered DOF framework).
//
// Algorithm.
//  1. Layers by signed CoC c (a diameter in pixels, negative in front of the focus). A pixel
//     with |c| < t = max(1, in_focus_coc_px) belongs wholly to the sharp layer, which is never
//     blurred. Each side of the focus (near, far) whose largest |c| is D_max >= t gets n layers
//     of diameters D_k = D_max q^(k - n), k = 1..n, q = kLayerRatio, n the smallest count with
//     D_1 < q t: the layers span the CoC range present in the frame, and a frame with small CoCs
//     gets few of them. D_max per side comes from one reduction over the CoC (it sizes the
//     TileMap's margin, see Skipping, so it is needed before the map); the map's
//     has_near() / has_far() switch a side off. The sharp layer is D_0 = 0 on both sides.
//  2. Soft edges: a pixel with D_k <= |c| < D_(k+1) is split between layers k and k + 1 with
//     weights linear in c^2, w_(k+1) = (c^2 - D_k^2) / (D_(k+1)^2 - D_k^2): the mix of the two
//     blurs has the variance c^2/16 of the pixel's own disc, and a pixel's weight moves
//     continuously from one layer to the next, so no seam shows where the CoC crosses a layer
//     edge. A layer that no pixel has weight in is not built (nor blurred).
//  3. Each layer's colour premultiplied by its weight (coverage), and the coverage itself, are
//     blurred with pyramid_blur_sigma (PyramidFilter::quasi) at sigma = D_k / 4: a disc of
//     diameter D has variance D^2/16 per axis, so the Gaussian of the same variance. Below one
//     pyramid level (sigma < 1.41, D < 5.7 px) the pyramid library's own coarse smoothing runs
//     alone (pyramid_blur with 0 levels). Cost O(pixels) per layer and plane, for any CoC.
//  4. Front to back — near layers from the largest |c| down, the sharp layer, far layers from
//     the smallest |c| up — each layer (premultiplied C, coverage A) goes "over" what lies in
//     front of it: out += T C, T *= 1 - min(A, 1) (T, the transmittance, starts at 1; a first
//     contribution is stored, not added to 0, so that -0 survives). Finally out /= 1 - T where
//     0 < 1 - T < 1: normalised by the accumulated coverage.
//  This is the compositing of the `scatter` reference with a handful of Gaussian-blurred layers
//  in place of 1 px layers of disc splats.
//
// Skipping and its exactness. A layer's pyramid is global, but its kernel has compact support:
// at most 4.25 sigma + 1 px per axis (measured, sigma 0.25 to 300; 4 sigma in the limit). A
// pixel with weight in layer k + 1 has |c| >= D_(k+1) / 2 (q = 2: the layers are an octave), so
// its disc radius is r >= D_(k+1) / 4 and the frame's largest radius R >= D_(k+1) / 2. A TileMap
// whose margin is ceil(1.7 R) + 4 px therefore reaches r + 1/2 + 1.7 R + 4 >= 1.1 D_(k+1) + 4
// px, beyond every layer kernel that the pixel feeds. The method composites a blurred layer
// only on the reached tiles; that cuts nothing (what it would cut is zero), and it makes the
// rest exact by construction: on an unreached tile only the sharp layer is composited, which
// returns the input bit for bit. With skip_in_focus those tiles are copied
// (copy_unreached_tiles); without it they are composited the full way; the bits are the same.
// Whole passes the frame does not need are left out: no near pixel, no near layer; an empty
// layer is not blurred; an all-sharp frame blurs nothing.
//
// Deviations from the seed. Seed 001 §4.5 splits a rendered scene by depth with a function tied
// to the blur's effective size; here the split is by signed CoC, geometric with soft, variance-
// preserving edges. The pyramid's border is the blur library's replicate border, where the
// scatter reference mirrors: they differ within about 2 sigma of the frame's edge. The layer
// blur is a Gaussian of the disc's variance, not the disc: a blurred highlight is a soft blob,
// not a bokeh disc with a hard rim. The pyramid's sigma (pyramid_plan) is the nearest Gaussian in
// L1, not in variance: the measured impulse variance is 3-13 % below D^2/16 once a pyramid level
// is used (exact below), which the mapping sigma = D / 4 leaves as it is.
//
// Validity. Colour any finite values (checked), any channel count; CoC any finite value
// (checked); |c| beyond kMaxDiameter is blurred as kMaxDiameter (a Gaussian already far wider
// than any frame). The result is a convex combination of input colours (all weights are
// non-negative), so it stays within the input's range per channel and a constant colour stays
// constant, up to float rounding. Sharp pixels that no near layer reaches keep their input
// value bit for bit. Independent of the thread count.
//
// Known artifacts.
//  - Disocclusion: the seed describes no treatment of what is hidden behind a foreground object
//    (§2.3 names it as what distinguishes the layered methods; Kraus & Strengert fill it by
//    pyramidal interpolation, which seed 001 does not describe). Here, as in the scatter
//    reference, nothing of the hidden background is known: inside the blurred rim of a near
//    object the coverage is below 1 and the final normalisation rescales the near colour, so the
//    rim stays the object's colour instead of showing the background behind it.
//  - Layers are treated as uncorrelated: where a surface's CoC crosses a layer edge, its two
//    layers partly cover each other and the nearer one weighs more (smoothly; no seam).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "tridiff/blur/pyramid.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"
#include "tridiff/threads.hpp"
#include "stage_clock.hpp"
#include "frame.hpp"
#include "tiled_gather.hpp"

namespace tridiff {
namespace {

using dof_detail::Span;
using dof_detail::Stages;
using dof_detail::TiledGather;

constexpr PyramidFilter kFilter = PyramidFilter::quasi;
// Neighbouring layers differ by this factor in diameter. Against the scatter reference on
// procedural_scene(640, 360) the RMSE was 0.0355, 0.0355 and 0.0357 for 1.25, 1.5 and 2 (11, 8
// and 6 layers): the error is the Gaussian's shape against the disc's, not the layer spacing,
// since the variance-preserving split gives every pixel its own variance. So the fewest layers.
constexpr double kLayerRatio = 2.0;
constexpr double kMaxDiameter = 1e7;  // px; sigma 2.5e6, far beyond any frame
constexpr std::ptrdiff_t kTile = TileMap::kDefaultTile;
// The TileMap margin, kReachPerRadius x the largest radius + kReachPx: the pyramid kernels'
// support (see "Skipping" above) fits inside the reach with a few pixels to spare.
constexpr double kReachPerRadius = 1.7;
constexpr std::ptrdiff_t kReachPx = 4;

// One side of the focus: layer diameters d[0] = 0 (the sharp layer) and d[1..n] ascending.
std::vector<double> layer_diameters(double largest, double sharp_below) {
  std::vector<double> d{0.0};
  if (!(largest >= sharp_below)) return d;
  const int n =
      1 + static_cast<int>(std::floor(std::log(largest / sharp_below) / std::log(kLayerRatio)));
  for (int k = 1; k <= n; ++k) d.push_back(largest * std::pow(kLayerRatio, k - n));
  return d;
}

// Where |c| = a (>= the sharp threshold) falls among the side's layers: the lower layer k and
// the weight of layer k + 1, linear in a^2 (the mix keeps the disc's variance a^2 / 16).
struct Split {
  std::int16_t lower = 0;
  float upper = 0;
};

Split split(double a, const std::vector<double>& d) {
  const int n = static_cast<int>(d.size()) - 1;
  if (a >= d[std::size_t(n)]) return {static_cast<std::int16_t>(n), 0.f};
  int k = std::clamp(
      static_cast<int>(std::floor(n + std::log(a / d[std::size_t(n)]) / std::log(kLayerRatio))), 0,
      n - 1);
  while (k > 0 && a < d[std::size_t(k)]) --k;
  while (k + 1 < n && a >= d[std::size_t(k + 1)]) ++k;
  const double lo = d[std::size_t(k)] * d[std::size_t(k)];
  const double hi = d[std::size_t(k + 1)] * d[std::size_t(k + 1)];
  return {static_cast<std::int16_t>(k), static_cast<float>((a * a - lo) / (hi - lo))};
}

// A layer: side -1 (near), 0 (the sharp layer) or +1 (far), its index on that side and diameter.
struct Layer {
  int side = 0, index = 0;
  double diameter = 0;
};

// The weight of a pixel (side, split) in `layer`.
inline float weight(std::int8_t side, Split s, const Layer& layer) {
  if (layer.side == 0) return side == 0 ? 1.f : s.lower == 0 ? 1.f - s.upper : 0.f;
  if (side != layer.side) return 0.f;
  if (s.lower == layer.index) return 1.f - s.upper;
  return s.lower + 1 == layer.index ? s.upper : 0.f;
}

// The blur of one layer plane: the quasi-convolution pyramid at sigma, or below one level the
// pyramid library's smoothing alone.
void blur_layer_plane(ConstPlane in, Plane out, double sigma, int threads) {
  if (sigma >= pyramid_sigma(kFilter, 1))
    pyramid_blur_sigma(out, in, kFilter, sigma, Border::replicate, threads);
  else
    pyramid_blur(out, in, kFilter, 0, sigma, Border::replicate, threads);
}

// What the frame asks of the method: the tiles, every pixel's side and split, and the layers
// in use, front to back.
struct LayerPlan {
  std::optional<TileMap> tiles;
  bool nothing_blurred = false;  // skipping and no tile needs work
  std::vector<std::int8_t> side_of;
  std::vector<Split> split_of;
  std::vector<Layer> layers;
  int near_layers = 0, far_layers = 0;
};

LayerPlan plan_layers(const DofFrame& frame, bool skip) {
  const ConstPlane coc = frame.coc();
  const std::ptrdiff_t width = frame.width(), height = frame.height();
  const int team = frame.threads();
  const FocusTest focus = frame.focus();
  LayerPlan plan;
  double near_max = 0, far_max = 0;  // the largest out-of-focus |c| on each side
#pragma omp parallel for num_threads(team) schedule(static) reduction(max : near_max, far_max)
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const float c = coc(x, y);
      if (focus.is_near(c)) near_max = std::max(near_max, -double(c));
      if (focus.is_far(c)) far_max = std::max(far_max, double(c));
    }
  near_max = std::min(near_max, kMaxDiameter);
  far_max = std::min(far_max, kMaxDiameter);
  const double max_radius = std::max(near_max, far_max) / 2;
  const std::ptrdiff_t margin =
      static_cast<std::ptrdiff_t>(std::ceil(kReachPerRadius * max_radius)) + kReachPx;
  const TileMap& tiles = plan.tiles.emplace(coc, focus.sharp_below, kTile, margin, team);
  plan.nothing_blurred = skip && tiles.work_fraction() == 0;
  if (plan.nothing_blurred) return plan;
  // No near (far) pixel: no near (far) layer, and no pass for it.
  const double sharp_below = focus.sharp_below;
  const std::vector<double> near_d = layer_diameters(tiles.has_near() ? near_max : 0, sharp_below);
  const std::vector<double> far_d = layer_diameters(tiles.has_far() ? far_max : 0, sharp_below);

  const std::size_t pixels = std::size_t(width * height);
  plan.side_of.assign(pixels, 0);
  plan.split_of.resize(pixels);
  // used[side][k]: some pixel has weight in layer k of that side (near side 0, far side 1).
  std::vector<char> used_near(near_d.size(), 0), used_far(far_d.size(), 0);
#pragma omp parallel num_threads(team)
  {
    std::vector<char> local_near(near_d.size(), 0), local_far(far_d.size(), 0);
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        const float c = coc(x, y);
        if (focus.is_sharp(c)) continue;
        const std::size_t i = std::size_t(y * width + x);
        const bool near = c < 0;
        const double a = std::min(double(std::fabs(c)), kMaxDiameter);
        const Split s = split(a, near ? near_d : far_d);
        plan.side_of[i] = near ? -1 : 1;
        plan.split_of[i] = s;
        std::vector<char>& used = near ? local_near : local_far;
        if (s.upper < 1.f) used[std::size_t(s.lower)] = 1;
        if (s.upper > 0.f) used[std::size_t(s.lower + 1)] = 1;
      }
#pragma omp critical
    for (std::size_t k = 0; k < near_d.size(); ++k) used_near[k] |= local_near[k];
#pragma omp critical
    for (std::size_t k = 0; k < far_d.size(); ++k) used_far[k] |= local_far[k];
  }
  // Front to back: near from the largest |c| down, the sharp layer, far from the smallest up.
  for (std::size_t k = near_d.size() - 1; k >= 1; --k)
    if (used_near[k]) {
      plan.layers.push_back({-1, int(k), near_d[k]});
      ++plan.near_layers;
    }
  plan.layers.push_back({0, 0, 0.0});
  for (std::size_t k = 1; k < far_d.size(); ++k)
    if (used_far[k]) {
      plan.layers.push_back({1, int(k), far_d[k]});
      ++plan.far_layers;
    }
  return plan;
}

// The layer's weights as alpha (plane `channels`) and the colour premultiplied by them; then,
// for a blurred layer, its pyramid blur into `blurred`.
void premultiply_and_blur(const DofFrame& frame, const LayerPlan& plan, const Layer& layer,
                          Image& premult, Image& blurred) {
  const Image& color = frame.color();
  const std::ptrdiff_t width = color.width(), height = color.height();
  const int channels = color.channels(), team = frame.threads();
#pragma omp parallel for num_threads(team) schedule(static)
  for (std::ptrdiff_t y = 0; y < height; ++y) {
    float* alpha = premult.plane(channels).row(y);
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const std::size_t i = std::size_t(y * width + x);
      alpha[x] = weight(plan.side_of[i], plan.split_of[i], layer);
    }
    for (int c = 0; c < channels; ++c) {
      const float* in = color.plane(c).row(y);
      float* o = premult.plane(c).row(y);
#pragma omp simd
      for (std::ptrdiff_t x = 0; x < width; ++x) o[x] = alpha[x] * in[x];
    }
  }
  if (layer.side == 0) return;
  // One pyramid per plane and thread: the planes are independent, and a pyramid's many
  // small steps each open a parallel region that costs more than it gains on small levels.
  const int planes = channels + 1;
  const int outer = std::min(team, planes), inner = std::max(1, team / planes);
#pragma omp parallel for num_threads(outer) schedule(dynamic)
  for (int c = 0; c < planes; ++c)
    blur_layer_plane(premult.plane(c), blurred.plane(c), layer.diameter / 4, inner);
}

// "Over" of one layer (colour planes premultiplied, then alpha) onto row y of out, front to
// back: out += t C, t *= 1 - alpha, on the given spans.
void composite_row(const Image& source, Image& out, Plane transmit, std::ptrdiff_t y,
                   const std::vector<Span>& spans) {
  const int channels = out.channels();
  const float* alpha = source.plane(channels).row(y);
  float* t_row = transmit.row(y);
  for (const auto& [x0, x1] : spans)
    for (std::ptrdiff_t x = x0; x < x1; ++x) {
      const float a = std::min(alpha[x], 1.f), t = t_row[x];
      if (!(a > 0) || t == 0) continue;
      for (int c = 0; c < channels; ++c) {
        const float v = t * source.plane(c).row(y)[x];
        float& o = out.plane(c).row(y)[x];
        o = o == 0 ? v : o + v;  // a first contribution keeps its sign, -0 too
      }
      t_row[x] = t * (1 - a);
    }
}

// Divides by the accumulated coverage where it is partial.
void normalise(Image& out, ConstPlane transmit, int team) {
#pragma omp parallel for num_threads(team) schedule(static)
  for (std::ptrdiff_t y = 0; y < out.height(); ++y) {
    const float* t_row = transmit.row(y);
    for (int c = 0; c < out.channels(); ++c) {
      float* o = out.plane(c).row(y);
      for (std::ptrdiff_t x = 0; x < out.width(); ++x) {
        const float covered = 1 - t_row[x];
        if (covered > 0 && covered < 1) o[x] /= covered;
      }
    }
  }
}

}  // namespace

namespace dof_detail {

void run_pyramid_layers(Image& out, const DofFrame& frame, const DofOptions& settings,
                        DofReport& report) {
  const Image& color = frame.color();
  const std::ptrdiff_t width = color.width(), height = color.height();
  const int channels = color.channels(), team = frame.threads();
  const bool skip = settings.skip_in_focus;
  Stages stages(report);

  // 1. Tiles, the layers of each side from the CoC range present, every pixel's split.
  const LayerPlan plan = plan_layers(frame, skip);
  if (plan.nothing_blurred) {
    // Nothing out of focus: the sharp layer alone, which is the input (what the full path gives
    // bit for bit: weight 1, transmittance 1, no normalisation).
    out = color;
    stages.end("copy");
    report.skipped_fraction = 1;
    report.notes = "no pixel out of focus: copied";
    return;
  }
  stages.end("layers");
  const TiledGather gather(*plan.tiles, skip, team);
  // A blurred layer is composited on the tiles it may reach; the sharp layer everywhere
  // without skipping (with skipping the unreached tiles are copied at the end).
  const TiledGather reached(*plan.tiles, true, team);

  // 2. Per layer: premultiply, blur (not the sharp layer), composite "over".
  out.reset(width, height, channels);
  Image transmit(width, height, 1);
  const Plane trans = transmit.plane(0);
  for (std::ptrdiff_t y = 0; y < height; ++y) std::fill_n(trans.row(y), width, 1.f);
  Image premult(width, height, channels + 1), blurred;
  if (plan.near_layers + plan.far_layers > 0) blurred.reset(width, height, channels + 1);
  double blur_seconds = 0, composite_seconds = 0;
  for (std::size_t l = 0; l < plan.layers.size(); ++l) {
    const Layer& layer = plan.layers[l];
    const bool sharp = layer.side == 0;
    stages.restart();
    premultiply_and_blur(frame, plan, layer, premult, blurred);
    blur_seconds += stages.lap();
    const Image& source = sharp ? premult : blurred;
    reached.for_each_row([] { return 0; },
                         [&](std::ptrdiff_t y, const std::vector<Span>& spans, int) {
                           composite_row(source, out, trans, y, spans);
                         },
                         sharp && !skip);
    composite_seconds += stages.lap();
    if (settings.progress) settings.progress(0.99 * double(l + 1) / double(plan.layers.size()));
  }
  stages.end("premultiply and pyramids", blur_seconds);

  // 3. Normalise by the accumulated coverage; copy the tiles nothing reaches.
  stages.restart();
  normalise(out, trans, team);
  gather.copy_the_rest(out, color);
  stages.end("composite", composite_seconds);

  report.skipped_fraction = gather.skipped_fraction();
  report.layered = plan.near_layers > 0;
  char ratio[16];
  std::snprintf(ratio, sizeof ratio, "%g", kLayerRatio);
  report.notes = std::to_string(plan.near_layers) + " near + " + std::to_string(plan.far_layers) +
                 " far blurred layers (diameter ratio " + ratio +
                 ") + the sharp layer; quasi-convolution pyramids at sigma = D / 4";
  if (settings.progress) settings.progress(1.0);
}

}  // namespace dof_detail
}  // namespace tridiff
