// The `bokeh` method (issue 26, lens character): the fast diffusion for the body of the frame,
// the lens's exact disc where the depth is smooth and far, and the out-of-focus highlights
// splatted as shaped sprites — the shaped bokeh of `scatter` where it shows (on the bright
// points of light), at the cost of `adi` elsewhere.
//
// Highlights. The threshold t is DofOptions::highlight_threshold, or kAutoThreshold = 1 when it
// is infinite (none asked for): brighter than a diffuse white in linear light, so only light
// sources and their speculars. A highlight is a pixel that is out of focus (|CoC| >=
// DofFrame::sharp_below) and whose largest channel m exceeds t. It is split in two:
//  - the body keeps v · k t / m, k = kBodyKeeps (its largest channel set to k t, the hue kept),
//    and is blurred with the rest of the frame (run_body below: `adi`'s diffusion with 1.25
//    times its conductance, kBodySpread, and the disc where the CoC is smooth and far,
//    disc_body.hpp; layers pass through);
//  - the sprite carries the rest, the part above t boosted by the gain g (HighlightBoost):
//        excess = v · (k t + (1 - k) t + g · (m - t)) / m - v · k t / m
//               = v · ((1 - k) t + g · (m - t)) / m,
//    splatted with the aperture's footprint for its CoC (aperture_footprint.hpp, the same
//    weights as scatter's splat: anti-aliased, area-normalised, mirror-folded at the border).
// With g = 1 body + sprites carry exactly the input's energy (adi conserves it per row and
// column, the disc gather for a uniform CoC (its weights are symmetric and fold as a mirror),
// a sprite's weights sum to 1). A frame without highlights is the body alone.
//
// Depth. A sprite lies behind nearer geometry: its weight at a covered pixel p is multiplied
// by the visibility clamp(c_p - c_h + 2, 0, 1) of the signed CoCs (negative = near) of p and
// of the highlight: 1 where p is not nearer than the highlight by more than 1 px of CoC (the
// highlight's own surface, which may tilt, and everything behind it), 0 where it is nearer by
// 2 px or more, a ramp between; and 0 for a far highlight (c_h > 0) on a pixel that is not far
// (sharp or near: the focal plane hides the far field, and a sharp pixel stays bit for bit). The occluded part of a sprite is lost (hidden), not
// renormalised. What this does not model: a near object's blurred halo, which extends beyond
// its own pixels, does not dim a far sprite (adi does not spread it either without layers;
// with layers the sprites are added over the near layer's halo). Sprites add to one another
// (light is additive).
//
// Cost: O(pixels) for the body (adi's, skipping the tiles in focus; the disc tiles add
// O(pixels x CoC), disc_body.hpp) plus O(highlights x CoC^2)
// for the sprites; sprites adding up to more than kMaxSplatWeights are refused (SplatWork,
// aperture_footprint.hpp), naming the largest CoC. Parallel: each thread owns a band of output
// rows and adds, in raster order of the highlights, the part of every sprite that falls in it:
// the result does not depend on the number of threads.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "tridiff/dof/method.hpp"
#include "tridiff/diffusion/adi.hpp"
#include "tridiff/image/copy.hpp"
#include "tridiff/threads.hpp"
#include "aperture_footprint.hpp"
#include "diffusion_dof.hpp"
#include "disc_body.hpp"
#include "frame.hpp"
#include "row_bands.hpp"
#include "stage_clock.hpp"
#include "tiled_gather.hpp"  // Stages

namespace tridiff {
namespace {

using dof_detail::ApertureFootprint;
using dof_detail::DiscTiles;
using dof_detail::fold;
using dof_detail::gather_discs;
using dof_detail::HighlightBoost;
using dof_detail::largest_channel;
using dof_detail::paste_discs;
using dof_detail::smooth_far_tiles;
using dof_detail::Stages;

constexpr float kAutoThreshold = 1.f;  // linear light: brighter than diffuse white

// The body's conductance, relative to adi's (whose blur has the thin-lens disc's variance). A
// diffusion blur is a bell; the disc is flat, and its transfer function 2 J1(a) / a falls
// faster through the middle frequencies than the bell's of equal variance, so at equal
// variance the bell leaves texture that the lens removes. Fitting the body's transfer function
// (the isotropic ADI step's, four implicit passes) to the disc's in least squares, weighted by
// the 1/f^2 power spectrum of natural images, gives 1.52 times the variance-matched beta for
// CoC diameters of 16-64 px (1.59 at 8, 1.87 at 4): 3.1 dB less weighted error; 1.25 gives
// 2.2 dB of it. Measured against the thin-lens truth at 1080p (docs/performance.md), 1.5 gains
// most on the textured scene (PSNR +0.44 dB, SSIM 0.967 -> 0.977) but costs the lamp scene
// 0.70 dB, whose glows just below the highlight threshold want the narrower bell; 1.25 keeps
// +0.38 dB and SSIM 0.974 there for 0.25 dB on the lamps. adi itself keeps the variance match:
// its highlights stay in the diffusion, and a wider bell spreads a lamp's light further than
// the disc does.
constexpr float kBodySpread = 1.25f;

// The share of the threshold a highlight leaves in the body: its largest channel becomes
// kBodyKeeps * t, and the sprite carries the rest. The body blurs a highlight as a bell (a
// lamp's CoC differs from the wall's around it, so no disc tile takes it), whose tail draws a
// halo around the sprite's sharp rim; the less it keeps, the sharper the disc (thin-lens truth,
// lamp scene at 1080p with layers: SSIM 0.9914 keeping all of t, 0.9922 half, 0.9925 a quarter,
// 0.9926 a tenth, PSNR +0.6 dB at a quarter; the textured scene -0.1 dB). Not 0: the body would
// have a dark hole where the light was, blurred into a dip around the sprite.
constexpr float kBodyKeeps = 0.25f;

struct Highlight {
  std::int32_t x = 0, y = 0;
  float coc = 0;           // signed, pixels
  float outer = 0;         // the footprint's bound
  double inv_sum = 0;      // 1 / the footprint's sum: 0 for a footprint without weight
  std::size_t excess = 0;  // index of its channels in Sprites::excess
};

struct Sprites {
  std::vector<Highlight> lights;  // raster order
  std::vector<float> excess;      // channels per light
};

// The out-of-focus highlights of the frame, in raster order, with their excess over the
// threshold (boosted), and the footprint's normaliser for each.
Sprites find_highlights(const DofFrame& frame, const HighlightBoost& boost,
                        const ApertureFootprint& footprint) {
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  const FocusTest focus = frame.focus();
  std::vector<std::vector<std::int32_t>> row_hits(std::size_t(frame.height()));
#pragma omp parallel for num_threads(frame.threads()) schedule(static)
  for (std::ptrdiff_t y = 0; y < frame.height(); ++y)
    for (std::ptrdiff_t x = 0; x < frame.width(); ++x)
      if (!focus.is_sharp(coc(x, y)) && largest_channel(color, x, y) > boost.threshold)
        row_hits[std::size_t(y)].push_back(std::int32_t(x));
  Sprites sprites;
  dof_detail::SplatWork work;
  const int channels = frame.channels();
  for (std::ptrdiff_t y = 0; y < frame.height(); ++y)
    for (const std::int32_t x : row_hits[std::size_t(y)]) {
      Highlight light{.x = x, .y = std::int32_t(y), .coc = coc(x, y)};
      work.add(light.coc, x, y);
      light.excess = sprites.excess.size();
      const float m = largest_channel(color, x, y);
      boost.require_finite(m, x, y);
      const float share =
          (boost.threshold * (1 - kBodyKeeps) + boost.gain * (m - boost.threshold)) / m;
      for (int c = 0; c < channels; ++c) sprites.excess.push_back(color(x, y, c) * share);
      sprites.lights.push_back(light);
    }
  work.require_within_budget("the highlights' sprites",
                             "lower the CoC, raise highlight_threshold, or use adi");
  const std::ptrdiff_t count = std::ptrdiff_t(sprites.lights.size());
#pragma omp parallel for num_threads(frame.threads()) schedule(dynamic, 4)
  for (std::ptrdiff_t i = 0; i < count; ++i) {
    Highlight& light = sprites.lights[std::size_t(i)];
    const double diameter = std::fabs(double(light.coc));
    light.outer = footprint.outer(diameter);
    const double sum = footprint.sum(diameter);
    light.inv_sum = sum > 0 ? 1.0 / sum : 0.0;
  }
  return sprites;
}

// out = the frame with every highlight's largest channel clamped to kBodyKeeps times the
// threshold, hue kept. out keeps its buffer when it has the frame's shape already (a caller
// that reuses it, as a video loop would, then pays no fresh pages for it).
void clamp_highlights(Image& out, const DofFrame& frame, const Sprites& sprites, float threshold) {
  if (out.width() != frame.width() || out.height() != frame.height() ||
      out.channels() != frame.channels())
    out.reset(frame.width(), frame.height(), frame.channels());
  // Copied on the frame's threads: the copy's first touch of fresh memory is most of its cost.
  if (&out != &frame.color()) copy_image(out, frame.color(), frame.threads());
  for (const Highlight& light : sprites.lights) {
    const float scale = kBodyKeeps * threshold / largest_channel(out, light.x, light.y);
    for (int c = 0; c < out.channels(); ++c) out(light.x, light.y, c) *= scale;
  }
}

// How much of a sprite of signed CoC `light_coc` shows at a pixel of signed CoC `coc`: the
// ramp, and nothing of a far sprite on a pixel that is not far (focus.is_far). Written
// without branches, so that add_solid_run's loop vectorises (GCC does not if-convert a
// conditional while floating-point comparisons may trap).
inline float visibility(float coc, float light_coc, FocusTest focus) {
  const float far_from = light_coc > 0 ? focus.sharp_below : -INFINITY;
  return std::min(std::max(coc - light_coc + 2.f, 0.f), 1.f) * float(coc >= far_from);
}

// Adds a fully covered run of `count` pixels of row y from x0 (inside the frame) of a sprite
// to out: add_pixel's arithmetic with coverage 1, a channel at a time.
void add_solid_run(const float* coc, std::ptrdiff_t count, const Highlight& light,
                   const float* excess, FocusTest focus, Image& out, std::ptrdiff_t x0,
                   std::ptrdiff_t y) {
  // The light's values are locals: the stores to the row could alias them.
  const float light_coc = light.coc;
  const double inv_sum = light.inv_sum;
  for (int c = 0; c < out.channels(); ++c) {
    float* row = out.plane(c).row(y) + x0;
    const double amount = double(excess[c]);
#pragma omp simd
    for (std::ptrdiff_t i = 0; i < count; ++i) {
      const double weight = inv_sum * double(visibility(coc[i], light_coc, focus));
      row[i] += static_cast<float>(weight * amount);  // + 0 where hidden
    }
  }
}

// Adds the part of every sprite that falls in rows [band0, band1) to out.
void splat_band(const DofFrame& frame, const Sprites& sprites, const ApertureFootprint& footprint,
                std::ptrdiff_t band0, std::ptrdiff_t band1, Image& out) {
  const ConstPlane coc = frame.coc();
  const std::ptrdiff_t width = frame.width(), height = frame.height();
  const int channels = frame.channels();
  const FocusTest focus = frame.focus();
  for (const Highlight& light : sprites.lights) {
    if (light.inv_sum == 0) continue;
    const std::ptrdiff_t reach = dof_detail::footprint_reach(light.outer);
    const std::ptrdiff_t qx = light.x, qy = light.y;
    if (qy - reach >= 0 && qy + reach < height && (qy + reach < band0 || qy - reach >= band1))
      continue;  // no fold, and the sprite's rows miss the band
    const double diameter = std::fabs(double(light.coc));
    const float* excess = sprites.excess.data() + light.excess;
    const auto add_pixel = [&](std::ptrdiff_t dx, std::ptrdiff_t dy, std::ptrdiff_t ty) {
      const double cover = footprint.coverage(diameter, light.outer, dx, dy);
      if (!(cover > 0)) return;
      const std::ptrdiff_t tx = fold(qx + dx, width);
      const float seen = visibility(coc(tx, ty), light.coc, focus);
      if (seen == 0) return;
      const double weight = cover * light.inv_sum * double(seen);
      for (int c = 0; c < channels; ++c)
        out(tx, ty, c) += static_cast<float>(weight * double(excess[c]));
    };
    for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy) {
      const std::ptrdiff_t ty = fold(qy + dy, height);
      if (ty < band0 || ty >= band1) continue;
      const std::ptrdiff_t hx = dof_detail::footprint_row_half_width(light.outer, dy);
      // The part of the row covered fully and inside the frame, [-solid, solid], takes the
      // same sums as add_pixel, in a loop without square roots or folds.
      std::ptrdiff_t solid = footprint.solid_half_width(light.outer, dy);
      if (qx - solid < 0 || qx + solid >= width) solid = -1;
      for (std::ptrdiff_t dx = -hx; dx < std::min<std::ptrdiff_t>(-solid, 0); ++dx)
        add_pixel(dx, dy, ty);
      if (solid >= 0)
        add_solid_run(coc.row(ty) + qx - solid, 2 * solid + 1, light, excess, focus, out,
                      qx - solid, ty);
      for (std::ptrdiff_t dx = solid + 1; dx <= hx; ++dx) add_pixel(dx, dy, ty);
    }
  }
}

void splat_sprites(const DofFrame& frame, const Sprites& sprites,
                   const ApertureFootprint& footprint, Image& out) {
  dof_detail::for_each_row_band(frame.height(), frame.threads(),
                                [&](std::ptrdiff_t band0, std::ptrdiff_t band1, int) {
                                  if (band0 < band1)
                                    splat_band(frame, sprites, footprint, band0, band1, out);
                                });
}

// The body: adi's isotropic diffusion with kBodySpread times its conductance, and the lens's
// disc on the tiles where the CoC it is given is smooth and far (disc_body.hpp). Without layers
// on the frame; with them on the background (the near field cut out and filled, |c| filled
// likewise, so a far tile is judged without the near objects in front of it, whose layer is
// composited over it afterwards), and the near layer diffusion alone: its discs would cost
// O(r) a pixel at the largest radii of the frame for almost nothing (procedural scene, 1080p:
// SSIM 0.9906 against 0.9905, 70-100 ms).
// The disc gathers are reported as the stage "discs" (in `report`, which diffusion_dof
// fills: the blur they run in counts the rest).
void run_body(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  const dof_detail::Diffuser diffusion = [](Image& dst, const Image& src, ConstPlane coc,
                                            const dof_detail::CocConductance& conductance,
                                            const DiffusionOptions& options) {
    return diffuse_isotropic(dst, src, coc, conductance, options);
  };
  const dof_detail::Diffuser with_discs = [&report](Image& dst, const Image& src, ConstPlane coc,
                                                    const dof_detail::CocConductance& conductance,
                                                    const DiffusionOptions& options) {
    const int threads = resolve_threads(options.threads);
    const auto gather_start = dof_detail::StageClock::now();
    // Gathered before the diffusion, which may write over its source (dst may be src).
    const DiscTiles discs = gather_discs(
        src, coc, smooth_far_tiles(coc, sharp_below_px(conductance.in_focus_px), threads), threads);
    double seconds = dof_detail::seconds_since(gather_start);
    const DiffusionReport diffused = diffuse_isotropic(dst, src, coc, conductance, options);
    const auto paste_start = dof_detail::StageClock::now();
    paste_discs(dst, discs, threads);
    seconds += dof_detail::seconds_since(paste_start);
    report.stages.push_back({"discs", seconds});
    return diffused;
  };
  dof_detail::diffusion_dof(out, frame, settings, report, with_discs, kBodySpread, &diffusion);
}

}  // namespace

namespace dof_detail {

void run_bokeh(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  Stages stages(report);
  const ApertureFootprint footprint(settings);
  const bool automatic = !std::isfinite(settings.highlight_threshold);
  const HighlightBoost boost{automatic ? kAutoThreshold : settings.highlight_threshold,
                             settings.highlight_gain};
  const Sprites sprites = find_highlights(frame, boost, footprint);
  stages.end("highlights");

  // Refused before `out` is written (the clamped copy goes there): a failed call leaves it.
  dof_detail::require_finite_conductance(
      frame, dof_detail::CocConductance{settings.in_focus_coc_px, kBodySpread});
  DofReport body_report;
  if (sprites.lights.empty()) {
    run_body(out, frame, settings, body_report);
  } else {
    clamp_highlights(out, frame, sprites, boost.threshold);
    run_body(out, DofFrame(frame, out), settings, body_report);  // in place
  }
  report.skipped_fraction = body_report.skipped_fraction;
  report.layered = body_report.layered;
  // The body's stages as "body <stage>", and "body rest" for what it took besides (the
  // highlights' clamped copy): they add up to the body's time.
  const double body_seconds = stages.lap();
  double listed = 0;
  for (const DofStage& stage : body_report.stages) {
    listed += stage.seconds;
    report.stages.push_back({"body " + stage.name, stage.seconds});
  }
  report.stages.push_back({"body rest", std::max(body_seconds - listed, 0.0)});

  splat_sprites(frame, sprites, footprint, out);
  stages.end("sprites");
  report.notes = std::to_string(sprites.lights.size()) + " out-of-focus highlights above " +
                 std::to_string(boost.threshold) + (automatic ? " (automatic)" : "") +
                 " splatted as sprites";
  if (settings.progress) settings.progress(1.0);
}

}  // namespace dof_detail
}  // namespace tridiff
