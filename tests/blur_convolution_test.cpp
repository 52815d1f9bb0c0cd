// Convolution methods ("direct", "separable", "fft") and the kernel functions behind them:
// kernels against their analytic facts, every convolution and border against a brute-force
// double sum written here, the registered methods against the double reference Gaussian,
// threads, and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "test_util.hpp"
#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/kernels.hpp"
#include "tridiff/blur/quality.hpp"
#include "tridiff/blur/reference.hpp"

namespace tridiff {
namespace {

using testing_util::contains;
using testing_util::invalid_argument_of;

constexpr Border kBorders[] = {Border::replicate, Border::mirror, Border::zero, Border::periodic};

// ---- helpers ----------------------------------------------------------------------------

using testing_util::random_image;

// A kernel of `size` random positive weights summing to 1: asymmetric, so that a flipped
// kernel or a swapped axis shows.
std::vector<float> random_kernel(std::ptrdiff_t size, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(0.1, 1.0);
  std::vector<double> w(size);
  double sum = 0;
  for (double& v : w) sum += v = value(rng);
  std::vector<float> kernel;
  for (double v : w) kernel.push_back(static_cast<float>(v / sum));
  return kernel;
}

// The definition, in double: out(x, y) = sum_{i,j} k(i, j) in(x + i - rx, y + j - ry), pixels
// outside read through border_index (-1: zero).
DoublePlane brute_force(ConstPlane in,
                        const std::function<double(std::ptrdiff_t, std::ptrdiff_t)>& k,
                        std::ptrdiff_t kw, std::ptrdiff_t kh, Border border) {
  const std::ptrdiff_t w = in.width(), h = in.height(), rx = kw / 2, ry = kh / 2;
  DoublePlane out(w, h);
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x) {
      double sum = 0;
      for (std::ptrdiff_t j = 0; j < kh; ++j) {
        const std::ptrdiff_t sy = border_index(y + j - ry, h, border);
        if (sy < 0) continue;
        for (std::ptrdiff_t i = 0; i < kw; ++i) {
          const std::ptrdiff_t sx = border_index(x + i - rx, w, border);
          if (sx >= 0) sum += k(i, j) * in(sx, sy);
        }
      }
      out(x, y) = sum;
    }
  return out;
}

DoublePlane brute_force_separable(ConstPlane in, const std::vector<float>& kx,
                                  const std::vector<float>& ky, Border border) {
  return brute_force(
      in, [&](std::ptrdiff_t i, std::ptrdiff_t j) { return double(kx[i]) * ky[j]; }, std::ssize(kx),
      std::ssize(ky), border);
}

double max_abs_difference(ConstPlane a, const DoublePlane& b) {
  double worst = 0;
  for (std::ptrdiff_t y = 0; y < a.height(); ++y)
    for (std::ptrdiff_t x = 0; x < a.width(); ++x)
      worst = std::max(worst, std::abs(double(a(x, y)) - b(x, y)));
  return worst;
}

double max_abs_difference(ConstPlane a, ConstPlane b) {
  return max_abs_difference(a, to_double(b));
}

// ---- kernels ----------------------------------------------------------------------------

double sum_of(const std::vector<float>& k) {
  double s = 0;
  for (float v : k) s += v;
  return s;
}

TEST(Kernels, GaussianSumsToOneIsSymmetricAndDropsAtMostTheStatedTail) {
  for (double sigma : {0.25, 0.5, 1.0, 1.7, 2.0, 4.0, 8.0, 32.0}) {
    SCOPED_TRACE("sigma " + std::to_string(sigma));
    const std::ptrdiff_t r = gaussian_radius(sigma);
    const std::vector<float> k = gaussian_kernel(sigma);
    ASSERT_EQ(std::ssize(k), 2 * r + 1);
    EXPECT_NEAR(sum_of(k), 1.0, 1e-6);
    EXPECT_TRUE(std::equal(k.begin(), k.end(), k.rbegin()));
    EXPECT_LE(r, reference_radius(sigma));
    EXPECT_GE(r, 1);
    // The mass outside [-r, r] of the reference kernel (support 6 sigma) is at most the stated
    // tail, and r is the smallest such radius.
    const std::ptrdiff_t big = reference_radius(sigma);
    const std::vector<double> full = sampled_gaussian(sigma, big);
    auto outside = [&](std::ptrdiff_t radius) {
      double s = 0;
      for (std::ptrdiff_t i = -big; i <= big; ++i)
        if (std::abs(i) > radius) s += full[i + big];
      return s;
    };
    EXPECT_LE(outside(r), kGaussianTailMass);
    if (r > 1) {
      EXPECT_GT(outside(r - 1), kGaussianTailMass);
    }
    // The weights are the normalised samples, rounded to float.
    const std::vector<double> exact = sampled_gaussian(sigma, r);
    for (std::ptrdiff_t i = 0; i <= 2 * r; ++i) EXPECT_EQ(k[i], static_cast<float>(exact[i]));
  }
  // About 5.3 sigma for sigma >= 1: r = 11 at sigma 2, 43 at sigma 8.
  EXPECT_EQ(gaussian_radius(2.0), 11);
  EXPECT_NEAR(double(gaussian_radius(8.0)) / 8.0, 5.35, 0.15);
}

TEST(Kernels, TriangleHasTheSeedWeightsAndVarianceMSquaredMinusOneOverSix) {
  for (std::ptrdiff_t n : {1, 3, 5, 15, 31}) {
    SCOPED_TRACE("size " + std::to_string(n));
    const std::vector<float> k = triangle_kernel(n);
    ASSERT_EQ(std::ssize(k), n);
    const double m = double(n + 1) / 2;
    EXPECT_NEAR(sum_of(k), 1.0, 1e-6);
    double variance = 0;
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const double offset = double(i - n / 2);
      variance += k[i] * offset * offset;
      // Seed 000 §5.3.2: the middle tap weighs m, each step away one less.
      EXPECT_NEAR(k[i] * m * m, m - std::abs(offset), 1e-5);
    }
    EXPECT_NEAR(variance, (m * m - 1) / 6, 1e-5 * m * m);
  }
  // Figure 5.2 of seed 000: size 15, middle tap 8 times the end taps.
  const std::vector<float> k15 = triangle_kernel(15);
  EXPECT_NEAR(k15[7] / k15[0], 8.0, 1e-6);
}

TEST(Kernels, BilinearBoxAveragesThePixelAndItsLowerRightNeighbours) {
  EXPECT_EQ(bilinear_box_kernel(), (std::vector<float>{0.f, 0.5f, 0.5f}));
  const Kernel2D box = bilinear_box_kernel_2d();
  ASSERT_EQ(box.width, 3);
  ASSERT_EQ(box.height, 3);
  for (std::ptrdiff_t j = 0; j < 3; ++j)
    for (std::ptrdiff_t i = 0; i < 3; ++i)
      EXPECT_EQ(box(i, j), i >= 1 && j >= 1 ? 0.25f : 0.f) << i << ", " << j;
  // On an image: (x, y) -> the mean of the 2 x 2 block whose top-left pixel it is.
  const Image in = random_image(5, 4, 7);
  Image out(5, 4, 1);
  convolve_2d(out.plane(0), in.plane(0), box, Border::replicate, 1);
  for (std::ptrdiff_t y = 0; y + 1 < 4; ++y)
    for (std::ptrdiff_t x = 0; x + 1 < 5; ++x)
      EXPECT_NEAR(out(x, y, 0),
                  (in(x, y, 0) + in(x + 1, y, 0) + in(x, y + 1, 0) + in(x + 1, y + 1, 0)) / 4,
                  1e-6);
}

TEST(Kernels, OuterProductAndTheGaussian2D) {
  const std::vector<float> kx = random_kernel(5, 1), ky = random_kernel(3, 2);
  const Kernel2D k = outer_product(kx, ky);
  ASSERT_EQ(k.width, 5);
  ASSERT_EQ(k.height, 3);
  for (std::ptrdiff_t j = 0; j < 3; ++j)
    for (std::ptrdiff_t i = 0; i < 5; ++i)
      EXPECT_EQ(k(i, j), static_cast<float>(double(kx[i]) * ky[j]));
  const Kernel2D g = gaussian_kernel_2d(1.5);
  EXPECT_EQ(g.width, 2 * gaussian_radius(1.5) + 1);
  double sum = 0;
  for (float v : g.weights) sum += v;
  EXPECT_NEAR(sum, 1.0, 1e-6);
}

// ---- every convolution against brute force ----------------------------------------------

struct Size {
  std::ptrdiff_t w, h;
};
constexpr Size kSizes[] = {{1, 1}, {2, 2}, {3, 3}, {17, 17}, {33, 33}, {17, 5}, {3, 33}, {2, 17}};

using SeparableConvolution = void (*)(Plane, ConstPlane, std::span<const float>,
                                      std::span<const float>, Border, int);
using Convolution2D = void (*)(Plane, ConstPlane, const Kernel2D&, Border, int);

// kx, ky pairs: asymmetric small ones, symmetric, one-tap, kernels wider than the image, and
// kernels with negative weights that do not sum to 1.
std::vector<std::pair<std::vector<float>, std::vector<float>>> test_kernels() {
  return {{random_kernel(3, 11), random_kernel(5, 12)},
          {{-0.25f, 1.f, 0.5f}, {0.5f, -0.5f, 0.3f, 0.1f, 0.2f}},
          {random_kernel(7, 13), random_kernel(1, 14)},
          {gaussian_kernel(1.3), gaussian_kernel(0.7)},
          {triangle_kernel(9), bilinear_box_kernel()},
          {random_kernel(41, 15), random_kernel(75, 16)}};
}

void expect_matches_brute_force_separable(SeparableConvolution convolve, double tolerance) {
  for (const Size size : kSizes)
    for (const auto& [kx, ky] : test_kernels())
      for (Border border : kBorders) {
        SCOPED_TRACE(std::to_string(size.w) + " x " + std::to_string(size.h) + ", kernel " +
                     std::to_string(kx.size()) + " x " + std::to_string(ky.size()) + ", " +
                     std::string(border_name(border)));
        const Image in = random_image(size.w, size.h, 3);
        Image out(size.w, size.h, 1);
        convolve(out.plane(0), in.plane(0), kx, ky, border, 1);
        EXPECT_LE(
            max_abs_difference(out.plane(0), brute_force_separable(in.plane(0), kx, ky, border)),
            tolerance);
      }
}

void expect_matches_brute_force_2d(Convolution2D convolve, double tolerance) {
  // A non-separable kernel: random weights, 5 x 3; and one wider than the small images.
  std::vector<Kernel2D> kernels;
  for (auto [w, h] : {std::pair{5, 3}, std::pair{1, 7}, std::pair{37, 39}}) {
    const std::vector<float> weights = random_kernel(w * h, static_cast<unsigned>(w + 31 * h));
    kernels.push_back({w, h, weights});
  }
  for (const Size size : kSizes)
    for (const Kernel2D& k : kernels)
      for (Border border : kBorders) {
        SCOPED_TRACE(std::to_string(size.w) + " x " + std::to_string(size.h) + ", kernel " +
                     std::to_string(k.width) + " x " + std::to_string(k.height) + ", " +
                     std::string(border_name(border)));
        const Image in = random_image(size.w, size.h, 4);
        Image out(size.w, size.h, 1);
        convolve(out.plane(0), in.plane(0), k, border, 1);
        const DoublePlane expected = brute_force(
            in.plane(0), [&](std::ptrdiff_t i, std::ptrdiff_t j) { return double(k(i, j)); },
            k.width, k.height, border);
        EXPECT_LE(max_abs_difference(out.plane(0), expected), tolerance);
      }
}

TEST(Convolution, SeparableMatchesBruteForceForEveryBorderSizeAndKernel) {
  expect_matches_brute_force_separable(convolve_separable, 1e-6);
}

TEST(Convolution, TwoDMatchesBruteForceForEveryBorderSizeAndKernel) {
  expect_matches_brute_force_2d(convolve_2d, 1e-6);
}

TEST(Convolution, FftSeparableMatchesBruteForceForEveryBorderSizeAndKernel) {
  expect_matches_brute_force_separable(fft_convolve_separable, 2e-6);
}

TEST(Convolution, FftTwoDMatchesBruteForceForEveryBorderSizeAndKernel) {
  expect_matches_brute_force_2d(fft_convolve, 2e-6);
}

TEST(Convolution, AViewInsideALargerPlaneReadsAndWritesOnlyItsRectangle) {
  Image in = random_image(40, 30, 5), out(40, 30, 1);
  const Rect area{3, 2, 21, 19};
  const std::vector<float> kx = random_kernel(5, 1), ky = random_kernel(7, 2);
  for (auto convolve :
       {SeparableConvolution(convolve_separable), SeparableConvolution(fft_convolve_separable)}) {
    std::fill_n(out.data(), out.plane_stride(), -1.f);
    convolve(out.plane(0).sub(area), in.plane(0).sub(area), kx, ky, Border::mirror, 2);
    const DoublePlane expected =
        brute_force_separable(in.plane(0).sub(area), kx, ky, Border::mirror);
    EXPECT_LE(max_abs_difference(ConstPlane(out.plane(0).sub(area)), expected), 2e-6);
    for (std::ptrdiff_t y = 0; y < 30; ++y)
      for (std::ptrdiff_t x = 0; x < 40; ++x)
        if (x < area.x || y < area.y || x >= area.x + area.width || y >= area.y + area.height) {
          ASSERT_EQ(out(x, y, 0), -1.f) << x << ", " << y;
        }
  }
}

TEST(Convolution, SeparableSplitsWideImagesIntoPanelsSeamlessly) {
  // A column kernel of 521 taps makes the per-thread ring of rows too tall for one panel of
  // 600 columns: the width is cut into panels, each recomputing its halo of kx.
  const Image in = random_image(600, 5, 41);
  const std::vector<float> kx = random_kernel(5, 42), ky = random_kernel(521, 43);
  Image out(600, 5, 1);
  for (Border border : {Border::replicate, Border::periodic}) {
    convolve_separable(out.plane(0), in.plane(0), kx, ky, border, 2);
    EXPECT_LE(max_abs_difference(out.plane(0), brute_force_separable(in.plane(0), kx, ky, border)),
              1e-6)
        << border_name(border);
  }
}

TEST(Convolution, SeparableEqualsTwoDForASeparableKernel) {
  const std::vector<float> kx = random_kernel(9, 21), ky = random_kernel(5, 22);
  const Image in = random_image(33, 17, 23);
  Image a(33, 17, 1), b(33, 17, 1), c(33, 17, 1);
  for (Border border : kBorders) {
    convolve_separable(a.plane(0), in.plane(0), kx, ky, border, 1);
    convolve_2d(b.plane(0), in.plane(0), outer_product(kx, ky), border, 1);
    fft_convolve(c.plane(0), in.plane(0), outer_product(kx, ky), border, 1);
    EXPECT_LE(max_abs_difference(a.plane(0), b.plane(0)), 1e-6) << border_name(border);
    EXPECT_LE(max_abs_difference(a.plane(0), c.plane(0)), 2e-6) << border_name(border);
  }
}

TEST(Convolution, OneAndTwoThreadsGiveTheSameResult) {
  const Image in = random_image(70, 45, 31);
  const std::vector<float> kx = gaussian_kernel(2.5), ky = random_kernel(9, 32);
  Image one(70, 45, 1), two(70, 45, 1);
  for (Border border : kBorders) {
    SCOPED_TRACE(border_name(border));
    // The spatial convolutions compute every row the same way on any thread: bit for bit,
    // whatever rows the stripes of 2 and 3 threads start on.
    // (A symmetric column kernel takes the two-rows-at-a-time path, an asymmetric one not.)
    for (const auto& [row_kernel, column_kernel] : {std::pair{kx, ky}, std::pair{ky, kx}}) {
      convolve_separable(one.plane(0), in.plane(0), row_kernel, column_kernel, border, 1);
      for (int threads : {2, 3}) {
        convolve_separable(two.plane(0), in.plane(0), row_kernel, column_kernel, border, threads);
        EXPECT_EQ(max_abs_difference(one.plane(0), two.plane(0)), 0.0) << threads << " threads";
      }
    }
    convolve_2d(one.plane(0), in.plane(0), outer_product(kx, ky), border, 1);
    convolve_2d(two.plane(0), in.plane(0), outer_product(kx, ky), border, 2);
    EXPECT_EQ(max_abs_difference(one.plane(0), two.plane(0)), 0.0);
    // FFTW may split the transform differently: equal up to rounding.
    fft_convolve_separable(one.plane(0), in.plane(0), kx, ky, border, 1);
    fft_convolve_separable(two.plane(0), in.plane(0), kx, ky, border, 2);
    EXPECT_LE(max_abs_difference(one.plane(0), two.plane(0)), 1e-6);
  }
}

// ---- bad input --------------------------------------------------------------------------

TEST(Convolution, BadKernelsAndPlanesAreInvalidArgumentsNamingTheArgument) {
  Image in(8, 6, 1), out(8, 6, 1), small(7, 6, 1);
  const std::vector<float> good{0.25f, 0.5f, 0.25f}, even{0.5f, 0.5f}, empty;
  const std::vector<float> nan{0.f, std::nanf(""), 0.f};
  const Kernel2D good2d = outer_product(good, good);
  const Kernel2D even2d{2, 3, {0, 0, 0, 0, 0, 0}}, empty2d{}, short2d{3, 3, {1.f}};
  for (auto convolve :
       {SeparableConvolution(convolve_separable), SeparableConvolution(fft_convolve_separable)}) {
    auto run = [&](std::span<const float> kx, std::span<const float> ky, Plane o, int threads) {
      return invalid_argument_of([&] { convolve(o, in.plane(0), kx, ky, Border::zero, threads); });
    };
    auto t = run(even, good, out.plane(0), 1);
    EXPECT_EQ(t.argument, "kx");
    EXPECT_TRUE(contains(t.message, "odd length"));
    EXPECT_EQ(run(good, even, out.plane(0), 1).argument, "ky");
    t = run(empty, good, out.plane(0), 1);
    EXPECT_EQ(t.argument, "kx");
    EXPECT_TRUE(contains(t.message, "empty"));
    EXPECT_EQ(run(good, empty, out.plane(0), 1).argument, "ky");
    EXPECT_EQ(run(good, nan, out.plane(0), 1).argument, "ky");
    EXPECT_EQ(run(good, good, small.plane(0), 1).argument, "out");
    EXPECT_EQ(run(good, good, out.plane(0), -1).argument, "threads");
    EXPECT_EQ(invalid_argument_of([&] {
                convolve(in.plane(0), in.plane(0), good, good, Border::zero, 1);
              }).argument,
              "out");
    EXPECT_EQ(invalid_argument_of([&] {
                convolve(out.plane(0), ConstPlane{}, good, good, Border::zero, 1);
              }).argument,
              "in");
  }
  for (auto convolve : {Convolution2D(convolve_2d), Convolution2D(fft_convolve)}) {
    auto run = [&](const Kernel2D& k) {
      return invalid_argument_of(
          [&] { convolve(out.plane(0), in.plane(0), k, Border::mirror, 1); });
    };
    EXPECT_EQ(run(even2d).argument, "kernel");
    EXPECT_TRUE(contains(run(even2d).message, "odd"));
    EXPECT_EQ(run(empty2d).argument, "kernel");
    EXPECT_EQ(run(short2d).argument, "kernel");
    EXPECT_EQ(invalid_argument_of([&] {
                convolve(small.plane(0), in.plane(0), good2d, Border::mirror, 1);
              }).argument,
              "out");
  }
  EXPECT_EQ(invalid_argument_of([] { triangle_kernel(4); }).argument, "size");
  EXPECT_EQ(invalid_argument_of([] { triangle_kernel(0); }).argument, "size");
  EXPECT_EQ(invalid_argument_of([] { gaussian_kernel(0.0); }).argument, "sigma");
  EXPECT_EQ(invalid_argument_of([] { gaussian_radius(NAN); }).argument, "sigma");
  EXPECT_EQ(invalid_argument_of([] {
              outer_product(std::vector<float>{1, 1}, std::vector<float>{1});
            }).argument,
            "kx");
}

// ---- the registered methods against the reference Gaussian ------------------------------

// Max |method - reference_gaussian| over the quality test patterns (values in [0, 1]).
double method_error(const BlurMethod& method, double sigma, Border border, std::ptrdiff_t size) {
  double worst = 0;
  for (const TestPattern& pattern : quality_test_set(size, 5)) {
    Image out;
    blur(out, pattern.image, method, {sigma, border, 1});
    const DoublePlane exact = reference_gaussian(pattern.image.plane(0), sigma, border, 1);
    worst = std::max(worst, max_abs_difference(out.plane(0), exact));
  }
  return worst;
}

void expect_within_registered_bound(const char* name, std::initializer_list<double> sigmas,
                                    std::ptrdiff_t size) {
  const BlurMethod& method = find_blur_method(name);
  EXPECT_TRUE(method.exact);
  EXPECT_LE(method.max_error, 1e-5);
  for (double sigma : sigmas)
    for (Border border : kBorders) {
      ASSERT_TRUE(method.borders.contains(border));
      const double error = method_error(method, sigma, border, size);
      EXPECT_LE(error, method.max_error)
          << name << ", sigma " << sigma << ", " << border_name(border);
      std::printf("  %s sigma %5.2f %-9s max error %.2e\n", name, sigma,
                  std::string(border_name(border)).c_str(), error);
    }
}

TEST(Methods, SeparableIsWithinItsRegisteredErrorOfTheReference) {
  expect_within_registered_bound("separable", {0.25, 1, 2, 4, 8, 16, 32}, 64);
  expect_within_registered_bound("separable", {128}, 24);  // its largest sigma
}

TEST(Methods, DirectIsWithinItsRegisteredErrorOfTheReference) {
  expect_within_registered_bound("direct", {0.25, 1, 2, 4}, 48);
  expect_within_registered_bound("direct", {8, 16}, 16);  // quadratic: small planes
}

TEST(Methods, FftIsWithinItsRegisteredErrorOfTheReference) {
  expect_within_registered_bound("fft", {0.25, 1, 2, 4, 8, 16, 32}, 64);
  expect_within_registered_bound("fft", {128}, 8);  // its largest sigma
}

// ---- gaussian-fir: the truncated Gaussian in strips ---------------------------------------

TEST(GaussianFir, WithinItsStatedErrorOfTheReferenceAcrossSigmas) {
  // Every radius it uses (2 at sigma 0.5 up to 11 at sigma 3).
  const BlurMethod& method = find_blur_method("gaussian-fir");
  EXPECT_FALSE(method.exact);
  for (double sigma : {0.5, 0.8, 1.0, 1.3, 1.7, 2.0, 2.5, 3.0}) {
    const double error = method_error(method, sigma, Border::replicate, 64);
    EXPECT_LE(error, method.max_error) << "sigma " << sigma;
    std::printf("  gaussian-fir sigma %4.2f max error %.2e\n", sigma, error);
  }
}

TEST(GaussianFir, EqualsTheSameTruncatedKernelAppliedByBruteForce) {
  // The kernel it states (the sampled Gaussian cut at a tail of 2e-4), summed in double by
  // brute force: the two agree up to float rounding, at sizes around the 16-row strips and
  // 16-column blocks, including planes narrower than the kernel.
  const BlurMethod& method = find_blur_method("gaussian-fir");
  for (double sigma : {0.7, 2.0, 3.0}) {
    const std::vector<float> k = gaussian_kernel(sigma, gaussian_radius(sigma, 2e-4));
    for (std::ptrdiff_t w : {1, 2, 3, 15, 16, 17, 33, 65})
      for (std::ptrdiff_t h : {1, 2, 15, 16, 17, 31, 33}) {
        const Image in = random_image(w, h, static_cast<unsigned>(w * 100 + h));
        Image out(w, h, 1);
        blur(out.plane(0), in.plane(0), method, {sigma, Border::replicate, 2});
        const DoublePlane exact = brute_force_separable(in.plane(0), k, k, Border::replicate);
        EXPECT_LE(max_abs_difference(out.plane(0), exact), 2e-6)
            << "sigma " << sigma << ", " << w << " x " << h;
      }
  }
}

TEST(GaussianFir, AViewInsideALargerPlaneAndThreadsAgree) {
  // A rectangle of a larger plane (pitch > width, its last row ending mid-row of the parent),
  // one and two threads: the same bits, and nothing outside the rectangle is written.
  const BlurMethod& method = find_blur_method("gaussian-fir");
  const Image in = random_image(61, 50, 3);
  const ConstPlane view = in.plane(0).sub({5, 3, 43, 41});
  Image one(61, 50, 1), two(61, 50, 1);
  blur(one.plane(0).sub({5, 3, 43, 41}), view, method, {2.0, Border::replicate, 1});
  blur(two.plane(0).sub({5, 3, 43, 41}), view, method, {2.0, Border::replicate, 2});
  for (std::ptrdiff_t y = 0; y < 50; ++y)
    for (std::ptrdiff_t x = 0; x < 61; ++x) {
      ASSERT_EQ(one(x, y, 0), two(x, y, 0)) << x << ", " << y;
      const bool inside = x >= 5 && x < 48 && y >= 3 && y < 44;
      if (!inside) {
        ASSERT_EQ(one(x, y, 0), 0.f) << x << ", " << y;
      }
    }
  const Image flat = testing_util::make_image(37, 21, 1, [](auto, auto, int) { return 0.625f; });
  Image out(37, 21, 1);
  blur(out.plane(0), flat.plane(0), method, {2.5});
  for (std::ptrdiff_t y = 0; y < 21; ++y)
    for (std::ptrdiff_t x = 0; x < 37; ++x) ASSERT_NEAR(out(x, y, 0), 0.625f, 1e-6);
}

TEST(Methods, SigmaOutsideTheRangeIsRejected) {
  Image in(8, 8, 1), out(8, 8, 1);
  EXPECT_EQ(invalid_argument_of([&] {
              blur(out.plane(0), in.plane(0), find_blur_method("direct"), {17.0});
            }).argument,
            "sigma");
  EXPECT_EQ(invalid_argument_of([&] {
              blur(out.plane(0), in.plane(0), find_blur_method("fft"), {0.1});
            }).argument,
            "sigma");
}

}  // namespace
}  // namespace tridiff
