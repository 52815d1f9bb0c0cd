// The `poisson` DOF method (Poisson-disc gather, seed 000 §5.3.3) against independent facts:
// sharp pixels and all-sharp frames returned bit for bit, constants kept, outputs inside the
// input's range, the impulse response's variance against the scatter disc's computed here by
// brute force, the `scatter` reference itself (uniform CoC and the procedural scene, with
// error bounds measured once and given ~1.5x headroom), no bleeding of a sharp neighbour,
// thread-count independence, and degenerate sizes and CoCs.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/scene.hpp"
#include "test_util.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

const DofMethod& poisson() { return find_dof_method("poisson"); }
const DofMethod& scatter() { return find_dof_method("scatter"); }

Image run(const DofMethod& method, const Image& color, const Image& coc,
          const DofOptions& settings = {}, DofReport* report = nullptr) {
  Image out;
  DofReport local;
  (report ? *report : local) = depth_of_field(out, color, coc.plane(0), method, settings);
  return out;
}

// A CoC map of random signed values in [lo, hi).
Image random_coc(std::ptrdiff_t width, std::ptrdiff_t height, float lo, float hi, unsigned seed) {
  const Image u = random_image(width, height, seed);
  return make_coc(width, height, [&](auto x, auto y) { return lo + (hi - lo) * u(x, y, 0); });
}

const std::vector<std::pair<std::ptrdiff_t, std::ptrdiff_t>> kSizes = {
    {1, 1}, {2, 3}, {3, 2}, {17, 5}, {5, 17}, {33, 31}, {64, 47}};

TEST(DofPoisson, IsRegisteredAsNotBlurringTheForeground) {
  EXPECT_FALSE(poisson().blurs_foreground);
  EXPECT_EQ(poisson().name, "poisson");
}

TEST(DofPoisson, AllSharpReturnsInputBitForBit) {
  for (auto [w, h] : kSizes)
    for (float threshold : {1.f, 5.f})
      for (bool skip : {true, false}) {
        const Image color = random_image(w, h, 3, -1.f, 3.f, 5);
        const float limit = 0.999f * threshold;
        const Image coc = random_coc(w, h, -limit, limit, 6);
        DofOptions settings;
        settings.skip_in_focus = skip;
        settings.in_focus_coc_px = threshold;
        const Image out = run(poisson(), color, coc, settings);
        std::ptrdiff_t differ = 0;
        for (int c = 0; c < 3; ++c)
          for (std::ptrdiff_t y = 0; y < h; ++y)
            for (std::ptrdiff_t x = 0; x < w; ++x)
              differ += !same_bits(out(x, y, c), color(x, y, c));
        EXPECT_EQ(differ, 0) << w << " x " << h << ", threshold " << threshold;
      }
}

TEST(DofPoisson, SharpPixelsKeepTheirValuesNextToBlur) {
  // A pixel gathers by its own CoC: a sharp pixel is its input whatever surrounds it.
  const std::ptrdiff_t w = 203, h = 157;
  const Image color = random_image(w, h, 3, 0.f, 4.f, 7);
  const Image coc = make_coc(w, h, [](auto x, auto y) {
    const float v = 22.f * std::sin(float(x) / 17.f) * std::cos(float(y) / 13.f);
    return std::fabs(v) < 6.f ? 0.1f * v : v;
  });
  for (bool skip : {true, false}) {
    DofOptions settings;
    settings.skip_in_focus = skip;
    const Image out = run(poisson(), color, coc, settings);
    const FocusChanges f = focus_changes(out, color, coc);
    EXPECT_EQ(f.sharp_changed, 0);
    EXPECT_GT(f.sharp, 5000);
    EXPECT_GT(f.blurred_moved, 5000);
  }
}

TEST(DofPoisson, ConstantStaysConstantForAnyCoc) {
  // Weights sum to one and the levels are normalised blurs: only rounding moves a constant.
  double worst = 0;
  for (auto [w, h] : kSizes)
    for (float value : {0.37f, 1000.f, -2.5f})
      for (float scale : {3.f, 40.f, 1e4f}) {
        const Image color = make_image(w, h, 3, [&](auto, auto, int) { return value; });
        const Image coc = random_coc(w, h, -scale, scale, 8);
        const Image out = run(poisson(), color, coc);
        for (int c = 0; c < 3; ++c)
          for (std::ptrdiff_t y = 0; y < h; ++y)
            for (std::ptrdiff_t x = 0; x < w; ++x) {
              const double rel = std::fabs(double(out(x, y, c)) - value) / std::fabs(value);
              worst = std::max(worst, rel);
              ASSERT_LE(rel, 1e-5)
                  << w << " x " << h << " CoC scale " << scale << " at (" << x << ", " << y << ")";
            }
      }
  std::printf("[ measured ] constant: worst relative change %.3g\n", worst);
}

TEST(DofPoisson, OutputWithinInputRange) {
  for (auto [w, h] : kSizes)
    for (float scale : {6.f, 30.f, 1e4f}) {
      Image color = random_image(w, h, 3, -2.f, 1.f, 9);
      color(w / 2, h / 2, 0) = 500.f;  // a highlight
      const Image coc = random_coc(w, h, -scale, scale, 10);
      const Image out = run(poisson(), color, coc);
      for (int c = 0; c < 3; ++c) {
        const ValueRange range = channel_range(color, c);
        for (std::ptrdiff_t y = 0; y < h; ++y)
          for (std::ptrdiff_t x = 0; x < w; ++x) {
            const float v = out(x, y, c);
            ASSERT_TRUE(std::isfinite(v));
            ASSERT_GE(v, range.lo) << w << " x " << h << " (" << x << ", " << y << ")";
            ASSERT_LE(v, range.hi) << w << " x " << h << " (" << x << ", " << y << ")";
          }
      }
    }
}

// The per-axis variance of the scatter reference's disc of diameter d, by brute force from its
// definition (method_scatter.cpp): coverage min(1, d/2 + 1/2 - |offset|) where positive.
double scatter_disc_variance(double diameter) {
  const double outer = 0.5 * diameter + 0.5;
  const int reach = int(std::ceil(outer));
  double sum = 0, moment = 0;
  for (int dy = -reach; dy <= reach; ++dy)
    for (int dx = -reach; dx <= reach; ++dx) {
      const double cov = std::min(1.0, outer - std::hypot(double(dx), double(dy)));
      if (cov <= 0) continue;
      sum += cov;
      moment += cov * dx * dx;
    }
  return moment / sum;
}

TEST(DofPoisson, UniformCocImpulseHasTheScatterDiscVariance) {
  const std::ptrdiff_t size = 257;
  Image impulse(size, size, 1);
  impulse(128, 128, 0) = 1.f;
  for (float diameter : {3.f, 6.f, 12.f, 20.f, 40.f, 80.f}) {
    const Image coc = make_coc(size, size, [&](auto, auto) { return diameter; });
    const Image out = run(poisson(), impulse, coc);
    double mass = 0, sx = 0, sy = 0;
    for (std::ptrdiff_t y = 0; y < size; ++y)
      for (std::ptrdiff_t x = 0; x < size; ++x) {
        mass += out(x, y, 0);
        sx += out(x, y, 0) * double(x);
        sy += out(x, y, 0) * double(y);
      }
    const double cx = sx / mass, cy = sy / mass;
    double vx = 0, vy = 0, cxy = 0;
    for (std::ptrdiff_t y = 0; y < size; ++y)
      for (std::ptrdiff_t x = 0; x < size; ++x) {
        const double v = out(x, y, 0) / mass;
        vx += v * (double(x) - cx) * (double(x) - cx);
        vy += v * (double(y) - cy) * (double(y) - cy);
        cxy += v * (double(x) - cx) * (double(y) - cy);
      }
    const double target = scatter_disc_variance(diameter);
    std::printf(
        "[ measured ] D=%g: mass %.5f, centroid (%.4f, %.4f), var_x %.3f var_y %.3f cov %.2e, "
        "scatter disc %.3f\n",
        double(diameter), mass, cx, cy, vx, vy, cxy, target);
    // Measured: mass 1 to 1e-5, centroid within 2e-4 px, variance within 6 % at D = 3 (the
    // bilinear term is an average there) and 0.5 % from D = 6 on, covariance < 1e-6 of it.
    EXPECT_NEAR(mass, 1.0, 1e-4) << diameter;
    EXPECT_NEAR(cx, 128.0, 1e-3) << diameter;
    EXPECT_NEAR(cy, 128.0, 1e-3) << diameter;
    const double tol = (diameter < 5 ? 0.09 : 0.0075) * target;
    EXPECT_NEAR(vx, target, tol) << diameter;
    EXPECT_NEAR(vy, target, tol) << diameter;
    EXPECT_NEAR(cxy, 0.0, 1e-5 * target) << diameter;
  }
}

TEST(DofPoisson, UniformCocCloseToScatter) {
  const std::ptrdiff_t w = 96, h = 80;
  const Image color = random_image(w, h, 3, 0.f, 1.f, 12);
  // Measured RMSE / max on values in [0, 1): D 2: 0.0186 / 0.067, 5: 0.0114 / 0.048,
  // 11: 0.0094 / 0.038, 24: 0.0044 / 0.017 (the taps' sampling noise); bounds 1.5x.
  const struct {
    float diameter;
    double rmse, max;
  } cases[] = {
      {2.f, 0.028, 0.10}, {5.f, 0.017, 0.072}, {11.f, 0.014, 0.057}, {24.f, 0.0066, 0.026}};
  for (const auto& c : cases) {
    const Image coc = make_coc(w, h, [&](auto, auto) { return c.diameter; });
    const auto e = image_difference(run(poisson(), color, coc), run(scatter(), color, coc));
    std::printf("[ measured ] uniform D=%g vs scatter: RMSE %.4f, max %.4f\n", double(c.diameter),
                e.rmse, e.max);
    EXPECT_LT(e.rmse, c.rmse) << c.diameter;
    EXPECT_LT(e.max, c.max) << c.diameter;
  }
}

TEST(DofPoisson, ProceduralSceneCloseToScatter) {
  const std::ptrdiff_t w = 320, h = 180;
  const Scene scene = procedural_scene(w, h, 2);
  Image coc(w, h, 1);
  coc_thin_lens(coc.plane(0), scene.depth.plane(0), scene.lens, 2);
  using Clock = std::chrono::steady_clock;
  auto t0 = Clock::now();
  const Image gathered = run(poisson(), scene.color, coc);
  auto t1 = Clock::now();
  const Image reference = run(scatter(), scene.color, coc);
  auto t2 = Clock::now();
  const auto e = image_difference(gathered, reference);
  std::printf(
      "[ measured ] scene %tdx%td vs scatter: RMSE %.4f, max %.4f; poisson %.3f s, "
      "scatter %.3f s\n",
      w, h, e.rmse, e.max, std::chrono::duration<double>(t1 - t0).count(),
      std::chrono::duration<double>(t2 - t1).count());
  // Measured RMSE 0.0246, max 1.78 (colour up to ~20 at highlights; the max is at the edge of
  // a blurred near object over sharp background, the stated limitation); bounds 1.5x.
  EXPECT_LT(e.rmse, 0.037);
  EXPECT_LT(e.max, 2.7);
}

TEST(DofPoisson, SharpNeighbourDoesNotBleedIntoBlur) {
  // A sharp bright line (50) through a blurred black field (CoC 12): the scatter reference gives
  // exactly 0 off the line (a sharp pixel is a point in front of the field).
  const std::ptrdiff_t w = 96, h = 64, line = 48;
  const Image color =
      make_image(w, h, 1, [&](auto x, auto, int) { return x == line ? 50.f : 0.f; });
  const Image coc = make_coc(w, h, [&](auto x, auto) { return x == line ? 0.f : 12.f; });
  const Image out = run(poisson(), color, coc);
  const Image reference = run(scatter(), color, coc);
  std::vector<double> leak(w, 0.0);
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x) {
      leak[std::size_t(std::abs(x - line))] =
          std::max(leak[std::size_t(std::abs(x - line))], double(out(x, y, 0)));
      if (x != line) {
        EXPECT_EQ(reference(x, y, 0), 0.f);
      }
    }
  std::printf(
      "[ measured ] sharp line 50 into CoC 12: max leak at distance 1,2,3,4,8: %.4f %.4f "
      "%.4f %.4f %.4f\n",
      leak[1], leak[2], leak[3], leak[4], leak[8]);
  EXPECT_EQ(out(line, 10, 0), 50.f);
  // Measured: at most 0.0045 (1e-4 of the line) at distance 1-4, 0 beyond: what remains is the
  // mask's 1/1024 share of a sharp pixel. Unweighted bilinear reads leaked 0.76 here.
  for (std::ptrdiff_t d = 1; d < w - line; ++d) EXPECT_LT(leak[std::size_t(d)], 0.007) << d;
}

TEST(DofPoisson, ForegroundKeepsSharpSilhouetteOverSharpBackground) {
  // The stated limitation (seed 000 §6.5, fig. 6.3): a blurred near square does not spread over
  // the sharp background, whose pixels keep their values bit for bit.
  const std::ptrdiff_t size = 96;
  const Image color = random_image(size, size, 3, 0.f, 1.f, 13);
  auto inside = [](std::ptrdiff_t x, std::ptrdiff_t y) {
    return x >= 32 && x < 64 && y >= 32 && y < 64;
  };
  const Image coc =
      make_coc(size, size, [&](auto x, auto y) { return inside(x, y) ? -16.f : 0.f; });
  const Image out = run(poisson(), color, coc);
  std::ptrdiff_t moved = 0;
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < size; ++y)
      for (std::ptrdiff_t x = 0; x < size; ++x)
        if (!inside(x, y)) moved += !same_bits(out(x, y, c), color(x, y, c));
  EXPECT_EQ(moved, 0);
}

TEST(DofPoisson, IndependentOfThreadCount) {
  const std::ptrdiff_t w = 131, h = 97;
  const Image color = random_image(w, h, 3, 0.f, 2.f, 14);
  const Image coc = make_coc(w, h, [](auto x, auto y) {
    return 30.f * std::sin(float(x) / 11.f) * std::cos(float(y) / 9.f);
  });
  DofOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const Image a = run(poisson(), color, coc, one), b = run(poisson(), color, coc, two);
  std::ptrdiff_t differ = 0;
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < h; ++y)
      for (std::ptrdiff_t x = 0; x < w; ++x) differ += !same_bits(a(x, y, c), b(x, y, c));
  EXPECT_EQ(differ, 0);
}

TEST(DofPoisson, FloatEdgeCases) {
  // Huge and tiny CoCs, -0, colours from denormal to 1e30, one channel and five.
  const float big = 1e12f, tiny = std::numeric_limits<float>::denorm_min();
  for (int channels : {1, 5}) {
    const Image color = make_image(17, 5, channels, [&](auto x, auto y, int c) {
      return (x + y + c) % 3 == 0 ? tiny : (x + y + c) % 3 == 1 ? 1e30f : -1e-30f;
    });
    const Image coc = make_coc(17, 5, [&](auto x, auto y) {
      const float values[] = {big, -big, -0.f, 1.f, -1.f, 0.999f, 1e9f, 2.5f};
      return values[(x + 3 * y) % 8];
    });
    DofReport report;
    const Image out = run(poisson(), color, coc, {}, &report);
    ASSERT_EQ(out.channels(), channels);
    for (int c = 0; c < channels; ++c)
      for (std::ptrdiff_t y = 0; y < 5; ++y)
        for (std::ptrdiff_t x = 0; x < 17; ++x) {
          ASSERT_TRUE(std::isfinite(out(x, y, c))) << x << ", " << y;
          EXPECT_LE(out(x, y, c), 1e30f * (1 + 1e-5f));
          EXPECT_GE(out(x, y, c), -1e-30f * (1 + 1e-5f));
        }
  }
}

TEST(DofPoisson, ReportsStagesAndSkipping) {
  const std::ptrdiff_t w = 256, h = 192;
  const Image color = random_image(w, h, 3, 0.f, 1.f, 15);
  const Image coc = make_coc(
      w, h, [](auto x, auto y) { return (x >= 68 && x < 124 && y >= 70 && y < 126) ? 14.f : 0.f; });
  DofReport report;
  run(poisson(), color, coc, {}, &report);
  EXPECT_GE(report.stages.size(), 2u);
  // Only the tiles holding the block's pixels gather: 2 x 2 of the 8 x 6 tiles of 32 px.
  EXPECT_NEAR(report.skipped_fraction, 1.0 - 4.0 / 48.0, 1e-12);
  EXPECT_FALSE(report.layered);
  EXPECT_FALSE(report.notes.empty());
}

}  // namespace
}  // namespace tridiff::test
