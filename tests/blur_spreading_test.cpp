// Polynomial spreading ("kosloff", seed 001 §3.6.2) and reshuffling ("reshuffle", §3.7): the
// kernels they realise against kernels computed here in double, every pixel (borders
// included) against brute-force convolution, the sigma mapping, seed 001 Table A.4, the
// registered error bounds, sizes, threads and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "test_util.hpp"
#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/quality.hpp"
#include "tridiff/blur/reference.hpp"
#include "tridiff/blur/reshuffle.hpp"
#include "tridiff/blur/spreading.hpp"

namespace tridiff {
namespace {

using testing_util::contains;
using testing_util::invalid_argument_of;

// ---- independent references -------------------------------------------------------------

// The blended tent of spreading.hpp, from its definition.
double tent(const SpreadingKernel& k, std::ptrdiff_t x) {
  const double r = static_cast<double>(k.radius), ax = static_cast<double>(std::abs(x));
  return (1 - k.blend) * std::max(r - ax, 0.0) / (r * r) +
         k.blend * std::max(r + 1 - ax, 0.0) / ((r + 1) * (r + 1));
}

// The tent sampled on [-R, R] (index k + R), R = radius + 1 (where it vanishes).
std::vector<double> tent_samples(const SpreadingKernel& k) {
  const std::ptrdiff_t reach = k.radius + 1;
  std::vector<double> samples(2 * reach + 1);
  for (std::ptrdiff_t x = -reach; x <= reach; ++x) samples[x + reach] = tent(k, x);
  return samples;
}

// Brute-force convolution in double with a width x height kernel (centred, index (j, i) ->
// j * width + i), reading outside pixels through border_index: every output pixel, borders
// included, from its definition.
DoublePlane brute_convolve(ConstPlane in, const std::vector<double>& kernel, std::ptrdiff_t width,
                           std::ptrdiff_t height, Border border) {
  const std::ptrdiff_t cx = width / 2, cy = height / 2, w = in.width(), h = in.height();
  DoublePlane out(w, h);
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x) {
      double sum = 0;
      for (std::ptrdiff_t j = 0; j < height; ++j)
        for (std::ptrdiff_t i = 0; i < width; ++i) {
          const std::ptrdiff_t sx = border_index(x - (i - cx), w, border);
          const std::ptrdiff_t sy = border_index(y - (j - cy), h, border);
          if (sx >= 0 && sy >= 0) sum += kernel[j * width + i] * in(sx, sy);
        }
      out(x, y) = sum;
    }
  return out;
}

// The same for the separable kernel k(x) k(y), as two 1D passes (kernel of odd length).
DoublePlane brute_separable(ConstPlane in, const std::vector<double>& k, Border border) {
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(k.size()), c = n / 2;
  const std::ptrdiff_t w = in.width(), h = in.height();
  DoublePlane rows(w, h), out(w, h);
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x)
      for (std::ptrdiff_t i = 0; i < n; ++i)
        if (const std::ptrdiff_t s = border_index(x - (i - c), w, border); s >= 0)
          rows(x, y) += k[i] * in(s, y);
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x)
      for (std::ptrdiff_t i = 0; i < n; ++i)
        if (const std::ptrdiff_t s = border_index(y - (i - c), h, border); s >= 0)
          out(x, y) += k[i] * rows(x, s);
  return out;
}

double max_difference(ConstPlane a, const DoublePlane& b) {
  double worst = 0;
  for (std::ptrdiff_t y = 0; y < a.height(); ++y)
    for (std::ptrdiff_t x = 0; x < a.width(); ++x)
      worst = std::max(worst, std::abs(a(x, y) - b(x, y)));
  return worst;
}

using testing_util::random_image;

Image impulse_image(std::ptrdiff_t w, std::ptrdiff_t h, std::ptrdiff_t x, std::ptrdiff_t y) {
  Image image(w, h, 1);
  image(x, y, 0) = 1.f;
  return image;
}

bool identical(ConstPlane a, ConstPlane b) {
  for (std::ptrdiff_t y = 0; y < a.height(); ++y)
    if (std::memcmp(a.row(y), b.row(y), a.width() * sizeof(float)) != 0) return false;
  return true;
}

struct Size {
  std::ptrdiff_t w, h;
};
const Size kSizes[] = {{1, 1}, {2, 2}, {3, 3}, {17, 17}, {33, 33}, {40, 23}, {23, 40}, {1, 9}};

// ---- polynomial spreading ----------------------------------------------------------------

TEST(Spreading, VarianceIsTheKernelsSecondMoment) {
  for (std::ptrdiff_t r : {1, 2, 5, 10, 33})
    for (double blend : {0.0, 0.3, 1.0}) {
      const SpreadingKernel k{r, blend};
      double mass = 0, moment = 0;
      for (std::ptrdiff_t x = -r - 1; x <= r + 1; ++x) {
        mass += tent(k, x);
        moment += static_cast<double>(x * x) * tent(k, x);
      }
      EXPECT_NEAR(mass, 1.0, 1e-13);
      EXPECT_NEAR(spreading_variance(k), moment, 1e-12 * (1 + moment)) << r << " " << blend;
      if (blend == 0) {
        EXPECT_NEAR(spreading_variance(k), (r * r - 1) / 6.0, 1e-12);
      }
    }
}

TEST(Spreading, SigmaMapsToATentOfTheScaledSigma) {
  for (double sigma : {0.5, 1.0, 2.0, 3.3, 4.0, 8.0, 16.0, 32.0, 1000.0}) {
    const SpreadingKernel k = spreading_kernel_for_sigma(sigma);
    EXPECT_GE(k.radius, 1);
    EXPECT_GE(k.blend, 0.0);
    EXPECT_LE(k.blend, 1.0);
    EXPECT_NEAR(std::sqrt(spreading_variance(k)), kTentSigmaScale * sigma, 1e-9 * sigma) << sigma;
  }
  // The half-width follows sqrt(6 s^2 + 1), s = 0.96 sigma: sigma 8 -> 7.68 -> r = 18.84.
  EXPECT_EQ(spreading_kernel_for_sigma(8).radius, 18);
}

TEST(Spreading, ImpulseResponseIsTheTensorTent) {
  for (const SpreadingKernel k : {SpreadingKernel{1, 0.0}, SpreadingKernel{2, 0.4},
                                  SpreadingKernel{7, 0.0}, SpreadingKernel{12, 0.75}}) {
    const std::ptrdiff_t n = 2 * k.radius + 9, c = n / 2;
    const Image in = impulse_image(n, n, c, c);
    Image out(n, n, 1);
    polynomial_spread(out.plane(0), in.plane(0), k, Border::zero, 1);
    double worst = 0;
    for (std::ptrdiff_t y = 0; y < n; ++y)
      for (std::ptrdiff_t x = 0; x < n; ++x)
        worst = std::max(worst, std::abs(out(x, y, 0) - tent(k, x - c) * tent(k, y - c)));
    EXPECT_LT(worst, 1e-7) << "radius " << k.radius << " blend " << k.blend;
  }
}

// The whole image, borders included, against brute force with the same kernel: replicate
// (the edge pixel repeated however far the kernel reaches) and zero.
TEST(Spreading, EveryPixelMatchesBruteForceIncludingBorders) {
  const SpreadingKernel kernels[] = {{1, 0.5}, {3, 0.0}, {6, 0.25}, {25, 0.6}, {60, 0.1}};
  unsigned seed = 1;
  for (const Size size : kSizes)
    for (const SpreadingKernel& k : kernels)
      for (Border border : {Border::replicate, Border::zero}) {
        const Image in = random_image(size.w, size.h, seed++);
        Image out(size.w, size.h, 1);
        polynomial_spread(out.plane(0), in.plane(0), k, border, 2);
        const DoublePlane expected = brute_separable(in.plane(0), tent_samples(k), border);
        EXPECT_LT(max_difference(out.plane(0), expected), 2e-6)
            << size.w << " x " << size.h << " radius " << k.radius << " " << border_name(border);
      }
}

TEST(Spreading, ConstantImageStaysConstant) {
  for (const Size size : {Size{1, 1}, Size{5, 3}, Size{64, 48}})
    for (double sigma : {0.5, 3.0, 40.0, 1000.0}) {
      const Image in =
          testing_util::make_image(size.w, size.h, 1, [](auto, auto, int) { return 0.7f; });
      Image out(size.w, size.h, 1);
      blur(out.plane(0), in.plane(0), find_blur_method("kosloff"), {sigma, Border::replicate, 1});
      for (std::ptrdiff_t y = 0; y < size.h; ++y)
        for (std::ptrdiff_t x = 0; x < size.w; ++x) ASSERT_NEAR(out(x, y, 0), 0.7f, 1e-6) << sigma;
    }
}

// A long line stresses the double running sums: an impulse at the far end of a 4096-pixel row
// must come out as the tent with no drift from the 4000 pixels before it.
TEST(Spreading, RunningSumsDoNotDriftOnLongLines) {
  const std::ptrdiff_t n = 4096;
  Image in = random_image(n, 1, 7);
  const SpreadingKernel k{20, 0.5};
  Image out(n, 1, 1);
  polynomial_spread(out.plane(0), in.plane(0), k, Border::replicate, 1);
  const DoublePlane expected = brute_separable(in.plane(0), tent_samples(k), Border::replicate);
  EXPECT_LT(max_difference(out.plane(0), expected), 1e-6);
}

// Seed 001 Table A.4, "D mean": the best-fitting sigma of the tent of half-width r. Our own
// harness (mean absolute difference over quality_test_set) must find the same within 3 %.
TEST(Spreading, EffectiveSigmaMatchesSeedTableA4) {
  const std::vector<TestPattern> patterns = quality_test_set(64);
  const struct {
    std::ptrdiff_t r;
    double seed_sigma;
  } rows[] = {{6, 2.509615}, {10, 4.25}, {20, 8.538462}};
  for (const auto& row : rows) {
    const SpreadingKernel k{row.r, 0.0};
    const PlaneBlur spread = [k](Plane out, ConstPlane in) {
      polynomial_spread(out, in, k, Border::replicate, 1);
    };
    const double own = std::sqrt(spreading_variance(k));
    const double fitted = effective_sigma(spread, patterns, 0.8 * own, 1.3 * own);
    EXPECT_NEAR(fitted, row.seed_sigma, 0.03 * row.seed_sigma) << "r = " << row.r;
    EXPECT_GT(fitted, own) << "a tent fits a wider Gaussian than its own sigma";
  }
}

// The registered method: its effective sigma is the requested one (the point of the 0.96
// scale), within 2 %.
TEST(Spreading, RegisteredEffectiveSigmaIsTheTarget) {
  const std::vector<TestPattern> patterns = quality_test_set(64);
  const BlurMethod& method = find_blur_method("kosloff");
  for (double sigma : {2.0, 4.0, 8.0}) {
    const double fitted = effective_sigma(plane_blur(method, {sigma, Border::replicate, 1}),
                                          patterns, 0.7 * sigma, 1.3 * sigma);
    EXPECT_NEAR(fitted, sigma, 0.02 * sigma);
  }
}

// ---- the registered bounds (both methods) ------------------------------------------------

// max |out - exact Gaussian| over the test patterns <= the registered max_error; and over ANY
// image in [0, 1]: both kernels sum to 1, so the worst image is the indicator of where the
// method's kernel exceeds the Gaussian, and its error is half the operator norm (l1 distance).
// For kosloff that worst case peaks at small sigma (0.089 at 1.25, ~0.07 from sigma 3 on; the
// tent's l1 distance to the Gaussian is scale-invariant), hence the sigmas checked.
TEST(SpreadingAndReshuffle, RegisteredMaxErrorHolds) {
  const std::vector<TestPattern> patterns = quality_test_set(64);
  for (const char* name : {"kosloff", "reshuffle"}) {
    const BlurMethod& method = find_blur_method(name);
    for (double sigma : {1.0, 2.0, 4.0, 8.0, 16.0, 32.0}) {
      const BlurOptions settings{sigma, Border::replicate, 1};
      double worst = 0;
      for (const TestPattern& p : patterns) {
        Image out(64, 64, 1);
        blur(out.plane(0), p.image.plane(0), method, settings);
        const DoublePlane exact = reference_gaussian(p.image.plane(0), sigma, Border::replicate, 1);
        worst = std::max(worst, blur_error(out.plane(0), exact).max_abs);
      }
      EXPECT_LE(worst, method.max_error) << name << " sigma " << sigma;
    }
    for (double sigma : {0.75, 1.25, 1.625, 2.125, 3.0, 8.0}) {
      const BlurOptions settings{sigma, Border::replicate, 1};
      EXPECT_LE(operator_norm_error(plane_blur(method, settings), sigma) / 2, method.max_error)
          << name << " sigma " << sigma;
    }
  }
}

TEST(SpreadingAndReshuffle, ThreadCountDoesNotChangeTheResult) {
  for (const char* name : {"kosloff", "reshuffle"})
    for (const Size size : {Size{33, 17}, Size{128, 96}})
      for (Border border : {Border::replicate, Border::zero}) {
        const Image in = random_image(size.w, size.h, 3);
        Image one(size.w, size.h, 1), two(size.w, size.h, 1);
        blur(one.plane(0), in.plane(0), find_blur_method(name), {3.0, border, 1});
        blur(two.plane(0), in.plane(0), find_blur_method(name), {3.0, border, 2});
        EXPECT_TRUE(identical(one.plane(0), two.plane(0))) << name;
      }
}

TEST(SpreadingAndReshuffle, TinyImagesMatchTheReferenceForReshuffle) {
  // reshuffle is exact: every size, every border, the exact Gaussian.
  const BlurMethod& method = find_blur_method("reshuffle");
  unsigned seed = 11;
  for (const Size size : kSizes)
    for (Border border : {Border::replicate, Border::mirror, Border::zero, Border::periodic}) {
      const Image in = random_image(size.w, size.h, seed++);
      Image out(size.w, size.h, 1);
      blur(out.plane(0), in.plane(0), method, {2.5, border, 0});
      const DoublePlane exact = reference_gaussian(in.plane(0), 2.5, border, 1);
      EXPECT_LT(max_difference(out.plane(0), exact), 1e-6)
          << size.w << " x " << size.h << " " << border_name(border);
    }
}

// ---- reshuffling -------------------------------------------------------------------------

TEST(Reshuffle, GaussianLinkageSetsArePairs) {
  const std::vector<double> g = sampled_gaussian(3.0, 18);
  const ReshuffledKernel k = reshuffle_kernel(g, 37, 1);
  ASSERT_EQ(k.weights.size(), 19u);  // the centre and one weight per distance
  EXPECT_EQ(k.taps(), 37);
  EXPECT_EQ(k.radius_x, 18);
  EXPECT_EQ(k.radius_y, 0);
  for (std::size_t i = 0; i < k.weights.size(); ++i) {
    const auto& set = k.links[i];
    ASSERT_TRUE(set.size() == 1 || set.size() == 2);
    for (const auto& link : set) EXPECT_EQ(k.weights[i], g[18 - link.dx]);
    if (set.size() == 2) {
      EXPECT_EQ(set[0].dx, -set[1].dx);
    }
  }
}

TEST(Reshuffle, RadialKernelSharesWeightsAlongCircles) {
  // exp(-(x^2 + y^2) / 8) on 9 x 9: equal for equal x^2 + y^2, including (0, 5)-type
  // coincidences; 81 taps but only as many weights as distinct x^2 + y^2 values.
  std::vector<double> kernel(81);
  std::vector<int> radii;
  for (int j = 0; j < 9; ++j)
    for (int i = 0; i < 9; ++i) {
      const int d2 = (i - 4) * (i - 4) + (j - 4) * (j - 4);
      kernel[j * 9 + i] = std::exp(-d2 / 8.0);
      radii.push_back(d2);
    }
  std::sort(radii.begin(), radii.end());
  const auto distinct = std::unique(radii.begin(), radii.end()) - radii.begin();
  const ReshuffledKernel k = reshuffle_kernel(kernel, 9, 9);
  EXPECT_EQ(static_cast<std::ptrdiff_t>(k.weights.size()), distinct);
  EXPECT_EQ(k.taps(), 81);
}

// Arbitrary (asymmetric, signed) 2D kernels: the impulse response is the kernel itself
// (convolution convention), and every pixel of every border matches brute force.
TEST(Reshuffle, ArbitraryKernel2DMatchesBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<double> kernel(5 * 3);
  for (double& w : kernel) w = value(rng);
  kernel[2] = kernel[9];  // a repeated weight: a linkage set of two
  const ReshuffledKernel k = reshuffle_kernel(kernel, 5, 3);
  EXPECT_EQ(k.weights.size(), 14u);

  const Image impulse = impulse_image(11, 9, 5, 4);
  Image response(11, 9, 1);
  reshuffle_filter(response.plane(0), impulse.plane(0), k, Border::zero, 1);
  for (std::ptrdiff_t y = 0; y < 9; ++y)
    for (std::ptrdiff_t x = 0; x < 11; ++x) {
      const bool inside = std::abs(x - 5) <= 2 && std::abs(y - 4) <= 1;
      const double expected = inside ? kernel[(y - 4 + 1) * 5 + (x - 5 + 2)] : 0.0;
      EXPECT_NEAR(response(x, y, 0), expected, 1e-7) << x << ", " << y;
    }

  unsigned seed = 21;
  for (const Size size : kSizes)
    for (Border border : {Border::replicate, Border::mirror, Border::zero, Border::periodic}) {
      const Image in = random_image(size.w, size.h, seed++);
      Image out(size.w, size.h, 1);
      reshuffle_filter(out.plane(0), in.plane(0), k, border, 2);
      EXPECT_LT(max_difference(out.plane(0), brute_convolve(in.plane(0), kernel, 5, 3, border)),
                1e-5)
          << size.w << " x " << size.h << " " << border_name(border);
    }
}

TEST(Reshuffle, Arbitrary1DKernelSeparableMatchesBruteForce) {
  const std::vector<double> kernel{0.05, -0.1, 0.3, 0.5, 0.3, 0.2, -0.25};  // asymmetric
  const ReshuffledKernel k = reshuffle_kernel(kernel, 7, 1);
  EXPECT_EQ(k.weights.size(), 6u);
  unsigned seed = 41;
  for (const Size size : kSizes)
    for (Border border : {Border::replicate, Border::mirror, Border::zero, Border::periodic}) {
      const Image in = random_image(size.w, size.h, seed++);
      Image out(size.w, size.h, 1);
      reshuffle_filter_separable(out.plane(0), in.plane(0), k, border, 1);
      EXPECT_LT(max_difference(out.plane(0), brute_separable(in.plane(0), kernel, border)), 1e-5)
          << size.w << " x " << size.h << " " << border_name(border);
    }
}

// Quantisation into levels: the realised kernel is the quantised one (computed here), with at
// most `levels` unique weights, within the stated l1 bound of the original.
TEST(Reshuffle, QuantisedKernelIsRealisedAndBounded) {
  const std::ptrdiff_t r = 12;
  const std::vector<double> g = sampled_gaussian(4.0, r);
  const double largest = *std::max_element(g.begin(), g.end());
  for (int levels : {4, 16, 64}) {
    const ReshuffledKernel k = reshuffle_kernel(g, 2 * r + 1, 1, levels);
    EXPECT_LE(static_cast<int>(k.weights.size()), levels);
    const double step = largest / levels;
    std::vector<double> expected(g.size());
    double l1 = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
      expected[i] = std::round(g[i] / step) * step;
      l1 += std::abs(expected[i] - g[i]);
    }
    EXPECT_LE(l1, static_cast<double>(g.size()) * largest / (2.0 * levels));
    const Image impulse = impulse_image(2 * r + 5, 1, r + 2, 0);
    Image response(2 * r + 5, 1, 1);
    reshuffle_filter(response.plane(0), impulse.plane(0), k, Border::zero, 1);  // along x only
    for (std::ptrdiff_t x = -r; x <= r; ++x)
      EXPECT_NEAR(response(x + r + 2, 0, 0), expected[x + r], 1e-7) << levels << " " << x;
  }
}

TEST(Reshuffle, ConstantImageStaysConstant) {
  const Image in = testing_util::make_image(30, 20, 1, [](auto, auto, int) { return 0.3f; });
  Image out(30, 20, 1);
  for (double sigma : {0.25, 2.0, 20.0}) {
    blur(out.plane(0), in.plane(0), find_blur_method("reshuffle"), {sigma, Border::mirror, 1});
    for (std::ptrdiff_t y = 0; y < 20; ++y)
      for (std::ptrdiff_t x = 0; x < 30; ++x) ASSERT_NEAR(out(x, y, 0), 0.3f, 1e-6);
  }
}

// ---- bad input ---------------------------------------------------------------------------

TEST(SpreadingAndReshuffle, BadInputNamesTheArgument) {
  Image in(8, 8, 1), out(8, 8, 1), small(4, 8, 1);
  const auto spread = [&](SpreadingKernel k, Border b) {
    polynomial_spread(out.plane(0), in.plane(0), k, b, 0);
  };
  EXPECT_EQ(invalid_argument_of([&] { spread({0, 0.0}, Border::replicate); }).argument, "kernel");
  EXPECT_EQ(invalid_argument_of([&] { spread({3, 1.5}, Border::replicate); }).argument, "kernel");
  EXPECT_EQ(invalid_argument_of([&] { spread({3, NAN}, Border::replicate); }).argument, "kernel");
  const auto mirror = invalid_argument_of([&] { spread({3, 0.0}, Border::mirror); });
  EXPECT_EQ(mirror.argument, "border");
  EXPECT_TRUE(contains(mirror.message, "mirror"));
  EXPECT_EQ(invalid_argument_of([&] {
              polynomial_spread(small.plane(0), in.plane(0), {3, 0.0}, Border::zero);
            }).argument,
            "out");
  EXPECT_EQ(invalid_argument_of([] { spreading_kernel_for_sigma(-1); }).argument, "sigma");
  EXPECT_EQ(invalid_argument_of([] { spreading_variance({-2, 0.0}); }).argument, "kernel");

  const std::vector<double> three{0.25, 0.5, 0.25};
  EXPECT_EQ(invalid_argument_of([] { reshuffle_kernel({}, 1, 1); }).argument, "kernel");
  EXPECT_EQ(invalid_argument_of([&] { reshuffle_kernel(three, 2, 1); }).argument, "width");
  EXPECT_EQ(invalid_argument_of([&] { reshuffle_kernel(three, 3, 0); }).argument, "height");
  EXPECT_EQ(invalid_argument_of([&] { reshuffle_kernel(three, 1, 1); }).argument, "kernel");
  EXPECT_EQ(invalid_argument_of([&] { reshuffle_kernel(three, 3, 1, -1); }).argument, "levels");
  const std::vector<double> with_nan{0.25, NAN, 0.25}, zeros{0.0, 0.0, 0.0};
  const auto nan = invalid_argument_of([&] { reshuffle_kernel(with_nan, 3, 1); });
  EXPECT_EQ(nan.argument, "kernel");
  EXPECT_TRUE(contains(nan.message, "non-finite"));
  EXPECT_EQ(invalid_argument_of([&] { reshuffle_kernel(zeros, 3, 1); }).argument, "kernel");
  const std::vector<double> square(9, 1.0 / 9);
  const ReshuffledKernel box = reshuffle_kernel(square, 3, 3);
  EXPECT_EQ(invalid_argument_of([&] {
              reshuffle_filter_separable(out.plane(0), in.plane(0), box, Border::zero);
            }).argument,
            "kernel");
  EXPECT_EQ(invalid_argument_of([&] {
              reshuffle_filter(out.plane(0), in.plane(0), ReshuffledKernel{}, Border::zero);
            }).argument,
            "kernel");
  EXPECT_EQ(invalid_argument_of([&] {
              reshuffle_filter(out.plane(0), in.plane(0), box, Border::zero, -1);
            }).argument,
            "threads");
  // Through the registry: kosloff has no mirror border, reshuffle no sigma above 64.
  EXPECT_EQ(
      invalid_argument_of([&] {
        blur(out.plane(0), in.plane(0), find_blur_method("kosloff"), {2.0, Border::mirror, 0});
      }).argument,
      "border");
  EXPECT_EQ(invalid_argument_of([&] {
              blur(out.plane(0), in.plane(0), find_blur_method("reshuffle"),
                   {100.0, Border::replicate, 0});
            }).argument,
            "sigma");
}

}  // namespace
}  // namespace tridiff
