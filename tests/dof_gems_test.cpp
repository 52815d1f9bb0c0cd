// The `gems` DOF method (seed 002, GPU Gems 3 ch. 28; dof/src/method_gems.cpp) against a plain
// double-precision rendition of the seed's listings written here (the seed's own InterpolateDof
// weights, saturate and min included), against the `scatter` reference on the procedural scene
// (measured error bounds), and against analytic facts: a constant image stays constant, an
// all-sharp frame is returned bit for bit, a uniform CoC blurs with the disc's variance D^2/16,
// the far CoC does not spread while a near one does, the clamp above the largest radius, the
// output stays in the input's range, threads, degenerate sizes and float edge cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "test_util.hpp"
#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/scene.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

const DofMethod& gems() { return find_dof_method("gems"); }

struct Result {
  Image out;
  DofReport report;
};

Result run(const Image& color, const Image& coc, const DofOptions& settings = {}) {
  Result r;
  r.report = depth_of_field(r.out, color, coc.plane(0), gems(), settings);
  EXPECT_EQ(r.out.width(), color.width());
  EXPECT_EQ(r.out.height(), color.height());
  EXPECT_EQ(r.out.channels(), color.channels());
  return r;
}

// ---------------------------------------------------------------------------------------------
// The seed's algorithm, plainly, in double. A quarter-resolution plane is a vector of rows.

using Grid = std::vector<std::vector<double>>;

// The mapping of tridiff's CoC onto the seed's (the method's header): R = the largest radius
// |c|/2 of an out-of-focus pixel, at most 256 px; small level = disc radius 2 sqrt(24/17),
// medium = 2 sqrt(12); the Gaussian of the large level and of the near CoC has
// sigma_q = sqrt(max(R^2/4 - 4, 4)) / 4 quarter pixels.
constexpr double kCap = 256;
const double kSmallRadius = 2 * std::sqrt(24.0 / 17.0);
const double kMediumRadius = 2 * std::sqrt(12.0);

std::ptrdiff_t clamp_index(std::ptrdiff_t i, std::ptrdiff_t n) {
  return std::min(std::max<std::ptrdiff_t>(i, 0), n - 1);
}

// The mirror border (d c b a | a b c d), folded as often as needed.
std::ptrdiff_t mirror_index(std::ptrdiff_t i, std::ptrdiff_t n) {
  const std::ptrdiff_t period = 2 * n;
  std::ptrdiff_t m = i % period;
  if (m < 0) m += period;
  return m < n ? m : period - 1 - m;
}

// Separable correlation with a symmetric kernel, mirror border.
Grid convolve(const Grid& in, const std::vector<double>& kernel) {
  const std::ptrdiff_t h = std::ptrdiff_t(in.size()), w = std::ptrdiff_t(in[0].size());
  const std::ptrdiff_t r = std::ptrdiff_t(kernel.size() / 2);
  Grid rows(in.size(), std::vector<double>(in[0].size(), 0.0)), out = rows;
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x)
      for (std::ptrdiff_t k = -r; k <= r; ++k)
        rows[y][x] += kernel[std::size_t(k + r)] * in[y][mirror_index(x + k, w)];
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x)
      for (std::ptrdiff_t k = -r; k <= r; ++k)
        out[y][x] += kernel[std::size_t(k + r)] * rows[mirror_index(y + k, h)][x];
  return out;
}

// Bilinear lookup of quarter grid q at native pixel (x, y): quarter pixel j centred on 4j + 1.5.
double upsample(const Grid& q, std::ptrdiff_t x, std::ptrdiff_t y) {
  const std::ptrdiff_t h = std::ptrdiff_t(q.size()), w = std::ptrdiff_t(q[0].size());
  const double u = (double(x) + 0.5) / 4 - 0.5, v = (double(y) + 0.5) / 4 - 0.5;
  const double fu = u - std::floor(u), fv = v - std::floor(v);
  const auto i = std::ptrdiff_t(std::floor(u)), j = std::ptrdiff_t(std::floor(v));
  auto at = [&](std::ptrdiff_t a, std::ptrdiff_t b) {
    return q[clamp_index(b, h)][clamp_index(a, w)];
  };
  return (1 - fv) * ((1 - fu) * at(i, j) + fu * at(i + 1, j)) +
         fv * ((1 - fu) * at(i, j + 1) + fu * at(i + 1, j + 1));
}

Image seed_reference(const Image& color, const Image& coc, float in_focus = 1.f) {
  const std::ptrdiff_t W = color.width(), H = color.height();
  const int C = color.channels();
  const double sharp_below = std::max(1.f, in_focus);
  double R = 0;
  for (std::ptrdiff_t y = 0; y < H; ++y)
    for (std::ptrdiff_t x = 0; x < W; ++x)
      if (std::fabs(coc(x, y, 0)) >= sharp_below)
        R = std::max(R, std::fabs(double(coc(x, y, 0))) / 2);
  R = std::min(R, kCap);
  if (R == 0) return color;
  const std::ptrdiff_t qw = (W + 3) / 4, qh = (H + 3) / 4;
  // Listing 28-1: block means and the block's largest near radius, the blocks of the last row
  // and column reaching into the frame's mirror image.
  const Grid zero(std::size_t(qh), std::vector<double>(std::size_t(qw), 0.0));
  std::vector<Grid> mean(std::size_t(C), zero);
  Grid d0 = zero;
  for (std::ptrdiff_t j = 0; j < qh; ++j)
    for (std::ptrdiff_t i = 0; i < qw; ++i) {
      for (std::ptrdiff_t y = 4 * j; y < 4 * j + 4; ++y)
        for (std::ptrdiff_t x = 4 * i; x < 4 * i + 4; ++x) {
          const std::ptrdiff_t sx = mirror_index(x, W), sy = mirror_index(y, H);
          for (int c = 0; c < C; ++c) mean[c][j][i] += color(sx, sy, c) / 16.0;
          const double v = coc(sx, sy, 0);
          if (v <= -sharp_below) d0[j][i] = std::max(d0[j][i], std::min(-v / 2, R));
        }
    }
  // The Gaussian (to 6 sigma: wider than the method's, which drops a tail of 1e-7).
  const double sigma = std::sqrt(std::max(R * R / 4 - 4, 4.0)) / 4;
  const auto radius = std::ptrdiff_t(std::ceil(6 * sigma));
  std::vector<double> gauss;
  double total = 0;
  for (std::ptrdiff_t k = -radius; k <= radius; ++k)
    total += gauss.emplace_back(std::exp(-double(k * k) / (2 * sigma * sigma)));
  for (double& g : gauss) g /= total;
  const std::vector<double> tent{0.25, 0.5, 0.25};  // listing 28-3's 1/16, 2/16, 4/16
  // §28.4.3 and listings 28-2, 28-3.
  const Grid db = convolve(d0, gauss);
  Grid d = d0;
  for (std::size_t j = 0; j < d.size(); ++j)
    for (std::size_t i = 0; i < d[j].size(); ++i)
      d[j][i] = 2 * std::max(d0[j][i], db[j][i]) - d0[j][i];
  const Grid near = convolve(d, tent);
  std::vector<Grid> medium, large;
  for (int c = 0; c < C; ++c) {
    medium.push_back(convolve(mean[c], tent));
    large.push_back(convolve(mean[c], gauss));
  }
  // Listing 28-4. The pinwheel of fig. 28-5 without its centre (which the frame-buffer blend
  // supplies), each of its 16 pixels weighing 1/17.
  const int pinwheel[16][2] = {{0, -2}, {1, -2}, {0, -1}, {1, -1}, {-2, -1}, {-1, -1},
                               {-2, 0}, {-1, 0}, {-1, 1}, {0, 1},  {-1, 2},  {0, 2},
                               {1, 0},  {2, 0},  {1, 1},  {2, 1}};
  Image out(W, H, C);
  for (std::ptrdiff_t y = 0; y < H; ++y)
    for (std::ptrdiff_t x = 0; x < W; ++x) {
      const double c = coc(x, y, 0);
      const double far = c >= sharp_below ? c / 2 : 0;
      const double r = std::min(std::max(far, upsample(near, x, y)), R);
      double wx, wy, wz, ww;  // unblurred, small, medium, large
      if (R > kMediumRadius) {
        // InterpolateDof literally: t = r / R, d0 + d1 + d2 = 1.
        const double t = r / R, e0 = kSmallRadius / R, e1 = (kMediumRadius - kSmallRadius) / R,
                     e2 = (R - kMediumRadius) / R;
        auto saturate = [](double v) { return std::clamp(v, 0.0, 1.0); };
        wx = saturate(t * (-1 / e0) + 1);
        const double y0 = saturate(t * (-1 / e1) + (1 - e2) / e1);
        const double z0 = saturate(t * (-1 / e2) + 1 / e2);
        ww = saturate(t * (1 / e2) + (e2 - 1) / e2);
        wy = std::min(y0, 1 - wx);
        wz = std::min(z0, 1 - y0);
      } else {  // the large level is never reached: linear through (0, r_s, r_m)
        ww = 0;
        if (r <= kSmallRadius) {
          wy = r / kSmallRadius;
          wx = 1 - wy;
          wz = 0;
        } else {
          wx = 0;
          wz = (r - kSmallRadius) / (kMediumRadius - kSmallRadius);
          wy = 1 - wz;
        }
      }
      const double alpha = wy * 16 / 17 + wz + ww;  // the blend's coverage
      for (int ch = 0; ch < C; ++ch) {
        double ring = 0;
        for (const auto& p : pinwheel)
          ring += color(mirror_index(x + p[0], W), mirror_index(y + p[1], H), ch) / 17;
        const double blended =
            wy * ring + wz * upsample(medium[ch], x, y) + ww * upsample(large[ch], x, y);
        out(x, y, ch) = float((1 - alpha) * color(x, y, ch) + blended);
      }
    }
  return out;
}

// Near and far blur up to 22 px with sharp regions between, crossing tile and block edges.
Image mixed_coc(std::ptrdiff_t width, std::ptrdiff_t height, float scale = 22.f) {
  return make_coc(width, height, [=](auto x, auto y) {
    const float v = scale * std::sin(float(x) / 11.f) * std::cos(float(y) / 9.f);
    return std::fabs(v) < 0.25f * scale ? 0.3f * v / scale : v;
  });
}

TEST(GemsDof, Registered) {
  const DofMethod& m = gems();
  EXPECT_TRUE(m.blurs_foreground);
  EXPECT_FALSE(m.summary.empty());
  EXPECT_FALSE(m.cost.empty());
}

// Float against the double rendition of the listings: a few roundings per stage, each of a
// weighted mean of values up to 40 (HDR highlights). Measured: at most 9.5e-7, a quarter of a
// float ulp at 40; the bound is 2 x 40 x FLT_EPSILON = 9.5e-6.
TEST(GemsDof, MatchesSeedListingsInDouble) {
  struct Case {
    std::ptrdiff_t width, height;
    float scale, in_focus;
    bool far_only = false;
  };
  for (const Case k :
       {Case{203, 157, 22.f, 1.f}, Case{61, 37, 60.f, 1.f}, Case{17, 5, 22.f, 1.f},
        Case{2, 3, 22.f, 1.f}, Case{1, 1, 22.f, 1.f}, Case{90, 66, 9.f, 3.f},
        Case{90, 66, 4.f, 1.f}, Case{33, 21, 1200.f, 1.f}, Case{101, 79, 30.f, 1.f, true}}) {
    Image color = random_image(k.width, k.height, 3, 0.f, 1.f, 7);
    color(0, 0, 0) = 40.f;
    color(k.width / 2, k.height / 2, 2) = 25.f;
    Image coc = mixed_coc(k.width, k.height, k.scale);
    if (k.width * k.height < 8) coc(0, 0, 0) = -k.scale;  // tiny frames: one near pixel
    if (k.far_only)
      coc = make_coc(k.width, k.height, [&](auto x, auto y) { return std::fabs(coc(x, y, 0)); });
    DofOptions settings;
    settings.in_focus_coc_px = k.in_focus;
    const Result r = run(color, coc, settings);
    const Image expected = seed_reference(color, coc, k.in_focus);
    const double err = image_difference(r.out, expected).max;
    EXPECT_LE(err, 2 * 40 * std::numeric_limits<float>::epsilon())
        << k.width << " x " << k.height << ", CoC scale " << k.scale;
    std::printf("[ measured ] %td x %td, CoC scale %g: max |float - double listing| %.3g\n",
                k.width, k.height, double(k.scale), err);
  }
}

// The procedural scene against the scatter reference. The seed trades accuracy for speed
// (Gaussian levels instead of discs, no depth order, a foreground spread over its background),
// so the bounds are loose: the measured RMSE 0.0411 and max 4.32 (at an HDR highlight, where
// the Gaussian levels and the disc differ most) with headroom 1.5.
TEST(GemsDof, CloseToScatterOnProceduralScene) {
  const Scene scene = procedural_scene(640, 360, 2);
  Image coc(640, 360, 1);
  coc_thin_lens(coc.plane(0), scene.depth.plane(0), scene.lens, 2);
  using Clock = std::chrono::steady_clock;
  auto t0 = Clock::now();
  const Result fast = run(scene.color, coc);
  const double fast_s = std::chrono::duration<double>(Clock::now() - t0).count();
  Image slow;
  DofReport slow_report;
  t0 = Clock::now();
  slow_report = depth_of_field(slow, scene.color, coc.plane(0), find_dof_method("scatter"), {});
  const double slow_s = std::chrono::duration<double>(Clock::now() - t0).count();
  double sum = 0, worst = 0;
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < 360; ++y)
      for (std::ptrdiff_t x = 0; x < 640; ++x) {
        const double e = double(fast.out(x, y, c)) - double(slow(x, y, c));
        sum += e * e;
        worst = std::max(worst, std::fabs(e));
      }
  const double rmse = std::sqrt(sum / (3.0 * 640 * 360));
  std::printf(
      "[ measured ] procedural 640x360 vs scatter: RMSE %.4f, max %.4f; gems %.3f s, scatter "
      "%.3f s; skipped %.3f; %s\n",
      rmse, worst, fast_s, slow_s, fast.report.skipped_fraction, fast.report.notes.c_str());
  for (const DofStage& stage : fast.report.stages)
    std::printf("[ measured ]   gems stage %s: %.4f s\n", stage.name.c_str(), stage.seconds);
  EXPECT_LE(rmse, 0.062);
  EXPECT_LE(worst, 6.5);
}

// A uniform CoC has no occlusion, so scatter is the disc convolution (mirror border) and gems
// its Gaussian-level stand-in of the same variance: they differ by the kernels' shapes. On a
// smooth image in [0, 1] (value noise of 8 px cells), borders included, measured: D = 8: RMSE
// 0.0059, max 0.034; D = 20: RMSE 0.0192, max 0.106 (0.068 away from the borders, where the
// quarter grid's mirror is not quite the frame's). The bounds are these with headroom 1.5.
TEST(GemsDof, CloseToScatterUnderUniformCoc) {
  const std::ptrdiff_t width = 131, height = 97;
  const Image cells = random_image(width / 8 + 2, height / 8 + 2, 3, 0.f, 1.f, 12);
  const Image color = make_image(width, height, 3, [&](auto x, auto y, int c) {
    const float u = float(x) / 8.f, v = float(y) / 8.f;
    const auto i = std::ptrdiff_t(u), j = std::ptrdiff_t(v);
    const float fu = u - float(i), fv = v - float(j);
    return (1 - fv) * ((1 - fu) * cells(i, j, c) + fu * cells(i + 1, j, c)) +
           fv * ((1 - fu) * cells(i, j + 1, c) + fu * cells(i + 1, j + 1, c));
  });
  struct Bound {
    float diameter;
    double rmse, max;
  };
  for (const Bound b :
       {Bound{8.f, 1.5 * 0.0059, 1.5 * 0.034}, Bound{-20.f, 1.5 * 0.0192, 1.5 * 0.106}}) {
    const Image coc = make_coc(width, height, [&](auto, auto) { return b.diameter; });
    const Result r = run(color, coc);
    Image slow;
    DofReport report;
    report = depth_of_field(slow, color, coc.plane(0), find_dof_method("scatter"), {});
    double sum = 0;
    for (int c = 0; c < 3; ++c)
      for (std::ptrdiff_t y = 0; y < height; ++y)
        for (std::ptrdiff_t x = 0; x < width; ++x) {
          const double e = double(r.out(x, y, c)) - double(slow(x, y, c));
          sum += e * e;
        }
    const double rmse = std::sqrt(sum / double(3 * width * height));
    const double worst = image_difference(r.out, slow).max;
    EXPECT_LE(rmse, b.rmse) << "D " << b.diameter;
    EXPECT_LE(worst, b.max) << "D " << b.diameter;
    std::printf("[ measured ] uniform D=%g vs scatter: RMSE %.4f, max %.4f\n", double(b.diameter),
                rmse, worst);
  }
}

// A constant colour stays constant for any CoC map: every level is a normalised average.
TEST(GemsDof, ConstantImageStaysConstant) {
  for (auto [w, h] : {std::pair{203, 157}, std::pair{17, 5}, std::pair{1, 1}, std::pair{2, 3}})
    for (float scale : {22.f, 3.f, 5000.f}) {
      const Image color = make_image(w, h, 3, [](auto, auto, int c) { return 0.25f + c; });
      Image coc = mixed_coc(w, h, scale);
      coc(0, 0, 0) = -scale;
      const Result r = run(color, coc);
      for (int c = 0; c < 3; ++c)
        for (std::ptrdiff_t y = 0; y < h; ++y)
          for (std::ptrdiff_t x = 0; x < w; ++x)
            ASSERT_NEAR(r.out(x, y, c), 0.25f + float(c), 4e-6f * (1.f + float(c)))
                << w << " x " << h << " scale " << scale << " at (" << x << ", " << y << ")";
    }
}

// Every pixel sharp (below the default threshold, or below a raised one): the input bit for bit.
TEST(GemsDof, AllSharpReturnsInputBitForBit) {
  const Image color = random_image(77, 45, 3, -1.f, 30.f, 4);
  struct Variant {
    Image coc;
    float in_focus;
  };
  const Variant variants[] = {
      {make_coc(77, 45, [](auto x, auto y) { return 0.9f * std::sin(float(x * y)); }), 1.f},
      {mixed_coc(77, 45, 4.9f), 5.f},
      {make_coc(77, 45, [](auto x, auto) { return x % 2 ? -0.f : 1e-40f; }), 0.f},
      {mixed_coc(77, 45, 1e30f), std::numeric_limits<float>::infinity()}};
  for (const Variant& v : variants)
    for (bool skip : {true, false}) {
      DofOptions settings;
      settings.in_focus_coc_px = v.in_focus;
      settings.skip_in_focus = skip;
      const Result r = run(color, v.coc, settings);
      EXPECT_EQ(differing_bits(r.out, color), 0) << "threshold " << v.in_focus;
      EXPECT_EQ(r.report.skipped_fraction, skip ? 1.0 : 0.0);
    }
}

// A uniform CoC of diameter D puts every pixel at the top node: the output is the large level,
// whose impulse response averaged over the 16 positions of a pixel in its 4 x 4 block has the
// variance of the disc, D^2/16 per axis (block 1.25 + Gaussian 16 sigma^2 + upsampling 2.75).
// The sampled Gaussian's variance is sigma^2 to ~1e-4; the bound is 1 %.
TEST(GemsDof, UniformCocHasDiscVariance) {
  const std::ptrdiff_t size = 200;
  for (float diameter : {16.f, 30.f, -44.f}) {
    double var_x = 0, var_y = 0, mass = 0;
    for (int phase = 0; phase < 16; ++phase) {
      Image impulse(size, size, 1);
      const std::ptrdiff_t px = 100 + phase % 4, py = 100 + phase / 4;
      impulse(px, py, 0) = 1.f;
      const Image coc = make_coc(size, size, [&](auto, auto) { return diameter; });
      const Result r = run(impulse, coc);
      double m = 0, vx = 0, vy = 0;
      for (std::ptrdiff_t y = 0; y < size; ++y)
        for (std::ptrdiff_t x = 0; x < size; ++x) {
          const double v = r.out(x, y, 0);
          m += v;
          vx += v * double((x - px) * (x - px));
          vy += v * double((y - py) * (y - py));
        }
      mass += m / 16;
      var_x += vx / m / 16;
      var_y += vy / m / 16;
    }
    const double target = double(diameter) * double(diameter) / 16;
    EXPECT_NEAR(var_x, target, 0.01 * target) << "D " << diameter;
    EXPECT_NEAR(var_y, target, 0.01 * target) << "D " << diameter;
    EXPECT_NEAR(mass, 1.0, 1e-5);
    std::printf("[ measured ] uniform D=%g: var_x %.4f var_y %.4f (D^2/16 = %.4f)\n",
                double(diameter), var_x, var_y, target);
  }
}

// Seed 002 keeps the far CoC per pixel: with no near pixel every sharp pixel keeps its value
// bit for bit, beside the blurred far field too; the far pixels do change.
TEST(GemsDof, FarCocDoesNotSpread) {
  const Image color = random_image(101, 83, 3, 0.f, 2.f, 9);
  const Image coc = make_coc(101, 83, [](auto x, auto y) {
    const float v = 30.f * std::sin(float(x) / 13.f) * std::cos(float(y) / 10.f);
    return v > 8.f ? v : 0.f;
  });
  const Result r = run(color, coc);
  std::ptrdiff_t sharp_moved = 0, far_moved = 0, far = 0;
  for (std::ptrdiff_t y = 0; y < 83; ++y)
    for (std::ptrdiff_t x = 0; x < 101; ++x) {
      bool same = true;
      for (int c = 0; c < 3; ++c) same = same && same_bits(r.out(x, y, c), color(x, y, c));
      if (coc(x, y, 0) > 0) {
        ++far;
        far_moved += !same;
      } else {
        sharp_moved += !same;
      }
    }
  EXPECT_EQ(sharp_moved, 0);
  EXPECT_EQ(far_moved, far);
  EXPECT_TRUE(contains(r.report.notes, "absent"));
}

// A blurred near square (D = -16) over a sharp background: seed 002 §28.4.3 spreads its CoC so
// that the background next to it is blurred (the foreground's soft silhouette), fading with
// distance; far beyond the Gaussian's reach (sigma_q = 1 quarter px, 6 quarter px = 24 px plus
// the 3 x 3 and upsampling) the background is untouched, bit for bit.
TEST(GemsDof, NearCocSpreadsOverSharpBackground) {
  const std::ptrdiff_t size = 160;
  const Image color = make_image(size, size, 3, [](auto x, auto y, int c) {
    const bool square = x >= 60 && x < 100 && y >= 60 && y < 100;
    return square ? (c == 0 ? 1.f : 0.f) : ((x / 2) % 2 ? 0.9f : 0.1f);
  });
  const Image coc = make_coc(size, size, [](auto x, auto y) {
    return x >= 60 && x < 100 && y >= 60 && y < 100 ? -16.f : 0.f;
  });
  const Result r = run(color, coc);
  auto distance = [](std::ptrdiff_t x, std::ptrdiff_t y) {
    return std::max(
        {std::ptrdiff_t(60) - x, x - 99, std::ptrdiff_t(60) - y, y - 99, std::ptrdiff_t(0)});
  };
  std::vector<double> ring(40, 0.0);
  std::vector<int> count(40, 0);
  std::ptrdiff_t far_moved = 0;
  for (std::ptrdiff_t y = 0; y < size; ++y)
    for (std::ptrdiff_t x = 0; x < size; ++x) {
      const std::ptrdiff_t d = distance(x, y);
      if (d == 0) continue;
      if (d < 40) {
        // Red excess: 0 on the grey background, 1 on the square.
        ring[std::size_t(d)] += r.out(x, y, 0) - 0.5 * (r.out(x, y, 1) + r.out(x, y, 2));
        ++count[std::size_t(d)];
      }
      if (d > 4 * 8 + 9)
        for (int c = 0; c < 3; ++c) far_moved += !same_bits(r.out(x, y, c), color(x, y, c));
    }
  for (std::size_t d = 1; d < ring.size(); ++d) ring[d] /= count[d];
  EXPECT_GT(ring[1], 0.2);  // the silhouette is soft outside the square
  EXPECT_GT(ring[1], ring[4]);
  EXPECT_GT(ring[4], ring[8]);
  EXPECT_LT(ring[30], 0.01);
  EXPECT_EQ(far_moved, 0);
  std::printf(
      "[ measured ] near square D=-16: red excess at 1, 2, 4, 8, 16 px: %.3f %.3f %.3f "
      "%.3f %.4f\n",
      ring[1], ring[2], ring[4], ring[8], ring[16]);
}

// Radii above 256 px are clamped: a uniform CoC of 600 px and one of 60000 px give the same bits
// (both the large level of R = 256), and a 1 x 1 frame returns its pixel.
TEST(GemsDof, HugeCocClampedToLargestLevel) {
  const Image color = random_image(70, 50, 3, 0.f, 1.f, 2);
  const Result a = run(color, make_coc(70, 50, [](auto, auto) { return 600.f; }));
  const Result b = run(color, make_coc(70, 50, [](auto, auto) { return -60000.f; }));
  EXPECT_EQ(differing_bits(a.out, b.out), 0);
  EXPECT_TRUE(contains(a.report.notes, "256.00 px clamped")) << a.report.notes;
  const Image one = make_image(1, 1, 3, [](auto, auto, int c) { return 0.3f * float(c + 1); });
  for (float d : {-1e30f, 5.f, 1e30f}) {
    const Result r = run(one, make_coc(1, 1, [&](auto, auto) { return d; }));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.out(0, 0, c), one(0, 0, c), 1e-6f) << d;
  }
}

// Every level is a convex combination of input values, so the output stays in the input's range
// per channel (up to a few roundings), negative and HDR values included.
TEST(GemsDof, OutputWithinInputRange) {
  Image color = random_image(203, 157, 3, -0.5f, 1.f, 5);
  color(10, 10, 0) = 40.f;
  color(150, 100, 2) = -25.f;
  const Image coc = mixed_coc(203, 157, 40.f);
  const Result r = run(color, coc);
  for (int c = 0; c < 3; ++c) {
    const ValueRange range = channel_range(color, c);
    for (std::ptrdiff_t y = 0; y < 157; ++y)
      for (std::ptrdiff_t x = 0; x < 203; ++x) {
        ASSERT_GE(r.out(x, y, c), range.lo) << x << ", " << y;
        ASSERT_LE(r.out(x, y, c), range.hi) << x << ", " << y;
      }
  }
}

TEST(GemsDof, ThreadCountAndSkippingChangeNoBit) {
  const Image color = random_image(203, 157, 4, 0.f, 3.f, 6);
  const Image coc = mixed_coc(203, 157, 30.f);
  DofOptions one, two, off;
  one.threads = 1;
  two.threads = 2;
  off.skip_in_focus = false;
  const Result a = run(color, coc, one), b = run(color, coc, two), c = run(color, coc, off);
  EXPECT_EQ(differing_bits(a.out, b.out), 0);
  EXPECT_EQ(differing_bits(a.out, c.out), 0);
  EXPECT_EQ(c.report.skipped_fraction, 0.0);
}

// A small near object in a large sharp frame: the near passes run, and the tiles beyond the
// near CoC's spread are still skipped, with the same bits as without skipping.
TEST(GemsDof, SkipsTilesBeyondNearSpread) {
  const std::ptrdiff_t width = 512, height = 384;
  const Image color = random_image(width, height, 3, 0.f, 1.f, 8);
  const Image coc = make_coc(width, height, [](auto x, auto y) {
    return x >= 40 && x < 70 && y >= 30 && y < 60 ? -12.f : 0.f;
  });
  DofOptions off;
  off.skip_in_focus = false;
  const Result a = run(color, coc), b = run(color, coc, off);
  EXPECT_EQ(differing_bits(a.out, b.out), 0);
  EXPECT_GT(a.report.skipped_fraction, 0.8);
  std::printf("[ measured ] near 30 x 30 block in 512 x 384: skipped_fraction %.3f\n",
              a.report.skipped_fraction);
}

}  // namespace
}  // namespace tridiff::test
