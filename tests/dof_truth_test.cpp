// The thin-lens truth (tridiff/dof/truth.hpp), its aperture shapes (aperture.hpp) and the score
// against it (quality.hpp): the rendered blur of a small light against coc_thin_lens's diameter
// on both sides of the focus, a vanishing aperture against the pinhole render, energy on a plane,
// the aperture sampler against a grid count of inside(), and the sRGB score's hand values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "test_util.hpp"
#include "tridiff/dof/aperture.hpp"
#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/quality.hpp"
#include "tridiff/dof/scene.hpp"
#include "tridiff/dof/truth.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

// A lens with a large blur at small sizes: CoC scale 18.7 px at 128 wide, focus 1 m.
ThinLens wide_open_lens() {
  ThinLens lens;
  lens.f_number = 0.5f;
  lens.focus_distance_m = 1.f;
  lens.max_coc_px = 1000.f;
  return lens;
}

// A black wall far away and, on the axis at `depth`, a disc of light facing the camera whose
// image has a radius of `radius_px` in a frame `width` wide.
RayTracedScene light_on_the_axis(const ThinLens& lens, float depth, float radius_px,
                                 std::ptrdiff_t width) {
  const float pixel = lens.sensor_width_mm / (lens.focal_length_mm * float(width));
  const float radius = radius_px * pixel * depth;
  return {"light", lens, [=](Vec3 origin, Vec3 dir) {
            const float t = (depth - origin.z) / dir.z;
            const float x = origin.x + t * dir.x, y = origin.y + t * dir.y;
            if (x * x + y * y <= radius * radius) return RayHit{t, {100.f, 100.f, 100.f}};
            return RayHit{(1000.f - origin.z) / dir.z, {0.f, 0.f, 0.f}};
          }};
}

// The per-axis variance of the image's intensity around its centroid (the mean of the two
// axes'), pixel centres at x + 0.5.
double intensity_variance(const Image& image) {
  double sum = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
  for (std::ptrdiff_t y = 0; y < image.height(); ++y)
    for (std::ptrdiff_t x = 0; x < image.width(); ++x) {
      const double v = image(x, y, 0), px = double(x) + 0.5, py = double(y) + 0.5;
      sum += v;
      sx += v * px;
      sy += v * py;
      sxx += v * px * px;
      syy += v * py * py;
    }
  const double mx = sx / sum, my = sy / sum;
  return 0.5 * (sxx / sum - mx * mx + syy / sum - my * my);
}

// A uniform disc of diameter D has the per-axis variance D^2 / 16; the light's own disc (radius
// R) adds R^2 / 4 and averaging over the pixel 1 / 12. So D = 4 sqrt(var - R^2 / 4 - 1 / 12).
// The light is 3 px in radius, not a point: a point's few hits per pixel leave the variance
// 10% noisy at 256 rays per pixel; at 3 px and 1024 it is within 0.3% (measured).
TEST(LensTruth, BlurDiameterIsCocThinLensBehindAndInFrontOfTheFocus) {
  const ThinLens lens = wide_open_lens();
  constexpr std::ptrdiff_t kSize = 96;
  constexpr float kLightRadiusPx = 3.f;
  for (const float depth : {4.f, 0.6f}) {
    const float coc = coc_thin_lens(depth, lens, kSize);  // +10.5 px and -9.4 px
    const Image image = render_thin_lens(light_on_the_axis(lens, depth, kLightRadiusPx, kSize),
                                         kSize, kSize, {1024, {}, 7, 2});
    const double diameter =
        4 * std::sqrt(intensity_variance(image) - kLightRadiusPx * kLightRadiusPx / 4 - 1.0 / 12);
    EXPECT_NEAR(diameter, std::fabs(coc), 0.01 * std::fabs(coc)) << "depth " << depth;
    // Nothing outside the disc (its radius, the light's, the pixel's half diagonal).
    const double reach = std::fabs(coc) / 2 + kLightRadiusPx + 0.71;
    for (std::ptrdiff_t y = 0; y < kSize; ++y)
      for (std::ptrdiff_t x = 0; x < kSize; ++x)
        if (std::hypot(double(x) + 0.5 - kSize / 2, double(y) + 0.5 - kSize / 2) > reach) {
          ASSERT_EQ(image(x, y, 0), 0.f) << x << ", " << y;
        }
  }
}

// Through a hexagon inscribed in the CoC disc the light spreads as the hexagon: the image of
// aperture point (u, v) lies (u, v) |c| / 2 pixels off (mirrored behind the focus, which the
// variance does not see), so the per-axis variance is (c / 2)^2 var_u + R^2 / 4 + 1 / 12, with
// var_u the shape's, counted on a fine grid with inside().
TEST(LensTruth, PolygonApertureSpreadsAsItsShape) {
  const ThinLens lens = wide_open_lens();
  constexpr std::ptrdiff_t kSize = 96;
  constexpr float kLightRadiusPx = 3.f;
  const ApertureShape hexagon{6, 10, 0};
  double area = 0, second_moment = 0;
  constexpr int kCount = 1000;
  for (int j = 0; j < kCount; ++j)
    for (int i = 0; i < kCount; ++i) {
      const float u = -1 + 2 * (i + 0.5f) / kCount, v = -1 + 2 * (j + 0.5f) / kCount;
      if (!inside(hexagon, u, v)) continue;
      ++area;
      second_moment += 0.5 * (double(u) * u + double(v) * v);
    }
  const float depth = 4.f, coc = coc_thin_lens(depth, lens, kSize);
  const Image image = render_thin_lens(light_on_the_axis(lens, depth, kLightRadiusPx, kSize), kSize,
                                       kSize, {1024, hexagon, 5, 2});
  const double expected =
      coc * coc / 4 * second_moment / area + kLightRadiusPx * kLightRadiusPx / 4 + 1.0 / 12;
  EXPECT_NEAR(intensity_variance(image), expected, 0.015 * expected);
}

TEST(LensTruth, VanishingApertureIsThePinholeRender) {
  RayTracedScene scene = find_ray_traced_scene("procedural");
  scene.lens.f_number = 1e5f;  // an aperture of 0.5 um
  const Scene pinhole = render_pinhole(scene, 128, 72, 16, 2);
  const Image lens = render_thin_lens(scene, 128, 72, {256, {}, 1, 2});
  Image coc(128, 72, 1);
  // Both are means of 256 points of each pixel (a regular grid, jittered strata): the same image
  // up to that sampling, which shows at edges and the 12-bright lights. Measured: 44.0 dB, as
  // far as the pinhole at 16 x 16 is from itself at 32 x 32 (44.0 dB); at 32 x 32 and 1024
  // rays 53 dB: the difference is sampling, nothing systematic.
  const TruthScore score = score_against_truth(lens, pinhole.color, coc.plane(0));
  EXPECT_GT(score.psnr, 41.0);
  EXPECT_GT(score.ssim, 0.995);
}

TEST(LensTruth, BlurKeepsTheMeanOfAPlane) {
  const ThinLens lens = wide_open_lens();
  const RayTracedScene plane{"plane", lens, [](Vec3 origin, Vec3 dir) {
                               const float t = (3.f - origin.z) / dir.z;
                               const float x = origin.x + t * dir.x, y = origin.y + t * dir.y;
                               const bool check =
                                   (int(std::floor(x * 40)) + int(std::floor(y * 40))) & 1;
                               return RayHit{t, {check ? 0.9f : 0.1f, 0.5f, 0.2f}};
                             }};
  const Scene pinhole = render_pinhole(plane, 96, 64, 4, 2);
  const Image lens_image = render_thin_lens(plane, 96, 64, {64, {}, 3, 2});
  double sharp = 0, blurred = 0, contrast_sharp = 0, contrast_blurred = 0;
  for (std::ptrdiff_t y = 0; y < 64; ++y)
    for (std::ptrdiff_t x = 0; x < 96; ++x) {
      sharp += pinhole.color(x, y, 0);
      blurred += lens_image(x, y, 0);
      if (x == 0) continue;
      contrast_sharp += std::fabs(pinhole.color(x, y, 0) - pinhole.color(x - 1, y, 0));
      contrast_blurred += std::fabs(lens_image(x, y, 0) - lens_image(x - 1, y, 0));
    }
  EXPECT_NEAR(blurred / sharp, 1.0, 0.005);
  // and the lens did blur the checks (1.1 px wide, CoC 9.4 px): what contrast is left is the
  // noise of 64 rays per pixel
  EXPECT_LT(contrast_blurred, 0.25 * contrast_sharp);
}

TEST(LensTruth, EffectiveApertureIsTheSeedsAperture) {
  // f = 50 mm, N = 2, focus 2.05 m: A = 25 mm, x 2.05 / 2 = 25.625 mm.
  ThinLens lens;
  lens.f_number = 2.f;
  lens.focus_distance_m = 2.05f;
  EXPECT_NEAR(effective_aperture_m(lens), 0.025625, 1e-8);
}

TEST(LensTruth, DeterministicWhateverTheThreadsAndRejectsBadSamples) {
  const Image one = lens_truth("lamps", 40, 24, 8, {}, 1),
              two = lens_truth("lamps", 40, 24, 8, {}, 2);
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < 24; ++y)
      for (std::ptrdiff_t x = 0; x < 40; ++x) ASSERT_EQ(one(x, y, c), two(x, y, c));
  EXPECT_EQ(invalid_argument_of([] { lens_truth("lamps", 8, 8, 12); }).argument, "samples");
  EXPECT_EQ(invalid_argument_of([] { lens_truth("nope", 8, 8, 8); }).argument, "scene");
  const RayTracedScene scene = find_ray_traced_scene("lamps");
  EXPECT_EQ(invalid_argument_of([&] {
              render_thin_lens(scene, 8, 8, {10, {}, 1, 0});
            }).argument,
            "samples");
}

// What the lamps scene is for, at 1920 wide (the depth map does not depend on the size): a
// subject at the focus, a second slightly in front (CoC -2 to -6 px), a near post far more blurred
// (CoC < -40 px) beside it in the image, many lamps far above 1 behind the focus, every |CoC| <=
// 60 px (within the methods' clamp at 64).
TEST(LampsScene, HasTheLayersItClaims) {
  const std::ptrdiff_t width = 384, height = 216;
  const Scene scene = lamps_scene(width, height, 2);
  ThinLens lens = scene.lens;
  lens.max_coc_px = 1e6f;
  auto coc_1920 = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
    return coc_thin_lens(scene.depth(x, y, 0), lens, 1920);
  };
  std::ptrdiff_t in_focus = 0, slightly_near = 0, lamps = 0, post_next_to_subject = 0;
  float largest = 0;
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const float c = coc_1920(x, y);
      largest = std::max(largest, std::fabs(c));
      in_focus += std::fabs(c) < 0.5f;
      slightly_near += c <= -2 && c >= -6;
      lamps += scene.color(x, y, 0) > 5 && c > 10;
      if (x > 0 && c <= -2 && c >= -6 && coc_1920(x - 1, y) < -40) ++post_next_to_subject;
    }
  EXPECT_GT(in_focus, width * height / 20);
  EXPECT_GT(slightly_near, width * height / 100);
  EXPECT_GT(lamps, 100);
  EXPECT_GT(post_next_to_subject, 10);
  EXPECT_LE(largest, 60.f);
}

TEST(ApertureShape, ValidateNamesTheBadParameter) {
  for (const int blades : {-1, 1, 2})
    EXPECT_EQ(invalid_argument_of([&] { validate(ApertureShape{blades}); }).argument,
              "aperture_blades");
  EXPECT_EQ(invalid_argument_of([] {
              validate(ApertureShape{6, 0, 1.5f});
            }).argument,
            "aperture_roundness");
  EXPECT_EQ(invalid_argument_of([] {
              validate(ApertureShape{6, 0, std::numeric_limits<float>::quiet_NaN()});
            }).argument,
            "aperture_roundness");
  EXPECT_EQ(invalid_argument_of([] {
              validate(ApertureShape{6, std::numeric_limits<float>::infinity(), 0});
            }).argument,
            "aperture_rotation");
  validate(ApertureShape{});
  validate(ApertureShape{3, 10, 1});
}

TEST(ApertureShape, InsideAtCornersAndEdges) {
  const auto at = [](double radius, double degrees) {
    const double a = degrees * 3.14159265358979 / 180;
    return std::pair{float(radius * std::cos(a)), float(radius * std::sin(a))};
  };
  const ApertureShape circle{}, hexagon{6}, turned{6, 30}, round{6, 0, 1}, half{6, 0, 0.5f};
  auto in = [&](const ApertureShape& s, std::pair<float, float> p) {
    return inside(s, p.first, p.second);
  };
  EXPECT_TRUE(in(circle, at(0.999, 17)));
  EXPECT_FALSE(in(circle, at(1.001, 17)));
  // A hexagon's corner straight up, its edges' middles at cos(30 deg) = 0.866 (at 120 deg).
  EXPECT_TRUE(in(hexagon, at(0.999, 90)));
  EXPECT_TRUE(in(hexagon, at(0.86, 120)));
  EXPECT_FALSE(in(hexagon, at(0.87, 120)));
  EXPECT_FALSE(in(turned, at(0.87, 90)));  // turned by 30: an edge's middle up
  EXPECT_TRUE(in(round, at(0.99, 120)));
  EXPECT_TRUE(in(half, at(0.93, 120)));  // half way: 0.933
  EXPECT_FALSE(in(half, at(0.94, 120)));
}

// The sampler's points lie in the shape, and any part of the shape gets its share of them: the
// share of a half-plane against the area fraction counted on a fine grid with inside().
TEST(ApertureShape, SamplerIsUniformOverTheShape) {
  for (const ApertureShape shape :
       {ApertureShape{}, ApertureShape{5, 12, 0}, ApertureShape{7, 0, 0.4f}}) {
    const ApertureSampler sampler(shape);
    constexpr int kGrid = 200;
    double in_part = 0;
    for (int j = 0; j < kGrid; ++j)
      for (int i = 0; i < kGrid; ++i) {
        const auto [u, v] = sampler((i + 0.5f) / kGrid, (j + 0.5f) / kGrid);
        ASSERT_TRUE(inside(shape, 0.999f * u, 0.999f * v))
            << shape.blades << ": " << u << ", " << v;
        in_part += u + 0.5f * v > 0.3f;
      }
    double area = 0, area_part = 0;
    constexpr int kCount = 1000;
    for (int j = 0; j < kCount; ++j)
      for (int i = 0; i < kCount; ++i) {
        const float u = -1 + 2 * (i + 0.5f) / kCount, v = -1 + 2 * (j + 0.5f) / kCount;
        if (!inside(shape, u, v)) continue;
        ++area;
        area_part += u + 0.5f * v > 0.3f;
      }
    EXPECT_NEAR(in_part / (kGrid * kGrid), area_part / area, 0.003) << shape.blades;
  }
}

TEST(TruthScore, AnImageAgainstItselfIsPerfect) {
  const Scene scene = procedural_scene(64, 36, 2);
  Image coc(64, 36, 1);
  coc_thin_lens(coc.plane(0), scene.depth.plane(0), scene.lens);
  const TruthScore score = score_against_truth(scene.color, scene.color, coc.plane(0));
  EXPECT_EQ(score.psnr, std::numeric_limits<double>::infinity());
  EXPECT_EQ(score.ssim, 1.0);
  EXPECT_EQ(score.psnr_edges, std::numeric_limits<double>::infinity());
  EXPECT_EQ(score.ssim_edges, 1.0);
  EXPECT_EQ(score.ssim_in_focus, 1.0);
}

TEST(TruthScore, RegionsPartitionTheFrame) {
  const Scene scene = lamps_scene(160, 90, 2);
  Image coc(160, 90, 1);
  coc_thin_lens(coc.plane(0), scene.depth.plane(0), scene.lens);
  const TruthRegions regions = truth_regions(coc.plane(0));
  std::ptrdiff_t counts[3] = {0, 0, 0};
  for (std::size_t i = 0; i < regions.edges.size(); ++i) {
    ASSERT_EQ(regions.edges[i] + regions.in_focus[i] + regions.defocused[i], 1) << i;
    counts[0] += regions.in_focus[i];
    counts[1] += regions.defocused[i];
    counts[2] += regions.edges[i];
  }
  for (const std::ptrdiff_t count : counts) EXPECT_GT(count, 100);
  const TruthScore score = score_against_truth(scene.color, scene.color, coc.plane(0));
  EXPECT_EQ(score.in_focus_pixels, counts[0]);
  EXPECT_EQ(score.defocused_pixels, counts[1]);
  EXPECT_EQ(score.edge_pixels, counts[2]);
}

// A CoC step from 0 to 10 px between columns 31 and 32: both sides are edge pixels with the
// larger radius 5 + the margin 3, so columns 23-40 are the edge region; the rest is in focus on
// the left, defocused on the right.
TEST(TruthScore, EdgeRegionOfAStep) {
  Image coc(64, 16, 1);
  for (std::ptrdiff_t y = 0; y < 16; ++y)
    for (std::ptrdiff_t x = 32; x < 64; ++x) coc(x, y, 0) = 10.f;
  const TruthRegions regions = truth_regions(coc.plane(0));
  for (std::ptrdiff_t y = 0; y < 16; ++y)
    for (std::ptrdiff_t x = 0; x < 64; ++x) {
      const std::size_t i = std::size_t(y * 64 + x);
      EXPECT_EQ(regions.edges[i], x >= 23 && x <= 40) << x;
      EXPECT_EQ(regions.in_focus[i], x < 23) << x;
    }
}

// Linear 0.5 against 0.51 in red only: sRGB 1.055 x^(1/2.4) - 0.055 of each, the difference d
// in one channel of three, PSNR -10 log10(d^2 / 3); values above 1 clip to 1 (no error).
TEST(TruthScore, SrgbPsnrOfAKnownOffset) {
  Image truth(32, 16, 3), out(32, 16, 3), coc(32, 16, 1);
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < 16; ++y)
      for (std::ptrdiff_t x = 0; x < 32; ++x) {
        const bool bright = x < 4;
        truth(x, y, c) = bright ? 1.f : 0.5f;
        out(x, y, c) = bright ? 3.f : (c == 0 ? 0.51f : 0.5f);
      }
  auto srgb = [](double v) { return 1.055 * std::pow(v, 1 / 2.4) - 0.055; };
  const double d = srgb(0.51f) - srgb(0.5);  // 0.006559
  const double expected = -10 * std::log10(d * d / 3 * 28.0 / 32.0);
  const TruthScore score = score_against_truth(out, truth, coc.plane(0));
  EXPECT_NEAR(score.psnr, expected, 0.005);
  EXPECT_NEAR(score.psnr_in_focus, expected, 0.005);
  EXPECT_EQ(score.edge_pixels, 0);
  EXPECT_TRUE(std::isnan(score.psnr_edges));
}

}  // namespace
}  // namespace tridiff::test
