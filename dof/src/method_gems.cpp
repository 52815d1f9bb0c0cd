// The `gems` method: the post-process depth of field of GPU Gems 3 ch. 28 (seed 002, Hammon,
// §28.4.3-28.5.5, listings 28-1 to 28-4) on the CPU: a variable-width blur that blends the
// unblurred image with three blur levels by CoC, and a blurred near-field CoC so that an
// out-of-focus foreground spreads over the sharp background behind it.
//
// The algorithm (seed 002 §28.5):
//  1. Downsample (listing 28-1): each 4 x 4 block of the frame gives one quarter-resolution pixel,
//     the block's mean colour and its near CoC D0 = the largest near radius in the block.
//  2. Blur the near CoC (§28.4.3): DB = a Gaussian of D0 on the quarter grid, the same Gaussian
//     that makes the large blur level from the downsampled colour (the seed shares the pass).
//  3. Combine (listing 28-2): D = 2 max(D0, DB) - D0, so a pixel beside a larger CoC takes that
//     larger CoC: the blurred foreground's edge is fully blurred whatever lies behind it.
//  4. A 3 x 3 blur, weights [1 2 1] x [1 2 1] / 16 (listing 28-3), of D and of the downsampled
//     colour; the blurred colour is the medium blur level.
//  5. Per pixel (listing 28-4): r = max(near, far), near = D bilinearly upsampled, far = the
//     pixel's own far radius (the far CoC is not spread, as in the seed); the output is a
//     piecewise-linear blend in r of the pixel, the small blur (17 pixels of a 5 x 5 pinwheel,
//     fig. 28-5), the medium and the large level (both bilinearly upsampled).
//
// Mapping tridiff's CoC onto the seed's normalised CoC t in [0, 1]. Radius r = |c| / 2 px. Each
// level stands for the disc radius of the same per-axis variance (a disc of radius r has r^2 / 4):
//  - small: the pinwheel's variance 24/17 px^2 gives r_s = 2 sqrt(24/17) = 2.38 px;
//  - medium: 4 x 4 block mean (1.25) + 3 x 3 blur on the quarter grid (0.5 x 16 = 8) + the
//    bilinear upsampling (16 f (1 - f) averaged over the four phases: 2.75) = 12 px^2,
//    r_m = 4 sqrt(3) = 6.93 px (the seed measured "a 3.6-pixel Gaussian", variance 13);
//  - large: 1.25 + 16 sigma_q^2 + 2.75 px^2 for a Gaussian of sigma_q quarter pixels.
// The seed's max blur radius (t = 1) is R = the frame's largest radius (TileMap::max_radius),
// capped at kMaxRadius; sigma_q is chosen so the large level stands for R, and
// t = r / R, d0 = r_s / R, d1 = (r_m - r_s) / R, d2 = (R - r_m) / R in the seed's
// InterpolateDof. A radius above R (a CoC beyond the cap, or the near spread D, which reaches 2R
// at a concave corner) is clamped to R: the seed's saturate(). When R <= r_m the large level is
// never reached and not computed (nodes 0, r_s, r_m only); when R <= r_s nor is the medium.
//
// Deviations from the seed, and why:
//  - The CoC comes in as pixels (any lens model), not from depth through the seed's linear
//    ramps; the "don't blur the sky" test (depth > 1e6) has no counterpart.
//  - The small blur averages its 17 pixels directly (the seed's five bilinear lookups, one of
//    them the frame-buffer blend, add up to the same 1/17 weights).
//  - The seed fixes the large radius per game; here it follows the frame (R above), so no
//    CoC in the frame is clamped below kMaxRadius.
//  - The near Gaussian's width follows R too: sigma_q for R, at least 1/2 quarter pixel.
//  - Borders: every read outside the frame or the quarter grid is mirrored (d c b a | a b c d,
//    Border::mirror), as the scatter reference folds its discs: the 4 x 4 blocks of the last
//    row / column when the size is not a multiple of 4, the Gaussian and 3 x 3 blurs, the
//    17-tap pattern and the bilinear upsampling (whose one-pixel overhang mirrors onto the edge
//    pixel, as a GPU clamp sampler would).
//  - Float throughout; the seed's half-precision and 8-bit render targets quantise.
//  - settings.layers is ignored: the seed has no layers (report.layered stays false).
//
// Validity: any CoC (clamped as above); colour magnitudes below ~1e37 (a sum of 17 values must
// not overflow). The output is a convex combination of blurs of the input with non-negative
// weights, so it stays within the input's range up to float rounding. A pixel with r = 0 (sharp,
// no near CoC spread onto it) is its input bit for bit.
//
// Known artifacts (seed 002 §28.7): sharp pixels beside a blurred foreground are blurred along
// with it (the "haze" of fig. 28-8; intended, by D); in-focus objects bleed onto a blurred
// background (the gather ignores depth); the blend of levels is a cross-fade, not a true disc,
// and a Gaussian's tail replaces the disc's hard rim; near CoC edges carry the 4 x 4 blockiness
// that the 3 x 3 blur and the bilinear upsampling soften.
//
// Skipping: a TileMap of 32 x 32 tiles with a margin of how far the near CoC spreads beyond
// its pixel: 4 (g + 1) + 5 px for the Gaussian's reach of g quarter pixels (derived at the
// margin's definition below; the kernel's cut tail, 1e-7 of its mass, ends the spread exactly).
// That is 37 px for R = 10.7 px, about 2.7 R + 9 for large R, and 0 without near pixels, since
// a far CoC changes only its own pixel. Tiles that nothing reaches are copied; elsewhere every
// pixel with r = 0 is copied too and the rest blended, and a level that no pixel of a row
// takes is not formed for that row. The quarter-resolution passes (1/16 of the pixels) run on
// the whole grid either way, so skipping on or off gives the same bits. No near pixel: steps
// 1 (CoC), 2, 3 and 4 (CoC) are left out and near = 0; R <= r_m: no large level; R <= r_s: no
// medium level.
//
// Parallel: OpenMP over rows; every value is computed the same way whatever the thread count.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tridiff/blur/kernels.hpp"
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

constexpr std::ptrdiff_t kBlock = 4;  // downsampling factor per axis (seed 002 §28.4.3)
constexpr float kMaxRadius = 256.f;   // px; larger radii are clamped (see the header)

// Per-axis variances in native px^2 of the fixed levels (header), and the disc radius of each.
constexpr double kBlockVariance = 1.25;     // mean of 4 pixels
constexpr double kUpsampleVariance = 2.75;  // bilinear from the quarter grid, phase average
constexpr double kSmallVariance = 24.0 / 17.0;
constexpr double kMediumVariance = kBlockVariance + 0.5 * kBlock * kBlock + kUpsampleVariance;

double disc_radius(double variance) { return 2.0 * std::sqrt(variance); }

// The Gaussian (quarter pixels) of the large level, standing for disc radius `radius`, and for
// the near CoC blur; never below 1/2 quarter pixel.
double large_sigma(double radius) {
  const double rest = radius * radius / 4.0 - kBlockVariance - kUpsampleVariance;
  return std::sqrt(std::max(rest, 4.0)) / double(kBlock);
}

// The 17 pixels of seed 002 fig. 28-5 (offsets dx, dy): the centre and four 2 x 2 squares
// turned about it (the four bilinear lookups of GetSmallBlurSample).
constexpr std::array<std::array<int, 2>, 17> kSmallTaps{{{0, 0},
                                                         {0, -2},
                                                         {1, -2},
                                                         {0, -1},
                                                         {1, -1},
                                                         {-2, -1},
                                                         {-1, -1},
                                                         {-2, 0},
                                                         {-1, 0},
                                                         {-1, 1},
                                                         {0, 1},
                                                         {-1, 2},
                                                         {0, 2},
                                                         {1, 0},
                                                         {2, 0},
                                                         {1, 1},
                                                         {2, 1}}};

// Blend weights of the unblurred pixel and the small, medium and large levels for radius r
// (0 < r <= top node): linear between neighbouring nodes 0, r_s, r_m, R (seed 002
// InterpolateDof with the d0, d1, d2 of the header).
struct Nodes {
  std::array<float, 4> radius{};
  int count = 0;  // nodes in use: 2 (0, r_s), 3 (+ r_m) or 4 (+ R)
};

std::array<float, 4> blend_weights(const Nodes& nodes, float r) {
  std::array<float, 4> w{};
  int k = 0;
  while (k + 2 < nodes.count && r > nodes.radius[std::size_t(k + 1)]) ++k;
  const float lo = nodes.radius[std::size_t(k)], hi = nodes.radius[std::size_t(k + 1)];
  const float upper = std::clamp((r - lo) / (hi - lo), 0.f, 1.f);
  w[std::size_t(k)] = 1.f - upper;
  w[std::size_t(k + 1)] = upper;
  return w;
}

// Bilinear upsampling from the quarter grid: native x reads quarter pixels i0 and i1 with weight
// 1 - f and f, the quarter pixel j centred on native 4j + 1.5. The lookup overhangs the grid by
// at most one pixel, where the mirror border and clamping agree.
struct Taps {
  std::vector<std::ptrdiff_t> i0, i1;
  std::vector<float> f;
};

Taps upsample_taps(std::ptrdiff_t native, std::ptrdiff_t quarter) {
  Taps t;
  t.i0.resize(std::size_t(native));
  t.i1.resize(std::size_t(native));
  t.f.resize(std::size_t(native));
  for (std::ptrdiff_t x = 0; x < native; ++x) {
    const double u = (double(x) + 0.5) / double(kBlock) - 0.5;
    const double base = std::floor(u);
    const auto i = static_cast<std::ptrdiff_t>(base);
    t.i0[std::size_t(x)] = std::clamp<std::ptrdiff_t>(i, 0, quarter - 1);
    t.i1[std::size_t(x)] = std::clamp<std::ptrdiff_t>(i + 1, 0, quarter - 1);
    t.f[std::size_t(x)] = static_cast<float>(u - base);
  }
  return t;
}

// Plane q of the quarter grid interpolated vertically at native row y: the row that
// upsample_span then interpolates horizontally.
void lerp_rows(ConstPlane q, const Taps& ty, std::ptrdiff_t y, float* row) {
  const float fy = ty.f[std::size_t(y)];
  const float* r0 = q.row(ty.i0[std::size_t(y)]);
  const float* r1 = q.row(ty.i1[std::size_t(y)]);
  for (std::ptrdiff_t i = 0; i < q.width(); ++i) row[i] = (1.f - fy) * r0[i] + fy * r1[i];
}

// dst[x] for x in [x0, x1): the quarter row interpolated horizontally at native column x.
void upsample_span(const float* quarter_row, const Taps& tx, std::ptrdiff_t x0, std::ptrdiff_t x1,
                   float* dst) {
  for (std::ptrdiff_t x = x0; x < x1; ++x) {
    const float fx = tx.f[std::size_t(x)];
    dst[x] =
        (1.f - fx) * quarter_row[tx.i0[std::size_t(x)]] + fx * quarter_row[tx.i1[std::size_t(x)]];
  }
}

// The small blur of one row: dst[x] for x in [x0, x1) is the mean of the 17 pinwheel pixels
// (kSmallTaps) from rows[k] = row y + k - 2 (mirrored). Columns are mirrored near the edges;
// the interior sums the same taps in the same order as straight runs, which vectorise.
void small_blur_span(const std::array<const float*, 5>& rows, std::ptrdiff_t width,
                     std::ptrdiff_t x0, std::ptrdiff_t x1, float* dst) {
  const float* r0 = rows[0];
  const float* r1 = rows[1];
  const float* r2 = rows[2];
  const float* r3 = rows[3];
  const float* r4 = rows[4];
  auto edge = [&](std::ptrdiff_t x) {
    float sum = 0;
    for (const auto& tap : kSmallTaps)
      sum += rows[std::size_t(tap[1] + 2)][border_index(x + tap[0], width, Border::mirror)];
    return sum * (1.f / 17.f);
  };
  const std::ptrdiff_t inner0 = std::clamp<std::ptrdiff_t>(2, x0, x1),
                       inner1 = std::clamp<std::ptrdiff_t>(width - 2, inner0, x1);
  for (std::ptrdiff_t x = x0; x < inner0; ++x) dst[x] = edge(x);
  for (std::ptrdiff_t x = inner0; x < inner1; ++x) {
    float sum = r2[x];  // kSmallTaps, in its order
    sum += r0[x];
    sum += r0[x + 1];
    sum += r1[x];
    sum += r1[x + 1];
    sum += r1[x - 2];
    sum += r1[x - 1];
    sum += r2[x - 2];
    sum += r2[x - 1];
    sum += r3[x - 1];
    sum += r3[x];
    sum += r4[x - 1];
    sum += r4[x];
    sum += r2[x + 1];
    sum += r2[x + 2];
    sum += r3[x + 1];
    sum += r3[x + 2];
    dst[x] = sum * (1.f / 17.f);
  }
  for (std::ptrdiff_t x = inner1; x < x1; ++x) dst[x] = edge(x);
}

// Step 1: the block means of every channel and (near_out non-empty) the block's largest near
// radius, clamped to max_radius; a pixel is near by focus.is_near. The blocks of the last
// row and column reach past the frame into its mirror image, so every block holds 16 pixels
// centred on 4j + 1.5 as the upsampling assumes.
void downsample(const Image& color, ConstPlane coc, FocusTest focus, float max_radius, Image& mean,
                Plane near_out, int threads) {
  const std::ptrdiff_t width = color.width(), height = color.height();
  const std::ptrdiff_t qw = mean.width(), qh = mean.height();
  const int channels = color.channels();
  std::vector<std::ptrdiff_t> column(std::size_t(qw * kBlock));
  for (std::ptrdiff_t x = 0; x < qw * kBlock; ++x)
    column[std::size_t(x)] = border_index(x, width, Border::mirror);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t j = 0; j < qh; ++j) {
    std::array<std::ptrdiff_t, kBlock> rows;
    for (std::ptrdiff_t k = 0; k < kBlock; ++k)
      rows[std::size_t(k)] = border_index(j * kBlock + k, height, Border::mirror);
    for (std::ptrdiff_t i = 0; i < qw; ++i) {
      const std::ptrdiff_t* cols = column.data() + i * kBlock;
      for (int c = 0; c < channels; ++c) {
        const ConstPlane in = color.plane(c);
        float sum = 0;
        for (const std::ptrdiff_t y : rows)
          for (std::ptrdiff_t k = 0; k < kBlock; ++k) sum += in(cols[k], y);
        mean(i, j, c) = sum * (1.f / float(kBlock * kBlock));
      }
      if (near_out.data() == nullptr) continue;
      float largest = 0;
      for (const std::ptrdiff_t y : rows)
        for (std::ptrdiff_t k = 0; k < kBlock; ++k) {
          const float c = coc(cols[k], y);
          if (focus.is_near(c)) largest = std::max(largest, -0.5f * c);
        }
      near_out(i, j) = std::min(largest, max_radius);
    }
  }
}

// What the frame asks of the method: the level nodes, the Gaussian of the large level and the
// near CoC, and the tiles to blend (with the near spread's margin).
struct Plan {
  float top = 0;  // the seed's max blur radius R
  Nodes nodes;
  double sigma_q = 0;
  std::vector<float> gaussian;
  bool near = false;
  std::optional<TileMap> spread_tiles;  // with a margin; else the frame's tiles
};

Plan plan_frame(const DofFrame& frame) {
  Plan plan;
  plan.top = std::min(frame.max_radius(), kMaxRadius);
  plan.near = frame.has_near();
  plan.nodes.radius = {0.f, float(disc_radius(kSmallVariance)), float(disc_radius(kMediumVariance)),
                       plan.top};
  plan.nodes.count = plan.top > plan.nodes.radius[2] ? 4 : plan.top > plan.nodes.radius[1] ? 3 : 2;
  plan.sigma_q = large_sigma(plan.top);
  plan.gaussian = gaussian_kernel(plan.sigma_q);
  const std::ptrdiff_t gaussian_reach = std::ptrdiff_t(plan.gaussian.size() / 2);
  // The near CoC of a pixel spreads to quarter pixels within the Gaussian's reach plus one (the
  // 3 x 3 blur), and a quarter pixel j is read by native pixels 4j - 2 ... 4j + 5: at most
  // 4 (reach + 1) + 5 native pixels from the near pixel (Chebyshev). Far pixels change only
  // themselves. The TileMap adds the margin to every disc (conservative for the far ones).
  const std::ptrdiff_t margin = plan.near ? kBlock * (gaussian_reach + 1) + 5 : 0;
  if (margin > 0)
    plan.spread_tiles.emplace(frame.coc(), frame.sharp_below(), TileMap::kDefaultTile, margin,
                              frame.threads());
  return plan;
}

// Steps 1-4 on the quarter grid: the medium and large levels and the spread near CoC D.
struct QuarterGrid {
  std::ptrdiff_t width = 0, height = 0;
  Image medium, large;
  Image spread;  // D after the 3 x 3 blur (near pixels only)
};

QuarterGrid quarter_grid(const DofFrame& frame, const Plan& plan, Stages& stages) {
  const Image& color = frame.color();
  const int team = frame.threads(), channels = color.channels();
  QuarterGrid grid;
  const std::ptrdiff_t qw = (color.width() + kBlock - 1) / kBlock,
                       qh = (color.height() + kBlock - 1) / kBlock;
  grid.width = qw;
  grid.height = qh;
  Image mean(qw, qh, channels), near_coc;
  if (plan.near) near_coc.reset(qw, qh, 1);
  downsample(color, frame.coc(), frame.focus(), plan.top, mean,
             plan.near ? near_coc.plane(0) : Plane(), team);
  stages.end("downsample");

  const std::array<float, 3> tent{0.25f, 0.5f, 0.25f};  // [1 2 1] / 4 per axis: listing 28-3
  const std::vector<float>& gaussian = plan.gaussian;
  if (plan.nodes.count >= 3) {
    grid.medium.reset(qw, qh, channels);
    for (int c = 0; c < channels; ++c)
      convolve_separable(grid.medium.plane(c), mean.plane(c), tent, tent, Border::mirror, team);
  }
  if (plan.nodes.count == 4) {
    grid.large.reset(qw, qh, channels);
    for (int c = 0; c < channels; ++c)
      convolve_separable(grid.large.plane(c), mean.plane(c), gaussian, gaussian, Border::mirror,
                         team);
  }
  stages.end("medium and large levels");

  if (!plan.near) return grid;
  Image blurred(qw, qh, 1), combined(qw, qh, 1);
  convolve_separable(blurred.plane(0), near_coc.plane(0), gaussian, gaussian, Border::mirror, team);
  for (std::ptrdiff_t j = 0; j < qh; ++j)
    for (std::ptrdiff_t i = 0; i < qw; ++i) {
      const float d0 = near_coc(i, j, 0), db = blurred(i, j, 0);
      combined(i, j, 0) = 2.f * std::max(d0, db) - d0;  // seed 002 §28.4.3
    }
  grid.spread.reset(qw, qh, 1);
  convolve_separable(grid.spread.plane(0), combined.plane(0), tent, tent, Border::mirror, team);
  stages.end("near coc");
  return grid;
}

// One thread's buffers for the blend: per column the weights of the unblurred pixel and the
// small, medium and large levels (all 0 for a pixel left as it is), and the levels along the
// row.
struct RowScratch {
  std::array<std::vector<float>, 4> weight, level;
  std::vector<char> blurred;
  std::vector<float> quarter_row;

  RowScratch(std::ptrdiff_t width, std::ptrdiff_t quarter_width) {
    for (std::size_t k = 0; k < 4; ++k) {
      weight[k].assign(std::size_t(width), 0.f);
      level[k].assign(std::size_t(width), 0.f);
    }
    blurred.resize(std::size_t(width));
    quarter_row.resize(std::size_t(quarter_width));
  }
};

// Step 5 on the computed spans of row y: first every pixel's weights, then per channel the
// levels along the row and their weighted sum.
void blend_row(Image& out, const DofFrame& frame, const Plan& plan, const QuarterGrid& grid,
               const Taps& tx, const Taps& ty, std::ptrdiff_t y, const std::vector<Span>& spans,
               RowScratch& scratch) {
  const Image& color = frame.color();
  const std::ptrdiff_t width = color.width(), height = color.height();
  const FocusTest focus = frame.focus();
  const bool near = plan.near;
  auto& [weight, level, blurred, quarter_row] = scratch;
  float* near_row = level[0].data();  // free until the channels' pass
  if (near) {
    lerp_rows(grid.spread.plane(0), ty, y, quarter_row.data());
    for (const auto& [x0, x1] : spans) upsample_span(quarter_row.data(), tx, x0, x1, near_row);
  }
  const float* coc_row = frame.coc().row(y);
  std::array<bool, 4> used{};  // whether some pixel of the row takes the level
  for (const auto& [x0, x1] : spans)
    for (std::ptrdiff_t x = x0; x < x1; ++x) {
      const auto i = std::size_t(x);
      const float c = coc_row[x];
      const float far = focus.is_far(c) ? 0.5f * c : 0.f;
      // Radii above the top node would extrapolate; clamp there (the top node is R when used).
      const float r = std::min(std::max(far, near ? near_row[i] : 0.f), plan.top);
      blurred[i] = r > 0;
      const std::array<float, 4> w =
          r > 0 ? blend_weights(plan.nodes, r) : std::array<float, 4>{1.f, 0.f, 0.f, 0.f};
      for (std::size_t k = 0; k < 4; ++k) {
        weight[k][i] = w[k];
        used[k] = used[k] || w[k] > 0;
      }
    }
  std::array<const float*, 5> rows;
  for (int ch = 0; ch < color.channels(); ++ch) {
    const ConstPlane in = color.plane(ch);
    for (std::ptrdiff_t k = 0; k < 5; ++k)
      rows[std::size_t(k)] = in.row(border_index(y + k - 2, height, Border::mirror));
    if (used[1])
      for (const auto& [x0, x1] : spans) small_blur_span(rows, width, x0, x1, level[1].data());
    for (std::size_t k = 2; k < 4; ++k) {
      if (!used[k]) continue;
      lerp_rows((k == 2 ? grid.medium : grid.large).plane(ch), ty, y, quarter_row.data());
      for (const auto& [x0, x1] : spans)
        upsample_span(quarter_row.data(), tx, x0, x1, level[k].data());
    }
    const float* in_row = rows[2];
    float* out_row = out.plane(ch).row(y);
    const float *w0 = weight[0].data(), *w1 = weight[1].data(), *w2 = weight[2].data(),
                *w3 = weight[3].data();
    const float *small = level[1].data(), *med = level[2].data(), *big = level[3].data();
    const char* moved = blurred.data();
    // A level no pixel of the row takes is left out; one that some pixel takes is finite
    // (below ~1e37) and weighs 0 elsewhere.
    for (const auto& [x0, x1] : spans)
      for (std::ptrdiff_t x = x0; x < x1; ++x) {
        float v = w0[x] * in_row[x];
        if (used[1]) v += w1[x] * small[x];
        if (used[2]) v += w2[x] * med[x];
        if (used[3]) v += w3[x] * big[x];
        out_row[x] = moved[x] ? v : in_row[x];  // r = 0: the input, bit for bit
      }
  }
}

std::string describe(const Plan& plan) {
  char line[200];
  std::snprintf(line, sizeof line,
                "levels at radius %.2f / %.2f / %.2f px (small / medium / large%s), Gaussian "
                "sigma %.2f quarter px; radii above %.2f px clamped; near CoC %s",
                double(plan.nodes.radius[1]), double(plan.nodes.radius[2]), double(plan.top),
                plan.nodes.count == 4 ? "" : ": unused", plan.sigma_q, double(plan.top),
                plan.near ? "spread" : "absent: near passes left out");
  return line;
}

}  // namespace

namespace dof_detail {

void run_gems(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  const Image& color = frame.color();
  Stages stages(report);
  out.reset(color.width(), color.height(), color.channels());
  if (!(frame.max_radius() > 0)) {  // every pixel sharp: the input, bit for bit
    for (int c = 0; c < color.channels(); ++c) copy_plane(out.plane(c), color.plane(c));
    stages.end("classify");
    report.skipped_fraction = settings.skip_in_focus ? 1.0 : 0.0;
    report.notes = "every pixel in focus";
    if (settings.progress) settings.progress(1.0);
    return;
  }
  const Plan plan = plan_frame(frame);
  const TiledGather gather(plan.spread_tiles ? *plan.spread_tiles : frame.tiles(),
                           settings.skip_in_focus, frame.threads());
  stages.end("classify");

  const QuarterGrid grid = quarter_grid(frame, plan, stages);

  const Taps tx = upsample_taps(color.width(), grid.width),
             ty = upsample_taps(color.height(), grid.height);
  gather.for_each_row([&] { return RowScratch(color.width(), grid.width); },
                      [&](std::ptrdiff_t y, const std::vector<Span>& spans, RowScratch& scratch) {
                        blend_row(out, frame, plan, grid, tx, ty, y, spans, scratch);
                      });
  gather.copy_the_rest(out, color);
  stages.end("blend");

  report.skipped_fraction = gather.skipped_fraction();
  report.layered = false;
  report.notes = describe(plan);
  if (settings.progress) settings.progress(1.0);
}

}  // namespace dof_detail
}  // namespace tridiff
