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
// O(pixels x CoC), disc_body.hpp) plus, for the sprites, O(highlights x CoC) with the round
// aperture (a row's fully visible run is two steps, summed once a row: SpriteStrip) and
// O(highlights x CoC^2) with a shaped one; sprites adding up to more than kMaxSplatWeights are
// refused (SplatWork, aperture_footprint.hpp), naming the largest CoC. Parallel: the threads
// take strips of output rows as they come free, and each adds the part of every sprite that
// falls in its strip: pixel by pixel in raster order of the highlights, the steps' sums after
// them. A row's result does not depend on the thread that took it, nor on their number.
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
  std::vector<Highlight> lights;    // raster order
  std::vector<float> excess;        // channels per light
  std::ptrdiff_t widest_reach = 0;  // the largest footprint_reach of a light
};

// The out-of-focus highlights of the frame, in raster order, with their excess over the
// threshold (boosted), and the footprint's normaliser for each.
Sprites find_highlights(const DofFrame& frame, const HighlightBoost& boost,
                        const ApertureFootprint& footprint) {
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  const FocusTest focus = frame.focus();
  std::vector<std::vector<std::int32_t>> row_hits(std::size_t(frame.height()));
#pragma omp parallel num_threads(frame.threads())
  {
    // A row's largest channels first, in vector lanes (pixel by pixel through the image's
    // accessors this scan took 16 ms of a 4K frame).
    std::vector<float> largest(std::size_t(frame.width()));
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < frame.height(); ++y) {
      std::copy_n(color.plane(0).row(y), frame.width(), largest.begin());
      for (int c = 1; c < color.channels(); ++c) {
        const float* value = color.plane(c).row(y);
        for (std::ptrdiff_t x = 0; x < frame.width(); ++x)
          largest[std::size_t(x)] = std::max(largest[std::size_t(x)], value[x]);
      }
      const float* k = coc.row(y);
      for (std::ptrdiff_t x = 0; x < frame.width(); ++x)
        if (largest[std::size_t(x)] > boost.threshold && !focus.is_sharp(k[x]))
          row_hits[std::size_t(y)].push_back(std::int32_t(x));
    }
  }
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
  for (const Highlight& light : sprites.lights)
    sprites.widest_reach = std::max(sprites.widest_reach, dof_detail::footprint_reach(light.outer));
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

// A strip of kStripRows output rows, where the sprites' runs that show in full are summed
// before they are added to the frame. A run of a sprite over pixels that all see it fully
// (visibility 1) adds the same amount to each: it is written as a step up at its first pixel
// and a step down after its last, in double, and one prefix sum per row adds them all. The
// sprite then costs O(its rows) instead of O(its pixels) (4K, 107k highlights of CoC up to
// 32 px: 47 million pixel additions). The runs' count is summed alongside: where no run is
// open the sum is reset to exactly 0, so that pixels outside every run (a sharp pixel next to
// a run) get nothing, not the rounding left by the steps.
constexpr std::ptrdiff_t kStripRows = 16;
// The strip's smallest CoC per row and block of kMinBlock pixels: a run shows in full when
// every block it touches is far enough behind the light (a test at a block's grain, so a run
// next to a nearer pixel may be added pixel by pixel instead; never the other way).
constexpr std::ptrdiff_t kMinBlock = 16;

struct SpriteStrip {
  ConstPlane coc;
  std::ptrdiff_t first_row = 0, width = 0;
  int channels = 0;
  // Per row of the strip: the steps (channel, x <= width), the runs opened minus those
  // closed at x, and the columns written. Kept at zero between strips: finish() clears what
  // it read.
  std::vector<double> steps;
  std::vector<std::int32_t> opens;
  std::vector<std::ptrdiff_t> low, high;  // the row's first and last step written, or low > high
  std::vector<float> block_min;           // (row, block), made when the row first asks
  std::vector<unsigned char> has_mins;

  SpriteStrip(ConstPlane frame_coc, int planes)
      : coc(frame_coc),
        width(frame_coc.width()),
        channels(planes),
        steps(std::size_t(kStripRows * planes * (width + 1)), 0.0),
        opens(std::size_t(kStripRows * (width + 1)), 0),
        low(std::size_t(kStripRows), width + 1),
        high(std::size_t(kStripRows), -1),
        block_min(std::size_t(kStripRows * blocks())),
        has_mins(std::size_t(kStripRows), 0) {}

  std::ptrdiff_t blocks() const { return (width + kMinBlock - 1) / kMinBlock; }

  void start(std::ptrdiff_t first) {
    first_row = first;
    std::fill(has_mins.begin(), has_mins.end(), 0);
  }

  // Whether every pixel of row y in [x0, x1] has a CoC of at least `least` (the CoC is finite,
  // DofFrame checks it: a NaN would drop out of the minima).
  bool all_at_least(std::ptrdiff_t y, std::ptrdiff_t x0, std::ptrdiff_t x1, float least) {
    const std::ptrdiff_t r = y - first_row;
    float* mins = block_min.data() + r * blocks();
    if (!has_mins[std::size_t(r)]) {
      const float* c = coc.row(y);
      for (std::ptrdiff_t b = 0; b < blocks(); ++b) {
        float lowest = INFINITY;
        for (std::ptrdiff_t x = b * kMinBlock; x < std::min(width, (b + 1) * kMinBlock); ++x)
          lowest = std::min(lowest, c[x]);
        mins[b] = lowest;
      }
      has_mins[std::size_t(r)] = 1;
    }
    for (std::ptrdiff_t b = x0 / kMinBlock; b <= x1 / kMinBlock; ++b)
      if (!(mins[b] >= least)) return false;
    return true;
  }

  // Adds weight * excess[c] to channel c of row y's pixels x0 .. x1.
  void add_run(std::ptrdiff_t y, std::ptrdiff_t x0, std::ptrdiff_t x1, double weight,
               const float* excess) {
    const std::ptrdiff_t r = y - first_row;
    for (int c = 0; c < channels; ++c) {
      double* row = steps.data() + (r * channels + c) * (width + 1);
      const double amount = weight * double(excess[c]);
      row[x0] += amount;
      row[x1 + 1] -= amount;
    }
    ++opens[std::size_t(r * (width + 1) + x0)];
    --opens[std::size_t(r * (width + 1) + x1 + 1)];
    low[std::size_t(r)] = std::min(low[std::size_t(r)], x0);
    high[std::size_t(r)] = std::max(high[std::size_t(r)], x1 + 1);
  }

  // Adds the runs to `out`, row by row, and clears the steps for the next strip.
  void finish(Image& out) {
    for (std::ptrdiff_t r = 0; r < kStripRows; ++r) {
      const std::ptrdiff_t x0 = low[std::size_t(r)], x1 = high[std::size_t(r)];
      if (x0 > x1) continue;
      std::int32_t* open = opens.data() + r * (width + 1);
      for (int c = 0; c < channels; ++c) {
        double* step = steps.data() + (r * channels + c) * (width + 1);
        float* to = out.plane(c).row(first_row + r);
        double sum = 0;
        std::int32_t count = 0;
        for (std::ptrdiff_t x = x0; x < x1; ++x) {
          sum += step[x];
          count += open[x];
          // Outside every run exactly nothing (the steps' rounding would leave a rest).
          if (count == 0) {
            sum = 0;
            continue;
          }
          to[x] += static_cast<float>(sum);
        }
        std::fill(step + x0, step + x1 + 1, 0.0);
      }
      std::fill(open + x0, open + x1 + 1, 0);
      low[std::size_t(r)] = width + 1;
      high[std::size_t(r)] = -1;
    }
  }
};

// Adds row ty (dy from the light's) of a sprite to out, or to the strip where a run of it shows
// in full.
void splat_row(const DofFrame& frame, const Highlight& light, const float* excess,
               const ApertureFootprint& footprint, std::ptrdiff_t dy, std::ptrdiff_t ty,
               SpriteStrip& strip, Image& out) {
  const ConstPlane coc = frame.coc();
  const std::ptrdiff_t width = frame.width();
  const int channels = frame.channels();
  const FocusTest focus = frame.focus();
  const std::ptrdiff_t qx = light.x;
  const double diameter = std::fabs(double(light.coc));
  const auto add_pixel = [&](std::ptrdiff_t dx) {
    const double cover = footprint.coverage(diameter, light.outer, dx, dy);
    if (!(cover > 0)) return;
    const std::ptrdiff_t tx = fold(qx + dx, width);
    const float seen = visibility(coc(tx, ty), light.coc, focus);
    if (seen == 0) return;
    const double weight = cover * light.inv_sum * double(seen);
    for (int c = 0; c < channels; ++c)
      out(tx, ty, c) += static_cast<float>(weight * double(excess[c]));
  };
  const std::ptrdiff_t hx = dof_detail::footprint_row_half_width(light.outer, dy);
  // The part of the row covered fully and inside the frame, [-solid, solid]: two steps where
  // every pixel of it sees the light in full, else add_pixel's sums in a loop without square
  // roots or folds (add_solid_run).
  std::ptrdiff_t solid = footprint.solid_half_width(light.outer, dy);
  if (qx - solid < 0 || qx + solid >= width) solid = -1;
  for (std::ptrdiff_t dx = -hx; dx < std::min<std::ptrdiff_t>(-solid, 0); ++dx) add_pixel(dx);
  if (solid >= 0) {
    // Visibility 1 wherever the CoC is at least the light's - 1 (and far, for a far light);
    // half a pixel of CoC to spare, so that the float arithmetic of visibility() gives 1 too.
    const float least = std::max(light.coc - 0.5f, light.coc > 0 ? focus.sharp_below : -INFINITY);
    if (strip.all_at_least(ty, qx - solid, qx + solid, least)) {
      strip.add_run(ty, qx - solid, qx + solid, light.inv_sum, excess);
    } else {
      add_solid_run(coc.row(ty) + qx - solid, 2 * solid + 1, light, excess, focus, out, qx - solid,
                    ty);
    }
  }
  for (std::ptrdiff_t dx = solid + 1; dx <= hx; ++dx) add_pixel(dx);
}

// Adds the part of every sprite that falls in the strip's rows [s0, s1) to out. A row takes
// its sprites' pixels in raster order of the highlights and then the sums of its steps, so
// the result does not depend on which thread takes the strip.
void splat_strip(const DofFrame& frame, const Sprites& sprites, const ApertureFootprint& footprint,
                 std::ptrdiff_t s0, std::ptrdiff_t s1, SpriteStrip& strip, Image& out) {
  const std::ptrdiff_t height = frame.height();
  const std::vector<Highlight>& lights = sprites.lights;
  const std::ptrdiff_t reach = sprites.widest_reach;
  // The lights of rows from y on start at row_at_least(y) (raster order).
  const auto row_at_least = [&](std::ptrdiff_t y) {
    return std::size_t(std::partition_point(lights.begin(), lights.end(),
                                            [y](const Highlight& h) { return h.y < y; }) -
                       lights.begin());
  };
  // The lights within reach of the strip, and those whose rows may fold at the top or the
  // bottom: [0, top_end), [first, last) and [bottom_begin, end), in order.
  const std::size_t top_end = row_at_least(reach), bottom_begin = row_at_least(height - reach);
  const std::size_t first = row_at_least(s0 - reach), last = row_at_least(s1 + reach);
  strip.start(s0);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    if (i >= top_end && i < first) i = first;
    if (i >= last && i < bottom_begin) i = bottom_begin;
    if (i >= lights.size()) break;
    const Highlight& light = lights[i];
    if (light.inv_sum == 0) continue;
    const float* excess = sprites.excess.data() + light.excess;
    const std::ptrdiff_t own = dof_detail::footprint_reach(light.outer);
    if (light.y - own >= 0 && light.y + own < height) {
      for (std::ptrdiff_t ty = std::max(s0, light.y - own); ty < std::min(s1, light.y + own + 1);
           ++ty)
        splat_row(frame, light, excess, footprint, ty - light.y, ty, strip, out);
      continue;
    }
    for (std::ptrdiff_t dy = -own; dy <= own; ++dy) {  // rows fold
      const std::ptrdiff_t ty = fold(light.y + dy, height);
      if (ty >= s0 && ty < s1) splat_row(frame, light, excess, footprint, dy, ty, strip, out);
    }
  }
  strip.finish(out);
}

// The strips are taken by the threads as they come free: the highlights of a frame are
// seldom spread evenly over its rows (halves of the rows, one to each thread, left one of
// them with most of the lamps).
void splat_sprites(const DofFrame& frame, const Sprites& sprites,
                   const ApertureFootprint& footprint, Image& out) {
  const std::ptrdiff_t strips = (frame.height() + kStripRows - 1) / kStripRows;
#pragma omp parallel num_threads(frame.threads())
  {
    SpriteStrip strip(frame.coc(), frame.channels());
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t k = 0; k < strips; ++k)
      splat_strip(frame, sprites, footprint, k * kStripRows,
                  std::min((k + 1) * kStripRows, frame.height()), strip, out);
  }
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
