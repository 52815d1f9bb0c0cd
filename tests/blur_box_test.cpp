// Summed-area tables and the box blurs ("box", "box-extended", "box-sat") against independent
// references: brute-force sums, brute-force repeated boxes with the replicate rule, kernel
// variances, the exact Gaussian (registered max_error), Tables A.6/A.7 of seed 001, and the
// float precision of the tiled table.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <random>
#include <vector>

#include "test_util.hpp"
#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/box.hpp"
#include "tridiff/blur/quality.hpp"
#include "tridiff/blur/reference.hpp"
#include "tridiff/blur/sat.hpp"

namespace tridiff {
namespace {

using testing_util::invalid_argument_of;

using testing_util::random_image;

std::ptrdiff_t clamp_to(std::ptrdiff_t i, std::ptrdiff_t n) {
  return i < 0 ? 0 : (i >= n ? n - 1 : i);
}

// Sum over [x0, x1] x [y0, y1] of the replicate-extended image, pixel by pixel.
double brute_box_sum(ConstPlane in, std::ptrdiff_t x0, std::ptrdiff_t y0, std::ptrdiff_t x1,
                     std::ptrdiff_t y1) {
  double sum = 0;
  for (std::ptrdiff_t y = y0; y <= y1; ++y)
    for (std::ptrdiff_t x = x0; x <= x1; ++x)
      sum += in(clamp_to(x, in.width()), clamp_to(y, in.height()));
  return sum;
}

struct Size {
  std::ptrdiff_t w, h;
};
const Size kSizes[] = {{1, 1}, {2, 2}, {3, 3}, {1, 5}, {17, 33}, {33, 17}, {70, 45}};

template <class Table>
void expect_table_entries(const Image& image, double tolerance) {
  const ConstPlane in = image.plane(0);
  const Table table(in, 2);
  for (std::ptrdiff_t y = -1; y < in.height(); ++y)
    for (std::ptrdiff_t x = -1; x < in.width(); ++x) {
      const double exact = x < 0 || y < 0 ? 0.0 : brute_box_sum(in, 0, 0, x, y);
      ASSERT_NEAR(table.at(x, y), exact, tolerance) << x << ", " << y;
    }
}

TEST(SummedAreaTable, EntriesAreBruteForceSums) {
  for (const Size s : kSizes) {
    const Image image = random_image(s.w, s.h, 7);
    expect_table_entries<SummedAreaTable>(image, 1e-9);
    expect_table_entries<TiledFloatSummedAreaTable>(image, 1e-4);
  }
}

TEST(SummedAreaTable, ReplicateSumsOfAnyRectangle) {
  const Image image = random_image(17, 9, 3);
  const SummedAreaTable exact(image.plane(0), 1);
  const TiledFloatSummedAreaTable tiled(image.plane(0), 1);
  // Rectangles inside, across every edge, wider than the image and wholly outside it.
  const std::ptrdiff_t xs[] = {-30, -3, -1, 0, 4, 16, 17, 40};
  const std::ptrdiff_t ys[] = {-12, -1, 0, 5, 8, 9, 25};
  for (std::ptrdiff_t x0 : xs)
    for (std::ptrdiff_t x1 : xs)
      for (std::ptrdiff_t y0 : ys)
        for (std::ptrdiff_t y1 : ys) {
          if (x1 < x0 || y1 < y0) continue;
          const double brute = brute_box_sum(image.plane(0), x0, y0, x1, y1);
          ASSERT_NEAR(exact.replicate_box_sum(x0, y0, x1, y1), brute, 1e-9 * (1 + brute));
          ASSERT_NEAR(tiled.replicate_box_sum(x0, y0, x1, y1), brute, 1e-4 * (1 + brute));
        }
  // The replicate border is not the box clamped to the image: a 3 x 3 box at the corner
  // counts the corner pixel 4 times.
  const ConstPlane in = image.plane(0);
  EXPECT_NEAR(exact.replicate_box_sum(-1, -1, 1, 1),
              4.0 * in(0, 0) + 2.0 * in(1, 0) + 2.0 * in(0, 1) + double(in(1, 1)), 1e-9);
}

template <class Table>
void expect_box_filter_is_brute_force(const Image& image, std::ptrdiff_t rx, std::ptrdiff_t ry) {
  const ConstPlane in = image.plane(0);
  const Table table(in, 2);
  Image out(in.width(), in.height(), 1);
  sat_box_filter(out.plane(0), table, rx, ry, 2);
  const double area = double(2 * rx + 1) * double(2 * ry + 1);
  for (std::ptrdiff_t y = 0; y < in.height(); ++y)
    for (std::ptrdiff_t x = 0; x < in.width(); ++x)
      ASSERT_NEAR(out(x, y, 0), brute_box_sum(in, x - rx, y - ry, x + rx, y + ry) / area, 2e-6)
          << in.width() << "x" << in.height() << " r " << rx << "," << ry << " at " << x << ","
          << y;
}

TEST(SatBoxFilter, WholeImageMatchesBruteForceReplicate) {
  const std::ptrdiff_t radii[][2] = {{0, 0}, {1, 1}, {2, 5}, {7, 3}, {20, 36}};
  for (const Size s : kSizes) {
    if (s.w * s.h > 33 * 33) continue;  // brute force: keep it quick
    const Image image = random_image(s.w, s.h, 11);
    for (const auto& r : radii) {
      expect_box_filter_is_brute_force<SummedAreaTable>(image, r[0], r[1]);
      expect_box_filter_is_brute_force<TiledFloatSummedAreaTable>(image, r[0], r[1]);
    }
  }
}

TEST(SummedAreaTable, ThreadCountDoesNotChangeTheResult) {
  const Image image = random_image(70, 45, 5);
  const SummedAreaTable a(image.plane(0), 1), b(image.plane(0), 2);
  const TiledFloatSummedAreaTable c(image.plane(0), 1), d(image.plane(0), 2);
  for (std::ptrdiff_t y = -1; y < 45; ++y)
    for (std::ptrdiff_t x = -1; x < 70; ++x) {
      ASSERT_EQ(a.at(x, y), b.at(x, y));
      ASSERT_EQ(c.at(x, y), d.at(x, y));
    }
}

// The float-precision claim of sat.hpp, on 4096-wide images: box sums from the tiled float
// table stay within 4 roundings of a local value (|local| <= 1024 on images in [0, 1]) of the
// double table's, whatever the image size; a plain float table loses the small boxes.
TEST(TiledFloatSummedAreaTable, PrecisionOnWideImages) {
  const std::ptrdiff_t w = 4096, h = 1024;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> unit(0, 1);
  const Image constant = testing_util::make_image(w, h, 1, [](auto, auto, int) { return 0.7f; });
  const Image noise = testing_util::make_image(w, h, 1, [&](auto, auto, int) { return unit(rng); });
  const Image halves = testing_util::make_image(
      w, h, 1, [&](auto x, auto, int) { return x < w / 2 ? 0.15f : 0.85f; });
  const double bound = 4 * 1024 * std::ldexp(1.0, -24);
  for (const Image* image : {&constant, &noise, &halves}) {
    const ConstPlane in = image->plane(0);
    const SummedAreaTable exact(in);
    const TiledFloatSummedAreaTable tiled(in);
    // A plain float table for comparison: the naive recurrence of eq. 2.2, rows then columns.
    std::vector<float> naive(w * h);
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      float run = 0;
      for (std::ptrdiff_t x = 0; x < w; ++x) {
        run += in(x, y);
        naive[y * w + x] = run + (y > 0 ? naive[(y - 1) * w + x] : 0.f);
      }
    }
    double tiled_worst = 0, naive_worst = 0;
    std::uniform_int_distribution<std::ptrdiff_t> px(1, w - 40), py(1, h - 40);
    for (int k = 0; k < 2000; ++k) {
      const std::ptrdiff_t x0 = px(rng), y0 = py(rng), side = 1 + k % 9 * 4;
      const std::ptrdiff_t x1 = x0 + side - 1, y1 = y0 + side - 1;
      const double truth = exact.replicate_box_sum(x0, y0, x1, y1);
      tiled_worst =
          std::max(tiled_worst, std::abs(tiled.replicate_box_sum(x0, y0, x1, y1) - truth));
      const auto n = [&](std::ptrdiff_t x, std::ptrdiff_t y) { return double(naive[y * w + x]); };
      const double naive_sum = n(x1, y1) - n(x0 - 1, y1) - n(x1, y0 - 1) + n(x0 - 1, y0 - 1);
      naive_worst = std::max(naive_worst, std::abs(naive_sum - truth));
    }
    EXPECT_LE(tiled_worst, bound);
    std::printf("box sums: tiled float worst %.3g, plain float worst %.3g\n", tiled_worst,
                naive_worst);
    if (image == &constant) {
      EXPECT_EQ(tiled_worst, 0.0);  // every tile is its mean
    }
    if (image != &constant) {
      EXPECT_GT(naive_worst, 0.05);  // a 1 x 1 box off by > 5% of the range
    }
  }
}

// A brute-force reference of the separable repeated (extended) boxes, in double: the image
// extended by replicating its edge far enough that no pass reaches the end of the extension,
// each pass along columns then rows over the whole extension, then the image cropped back.
DoublePlane brute_passes(ConstPlane in, const std::vector<BoxPass>& passes) {
  std::ptrdiff_t margin = 1;
  for (const BoxPass& p : passes) margin += p.radius + 1;
  const std::ptrdiff_t w = in.width() + 2 * margin, h = in.height() + 2 * margin;
  DoublePlane plane(w, h);
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x)
      plane(x, y) = in(clamp_to(x - margin, in.width()), clamp_to(y - margin, in.height()));
  const auto along = [&](bool columns, const BoxPass& p) {
    DoublePlane out = plane;
    const std::ptrdiff_t n = columns ? h : w;
    const double norm = 1 / (2.0 * double(p.radius) + 1 + 2 * p.end_weight);
    for (std::ptrdiff_t y = 0; y < h; ++y)
      for (std::ptrdiff_t x = 0; x < w; ++x) {
        const std::ptrdiff_t i = columns ? y : x;
        const auto at = [&](std::ptrdiff_t k) {
          const std::ptrdiff_t c = clamp_to(k, n);
          return columns ? plane(x, c) : plane(c, y);
        };
        double sum = p.end_weight * (at(i - p.radius - 1) + at(i + p.radius + 1));
        for (std::ptrdiff_t k = i - p.radius; k <= i + p.radius; ++k) sum += at(k);
        out(x, y) = sum * norm;
      }
    plane = out;
  };
  for (const BoxPass& p : passes) along(true, p), along(false, p);
  DoublePlane cropped(in.width(), in.height());
  for (std::ptrdiff_t y = 0; y < in.height(); ++y)
    for (std::ptrdiff_t x = 0; x < in.width(); ++x) cropped(x, y) = plane(x + margin, y + margin);
  return cropped;
}

std::vector<BoxPass> extended_passes(double sigma, int passes = kDefaultBoxPasses) {
  const ExtendedBox box = extended_box(sigma, passes);
  return std::vector<BoxPass>(passes, BoxPass{box.radius, box.alpha});
}

std::vector<BoxPass> passes_of(std::string_view method, double sigma) {
  return method == "box-extended" ? extended_passes(sigma) : plain_box_passes(sigma);
}

TEST(BoxMethods, MatchBruteForceReplicateOnWholeImage) {
  const Size sizes[] = {{1, 1}, {2, 2}, {3, 3}, {2, 17}, {17, 33}, {33, 17}};
  for (const char* name : {"box", "box-extended", "box-sat"}) {
    const BlurMethod& method = find_blur_method(name);
    for (const Size s : sizes)
      for (double sigma : {2.0, 3.3, 12.0}) {  // 12: boxes wider than the image
        const Image image = random_image(s.w, s.h, 13);
        Image out(s.w, s.h, 1);
        blur(out.plane(0), image.plane(0), method, {sigma, Border::replicate, 2});
        const DoublePlane expected = brute_passes(image.plane(0), passes_of(name, sigma));
        for (std::ptrdiff_t y = 0; y < s.h; ++y)
          for (std::ptrdiff_t x = 0; x < s.w; ++x)
            ASSERT_NEAR(out(x, y, 0), expected(x, y), 2e-6)
                << name << " " << s.w << "x" << s.h << " sigma " << sigma << " at " << x << ","
                << y;
      }
  }
}

TEST(BoxMethods, ThreadCountDoesNotChangeTheResult) {
  const Image image = random_image(70, 45, 17);
  for (const char* name : {"box", "box-extended", "box-sat"}) {
    Image one(70, 45, 1), two(70, 45, 1);
    blur(one.plane(0), image.plane(0), find_blur_method(name), {4.5, Border::replicate, 1});
    blur(two.plane(0), image.plane(0), find_blur_method(name), {4.5, Border::replicate, 2});
    for (std::ptrdiff_t y = 0; y < 45; ++y)
      for (std::ptrdiff_t x = 0; x < 70; ++x) ASSERT_EQ(one(x, y, 0), two(x, y, 0)) << name;
  }
}

// The 1D impulse response of the passes (a row plane: the column passes are the identity).
std::vector<double> impulse_response(const std::vector<BoxPass>& passes, std::ptrdiff_t half) {
  Image impulse(2 * half + 1, 1, 1), response(2 * half + 1, 1, 1);
  impulse(half, 0, 0) = 1;
  box_passes(response.plane(0), impulse.plane(0), passes, 1);
  std::vector<double> k(2 * half + 1);
  for (std::ptrdiff_t i = 0; i <= 2 * half; ++i) k[i] = response(i, 0, 0);
  return k;
}

double variance_of(const std::vector<double>& k) {
  const std::ptrdiff_t half = static_cast<std::ptrdiff_t>(k.size() / 2);
  double mass = 0, second = 0;
  for (std::ptrdiff_t i = 0; i < std::ptrdiff_t(k.size()); ++i) {
    mass += k[i];
    second += k[i] * double(i - half) * double(i - half);
  }
  EXPECT_NEAR(mass, 1, 1e-5);
  return second / mass;
}

TEST(BoxWidths, IdealWidthsRule) {
  EXPECT_EQ(box_widths(1, 3), (std::vector<std::ptrdiff_t>{1, 1, 3}));
  for (double sigma : {0.0, 0.7, 2.0, 3.3, 8.0, 31.7, 300.0})
    for (int n = 1; n <= 6; ++n) {
      const std::vector<std::ptrdiff_t> w = box_widths(sigma, n);
      ASSERT_EQ(std::ptrdiff_t(w.size()), n);
      double variance = 0;
      for (std::ptrdiff_t width : w) {
        EXPECT_EQ(width % 2, 1);
        EXPECT_LE(width, w.front() + 2);
        variance += box_variance(width);
      }
      // The nearest m misses sigma^2 by at most half of one step (wl + 2)^2 - wl^2.
      const double step = (box_variance(w.front() + 2) - box_variance(w.front()));
      EXPECT_LE(std::abs(variance - sigma * sigma), step / 2 + 1e-9) << sigma << " " << n;
    }
}

TEST(BoxKernels, ImpulseVarianceIsTheSumOfThePasses) {
  for (double sigma : {1.0, 2.0, 2.7, 5.0, 12.3}) {
    const std::ptrdiff_t half = static_cast<std::ptrdiff_t>(8 * sigma) + 8;
    double plain_sum = 0;
    for (std::ptrdiff_t width : box_widths(sigma, 3)) plain_sum += box_variance(width);
    EXPECT_NEAR(variance_of(impulse_response(plain_box_passes(sigma), half)), plain_sum,
                2e-4 * plain_sum);
    // The extended boxes hit sigma^2 exactly, for any pass count.
    for (int n : {1, 3, 5}) {
      EXPECT_NEAR(extended_box(sigma, n).variance() * n, sigma * sigma, 1e-9 * sigma * sigma);
      EXPECT_LT(extended_box(sigma, n).alpha, 1.0);
      EXPECT_NEAR(variance_of(impulse_response(extended_passes(sigma, n), half)), sigma * sigma,
                  2e-4 * sigma * sigma);
    }
  }
}

// Worst error over all images in [0, 1] of a linear blur against the Gaussian: half the l1
// norm of the difference of the impulse responses (both sum to 1).
double worst_error(const std::vector<BoxPass>& passes, double sigma) {
  return 0.5 * operator_norm_error(
                   [&](Plane out, ConstPlane in) { box_passes(out, in, passes, 2); }, sigma);
}

TEST(BoxExtended, LowersTheErrorOfPlainBoxesAtTheSamePassCount) {
  for (int n : {3, 4}) {
    double plain_worst = 0, extended_worst = 0;
    for (double sigma = 1.25; sigma <= 6; sigma += 0.25) {
      const double plain = worst_error(plain_box_passes(sigma, n), sigma);
      const double extended = worst_error(extended_passes(sigma, n), sigma);
      plain_worst = std::max(plain_worst, plain);
      extended_worst = std::max(extended_worst, extended);
    }
    EXPECT_LT(extended_worst, 0.6 * plain_worst) << n;
  }
  // Where odd widths cannot reach sigma^2 the plain boxes are far off; the extended are not.
  EXPECT_LT(worst_error(extended_passes(1.0), 1.0), 0.1 * worst_error(plain_box_passes(1.0), 1.0));
}

TEST(BoxMethods, RegisteredMaxErrorHolds) {
  const std::vector<TestPattern> patterns = quality_test_set(64);
  for (double sigma : {1.0, 2.0, 4.0, 8.0, 16.0, 32.0}) {
    std::vector<DoublePlane> exact;
    for (const TestPattern& p : patterns)
      exact.push_back(reference_gaussian(p.image.plane(0), sigma, Border::replicate));
    for (const char* name : {"box", "box-extended", "box-sat"}) {
      const BlurMethod& method = find_blur_method(name);
      if (sigma < method.min_sigma) continue;
      const BlurOptions settings{sigma, Border::replicate, 2};
      for (std::size_t i = 0; i < patterns.size(); ++i) {
        Image out(64, 64, 1);
        blur(out.plane(0), patterns[i].image.plane(0), method, settings);
        EXPECT_LE(blur_error(out.plane(0), exact[i]).max_abs, method.max_error)
            << name << " sigma " << sigma << " " << patterns[i].name;
      }
      // The bound over every image, not just these patterns.
      if (sigma <= 8) {
        EXPECT_LE(0.5 * operator_norm_error(plane_blur(method, settings), sigma), method.max_error)
            << name << " sigma " << sigma;
      }
    }
  }
  // The worst sigmas of the sweeps that set the bounds.
  EXPECT_LE(worst_error(plain_box_passes(2.0), 2.0), find_blur_method("box").max_error);
  EXPECT_LE(worst_error(extended_passes(1.4), 1.4), find_blur_method("box-extended").max_error);
}

// Seed 001 Tables A.6/A.7: the sigma of the Gaussian nearest to w x w boxes applied i times
// (D mean; the thesis searched in steps of 0.25). The variance rule sqrt(i (w^2 - 1) / 12)
// lies a little below them; our effective sigma must agree with the tables within a step.
TEST(BoxMethods, EffectiveSigmaMatchesTablesA6A7) {
  std::vector<TestPattern> patterns = quality_test_set(64);
  patterns.resize(3);  // edges, discs, lines: enough to pin the sigma, and quick
  struct Case {
    std::ptrdiff_t width;
    int passes;
    double table;
  };
  const Case cases[] = {{9, 1, 2.875}, {9, 2, 3.754808}, {9, 3, 4.586538},
                        {9, 4, 5.25},  {3, 3, 1.5},      {3, 4, 1.75}};
  for (const Case& c : cases) {
    const std::vector<BoxPass> passes(c.passes, BoxPass{(c.width - 1) / 2, 0});
    const PlaneBlur blur_plane = [&](Plane out, ConstPlane in) { box_passes(out, in, passes); };
    const double found = effective_sigma(blur_plane, patterns, c.table - 1, c.table + 1);
    std::printf("w %td x %d: effective sigma %.3f, table %.3f, variance rule %.3f\n", c.width,
                c.passes, found, c.table, std::sqrt(c.passes * box_variance(c.width)));
    EXPECT_NEAR(found, c.table, 0.3) << "w " << c.width << " i " << c.passes;
    EXPECT_GE(found, std::sqrt(c.passes * box_variance(c.width)) - 0.05);
  }
}

TEST(BoxMethods, BadArguments) {
  EXPECT_EQ(invalid_argument_of([] { box_widths(-1, 3); }).argument, "sigma");
  EXPECT_EQ(invalid_argument_of([] { box_widths(2, 0); }).argument, "passes");
  EXPECT_EQ(invalid_argument_of([] { extended_box(NAN, 3); }).argument, "sigma");
  const Image image = random_image(8, 8, 1);
  Image small(4, 4, 1);
  const SummedAreaTable table(image.plane(0));
  EXPECT_EQ(invalid_argument_of([&] { sat_box_filter(small.plane(0), table, 1, 1); }).argument,
            "out");
  Image out(8, 8, 1);
  EXPECT_EQ(invalid_argument_of([&] { sat_box_filter(out.plane(0), table, -1, 1); }).argument,
            "radius");
  EXPECT_EQ(invalid_argument_of([&] { SummedAreaTable(image.plane(0), -1); }).argument, "threads");
  const std::vector<BoxPass> bad{{-1, 0}};
  EXPECT_EQ(invalid_argument_of([&] { box_passes(out.plane(0), image.plane(0), bad); }).argument,
            "passes");
  for (const char* name : {"box", "box-extended", "box-sat"})
    EXPECT_EQ(invalid_argument_of([&] {
                blur(out.plane(0), image.plane(0), find_blur_method(name), {4, Border::zero, 1});
              }).argument,
              "border");
}

}  // namespace
}  // namespace tridiff
