// Pyramid blur (seed 001 §3.5): the effective sigma per level against seed 001 Tables A.1-A.3,
// the phase-averaged variance against its closed form, invariants (constants, mass, range,
// exact replicate borders, any size), threads, and the registered error bounds against the
// exact Gaussian.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "test_util.hpp"
#include "tridiff/blur/pyramid.hpp"
#include "tridiff/blur/quality.hpp"
#include "tridiff/blur/reference.hpp"

namespace tridiff {
namespace {

using testing_util::invalid_argument_of;
using testing_util::make_image;

constexpr PyramidFilter kFilters[] = {PyramidFilter::box2, PyramidFilter::box4,
                                      PyramidFilter::quasi};

// Seed 001 appendix A, row "D mean": the mean over 53 images of the best-fitting sigma,
// levels 1 to 5.
struct SeedTable {
  PyramidFilter filter;
  const char* table;
  double sigma[5];
};
constexpr SeedTable kSeedTables[] = {
    {PyramidFilter::quasi, "A.1", {1.5, 3.004808, 6.235577, 12.668269, 25.466346}},
    {PyramidFilter::box2, "A.2", {1.139423, 2.24519, 4.51442, 9.34134, 18.71153}},
    {PyramidFilter::box4, "A.3", {1.504808, 3.25, 6.533654, 13.408654, 26.947115}},
};

// How far our effective sigma may lie from the seed's. The seed searched sigma on a grid of
// 0.25 (every median in Tables A.1-A.3 is a multiple of 0.25, and quasi level 1 has standard
// deviation 0: all 53 images snapped to 1.5), so its per-image values carry up to 0.125 of
// rounding, which averaging does not remove when most images round the same way. Its test
// set is 48 photographs and 5 synthetic images where ours is quality_test_set's 5 synthetic
// patterns; the per-pattern fits on our own set spread by about +-3% around the joint fit
// (box2 level 3: lines 4.21, texture 4.80), hence 3% for the image content.
double seed_tolerance(double seed_sigma) { return 0.125 + 0.03 * seed_sigma; }

PlaneBlur levels_blur(PyramidFilter filter, int levels) {
  return [filter, levels](Plane out, ConstPlane in) { pyramid_blur(out, in, filter, levels); };
}

double measured_sigma(PyramidFilter filter, int levels, std::ptrdiff_t size) {
  const std::vector<TestPattern> patterns = quality_test_set(size);
  const double guess = pyramid_sigma(filter, levels);
  return effective_sigma(levels_blur(filter, levels), patterns, 0.8 * guess, 1.25 * guess);
}

TEST(BlurPyramid, StoredSigmaTableMatchesSeedTablesA1ToA3) {
  for (const SeedTable& seed : kSeedTables)
    for (int levels = 1; levels <= 5; ++levels) {
      const double ours = pyramid_sigma(seed.filter, levels);
      const double theirs = seed.sigma[levels - 1];
      EXPECT_NEAR(ours, theirs, seed_tolerance(theirs))
          << "Table " << seed.table << ", " << pyramid_filter_name(seed.filter) << ", " << levels
          << " levels";
    }
}

// Levels 1-3 of every filter, measured here on 96 x 96 patterns (at 6 px of blur, 6 sigma
// reach across much of the image, but the borders are exact replicate, as the reference's):
// against the seed, and against the stored table (measured on 1024 x 1024). Levels 4-5 need
// 512+ px patterns and take seconds each: the stored table covers them.
TEST(BlurPyramid, MeasuredSigmaMatchesSeedTablesA1ToA3) {
  for (const SeedTable& seed : kSeedTables)
    for (int levels = 1; levels <= 3; ++levels) {
      const double sigma = measured_sigma(seed.filter, levels, 96);
      const double theirs = seed.sigma[levels - 1];
      EXPECT_NEAR(sigma, theirs, seed_tolerance(theirs))
          << "Table " << seed.table << ", " << pyramid_filter_name(seed.filter) << ", " << levels
          << " levels";
      // Smaller patterns hold fewer phases of each edge against the coarse grid; the 2x2 box,
      // the least shift-invariant, moves most (per-pattern fits spread by +-7%).
      const double stored = pyramid_sigma(seed.filter, levels);
      EXPECT_NEAR(sigma, stored, 0.05 * stored)
          << pyramid_filter_name(seed.filter) << ", " << levels << " levels";
    }
}

// The blur of an impulse depends on the impulse's phase against the coarse grid, but averaged
// over the 2^L phases its variance is exactly the sum of the composite analysis and synthesis
// variances: (v_a + v_u) (4^L - 1) / 3 per axis, with v_u = 3/4 for the B-spline ([1 3 3 1] / 8
// at offsets -1.5 .. 1.5) and v_a = 1/4 (2x2 box), 5/4 (4x4 box), 68/64 (quasi: 13 at +-1.5,
// 19 at +-0.5, over 64). Each phase conserves mass, and the average is centred.
double analysis_variance(PyramidFilter filter) {
  switch (filter) {
    case PyramidFilter::box2: return 0.25;
    case PyramidFilter::box4: return 1.25;
    case PyramidFilter::quasi: return 68.0 / 64;
  }
  return 0;
}

struct Moments {
  double mass = 0, mean = 0, variance = 0;
};

// Moments of the response to a unit impulse at `at` of a 1 x n (rows) or n x 1 (columns)
// image: the other axis is constant under the replicate border, so this is the 1D pyramid.
Moments impulse_moments(PyramidFilter filter, int levels, std::ptrdiff_t n, std::ptrdiff_t at,
                        bool along_rows) {
  const std::ptrdiff_t w = along_rows ? n : 1, h = along_rows ? 1 : n;
  Image in(w, h, 1), out(w, h, 1);
  in.plane(0).data()[along_rows ? at : at * in.pitch()] = 1;
  pyramid_blur(out.plane(0), in.plane(0), filter, levels);
  Moments m;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const double v = along_rows ? out(i, 0, 0) : out(0, i, 0);
    const double d = static_cast<double>(i - at);
    m.mass += v, m.mean += v * d, m.variance += v * d * d;
  }
  return m;
}

TEST(BlurPyramid, PhaseAveragedVarianceMatchesClosedForm) {
  const std::ptrdiff_t n = 256, centre = 128;  // the responses reach < 4 * 2^L = 64 px
  for (PyramidFilter filter : kFilters)
    for (int levels = 1; levels <= 4; ++levels)
      for (bool along_rows : {true, false}) {
        const int phases = 1 << levels;
        Moments average;
        for (int p = 0; p < phases; ++p) {
          const Moments m = impulse_moments(filter, levels, n, centre + p, along_rows);
          EXPECT_NEAR(m.mass, 1.0, 1e-5) << "phase " << p;
          average.mean += m.mean / phases;
          average.variance += m.variance / phases;
        }
        const double expected =
            (analysis_variance(filter) + 0.75) * (std::pow(4.0, levels) - 1) / 3;
        EXPECT_NEAR(average.mean, 0.0, 1e-4) << pyramid_filter_name(filter) << " " << levels;
        EXPECT_NEAR(average.variance, expected, 1e-5 * expected + 1e-4)
            << pyramid_filter_name(filter) << ", " << levels << " levels, "
            << (along_rows ? "rows" : "columns");
      }
}

Image random_image(std::ptrdiff_t w, std::ptrdiff_t h, unsigned seed, float lo = 0.f,
                   float hi = 1.f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(lo, hi);
  return make_image(w, h, 1, [&](std::ptrdiff_t, std::ptrdiff_t, int) { return value(rng); });
}

struct Size2 {
  std::ptrdiff_t w, h;
};
constexpr Size2 kOddSizes[] = {{1, 1},   {2, 2},    {3, 3},   {17, 17}, {33, 33},
                               {31, 31}, {65, 65},  {63, 1},  {1, 33},  {2, 17},
                               {17, 3},  {129, 31}, {33, 64}, {5, 127}, {64, 64}};

TEST(BlurPyramid, ConstantImageStaysConstant) {
  for (const Size2 s : kOddSizes)
    for (PyramidFilter filter : kFilters)
      for (int levels : {1, 3, 7}) {
        const Image in = make_image(s.w, s.h, 1, [](auto, auto, int) { return 0.3721f; });
        Image out(s.w, s.h, 1);
        pyramid_blur(out.plane(0), in.plane(0), filter, levels, 0.8, Border::replicate, 0);
        for (std::ptrdiff_t y = 0; y < s.h; ++y)
          for (std::ptrdiff_t x = 0; x < s.w; ++x)
            ASSERT_NEAR(out(x, y, 0), 0.3721f, 1e-6)
                << s.w << " x " << s.h << ", " << pyramid_filter_name(filter) << ", " << levels;
      }
}

TEST(BlurPyramid, AnySizeGivesFiniteValuesWithinInputRange) {
  for (const Size2 s : kOddSizes)
    for (PyramidFilter filter : kFilters)
      for (int levels : {1, 2, 5, 9}) {
        const Image in = random_image(s.w, s.h, 11, 0.2f, 0.7f);
        float lo = 1, hi = 0;
        for (std::ptrdiff_t y = 0; y < s.h; ++y)
          for (std::ptrdiff_t x = 0; x < s.w; ++x)
            lo = std::min(lo, in(x, y, 0)), hi = std::max(hi, in(x, y, 0));
        Image out(s.w, s.h, 1);
        pyramid_blur(out.plane(0), in.plane(0), filter, levels, 0.5, Border::replicate, 0);
        for (std::ptrdiff_t y = 0; y < s.h; ++y)
          for (std::ptrdiff_t x = 0; x < s.w; ++x) {
            const float v = out(x, y, 0);
            ASSERT_TRUE(std::isfinite(v));
            ASSERT_GE(v, lo - 1e-6f) << s.w << " x " << s.h << " at " << x << ", " << y;
            ASSERT_LE(v, hi + 1e-6f) << s.w << " x " << s.h << " at " << x << ", " << y;
          }
      }
}

// The border is the replicate rule exactly: padding the image with 2^L * k replicated pixels
// on every side (which keeps the coarse grid aligned) and cropping the blur gives the blur.
// Padding the right and bottom by one pixel (odd to even) changes nothing either.
TEST(BlurPyramid, BordersAreExactlyTheReplicateExtension) {
  const std::ptrdiff_t w = 37, h = 29;
  const Image in = random_image(w, h, 5);
  for (PyramidFilter filter : kFilters)
    for (int levels : {1, 3}) {
      Image out(w, h, 1);
      pyramid_blur(out.plane(0), in.plane(0), filter, levels, 0.9, Border::replicate, 0);
      for (const auto& [left, right] :
           {std::pair<std::ptrdiff_t, std::ptrdiff_t>{16, 16}, {0, 1}}) {
        const auto clamped = [&](std::ptrdiff_t x, std::ptrdiff_t y, int) {
          return in(std::clamp<std::ptrdiff_t>(x - left, 0, w - 1),
                    std::clamp<std::ptrdiff_t>(y - left, 0, h - 1), 0);
        };
        const Image padded = make_image(w + left + right, h + left + right, 1, clamped);
        Image padded_out(padded.width(), padded.height(), 1);
        pyramid_blur(padded_out.plane(0), padded.plane(0), filter, levels, 0.9, Border::replicate,
                     0);
        for (std::ptrdiff_t y = 0; y < h; ++y)
          for (std::ptrdiff_t x = 0; x < w; ++x)
            ASSERT_NEAR(padded_out(x + left, y + left, 0), out(x, y, 0), 1e-6)
                << pyramid_filter_name(filter) << ", " << levels << " levels, pad " << left << "/"
                << right << ", at " << x << ", " << y;
      }
    }
}

double plane_sum(ConstPlane p) {
  double sum = 0;
  for (std::ptrdiff_t y = 0; y < p.height(); ++y)
    for (std::ptrdiff_t x = 0; x < p.width(); ++x) sum += p(x, y);
  return sum;
}

// Content far from the edges (further than the blur reaches, < 4 * 2^L px): the mass is
// conserved to float rounding, on odd sizes too.
TEST(BlurPyramid, MassOfContentAwayFromEdgesIsConserved) {
  const std::ptrdiff_t w = 151, h = 133;
  const Image noise = random_image(w, h, 3);
  const Image in = make_image(w, h, 1, [&](std::ptrdiff_t x, std::ptrdiff_t y, int) {
    return x >= 60 && x < 91 && y >= 50 && y < 83 ? noise(x, y, 0) : 0.f;
  });
  for (PyramidFilter filter : kFilters)
    for (int levels : {1, 2, 3}) {
      Image out(w, h, 1);
      pyramid_blur(out.plane(0), in.plane(0), filter, levels, 0.6, Border::replicate, 0);
      EXPECT_NEAR(plane_sum(out.plane(0)), plane_sum(in.plane(0)), 1e-6 * plane_sum(in.plane(0)))
          << pyramid_filter_name(filter) << ", " << levels << " levels";
    }
}

// With content up to the edges the replicate border adds or removes mass, for the exact
// Gaussian too: the pyramid's mean follows the exact Gaussian's.
TEST(BlurPyramid, MeanFollowsTheExactGaussian) {
  const std::vector<TestPattern> patterns = quality_test_set(96, 4);
  for (const TestPattern& p : patterns)
    for (PyramidFilter filter : kFilters)
      for (double sigma : {2.0, 7.0}) {
        Image out(96, 96, 1);
        pyramid_blur_sigma(out.plane(0), p.image.plane(0), filter, sigma);
        const DoublePlane exact = reference_gaussian(p.image.plane(0), sigma, Border::replicate);
        double exact_sum = 0;
        for (double v : exact.values) exact_sum += v;
        EXPECT_NEAR(plane_sum(out.plane(0)) / (96 * 96), exact_sum / (96 * 96), 2e-3)
            << p.name << ", " << pyramid_filter_name(filter) << ", sigma " << sigma;
      }
}

TEST(BlurPyramid, OneAndTwoThreadsGiveIdenticalResults) {
  const Image in = random_image(129, 67, 9);
  for (PyramidFilter filter : kFilters) {
    Image one(129, 67, 1), two(129, 67, 1);
    pyramid_blur(one.plane(0), in.plane(0), filter, 3, 0.7, Border::replicate, 1);
    pyramid_blur(two.plane(0), in.plane(0), filter, 3, 0.7, Border::replicate, 2);
    EXPECT_EQ(std::memcmp(one.data(), two.data(), 129 * 67 * sizeof(float)), 0)
        << pyramid_filter_name(filter);
  }
}

TEST(BlurPyramid, PlanPicksLevelsAndFillsTheGapWithCoarseSmoothing) {
  for (PyramidFilter filter : kFilters) {
    for (int levels = 1; levels <= 7; ++levels) {
      const PyramidPlan exact = pyramid_plan(filter, pyramid_sigma(filter, levels));
      EXPECT_EQ(exact.levels, levels);
      EXPECT_NEAR(exact.coarse_sigma, 0.0, 1e-6);
      // Just short of the next level: the same levels, and the variance the next level adds.
      const double next = pyramid_sigma(filter, levels + 1);
      const PyramidPlan gap = pyramid_plan(filter, next * 0.999);
      EXPECT_EQ(gap.levels, levels);
      const double added = std::pow(4.0, levels) * gap.coarse_sigma * gap.coarse_sigma;
      EXPECT_NEAR(added + std::pow(pyramid_sigma(filter, levels), 2), std::pow(next * 0.999, 2),
                  1e-9 * next * next);
    }
  }
}

// Between levels the effective sigma follows the target: the coarse smoothing adds variance
// as planned.
TEST(BlurPyramid, EffectiveSigmaBetweenLevelsFollowsTheTarget) {
  const std::vector<TestPattern> patterns = quality_test_set(96, 2);
  for (PyramidFilter filter : kFilters)
    for (double target : {4.5}) {  // between levels 2 and 3 of every filter
      const PlaneBlur blur = [&](Plane out, ConstPlane in) {
        pyramid_blur_sigma(out, in, filter, target);
      };
      const double sigma = effective_sigma(blur, patterns, 0.8 * target, 1.25 * target);
      EXPECT_NEAR(sigma, target, 0.04 * target) << pyramid_filter_name(filter);
    }
}

// The registered bound: max |pyramid - exact Gaussian of sigma| over the test patterns (values
// in [0, 1]) at sigmas across [min_sigma, max_sigma], on and between levels.
TEST(BlurPyramid, RegisteredMaxErrorHoldsOnTheTestPatterns) {
  const std::vector<TestPattern> patterns = quality_test_set(128, 7);
  for (const char* name : {"pyramid-box2", "pyramid-box4", "pyramid-quasi"}) {
    const BlurMethod& method = find_blur_method(name);
    EXPECT_FALSE(method.exact);
    EXPECT_TRUE(method.borders.contains(Border::replicate));
    EXPECT_FALSE(method.borders.contains(Border::mirror));
    double worst = 0;
    for (double sigma : {method.min_sigma, 1.7, 2.6, 5.0, 9.6, 21.0, method.max_sigma}) {
      BlurOptions settings;
      settings.sigma = sigma;
      for (const TestPattern& p : patterns) {
        Image out(p.image.width(), p.image.height(), 1);
        blur(out.plane(0), p.image.plane(0), method, settings);
        const DoublePlane exact = reference_gaussian(p.image.plane(0), sigma, Border::replicate);
        const double error = blur_error(out.plane(0), exact).max_abs;
        worst = std::max(worst, error);
        EXPECT_LE(error, method.max_error) << name << ", sigma " << sigma << ", " << p.name;
      }
    }
    // The bound is not loose by more than a factor 1.5.
    EXPECT_GT(worst, method.max_error / 1.5) << name;
  }
}

TEST(BlurPyramid, RejectsBadArguments) {
  Image a(8, 8, 1), b(8, 8, 1), c(9, 8, 1);
  const auto argument = [](const std::function<void()>& f) {
    return invalid_argument_of(f).argument;
  };
  EXPECT_EQ(argument([&] { pyramid_blur(b.plane(0), a.plane(0), PyramidFilter::quasi, -1); }),
            "levels");
  EXPECT_EQ(argument([&] { pyramid_blur(b.plane(0), a.plane(0), PyramidFilter::quasi, 31); }),
            "levels");
  EXPECT_EQ(argument([&] { pyramid_blur(c.plane(0), a.plane(0), PyramidFilter::quasi, 1); }),
            "out");
  EXPECT_EQ(argument([&] { pyramid_blur(a.plane(0), a.plane(0), PyramidFilter::quasi, 1); }),
            "out");
  EXPECT_EQ(argument([&] {
              pyramid_blur(b.plane(0), a.plane(0), PyramidFilter::box2, 1, Border::mirror);
            }),
            "border");
  EXPECT_EQ(argument([&] {
              pyramid_blur(b.plane(0), a.plane(0), PyramidFilter::box2, 1, -0.5, Border::replicate,
                           0);
            }),
            "coarse_sigma");
  EXPECT_EQ(argument([&] {
              pyramid_blur(b.plane(0), a.plane(0), PyramidFilter::box2, 1, NAN, Border::replicate,
                           0);
            }),
            "coarse_sigma");
  EXPECT_EQ(argument([&] {
              pyramid_blur(b.plane(0), a.plane(0), PyramidFilter::box4, 1, Border::replicate, -1);
            }),
            "threads");
  EXPECT_EQ(argument([] { pyramid_sigma(PyramidFilter::quasi, 0); }), "levels");
  EXPECT_EQ(argument([] { pyramid_plan(PyramidFilter::quasi, 1.0); }), "sigma");
  EXPECT_EQ(argument([] { pyramid_plan(PyramidFilter::quasi, INFINITY); }), "sigma");
}

}  // namespace
}  // namespace tridiff
