// The summed-area-table DOF methods `sat` and `sat-layers` (dof/src/method_sat.cpp, seed 003)
// against facts that do not come from their code: a uniform CoC is the three-box kernel of seed
// 003 computed here by brute force in double over the half-resolution image (any size, boxes far
// larger than the frame, 4096-wide rows), in-focus identity bit for bit, constant colour under
// any CoC map, outputs within the input's range, no leak of sharp colours into the background
// (sat-layers), the near layer spreading over a sharp background and hiding a small far blur
// behind it, thread-count independence, skipping, and the error against the `scatter` reference
// on the procedural scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "test_util.hpp"
#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/scene.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

struct Result {
  Image out;
  DofReport report;
};

Result run(const char* name, const Image& color, const Image& coc,
           const DofOptions& settings = {}) {
  Result r;
  r.report = depth_of_field(r.out, color, coc.plane(0), find_dof_method(name), settings);
  EXPECT_EQ(r.out.width(), color.width());
  EXPECT_EQ(r.out.height(), color.height());
  EXPECT_EQ(r.out.channels(), color.channels());
  return r;
}

constexpr const char* kMethods[] = {"sat", "sat-layers"};

// ---------------------------------------------------------------------------------------------
// The brute-force three-box kernel, written from seed 003 without the tables.

// The half-resolution image in double: the mean of each 2 x 2 block, the edge pixel repeated
// where an odd size leaves a block half outside.
struct HalfRes {
  std::ptrdiff_t width, height;
  std::vector<double> values;  // width x height per channel
  double at(std::ptrdiff_t i, std::ptrdiff_t j, int c) const {
    return values[std::size_t((c * height + j) * width + i)];
  }
};

HalfRes half_res(const Image& color) {
  HalfRes h{(color.width() + 1) / 2, (color.height() + 1) / 2, {}};
  h.values.resize(std::size_t(h.width * h.height * color.channels()));
  for (int c = 0; c < color.channels(); ++c)
    for (std::ptrdiff_t j = 0; j < h.height; ++j)
      for (std::ptrdiff_t i = 0; i < h.width; ++i) {
        double sum = 0;
        for (std::ptrdiff_t y : {2 * j, 2 * j + 1})
          for (std::ptrdiff_t x : {2 * i, 2 * i + 1})
            sum += color(std::min(x, color.width() - 1), std::min(y, color.height() - 1), c);
        h.values[std::size_t((c * h.height + j) * h.width + i)] = sum / 4;
      }
  return h;
}

// How much of [lo, hi] lies in cell i of a line of n cells extended by its edge cells: cell 0
// reaches to -infinity and cell n - 1 to +infinity (the replicate border).
double overlap(double lo, double hi, std::ptrdiff_t i, std::ptrdiff_t n) {
  const double cell_lo = i == 0 ? -INFINITY : double(i);
  const double cell_hi = i == n - 1 ? INFINITY : double(i + 1);
  return std::max(0.0, std::min(hi, cell_hi) - std::max(lo, cell_lo));
}

// The mean of the half-resolution image (upsampled by pixel replication) over the
// full-resolution box of half-extents (ax, ay) about the centre of pixel (x, y).
double box_mean(const HalfRes& h, int c, std::ptrdiff_t x, std::ptrdiff_t y, double ax, double ay) {
  const double x0 = (double(x) + 0.5 - ax) / 2, x1 = (double(x) + 0.5 + ax) / 2;
  const double y0 = (double(y) + 0.5 - ay) / 2, y1 = (double(y) + 0.5 + ay) / 2;
  auto first = [](double lo, std::ptrdiff_t n) {
    return std::clamp<std::ptrdiff_t>(std::ptrdiff_t(std::floor(std::max(lo, -1.0))), 0, n - 1);
  };
  auto last = [](double hi, std::ptrdiff_t n) {
    return std::clamp<std::ptrdiff_t>(std::ptrdiff_t(std::min(std::ceil(hi), double(n))), 0, n - 1);
  };
  double sum = 0;
  for (std::ptrdiff_t j = first(y0, h.height); j <= last(y1, h.height); ++j) {
    const double wy = overlap(y0, y1, j, h.height);
    for (std::ptrdiff_t i = first(x0, h.width); i <= last(x1, h.width); ++i)
      sum += overlap(x0, x1, i, h.width) * wy * h.at(i, j, c);
  }
  return sum / ((x1 - x0) * (y1 - y0));
}

// Seed 003: the average of the boxes R x R/2, 3R/4 x 3R/4 and R/2 x R (half-extents), R = |c|/2.
double three_box(const HalfRes& h, int c, std::ptrdiff_t x, std::ptrdiff_t y, double coc) {
  const double r = std::fabs(coc) / 2;
  return (box_mean(h, c, x, y, r, r / 2) + box_mean(h, c, x, y, 0.75 * r, 0.75 * r) +
          box_mean(h, c, x, y, r / 2, r)) /
         3;
}

double max_abs(const Image& image) {
  double m = 0;
  for (int c = 0; c < image.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < image.height(); ++y)
      for (std::ptrdiff_t x = 0; x < image.width(); ++x)
        m = std::max(m, std::fabs(double(image(x, y, c))));
  return m;
}

// The largest |out - three_box| over the image, for a uniform CoC.
double worst_against_three_box(const Image& out, const Image& color, double coc) {
  const HalfRes h = half_res(color);
  double worst = 0;
  for (int c = 0; c < color.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < color.height(); ++y)
      for (std::ptrdiff_t x = 0; x < color.width(); ++x)
        worst = std::max(worst, std::fabs(double(out(x, y, c)) - three_box(h, c, x, y, coc)));
  return worst;
}

// A CoC map with sharp regions, far blur and near blur up to 22 px.
Image mixed_coc(std::ptrdiff_t width, std::ptrdiff_t height) {
  return make_coc(width, height, [](auto x, auto y) {
    const float v = 22.f * std::sin(float(x) / 11.f) * std::cos(float(y) / 9.f);
    return std::fabs(v) < 5.f ? 0.3f * v / 5.f : v;
  });
}

// ---------------------------------------------------------------------------------------------

TEST(SatDof, Registered) {
  const DofMethod& sat = find_dof_method("sat");
  const DofMethod& layers = find_dof_method("sat-layers");
  EXPECT_TRUE(sat.unbounded_blur);
  EXPECT_TRUE(layers.unbounded_blur);
  EXPECT_FALSE(sat.blurs_foreground);  // a gather with the pixel's own CoC
  EXPECT_TRUE(layers.blurs_foreground);
}

// Uniform CoC: every pixel is the seed's three-box average of the half-resolution image, at sizes
// down to 1 x 1, odd sizes, and CoCs far larger than the frame. sat-layers gives the same: one
// layer (far for c > 0, near for c < 0) whose coverage is 1 everywhere. Tolerance: the float
// half-resolution image and the float output, 8 float epsilons of the largest |value|.
TEST(SatDof, UniformCocIsTheThreeBoxAverage) {
  struct Size {
    std::ptrdiff_t width, height;
  };
  double worst_ratio = 0;
  for (const Size size : {Size{1, 1}, Size{2, 3}, Size{17, 5}, Size{64, 41}, Size{131, 97}}) {
    Image color = random_image(size.width, size.height, 3, -0.5f, 2.f, 13);
    color(0, 0, 1) = 30.f;  // a highlight on the border
    const HalfRes h = half_res(color);
    const double tol = 8 * FLT_EPSILON * max_abs(color);
    for (float d : {1.f, 2.5f, -3.7f, 9.f, -16.f, 41.f, 300.f}) {
      if (d > 100.f && size.width > 17) continue;  // the brute force reads every cell per box
      const Image coc = make_coc(size.width, size.height, [&](auto, auto) { return d; });
      std::vector<double> expected;
      for (int c = 0; c < 3; ++c)
        for (std::ptrdiff_t y = 0; y < size.height; ++y)
          for (std::ptrdiff_t x = 0; x < size.width; ++x)
            expected.push_back(three_box(h, c, x, y, d));
      for (const char* name : kMethods) {
        const Result r = run(name, color, coc);
        double worst = 0;
        std::size_t i = 0;
        for (int c = 0; c < 3; ++c)
          for (std::ptrdiff_t y = 0; y < size.height; ++y)
            for (std::ptrdiff_t x = 0; x < size.width; ++x)
              worst = std::max(worst, std::fabs(double(r.out(x, y, c)) - expected[i++]));
        EXPECT_LE(worst, tol) << name << " " << size.width << " x " << size.height << ", CoC " << d;
        worst_ratio = std::max(worst_ratio, worst / tol);
      }
    }
  }
  std::printf("[ measured ] worst error against the brute-force three boxes: %.3f x tolerance\n",
              worst_ratio);
}

// A box much larger than the frame is mostly the replicated border: the three-box mean tends to
// the mean of the four corner cells of the half-resolution image, with the edges' share of the
// area, O(frame / R), as the difference.
TEST(SatDof, HugeCocTendsToTheCornerMean) {
  const Image color = random_image(9, 7, 2, 0.f, 1.f, 17);
  const HalfRes h = half_res(color);
  for (float d : {1e6f, -1e7f})
    for (const char* name : kMethods) {
      const Image coc = make_coc(9, 7, [&](auto, auto) { return d; });
      const Result r = run(name, color, coc);
      for (int c = 0; c < 2; ++c) {
        const double corners = (h.at(0, 0, c) + h.at(4, 0, c) + h.at(0, 3, c) + h.at(4, 3, c)) / 4;
        for (std::ptrdiff_t y = 0; y < 7; ++y)
          for (std::ptrdiff_t x = 0; x < 9; ++x) {
            ASSERT_TRUE(std::isfinite(r.out(x, y, c)));
            EXPECT_NEAR(r.out(x, y, c), corners, 20.0 / std::fabs(d)) << name << " " << d;
          }
      }
    }
}

// The SAT's precision: 4096-wide rows of HDR values (0..100) and a small box (CoC 2: boxes of
// 0.5 to 0.56 half-resolution cells). A plain float table would hold entries up to
// 4096 x 64 x 50 / 4 = 3.3e6 (ulp 0.25): errors of ~0.5 on a box sum of ~25, 2 % and far above
// the tolerance; the double table keeps the error at the float rounding of the values.
TEST(SatDof, PrecisionAt4096WideRows) {
  const std::ptrdiff_t width = 4096, height = 64;
  const Image color = random_image(width, height, 1, 0.f, 100.f, 23);
  const double tol = 8 * FLT_EPSILON * max_abs(color);
  for (float d : {2.f, -2.f, 3.3f})
    for (const char* name : kMethods) {
      const Image coc = make_coc(width, height, [&](auto, auto) { return d; });
      const double worst = worst_against_three_box(run(name, color, coc).out, color, d);
      EXPECT_LE(worst, tol) << name << " CoC " << d;
      std::printf("[ measured ] %s 4096 x 64, CoC %.1f: worst error %.3g (tolerance %.3g)\n", name,
                  double(d), worst, tol);
    }
}

// Every pixel in focus (|CoC| below max(1, in_focus_coc_px)): output = input bit for bit, with
// and without skipping; negative values, signed zeros and a huge value included.
TEST(SatDof, InFocusEverywhereIsIdentity) {
  const std::ptrdiff_t width = 70, height = 45;
  Image color = random_image(width, height, 4, -1.f, 3.f, 9);
  color(3, 4, 1) = -0.f;
  color(7, 7, 0) = 1e30f;
  struct Variant {
    float limit, threshold;
  };
  for (const Variant v : {Variant{0.99f, 1.f}, Variant{4.9f, 5.f}}) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> dist(-v.limit, v.limit);
    const Image coc = make_coc(width, height, [&](auto, auto) { return dist(rng); });
    for (const char* name : kMethods)
      for (bool skip : {true, false}) {
        DofOptions settings;
        settings.skip_in_focus = skip;
        settings.in_focus_coc_px = v.threshold;
        const Result r = run(name, color, coc, settings);
        std::ptrdiff_t differ = 0;
        for (int c = 0; c < 4; ++c)
          for (std::ptrdiff_t y = 0; y < height; ++y)
            for (std::ptrdiff_t x = 0; x < width; ++x)
              differ += !same_bits(r.out(x, y, c), color(x, y, c));
        EXPECT_EQ(differ, 0) << name << " threshold " << v.threshold << (skip ? " skip" : "");
        EXPECT_FALSE(r.report.layered) << name;
        EXPECT_EQ(r.report.skipped_fraction, skip ? 1.0 : 0.0) << name;
      }
  }
}

// The sharp threshold is strict: |c| = 1 blurs, the float just below it does not, -0 is sharp.
TEST(SatDof, SharpThresholdIsStrict) {
  const Image color = random_image(12, 10, 1, 0.f, 1.f, 31);
  const float below = std::nextafter(1.f, 0.f);
  for (const char* name : kMethods)
    for (float d : {1.f, -1.f, below, -below, -0.f}) {
      const Image coc = make_coc(12, 10, [&](auto, auto) { return d; });
      const Result r = run(name, color, coc);
      std::ptrdiff_t same = 0;
      for (std::ptrdiff_t y = 0; y < 10; ++y)
        for (std::ptrdiff_t x = 0; x < 12; ++x) same += same_bits(r.out(x, y, 0), color(x, y, 0));
      if (std::fabs(d) < 1.f) {
        EXPECT_EQ(same, 120) << name << " CoC " << d;
      } else {
        EXPECT_LT(same, 12) << name << " CoC " << d;  // a half-resolution blur moves nearly all
      }
    }
}

// A constant colour stays constant for any CoC map: every weight of both methods sums to one.
TEST(SatDof, ConstantColourStaysConstant) {
  const std::ptrdiff_t width = 101, height = 77;
  const Image coc = mixed_coc(width, height);
  for (float value : {0.37f, 250.f, -3.f})
    for (const char* name : kMethods) {
      const Image color = make_image(width, height, 2, [&](auto, auto, int) { return value; });
      const Result r = run(name, color, coc);
      double worst = 0;
      for (int c = 0; c < 2; ++c)
        for (std::ptrdiff_t y = 0; y < height; ++y)
          for (std::ptrdiff_t x = 0; x < width; ++x)
            worst = std::max(worst, std::fabs(double(r.out(x, y, c)) - value));
      EXPECT_LE(worst, 4 * FLT_EPSILON * std::fabs(value)) << name << " value " << value;
    }
}

// Both methods are convex combinations of the input: the output stays in the input's range per
// channel (two-sided: negative values too), up to float rounding.
TEST(SatDof, OutputWithinInputRange) {
  const std::ptrdiff_t width = 150, height = 111;
  Image color = random_image(width, height, 3, 0.f, 1.f, 7);
  color(10, 10, 0) = 40.f;
  for (std::ptrdiff_t y = 0; y < 40; ++y)
    for (std::ptrdiff_t x = 60; x < 90; ++x) color(x, y, 1) = -0.5f - 0.01f * float(x);
  const Image coc = mixed_coc(width, height);
  for (const char* name : kMethods) {
    const Result r = run(name, color, coc);
    for (int c = 0; c < 3; ++c) {
      float lo = INFINITY, hi = -INFINITY, out_lo = INFINITY, out_hi = -INFINITY;
      for (std::ptrdiff_t y = 0; y < height; ++y)
        for (std::ptrdiff_t x = 0; x < width; ++x) {
          lo = std::min(lo, color(x, y, c));
          hi = std::max(hi, color(x, y, c));
          out_lo = std::min(out_lo, r.out(x, y, c));
          out_hi = std::max(out_hi, r.out(x, y, c));
        }
      const float slack = 4 * FLT_EPSILON * std::max(std::fabs(lo), std::fabs(hi));
      EXPECT_GE(out_lo, lo - slack) << name << " channel " << c;
      EXPECT_LE(out_hi, hi + slack) << name << " channel " << c;
    }
  }
}

// The result does not depend on the thread count, nor on skipping, bit for bit; with a near
// field present (sat-layers' foreground pass runs) and odd tile edges.
TEST(SatDof, ThreadsAndSkippingChangeNoBit) {
  const std::ptrdiff_t width = 203, height = 157;
  const Image color = random_image(width, height, 3, 0.f, 2.f, 3);
  // Mostly sharp: a near disc and a far corner, so that some tiles are skipped; then the near
  // disc alone (sat-layers without far tables when skipping).
  auto near_disc = [](std::ptrdiff_t x, std::ptrdiff_t y) {
    return std::hypot(double(x - 60), double(y - 50)) < 20;
  };
  const Image cocs[] = {
      make_coc(width, height,
               [&](auto x, auto y) {
                 if (near_disc(x, y)) return -13.f;
                 if (x > 170 && y > 110) return 9.f + 0.1f * float(y);
                 return 0.2f;
               }),
      make_coc(width, height, [&](auto x, auto y) { return near_disc(x, y) ? -13.f : 0.f; })};
  for (const Image& coc : cocs)
    for (const char* name : kMethods) {
      DofOptions one, two, no_skip;
      one.threads = 1;
      two.threads = 2;
      no_skip.threads = 2;
      no_skip.skip_in_focus = false;
      const Result a = run(name, color, coc, one), b = run(name, color, coc, two),
                   c = run(name, color, coc, no_skip);
      std::ptrdiff_t threads_differ = 0, skip_differ = 0;
      for (int ch = 0; ch < 3; ++ch)
        for (std::ptrdiff_t y = 0; y < height; ++y)
          for (std::ptrdiff_t x = 0; x < width; ++x) {
            threads_differ += !same_bits(a.out(x, y, ch), b.out(x, y, ch));
            skip_differ += !same_bits(b.out(x, y, ch), c.out(x, y, ch));
          }
      EXPECT_EQ(threads_differ, 0) << name;
      EXPECT_EQ(skip_differ, 0) << name;
      // The TileMap stamps whole tiles' reach: 25 of the 35 tiles are reached with the far
      // corner (27 % skipped).
      EXPECT_GT(b.report.skipped_fraction, 0.2) << name;
      EXPECT_EQ(c.report.skipped_fraction, 0.0) << name;
      EXPECT_EQ(b.report.layered, std::string(name) == "sat-layers") << name;
    }
}

// Seed 003's leak: a sharp white object beside a black blurred background. `sat` gathers the
// white into the background's blur within R of the edge; sat-layers reads the background from
// the far layer alone, which holds only black: exactly 0 there.
TEST(SatDof, LayersStopSharpColourLeakingIntoBackground) {
  const std::ptrdiff_t width = 96, height = 64;
  const Image color =
      make_image(width, height, 1, [](auto x, auto, int) { return x < 48 ? 1.f : 0.f; });
  const Image coc = make_coc(width, height, [](auto x, auto) { return x < 48 ? 0.f : 12.f; });
  const Result plain = run("sat", color, coc), layered = run("sat-layers", color, coc);
  double plain_leak = 0, layered_leak = 0;
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 48; x < width; ++x) {
      plain_leak = std::max(plain_leak, double(plain.out(x, y, 0)));
      layered_leak = std::max(layered_leak, double(layered.out(x, y, 0)));
    }
  // The pixel next to the edge: half of the widest box (half-extent 6) covers white cells.
  EXPECT_GT(plain.out(48, 30, 0), 0.25f);
  EXPECT_GT(plain_leak, 0.25);
  EXPECT_EQ(layered_leak, 0.0);
  // The sharp side is untouched by both.
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < 48; ++x) {
      EXPECT_EQ(plain.out(x, y, 0), 1.f);
      EXPECT_EQ(layered.out(x, y, 0), 1.f);
    }
  std::printf("[ measured ] leak into the background: sat %.3f, sat-layers %.3f\n", plain_leak,
              layered_leak);
}

// A blurred near square (pure red, CoC -16, R = 8) over sharp grey stripes. sat-layers spreads
// the red over the background within about R of the square (the near layer's coverage there is
// the box-filtered square: about 1/2 at the edge, falling to 0 at R + the half-resolution cell),
// while `sat` (a gather) leaves every sharp pixel as it was. Far from the square both are the
// input, bit for bit.
TEST(SatDof, NearLayerSpreadsOverSharpBackground) {
  const std::ptrdiff_t size = 160, s0 = 48, s1 = 112;
  auto square = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
    return x >= s0 && x < s1 && y >= s0 && y < s1;
  };
  const Image color = make_image(size, size, 3, [&](auto x, auto y, int c) {
    if (square(x, y)) return c == 0 ? 1.f : 0.f;
    return (x / 2) % 2 ? 0.9f : 0.1f;
  });
  const Image coc =
      make_coc(size, size, [&](auto x, auto y) { return square(x, y) ? -16.f : 0.f; });
  auto red_excess = [](const Image& im, std::ptrdiff_t x, std::ptrdiff_t y) {
    return double(im(x, y, 0)) - 0.5 * (double(im(x, y, 1)) + double(im(x, y, 2)));
  };
  const Result plain = run("sat", color, coc), layered = run("sat-layers", color, coc);
  EXPECT_TRUE(layered.report.layered);
  // Mean red excess over the rows of the square's middle, at distance k left of its edge.
  auto ring = [&](const Image& im, std::ptrdiff_t k) {
    double sum = 0;
    for (std::ptrdiff_t y = 64; y < 96; ++y) sum += red_excess(im, s0 - 1 - k, y);
    return sum / 32;
  };
  EXPECT_GT(ring(layered.out, 0), 0.3);
  EXPECT_LT(ring(layered.out, 0), 0.7);
  for (std::ptrdiff_t k = 0; k < 8; ++k) EXPECT_GE(ring(layered.out, k), ring(layered.out, k + 1));
  EXPECT_GT(ring(layered.out, 4), 0.02);
  EXPECT_EQ(ring(layered.out, 12), 0.0);
  for (std::ptrdiff_t k = 0; k < 16; ++k) EXPECT_EQ(ring(plain.out, k), 0.0);
  // Far from the square (beyond R + margin), the input bit for bit.
  std::ptrdiff_t moved = 0;
  for (std::ptrdiff_t y = 0; y < size; ++y)
    for (std::ptrdiff_t x = 0; x < size; ++x) {
      if (x >= s0 - 12 && x < s1 + 12 && y >= s0 - 12 && y < s1 + 12) continue;
      for (int c = 0; c < 3; ++c) moved += !same_bits(layered.out(x, y, c), color(x, y, c));
    }
  EXPECT_EQ(moved, 0);
  std::printf("[ measured ] near halo (red excess) at 1, 3, 5, 7, 9 px: %.3f %.3f %.3f %.3f %.4f\n",
              ring(layered.out, 0), ring(layered.out, 2), ring(layered.out, 4),
              ring(layered.out, 6), ring(layered.out, 8));
}

// Behind a near object the far layer is read with the far pixels' own (small) radius: a bright
// far pixel (CoC 2) just outside a blurred near square (pure red, CoC -16) does not show through
// the square more than R_far + 1.5 px inside its edge, where the output is the square's colour
// exactly (G = B = 0), as in the scatter, whose far splats reach 1.5 px. `sat` gathers the
// highlight into the square with the square's radius.
TEST(SatDof, NearObjectHidesSmallBlurBehindIt) {
  const std::ptrdiff_t size = 128, s0 = 40, s1 = 88;
  auto square = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
    return x >= s0 && x < s1 && y >= s0 && y < s1;
  };
  Image color = make_image(size, size, 3, [&](auto x, auto y, int c) {
    return square(x, y) ? (c == 0 ? 1.f : 0.f) : 0.2f;
  });
  for (int c = 0; c < 3; ++c) color(s0 - 1, 64, c) = 1000.f;  // a highlight left of the edge
  const Image coc =
      make_coc(size, size, [&](auto x, auto y) { return square(x, y) ? -16.f : 2.f; });
  const Result plain = run("sat", color, coc), layered = run("sat-layers", color, coc);
  double layered_green = 0, plain_green = 0;
  for (std::ptrdiff_t y = 56; y < 72; ++y)
    for (std::ptrdiff_t x = s0 + 3; x < s0 + 8; ++x) {
      layered_green = std::max(layered_green, double(layered.out(x, y, 1)));
      plain_green = std::max(plain_green, double(plain.out(x, y, 1)));
    }
  EXPECT_EQ(layered_green, 0.0);
  EXPECT_GT(plain_green, 1.0);
  // Reference: the scatter shows no green there either.
  Image reference;
  DofReport report;
  report = depth_of_field(reference, color, coc.plane(0), find_dof_method("scatter"), {});
  double scatter_green = 0;
  for (std::ptrdiff_t y = 56; y < 72; ++y)
    for (std::ptrdiff_t x = s0 + 3; x < s0 + 8; ++x)
      scatter_green = std::max(scatter_green, double(reference(x, y, 1)));
  EXPECT_LT(scatter_green, 1e-6);
  std::printf(
      "[ measured ] green 3-7 px inside the near edge: sat %.3f, sat-layers %.3g, "
      "scatter %.3g\n",
      plain_green, layered_green, scatter_green);
}

// Against the scatter reference on the procedural scene (640 x 360, thin-lens CoC). Both are
// approximations of it (half resolution, boxes for discs, gathers for splats); the bounds are the
// measured errors with 1.5x headroom: sat RMSE 0.0385 / max 4.60 (a highlight's leak),
// sat-layers RMSE 0.0286 / max 1.30. The layers must be the closer of the two.
TEST(SatDof, ErrorAgainstScatterOnProceduralScene) {
  const Scene scene = procedural_scene(640, 360, 2);
  Image coc(640, 360, 1);
  coc_thin_lens(coc.plane(0), scene.depth.plane(0), scene.lens, 2);
  using Clock = std::chrono::steady_clock;
  auto timed = [&](const char* name, double& seconds) {
    DofOptions settings;
    settings.threads = 2;
    const auto start = Clock::now();
    Result r = run(name, scene.color, coc, settings);
    seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return r;
  };
  double t_scatter = 0, t_sat = 0, t_layers = 0;
  const Result reference = timed("scatter", t_scatter);
  const Result sat = timed("sat", t_sat), layers = timed("sat-layers", t_layers);
  auto errors = [&](const Image& out, double& rmse, double& max_error) {
    double sum = 0;
    max_error = 0;
    for (int c = 0; c < 3; ++c)
      for (std::ptrdiff_t y = 0; y < 360; ++y)
        for (std::ptrdiff_t x = 0; x < 640; ++x) {
          const double e = double(out(x, y, c)) - double(reference.out(x, y, c));
          sum += e * e;
          max_error = std::max(max_error, std::fabs(e));
        }
    rmse = std::sqrt(sum / (3.0 * 640 * 360));
  };
  double sat_rmse, sat_max, layers_rmse, layers_max;
  errors(sat.out, sat_rmse, sat_max);
  errors(layers.out, layers_rmse, layers_max);
  std::printf(
      "[ measured ] procedural 640 x 360, 2 threads: sat RMSE %.4f max %.3f (%.3f s), "
      "sat-layers RMSE %.4f max %.3f (%.3f s), scatter %.3f s\n",
      sat_rmse, sat_max, t_sat, layers_rmse, layers_max, t_layers, t_scatter);
  EXPECT_LE(sat_rmse, 1.5 * 0.0385);
  EXPECT_LE(sat_max, 1.5 * 4.60);
  EXPECT_LE(layers_rmse, 1.5 * 0.0286);
  EXPECT_LE(layers_max, 1.5 * 1.30);
  EXPECT_LT(layers_rmse, sat_rmse);
}

}  // namespace
}  // namespace tridiff::test
