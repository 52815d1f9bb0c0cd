// The scatter reference DOF (`scatter`, dof/src/method_scatter.cpp) against facts that do not
// come from its code: energy per channel under a uniform CoC (mirror border), the impulse
// response's analytic disc (weights sum to 1, support D/2 + 1/2, flat interior 4/(pi D^2),
// variance D^2/16 per axis), in-focus identity bit for bit, a sharp near object untouched over a
// blurred background, a blurred near object spreading over a sharp background by the area of a
// circular segment, constant colour under any CoC map, threads, and bad input.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "test_util.hpp"
#include "tridiff/dof/method.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

const DofMethod& scatter() { return find_dof_method("scatter"); }

Image run(const Image& color, const Image& coc, const DofOptions& settings = {}) {
  Image out;
  DofReport report;
  report = depth_of_field(out, color, coc.plane(0), scatter(), settings);
  EXPECT_EQ(out.width(), color.width());
  EXPECT_EQ(out.height(), color.height());
  EXPECT_EQ(out.channels(), color.channels());
  return out;
}

double channel_sum(const Image& image, int c) {
  double sum = 0;
  for (std::ptrdiff_t y = 0; y < image.height(); ++y)
    for (std::ptrdiff_t x = 0; x < image.width(); ++x) sum += image(x, y, c);
  return sum;
}

// A CoC map that mixes sharp regions, far blur and near blur up to 22 px, with many layers.
Image mixed_coc(std::ptrdiff_t width, std::ptrdiff_t height) {
  return make_coc(width, height, [](auto x, auto y) {
    const float v = 22.f * std::sin(float(x) / 11.f) * std::cos(float(y) / 9.f);
    return std::fabs(v) < 5.f ? 0.3f * v / 5.f : v;
  });
}

TEST(ScatterReference, Registered) {
  const DofMethod& m = scatter();
  EXPECT_TRUE(m.blurs_foreground);
  EXPECT_FALSE(m.unbounded_blur);
  EXPECT_FALSE(m.summary.empty());
  EXPECT_FALSE(m.cost.empty());
}

// Uniform CoC: one layer; the mirror-folded discs keep every splat's energy in the frame, so the
// total per channel is the input's — also for discs larger than the frame (several folds) and
// for the near field (negative CoC).
TEST(ScatterReference, UniformCocConservesEnergyPerChannel) {
  const std::ptrdiff_t width = 61, height = 47;
  const Image color = random_image(width, height, 3, 0.f, 2.f, 5);
  for (float d : {1.f, 3.7f, 9.3f, -17.f, 40.6f, 130.f}) {
    const Image coc = make_coc(width, height, [&](auto, auto) { return d; });
    for (bool skip : {true, false}) {
      if (!skip && std::fabs(d) > 20.f) continue;  // the large discs once: they cost the most
      DofOptions settings;
      settings.skip_in_focus = skip;
      const Image out = run(color, coc, settings);
      for (int c = 0; c < 3; ++c) {
        const double before = channel_sum(color, c), after = channel_sum(out, c);
        EXPECT_NEAR(after, before, 1e-6 * before) << "CoC " << d << " channel " << c;
        if (skip && c == 0)
          std::printf("[ measured ] CoC %.1f: relative energy change %.2e\n", double(d),
                      (after - before) / before);
      }
    }
  }
}

// The impulse response under a uniform CoC D is the disc itself: weights summing to 1, zero at
// distance >= D/2 + 1/2 (the one-pixel anti-aliasing ramp centred on the rim), a flat interior of
// 1/area = 4/(pi D^2), centred, and the per-axis variance of a uniform disc of radius D/2, D^2/16,
// plus what the ramp adds: with w(rho) the ramp from r - 1/2 to r + 1/2 in place of the step at
// r, int (ramp - step) t dt = 1/24, so int rho^3 w = r^4/4 + r^2/8 and int rho w = r^2/2 + 1/24,
// E[rho^2] = r^2/2 + 5/24 + O(1/r^2), i.e. 5/48 ~ 0.1 px^2 per axis; the lattice adds a few
// hundredths either way.
TEST(ScatterReference, ImpulseGivesTheAreaNormalisedDisc) {
  const std::ptrdiff_t size = 67, centre = 33;
  for (float d : {4.f, 9.f, 16.f, 25.f}) {
    Image color(size, size, 1);
    color(centre, centre, 0) = 1.f;
    const Image coc = make_coc(size, size, [&](auto, auto) { return d; });
    const Image out = run(color, coc);
    double sum = 0, mx = 0, my = 0, vx = 0, vy = 0, interior_lo = 1e9, interior_hi = 0;
    std::ptrdiff_t outside = 0;
    for (std::ptrdiff_t y = 0; y < size; ++y)
      for (std::ptrdiff_t x = 0; x < size; ++x) {
        const double w = out(x, y, 0), dx = double(x - centre), dy = double(y - centre);
        const double rho = std::hypot(dx, dy);
        sum += w;
        mx += w * dx;
        my += w * dy;
        vx += w * dx * dx;
        vy += w * dy * dy;
        outside += rho >= 0.5 * d + 0.5 && std::fabs(w) > 1e-7;
        if (rho <= 0.5 * d - 0.5) {
          interior_lo = std::min(interior_lo, w);
          interior_hi = std::max(interior_hi, w);
        }
      }
    const double flat = 4.0 / (std::numbers::pi * d * d), var = d * d / 16.0;
    EXPECT_NEAR(sum, 1.0, 1e-5) << "D " << d;
    EXPECT_EQ(outside, 0) << "D " << d;
    EXPECT_NEAR(mx, 0.0, 1e-5) << "D " << d;
    EXPECT_NEAR(my, 0.0, 1e-5) << "D " << d;
    // The interior is flat (the same weight everywhere) and close to 1 / (pi r^2): the lattice
    // disc's area differs from pi r^2 by the rim's discretisation, < 8 % for D >= 4.
    EXPECT_NEAR(interior_hi / interior_lo, 1.0, 1e-5) << "D " << d;
    EXPECT_NEAR(interior_hi / flat, 1.0, 0.08) << "D " << d;
    // Variance per axis: D^2/16 + 0.1 from the ramp, within 0.1 px^2 + 0.5 %.
    EXPECT_NEAR(vx, var + 0.1, 0.1 + 0.005 * var) << "D " << d;
    EXPECT_NEAR(vy, var + 0.1, 0.1 + 0.005 * var) << "D " << d;
    EXPECT_NEAR(vx, vy, 1e-5 * var) << "D " << d;  // the disc is isotropic on the lattice axes
    std::printf("[ measured ] D %.0f: sum %.7f, var x %.4f (D^2/16 = %.4f), interior %.3f x flat\n",
                double(d), sum, vx, var, interior_hi / flat);
  }
  // An impulse in a corner: the part of the disc beyond the border is reflected back in, so the
  // weights still sum to 1.
  Image color(size, size, 1);
  color(1, 2, 0) = 1.f;
  const Image coc = make_coc(size, size, [](auto, auto) { return 20.f; });
  EXPECT_NEAR(channel_sum(run(color, coc), 0), 1.0, 1e-5);
}

// Every pixel in focus (|CoC| below max(1, in_focus_coc_px)): a point each, output = input bit for
// bit, with and without skipping; negative values and signed zeros included.
TEST(ScatterReference, InFocusEverywhereIsIdentity) {
  const std::ptrdiff_t width = 70, height = 45;
  Image color = random_image(width, height, 4, -1.f, 3.f, 9);
  color(3, 4, 1) = -0.f;
  color(60, 40, 2) = 0.f;
  color(7, 7, 0) = 1e30f;
  struct Variant {
    float limit, threshold;
  };
  for (const Variant v : {Variant{0.99f, 1.f}, Variant{4.9f, 5.f}}) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> dist(-v.limit, v.limit);
    const Image coc = make_coc(width, height, [&](auto, auto) { return dist(rng); });
    for (bool skip : {true, false}) {
      DofOptions settings;
      settings.skip_in_focus = skip;
      settings.in_focus_coc_px = v.threshold;
      const Image out = run(color, coc, settings);
      std::ptrdiff_t differ = 0;
      for (int c = 0; c < 4; ++c)
        for (std::ptrdiff_t y = 0; y < height; ++y)
          for (std::ptrdiff_t x = 0; x < width; ++x)
            differ += !same_bits(out(x, y, c), color(x, y, c));
      EXPECT_EQ(differ, 0) << "threshold " << v.threshold << (skip ? " skip" : " no skip");
    }
  }
}

// A sharp object in front of a blurred background: the object's pixels (points, nearer than
// every background splat) are exactly their input — no colour of the background leaks onto
// them — while the background around them is blurred.
TEST(ScatterReference, SharpNearObjectStaysSharpOverBlurredBackground) {
  const std::ptrdiff_t size = 96;
  const Image color = random_image(size, size, 3, 0.f, 1.f, 21);
  auto object = [](std::ptrdiff_t x, std::ptrdiff_t y) {
    return x >= 30 && x < 62 && y >= 35 && y < 70;
  };
  for (float object_coc : {0.f, -0.6f, 0.8f}) {
    const Image coc =
        make_coc(size, size, [&](auto x, auto y) { return object(x, y) ? object_coc : 14.f; });
    for (bool skip : {true, false}) {
      DofOptions settings;
      settings.skip_in_focus = skip;
      const Image out = run(color, coc, settings);
      std::ptrdiff_t object_moved = 0, background_moved = 0, background = 0;
      for (std::ptrdiff_t y = 0; y < size; ++y)
        for (std::ptrdiff_t x = 0; x < size; ++x)
          for (int c = 0; c < 3; ++c) {
            const bool same = same_bits(out(x, y, c), color(x, y, c));
            if (object(x, y)) {
              object_moved += !same;
            } else {
              ++background;
              background_moved += !same;
            }
          }
      EXPECT_EQ(object_moved, 0) << "object CoC " << object_coc;
      EXPECT_EQ(background_moved, background) << "object CoC " << object_coc;
    }
  }
}

// A blurred near object (the left half, colour 1, CoC -12: radius 6) in front of a sharp
// background (colour 0): at distance d outside the edge, the near layer's coverage is the share of
// a disc of radius r = 6 beyond a chord at distance d — the circular segment
// (r^2 acos(d/r) - d sqrt(r^2 - d^2)) / (pi r^2) — and the output is that coverage times the
// object's colour. Beyond r + 1/2 nothing reaches. Inside the object the far splats are
// normalised by the accumulated coverage, so it keeps its colour.
TEST(ScatterReference, BlurredNearObjectSpreadsOverSharpBackground) {
  const std::ptrdiff_t width = 96, height = 40, edge = 48;
  const double r = 6.0;
  const Image color =
      make_image(width, height, 1, [&](auto x, auto, int) { return x < edge ? 1.f : 0.f; });
  const Image coc = make_coc(width, height, [&](auto x, auto) { return x < edge ? -12.f : 0.f; });
  const Image out = run(color, coc);
  for (std::ptrdiff_t y = 0; y < height; ++y) {
    for (std::ptrdiff_t k = 0; k < 6; ++k) {
      const double d = double(k) + 0.5;
      const double segment =
          (r * r * std::acos(d / r) - d * std::sqrt(r * r - d * d)) / (std::numbers::pi * r * r);
      const double got = out(edge + k, y, 0);
      EXPECT_GT(got, 0.0) << "x " << edge + k << " y " << y;
      EXPECT_NEAR(got, segment, 0.005) << "x " << edge + k << " y " << y;
      if (y == height / 2)
        std::printf("[ measured ] %.1f px outside the edge: coverage %.4f, segment %.4f\n", d, got,
                    segment);
    }
    for (std::ptrdiff_t x = edge + 7; x < width; ++x)
      EXPECT_EQ(out(x, y, 0), 0.f) << x << ", " << y;
    for (std::ptrdiff_t x = 0; x < edge; ++x)
      EXPECT_NEAR(out(x, y, 0), 1.f, 1e-5) << x << ", " << y;
  }
}

// A constant colour stays constant whatever the CoC map: the depth-composited weights sum to 1
// at every pixel ("over" telescopes to 1 - T, then the normalisation by 1 - T).
TEST(ScatterReference, ConstantColourStaysConstantForAnyCoc) {
  const std::ptrdiff_t width = 90, height = 70;
  const float value[4] = {0.25f, 1.f, 3.5f, 1000.f};
  const Image color = make_image(width, height, 4, [&](auto, auto, int c) { return value[c]; });
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> noise(-20.f, 20.f);
  const Image maps[] = {mixed_coc(width, height),
                        make_coc(width, height, [&](auto, auto) { return noise(rng); }),
                        make_coc(width, height, [](auto x, auto) { return float(x) - 45.f; })};
  for (const Image& coc : maps) {
    const Image out = run(color, coc);
    float worst = 0;
    for (int c = 0; c < 4; ++c)
      for (std::ptrdiff_t y = 0; y < height; ++y)
        for (std::ptrdiff_t x = 0; x < width; ++x)
          worst = std::max(worst, std::fabs(out(x, y, c) - value[c]) / value[c]);
    EXPECT_LT(worst, 1e-5f);
    std::printf("[ measured ] constant colour: largest relative change %.2e\n", double(worst));
  }
}

TEST(ScatterReference, ThreadCountDoesNotChangeABit) {
  const std::ptrdiff_t width = 110, height = 83;
  const Image color = random_image(width, height, 3, 0.f, 4.f, 31);
  const Image coc = mixed_coc(width, height);
  DofOptions one;
  one.threads = 1;
  const Image reference = run(color, coc, one);
  for (int threads : {2, 3}) {
    DofOptions settings;
    settings.threads = threads;
    const Image out = run(color, coc, settings);
    std::ptrdiff_t differ = 0;
    for (int c = 0; c < 3; ++c)
      for (std::ptrdiff_t y = 0; y < height; ++y)
        for (std::ptrdiff_t x = 0; x < width; ++x)
          differ += !same_bits(out(x, y, c), reference(x, y, c));
    EXPECT_EQ(differ, 0) << threads << " threads";
  }
}

TEST(ScatterReference, BadInputIsRejected) {
  const Image color = random_image(20, 12, 3, 0.f, 1.f, 2);
  Image out;
  DofReport report;
  const Image small(19, 12, 1);
  EXPECT_EQ(invalid_argument_of([&] {
              depth_of_field(out, color, small.plane(0), scatter(), {});
            }).argument,
            "coc");
  Image coc = make_coc(20, 12, [](auto, auto) { return 5.f; });
  coc(4, 9, 0) = std::numeric_limits<float>::quiet_NaN();
  const Thrown nan_coc = invalid_argument_of([&] { run(color, coc); });
  EXPECT_EQ(nan_coc.argument, "coc");
  EXPECT_TRUE(contains(nan_coc.message, "pixel (4, 9)"));
  Image bad_color = color;
  bad_color(11, 3, 2) = std::numeric_limits<float>::infinity();
  const Image good_coc = make_coc(20, 12, [](auto, auto) { return 5.f; });
  const Thrown inf_color = invalid_argument_of([&] { run(bad_color, good_coc); });
  EXPECT_EQ(inf_color.argument, "color");
  EXPECT_TRUE(contains(inf_color.message, "pixel (11, 3)"));
  Image huge = good_coc;
  huge(2, 1, 0) = -1e20f;  // finite, but a disc no machine could splat
  const Thrown too_large = invalid_argument_of([&] { run(color, huge); });
  EXPECT_EQ(too_large.argument, "coc");
  EXPECT_TRUE(contains(too_large.message, "pixel (2, 1)"));
  DofOptions negative;
  negative.threads = -1;
  EXPECT_EQ(invalid_argument_of([&] { run(color, good_coc, negative); }).argument, "threads");
}

}  // namespace
}  // namespace tridiff::test
