// The blur framework: borders, the registry's checks, the exact reference (against a brute-force
// 2D sum in long double), the quality harness (against facts of the Gaussian), and the
// recursive Gaussian (against the reference).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "test_util.hpp"
#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/quality.hpp"
#include "tridiff/blur/reference.hpp"

namespace tridiff {
namespace {

using testing_util::contains;
using testing_util::invalid_argument_of;
using testing_util::make_image;
using testing_util::random_image;

TEST(BlurBorder, IndexRules) {
  // replicate: clamp; zero: -1; periodic: wrap; mirror: d c b a | a b c d.
  EXPECT_EQ(border_index(-3, 5, Border::replicate), 0);
  EXPECT_EQ(border_index(9, 5, Border::replicate), 4);
  EXPECT_EQ(border_index(-1, 5, Border::zero), -1);
  EXPECT_EQ(border_index(5, 5, Border::zero), -1);
  EXPECT_EQ(border_index(-1, 5, Border::periodic), 4);
  EXPECT_EQ(border_index(12, 5, Border::periodic), 2);
  const std::ptrdiff_t mirrored[] = {2, 1, 0, 0, 1, 2, 3, 4, 4, 3, 2, 1, 0, 0};
  for (std::ptrdiff_t i = -3; i <= 10; ++i)
    EXPECT_EQ(border_index(i, 5, Border::mirror), mirrored[i + 3]) << i;
  // A line of one pixel: every rule but zero reads that pixel, from however far away.
  for (Border b : {Border::replicate, Border::mirror, Border::periodic})
    for (std::ptrdiff_t i : {-100, -1, 1, 77}) EXPECT_EQ(border_index(i, 1, b), 0);
}

TEST(BlurReference, KernelIsNormalisedWithTheGaussianVariance) {
  for (double sigma : {0.7, 1.0, 3.0, 12.5}) {
    const std::ptrdiff_t r = reference_radius(sigma);
    EXPECT_GE(r, 6 * sigma);
    const std::vector<double> k = sampled_gaussian(sigma, r);
    double sum = 0, variance = 0;
    for (std::ptrdiff_t i = -r; i <= r; ++i) sum += k[i + r], variance += i * i * k[i + r];
    EXPECT_NEAR(sum, 1, 1e-14);
    // The sampled Gaussian's variance is sigma^2 to within exp(-2 pi^2 sigma^2) terms.
    EXPECT_NEAR(variance, sigma * sigma, sigma >= 1 ? 1e-6 * sigma * sigma : 1e-2) << sigma;
  }
}

// Brute force: out(x, y) = sum over the 2D kernel, each tap through border_index, in long double.
long double brute_gaussian(ConstPlane in, std::ptrdiff_t x, std::ptrdiff_t y, double sigma,
                           Border border) {
  const std::ptrdiff_t r = reference_radius(sigma);
  long double sum = 0, norm = 0;
  for (std::ptrdiff_t dy = -r; dy <= r; ++dy)
    for (std::ptrdiff_t dx = -r; dx <= r; ++dx) {
      const long double w = std::exp(-(dx * dx + dy * dy) / (2.0L * sigma * sigma));
      norm += w;
      const std::ptrdiff_t sx = border_index(x + dx, in.width(), border);
      const std::ptrdiff_t sy = border_index(y + dy, in.height(), border);
      if (sx >= 0 && sy >= 0) sum += w * in(sx, sy);
    }
  return sum / norm;
}

TEST(BlurReference, MatchesBruteForce2DSumForEveryBorder) {
  const Image image = random_image(13, 9, 3);
  for (Border border : {Border::replicate, Border::mirror, Border::zero, Border::periodic})
    for (double sigma : {0.8, 2.5}) {  // 2.5: the kernel (r = 15) is wider than the image
      const DoublePlane out = reference_gaussian(image.plane(0), sigma, border, 2);
      for (std::ptrdiff_t y = 0; y < 9; ++y)
        for (std::ptrdiff_t x = 0; x < 13; ++x)
          ASSERT_NEAR(out(x, y),
                      static_cast<double>(brute_gaussian(image.plane(0), x, y, sigma, border)),
                      1e-14)
              << border_name(border) << " sigma " << sigma << " at " << x << ", " << y;
    }
}

TEST(BlurReference, PeriodicAndMirrorConserveMass) {
  const Image image = random_image(31, 20, 4);
  double mass = 0;
  for (std::ptrdiff_t y = 0; y < 20; ++y)
    for (std::ptrdiff_t x = 0; x < 31; ++x) mass += image(x, y, 0);
  for (Border border : {Border::periodic, Border::mirror}) {
    const DoublePlane out = reference_gaussian(image.plane(0), 4.0, border);
    double blurred = 0;
    for (double v : out.values) blurred += v;
    EXPECT_NEAR(blurred, mass, 1e-10 * mass) << border_name(border);
  }
}

TEST(BlurQuality, IdenticalImagesHaveNoError) {
  const Image image = random_image(40, 30, 5);
  const BlurError e = blur_error(image.plane(0), to_double(image.plane(0)));
  EXPECT_EQ(e.max_abs, 0);
  EXPECT_EQ(e.rmse, 0);
  EXPECT_TRUE(std::isinf(e.psnr));
  EXPECT_NEAR(e.ssim, 1, 1e-12);
}

TEST(BlurQuality, ErrorMeasuresOfAKnownOffset) {
  // A constant offset of 0.1: max = rmse = 0.1, PSNR = 20 dB; SSIM of a uniform image against
  // its offset is (2 mu1 mu2 + C1) / (mu1^2 + mu2^2 + C1) (no variance term).
  Image a(24, 24, 1);
  DoublePlane b(24, 24);
  for (std::ptrdiff_t y = 0; y < 24; ++y)
    for (std::ptrdiff_t x = 0; x < 24; ++x) a(x, y, 0) = 0.5f, b(x, y) = 0.6;
  const BlurError e = blur_error(a.plane(0), b);
  EXPECT_NEAR(e.max_abs, 0.1, 1e-7);
  EXPECT_NEAR(e.rmse, 0.1, 1e-7);
  EXPECT_NEAR(e.psnr, 20, 1e-5);
  const double c1 = 1e-4, expected = (2 * 0.5 * 0.6 + c1) / (0.25 + 0.36 + c1);
  EXPECT_NEAR(e.ssim, expected, 1e-9);
}

TEST(BlurQuality, TestSetIsInUnitRangeAndVaried) {
  const std::vector<TestPattern> set = quality_test_set(64);
  ASSERT_EQ(set.size(), 5u);
  for (const TestPattern& p : set) {
    float lo = 1, hi = 0;
    for (std::ptrdiff_t y = 0; y < 64; ++y)
      for (std::ptrdiff_t x = 0; x < 64; ++x)
        lo = std::min(lo, p.image(x, y, 0)), hi = std::max(hi, p.image(x, y, 0));
    EXPECT_GE(lo, 0) << p.name;
    EXPECT_LE(hi, 1) << p.name;
    EXPECT_GT(hi - lo, 0.5) << p.name;  // every pattern has contrast
  }
}

TEST(BlurQuality, EffectiveSigmaOfTwoGaussiansInARow) {
  // Gaussians compose: sigma 2 after sigma 1.5 is the Gaussian of sigma 2.5 (sampled kernels
  // compose to within 1e-3 in sigma at these sizes).
  const std::vector<TestPattern> set = quality_test_set(48);
  const PlaneBlur twice = [](Plane out, ConstPlane in) {
    const DoublePlane first = reference_gaussian(in, 1.5, Border::replicate);
    const DoublePlane second = reference_gaussian(first, 2.0, Border::replicate);
    for (std::ptrdiff_t y = 0; y < in.height(); ++y)
      for (std::ptrdiff_t x = 0; x < in.width(); ++x) out(x, y) = static_cast<float>(second(x, y));
  };
  EXPECT_NEAR(effective_sigma(twice, set, 1.0, 5.0), 2.5, 2e-3);
}

TEST(BlurRegistry, UnknownNameListsTheKnownOnes) {
  const auto thrown = invalid_argument_of([] { find_blur_method("gauss-magic"); });
  EXPECT_EQ(thrown.argument, "method");
  EXPECT_TRUE(contains(thrown.message, "gauss-magic"));
  EXPECT_TRUE(contains(thrown.message, "iir-deriche"));
}

TEST(BlurRegistry, EveryMethodIsDescribed) {
  ASSERT_FALSE(blur_methods().empty());
  for (const BlurMethod& m : blur_methods()) {
    EXPECT_FALSE(m.name.empty());
    EXPECT_FALSE(m.summary.empty()) << m.name;
    EXPECT_FALSE(m.cost.empty()) << m.name;
    EXPECT_GT(m.max_error, 0) << m.name;
    EXPECT_TRUE(!m.exact || m.max_error <= 1e-5) << m.name;
    EXPECT_LT(m.min_sigma, m.max_sigma) << m.name;
    // Replicate everywhere but in the diffusion methods, whose border is insulated (mirror).
    EXPECT_TRUE(m.borders.contains(Border::replicate) ||
                (m.name.starts_with("diffusion") && m.borders.contains(Border::mirror)))
        << m.name;
    EXPECT_EQ(&find_blur_method(m.name), &m);
  }
}

TEST(BlurRegistry, BadArgumentsAreNamed) {
  const BlurMethod& method = find_blur_method("iir-deriche");
  Image in(16, 8, 1), out(16, 8, 1), small(15, 8, 1);
  const auto argument = [&](Plane dst, BlurOptions s) {
    return invalid_argument_of([&] { blur(dst, in.plane(0), method, s); }).argument;
  };
  EXPECT_EQ(argument(small.plane(0), {2.0}), "out");
  EXPECT_EQ(argument(out.plane(0), {NAN}), "sigma");
  EXPECT_EQ(argument(out.plane(0), {0.0}), "sigma");
  EXPECT_EQ(argument(out.plane(0), {1e6}), "sigma");
  EXPECT_EQ(argument(out.plane(0), {2.0, Border::periodic}), "border");
  EXPECT_EQ(argument(out.plane(0), {2.0, Border::replicate, -1}), "threads");
  EXPECT_EQ(invalid_argument_of([&] {
              blur(in.plane(0).sub({1, 0, 15, 8}), in.plane(0), method, {2.0});
            }).argument,
            "out");
}

// The recursive Gaussians: iir-deriche at any sigma, iir-decimated (the same filter on a
// decimated plane) from sigma 8.

struct RecursiveCase {
  const char* name;
  std::vector<double> sigmas;  // spanning the method's range, and its level changes
  double small_sigma;          // for the small and odd sizes
  double operator_norm_bound;  // l1 error of the impulse responses
};
const std::vector<RecursiveCase>& recursive_cases() {
  static const std::vector<RecursiveCase> cases{
      {"iir-deriche", {1.0, 2.0, 4.0, 8.0, 16.0, 32.0}, 3.0, 1.5e-3},
      // 4, 8, 16, 32 are where f steps to 2, 4, 8, 16; the others lie between.
      {"iir-decimated", {4.0, 6.0, 8.0, 11.0, 16.0, 24.0, 32.0, 64.0}, 9.0, 2e-3}};
  return cases;
}

TEST(BlurRecursive, WithinItsStatedErrorAcrossSigmas) {
  for (const RecursiveCase& c : recursive_cases()) {
    const BlurMethod& method = find_blur_method(c.name);
    for (double sigma : c.sigmas) {
      const auto n = std::max<std::ptrdiff_t>(64, static_cast<std::ptrdiff_t>(4 * sigma));
      double worst = 0;
      for (const TestPattern& p : quality_test_set(n)) {
        Image out(n, n, 1);
        blur(out.plane(0), p.image.plane(0), method, {sigma});
        const DoublePlane exact = reference_gaussian(p.image.plane(0), sigma, Border::replicate);
        worst = std::max(worst, blur_error(out.plane(0), exact).max_abs);
      }
      EXPECT_LE(worst, method.max_error) << c.name << " sigma " << sigma;
    }
  }
}

TEST(BlurRecursive, OperatorNormErrorIsSmall) {
  // Deriche's coefficients fit the Gaussian to about 1e-3 in l1 (measured 0.95e-3 to 1.3e-3
  // for sigma 1 to 64); the max error on images in [0, 1] is well below that bound. On the
  // decimated plane the impulse response also depends on the impulse's phase on the coarse
  // grid: measured 0.74e-3 to 1.6e-3, the most where sigma / f = 2 exactly (sigma 16).
  for (const RecursiveCase& c : recursive_cases())
    for (double sigma : {1.0, 2.0, 8.0, 16.0, 32.0})
      if (sigma >= find_blur_method(c.name).min_sigma) {
        EXPECT_LE(operator_norm_error(plane_blur(find_blur_method(c.name), {sigma}), sigma),
                  c.operator_norm_bound)
            << c.name << " " << sigma;
      }
}

TEST(BlurRecursive, OddSizesAndBordersMatchTheReference) {
  // Sizes below, at and above the 16 lanes, odd and 2^k +- 1, every supported border.
  for (const RecursiveCase& c : recursive_cases()) {
    const BlurMethod& method = find_blur_method(c.name);
    for (std::ptrdiff_t w : {1, 2, 3, 15, 17, 33})
      for (std::ptrdiff_t h : {1, 2, 17, 31})
        for (Border border : {Border::replicate, Border::zero}) {
          if (!method.borders.contains(border)) continue;
          const Image in = random_image(w, h, static_cast<unsigned>(w * 100 + h));
          Image out(w, h, 1);
          blur(out.plane(0), in.plane(0), method, {c.small_sigma, border, 2});
          const DoublePlane exact = reference_gaussian(in.plane(0), c.small_sigma, border);
          EXPECT_LE(blur_error(out.plane(0), exact).max_abs, method.max_error)
              << c.name << " " << w << " x " << h << " " << border_name(border);
        }
  }
}

// At sigma 20 the sections' outputs are about (1 - |z|)^-2 times the input and cancel in the
// sum, so their roundings show: iir-deriche measured 0.4e-6 (6 eps) with FMA contraction
// (-march=native here) and 2.9e-6 (38 eps) on the x86-64 baseline (TRIDIFF_NATIVE=OFF).
TEST(BlurRecursive, ConstantStaysConstantAndThreadsAgree) {
  for (const RecursiveCase& c : recursive_cases()) {
    const BlurMethod& method = find_blur_method(c.name);
    Image flat = make_image(70, 45, 1, [](auto, auto, int) { return 0.625f; });
    Image out(70, 45, 1);
    blur(out.plane(0), flat.plane(0), method, {20.0});
    for (std::ptrdiff_t y = 0; y < 45; ++y)
      for (std::ptrdiff_t x = 0; x < 70; ++x) ASSERT_NEAR(out(x, y, 0), 0.625f, 1e-5) << c.name;
    const Image in = random_image(70, 45, 9);
    Image one(70, 45, 1), two(70, 45, 1);
    blur(one.plane(0), in.plane(0), method, {2 * c.small_sigma, Border::replicate, 1});
    blur(two.plane(0), in.plane(0), method, {2 * c.small_sigma, Border::replicate, 2});
    for (std::ptrdiff_t y = 0; y < 45; ++y)
      for (std::ptrdiff_t x = 0; x < 70; ++x) ASSERT_EQ(one(x, y, 0), two(x, y, 0)) << c.name;
  }
}

// The diffusion blurs: variance sigma^2 per axis exactly (from the impulse response's second
// moment), mass conserved, and within the stated error of the mirror-border Gaussian.

struct Moments {
  double mass = 0, variance_x = 0, variance_y = 0;
};
Moments impulse_moments(const BlurMethod& method, double sigma, std::ptrdiff_t n) {
  Image impulse(n, n, 1), out(n, n, 1);
  const std::ptrdiff_t c = n / 2;
  impulse(c, c, 0) = 1;
  blur(out.plane(0), impulse.plane(0), method, {sigma, Border::mirror, 2});
  Moments m;
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x) {
      const double v = out(x, y, 0);
      m.mass += v;
      m.variance_x += v * (x - c) * (x - c);
      m.variance_y += v * (y - c) * (y - c);
    }
  return m;
}

TEST(BlurDiffusion, VarianceIsSigmaSquaredAndMassIsConserved) {
  for (const char* name : {"diffusion-explicit", "diffusion-implicit"})
    for (double sigma : {1.0, 2.5, 4.0}) {
      // Wide enough that the tails (exponential for the implicit steps) do not reach the border.
      const Moments m = impulse_moments(find_blur_method(name), sigma, 24 * 4 + 1);
      EXPECT_NEAR(m.mass, 1, 1e-5) << name;
      EXPECT_NEAR(m.variance_x, sigma * sigma, 2e-4 * sigma * sigma) << name << " " << sigma;
      EXPECT_NEAR(m.variance_y, sigma * sigma, 2e-4 * sigma * sigma) << name << " " << sigma;
    }
}

TEST(BlurDiffusion, WithinTheStatedErrorOfTheInsulatedGaussian) {
  for (const char* name : {"diffusion-explicit", "diffusion-implicit"}) {
    const BlurMethod& method = find_blur_method(name);
    for (double sigma : {1.0, 2.0, 4.0}) {
      double worst = 0;
      for (const TestPattern& p : quality_test_set(48)) {
        Image out(48, 48, 1);
        blur(out.plane(0), p.image.plane(0), method, {sigma, Border::mirror});
        const DoublePlane exact = reference_gaussian(p.image.plane(0), sigma, Border::mirror);
        worst = std::max(worst, blur_error(out.plane(0), exact).max_abs);
      }
      EXPECT_LE(worst, method.max_error) << name << " sigma " << sigma;
      // More steps, closer to the Gaussian: the explicit kernel converges as 2 sigma^2 grows.
      if (sigma >= 4) {
        EXPECT_LE(worst, 0.1) << name;
      }
    }
  }
}

TEST(BlurImage, EveryChannelIsBlurredAndOutIsSized) {
  const BlurMethod& method = find_blur_method("iir-deriche");
  const Image in =
      make_image(20, 10, 3, [](auto x, auto, int c) { return c == 1 ? x / 20.f : 0.f; });
  Image out;
  blur(out, in, method, {2.0});
  ASSERT_EQ(out.width(), 20);
  ASSERT_EQ(out.channels(), 3);
  EXPECT_NEAR(out(10, 5, 1), 0.5f, 0.03);  // a ramp stays a ramp away from the edges
  EXPECT_NEAR(out(10, 5, 0), 0.f, 1e-6);
  EXPECT_EQ(invalid_argument_of([&] { blur(const_cast<Image&>(in), in, method, {2.0}); }).argument,
            "out");
}

}  // namespace
}  // namespace tridiff
