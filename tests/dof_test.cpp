// Depth of field: the CoC models against the formulas of the seeds evaluated independently
// (thin lens, seed 000 eq. 3.2; artist curve, seed 002 §28.5.3), the method registry, the
// properties every diffusion DOF method must keep (sharp pixels untouched, skipping changes
// nothing, mass conserved, no new extrema, a uniform CoC blurs like its disc), the layered
// near field that removes the blocking artifact of seed 000 §6.5, input checking, and the
// procedural scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/near_layer.hpp"
#include "tridiff/dof/scene.hpp"
#include "test_util.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Result {
  Image out;
  DofReport report;
};

Result run(const DofMethod& method, const Image& color, const Image& coc,
           const DofOptions& settings = {}) {
  Result r;
  r.report = depth_of_field(r.out, color, coc.plane(0), method, settings);
  return r;
}

double channel_sum(const Image& image, int c) {
  double sum = 0;
  for (std::ptrdiff_t y = 0; y < image.height(); ++y)
    for (std::ptrdiff_t x = 0; x < image.width(); ++x) sum += image(x, y, c);
  return sum;
}

// ---------------------------------------------------------------------------------------------
// Thin lens (seed 000 eq. 3.2)

// Seed 000 eq. 3.2 taken literally, in long double: coc = |f d/(d - f) - f d_f/(d_f - f)|
// (d - f)/(a d), metres on the sensor (a the f-number), then pixels: the sensor width spans the
// image width. Unsigned and unclamped.
long double eq_3_2_px(long double d, const ThinLens& lens, std::ptrdiff_t width) {
  const long double f = static_cast<long double>(lens.focal_length_mm) / 1000.0L;
  const long double df = lens.focus_distance_m;
  const long double a = lens.f_number;
  const long double coc_m = std::fabs(f * d / (d - f) - f * df / (df - f)) * ((d - f) / (a * d));
  return coc_m * 1000.0L / static_cast<long double>(lens.sensor_width_mm) *
         static_cast<long double>(width);
}

TEST(ThinLens, MatchesSeedEquation32OverSweep) {
  int checked = 0;
  double worst = 0;
  for (float focal : {18.f, 35.f, 50.f, 85.f, 200.f})
    for (float n : {1.4f, 2.8f, 8.f, 22.f})
      for (float focus : {0.5f, 1.7f, 3.2f, 10.f, 100.f})
        for (std::ptrdiff_t width : {640, 1920}) {
          ThinLens lens{focal, n, focus, 36.f, 1e30f};
          ASSERT_NO_THROW(validate(lens));
          for (float k : {0.05f, 0.2f, 0.5f, 0.9f, 0.99f, 1.001f, 1.1f, 2.f, 5.f, 30.f, 1e4f}) {
            const float d = focus * k;
            if (d <= 1.01f * focal / 1000.f) continue;  // a point inside the focal length
            const long double expected = eq_3_2_px(d, lens, width);
            const float got = coc_thin_lens(d, lens, width);
            const double err = std::fabs(double(std::fabs(got)) - double(expected));
            // Float: relative 1e-5, but near the focus the CoC is a small difference of
            // large terms, so the error is bounded by the far-field CoC's scale instead.
            const double far = double(eq_3_2_px(1e12L, lens, width));
            const double tol = 1e-5 * std::max(double(expected), far) + 1e-9;
            EXPECT_LE(err, tol) << "focal " << focal << " mm, f/" << n << ", focus " << focus
                                << " m, d " << d << " m, width " << width << ": got " << got
                                << ", eq. 3.2 gives " << double(expected);
            worst = std::max(worst, err / std::max(double(expected), 1e-30));
            ++checked;
          }
        }
  EXPECT_GT(checked, 1000);
  std::printf("[ measured ] %d points, worst relative error %.3g\n", checked, worst);
}

TEST(ThinLens, ZeroAtFocusDistance) {
  for (float focus : {0.3f, 3.2f, 47.f}) {
    const ThinLens lens{50.f, 2.8f, focus, 36.f, 64.f};
    EXPECT_EQ(coc_thin_lens(focus, lens, 1920), 0.f) << "focus " << focus;
  }
}

TEST(ThinLens, SignedNegativeBeforeFocusPositiveBeyond) {
  const ThinLens lens{50.f, 2.8f, 3.2f, 36.f, 64.f};
  for (float d : {0.1f, 1.f, 2.f, 3.1f, 3.199f}) EXPECT_LT(coc_thin_lens(d, lens, 1920), 0.f) << d;
  for (float d : {3.201f, 3.3f, 5.f, 100.f, 1e6f})
    EXPECT_GT(coc_thin_lens(d, lens, 1920), 0.f) << d;
  // The sign is the side, the magnitude eq. 3.2.
  EXPECT_NEAR(coc_thin_lens(2.f, lens, 1920), -double(eq_3_2_px(2.0L, lens, 1920)), 1e-4);
}

TEST(ThinLens, MagnitudeClampedAtMaxCoc) {
  ThinLens lens{50.f, 1.4f, 3.2f, 36.f, 20.f};
  // Unclamped: 1e6 m gives ~ 1920/36 * 1000 * A f/(d_f - f) = 30 px; 0.3 m far more.
  ASSERT_GT(eq_3_2_px(1e6L, lens, 1920), 25.0L);
  ASSERT_GT(eq_3_2_px(0.3L, lens, 1920), 25.0L);
  EXPECT_EQ(coc_thin_lens(1e6f, lens, 1920), 20.f);
  EXPECT_EQ(coc_thin_lens(0.3f, lens, 1920), -20.f);
  for (float d = 0.06f; d < 1e4f; d *= 1.07f)
    EXPECT_LE(std::fabs(coc_thin_lens(d, lens, 1920)), 20.f) << d;
  // Below the clamp the value is eq. 3.2 itself.
  const long double below = eq_3_2_px(4.f, lens, 1920);
  ASSERT_LT(below, 20.0L);
  EXPECT_NEAR(coc_thin_lens(4.f, lens, 1920), double(below), 1e-5 * double(below));
  // A zero budget: every pixel sharp.
  lens.max_coc_px = 0.f;
  EXPECT_EQ(std::fabs(coc_thin_lens(0.3f, lens, 1920)), 0.f);
}

TEST(ThinLens, FarFieldLimitIsApertureTimesFocalOverFocusMinusFocal) {
  for (float focal : {24.f, 50.f, 135.f})
    for (float focus : {1.f, 3.2f, 20.f}) {
      const ThinLens lens{focal, 2.f, focus, 36.f, 1e30f};
      const long double f = focal / 1000.0L, a = f / 2.0L;
      const long double limit = a * f / (focus - f) * 1000.0L / 36.0L * 1920.0L;
      EXPECT_NEAR(coc_thin_lens(1e12f, lens, 1920), double(limit), 1e-5 * double(limit))
          << focal << " mm, focus " << focus;
      // Monotone approach from below.
      EXPECT_LT(coc_thin_lens(100.f * focus, lens, 1920), coc_thin_lens(1e12f, lens, 1920));
    }
}

// The map (computed in float for speed) against eq. 3.2 in long double, with the image width
// the map's own. Its error is a few float roundings of the CoC scale A f/(d_f - f) (the far-field
// CoC): near the focus |1 - d_f/d| cancels, so the bound is relative to that scale.
TEST(ThinLens, MapMatchesSeedEquation32) {
  const std::ptrdiff_t width = 1920, height = 3;
  Image depth = make_image(width, height, 1, [](auto x, auto y, int) {
    return 0.06f * std::pow(1.01f, float(x)) * (1.f + 0.3f * float(y));  // 0.06 m ... 11 km
  });
  int checked = 0;
  double worst = 0;
  for (const ThinLens lens :
       {ThinLens{35.f, 2.f, 2.5f, 36.f, 1e30f}, ThinLens{85.f, 1.4f, 3.2f, 24.f, 1e30f},
        ThinLens{50.f, 8.f, 10.f, 36.f, 40.f}}) {
    Image coc(width, height, 1);
    coc_thin_lens(coc.plane(0), depth.plane(0), lens, 2);
    const long double f = lens.focal_length_mm / 1000.0L;
    const long double scale = (f / lens.f_number) * f / (lens.focus_distance_m - f) * 1000.0L /
                              lens.sensor_width_mm * width;
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        const float d = depth(x, y, 0);
        if (d <= 1.01f * lens.focal_length_mm / 1000.f) continue;
        const long double unclamped = eq_3_2_px(d, lens, width);
        const double expected = double(std::min<long double>(unclamped, lens.max_coc_px)) *
                                (d < lens.focus_distance_m ? -1 : 1);
        const double err = std::fabs(double(coc(x, y, 0)) - expected);
        EXPECT_LE(err, 1e-5 * std::max(std::fabs(expected), double(scale)))
            << "d " << d << " m: map " << coc(x, y, 0) << ", eq. 3.2 " << expected;
        worst = std::max(worst, err / std::max(std::fabs(expected), double(scale)));
        ++checked;
      }
    // Exactly zero at the focus distance.
    Image at_focus = make_image(16, 1, 1, [&](auto, auto, int) { return lens.focus_distance_m; });
    Image zero(16, 1, 1);
    coc_thin_lens(zero.plane(0), at_focus.plane(0), lens);
    EXPECT_EQ(zero(3, 0, 0), 0.f);
  }
  std::printf("[ measured ] map: %d points, worst error %.3g of max(|CoC|, far-field CoC)\n",
              checked, worst);
  ThinLens lens;
  Image wrong(width - 1, height, 1);
  EXPECT_EQ(
      invalid_argument_of([&] { coc_thin_lens(wrong.plane(0), depth.plane(0), lens); }).argument,
      "coc");
}

TEST(ThinLens, ValidateNamesTheBadParameter) {
  auto bad = [](auto edit) {
    ThinLens lens;
    edit(lens);
    return invalid_argument_of([&] { validate(lens); });
  };
  EXPECT_NO_THROW(validate(ThinLens{}));
  EXPECT_EQ(bad([](ThinLens& l) { l.focal_length_mm = 0.f; }).argument, "focal_length");
  EXPECT_EQ(bad([](ThinLens& l) { l.focal_length_mm = -50.f; }).argument, "focal_length");
  EXPECT_EQ(bad([](ThinLens& l) { l.f_number = 0.f; }).argument, "f_number");
  EXPECT_EQ(bad([](ThinLens& l) { l.focus_distance_m = kNaN; }).argument, "focus");
  EXPECT_EQ(bad([](ThinLens& l) { l.sensor_width_mm = -1.f; }).argument, "sensor_width");
  EXPECT_EQ(bad([](ThinLens& l) { l.max_coc_px = kNaN; }).argument, "max_coc");
  // Focus at or inside the focal length: no real image.
  const Thrown inside = bad([](ThinLens& l) { l.focus_distance_m = 0.04f; });
  EXPECT_EQ(inside.argument, "focus");
  EXPECT_TRUE(contains(inside.message, "focal length"));
  EXPECT_EQ(bad([](ThinLens& l) { l.focus_distance_m = 0.05f; }).argument, "focus");
  // The map validates too.
  Image depth(4, 4, 1), coc(4, 4, 1);
  ThinLens lens;
  lens.f_number = 0.f;
  EXPECT_EQ(
      invalid_argument_of([&] { coc_thin_lens(coc.plane(0), depth.plane(0), lens); }).argument,
      "f_number");
}

// ---------------------------------------------------------------------------------------------
// Artist curve (seed 002 §28.5.3)

ArtistCurve example_curve() {
  ArtistCurve c;
  c.near_start_m = 1.f;
  c.near_end_m = 3.f;
  c.far_start_m = 10.f;
  c.far_end_m = 20.f;
  c.near_radius_px = 8.f;
  c.far_radius_px = 5.f;
  return c;
}

TEST(ArtistCurve, PiecewiseLinearThroughBreakpoints) {
  const ArtistCurve c = example_curve();
  ASSERT_NO_THROW(validate(c));
  struct Point {
    float d, coc;
  };
  // Diameter = 2 x radius, negative in the near field.
  for (const Point p : {Point{0.01f, -16.f},
                        {0.5f, -16.f},
                        {1.f, -16.f},
                        {1.5f, -12.f},
                        {2.f, -8.f},
                        {2.5f, -4.f},
                        {3.f, 0.f},
                        {5.f, 0.f},
                        {10.f, 0.f},
                        {12.5f, 2.5f},
                        {15.f, 5.f},
                        {17.5f, 7.5f},
                        {20.f, 10.f},
                        {50.f, 10.f},
                        {1e6f, 10.f}})
    EXPECT_NEAR(coc_artist_curve(p.d, c), p.coc, 1e-5) << "d = " << p.d;
  // Continuous and monotone (non-decreasing in d) across the whole range.
  float previous = coc_artist_curve(0.f, c);
  for (float d = 0.f; d < 30.f; d += 0.01f) {
    const float v = coc_artist_curve(d, c);
    EXPECT_GE(v, previous) << d;
    // Steepest part: the near ramp, diameter 16 px over 2 m = 8 px per m, 0.08 px per step.
    EXPECT_LE(v - previous, 0.0801f) << d;
    previous = v;
  }
}

// A degenerate region gives no blur in coc_artist_curve(distance, curve), which does not
// validate; validate() accepts the one turned off by a zero radius and refuses an empty or
// reversed range that has a radius (it would silently blur nothing).
TEST(ArtistCurve, DegenerateNearRegionHasNoNearBlur) {
  for (auto edit : std::vector<std::function<void(ArtistCurve&)>>{
           [](ArtistCurve& c) { c.near_end_m = c.near_start_m; },
           [](ArtistCurve& c) { c.near_end_m = 0.5f; },  // end before start
           [](ArtistCurve& c) { c.near_radius_px = 0.f; }}) {
    ArtistCurve c = example_curve();
    edit(c);
    if (c.near_radius_px > 0)
      EXPECT_EQ(invalid_argument_of([&] { validate(c); }).argument, "near_end");
    else
      ASSERT_NO_THROW(validate(c));
    for (float d : {0.f, 0.01f, 0.5f, 1.f, 2.f, 3.f, 5.f, 10.f})
      EXPECT_EQ(coc_artist_curve(d, c), 0.f) << d;
    EXPECT_NEAR(coc_artist_curve(15.f, c), 5.f, 1e-5);  // the far field untouched
  }
}

TEST(ArtistCurve, DegenerateFarRegionHasNoFarBlur) {
  for (auto edit : std::vector<std::function<void(ArtistCurve&)>>{
           [](ArtistCurve& c) { c.far_end_m = c.far_start_m; },
           [](ArtistCurve& c) { c.far_end_m = 4.f; },
           [](ArtistCurve& c) { c.far_radius_px = 0.f; }}) {
    ArtistCurve c = example_curve();
    edit(c);
    if (c.far_radius_px > 0)
      EXPECT_EQ(invalid_argument_of([&] { validate(c); }).argument, "far_end");
    else
      ASSERT_NO_THROW(validate(c));
    for (float d : {3.f, 5.f, 10.f, 15.f, 20.f, 1e6f}) EXPECT_EQ(coc_artist_curve(d, c), 0.f) << d;
    EXPECT_NEAR(coc_artist_curve(2.f, c), -8.f, 1e-5);  // the near field untouched
  }
  // Both degenerate: nothing blurs (the default curve).
  for (float d : {0.1f, 1.f, 100.f}) EXPECT_EQ(coc_artist_curve(d, ArtistCurve{}), 0.f);
  EXPECT_NO_THROW(validate(ArtistCurve{}));
}

// A region with a radius but an empty or reversed range: refused by validate and by the map,
// naming the end and saying what it must exceed (a reversed range used to turn the blur off).
TEST(ArtistCurve, EmptyOrReversedRangeWithARadiusIsRefused) {
  Image depth = make_image(4, 4, 1, [](auto, auto, int) { return 2.f; }), coc(4, 4, 1);
  struct Case {
    void (*edit)(ArtistCurve&);
    const char* argument;
    const char* names;
  };
  for (const Case& k :
       {Case{[](ArtistCurve& c) { c.near_end_m = c.near_start_m; }, "near_end", "near_start"},
        Case{[](ArtistCurve& c) { std::swap(c.near_start_m, c.near_end_m); }, "near_end",
             "near_start"},
        Case{[](ArtistCurve& c) { c.near_start_m = c.near_end_m = 0.f; }, "near_end", "near_start"},
        Case{[](ArtistCurve& c) { c.far_end_m = c.far_start_m; }, "far_end", "far_start"},
        Case{[](ArtistCurve& c) { std::swap(c.far_start_m, c.far_end_m); }, "far_end",
             "far_start"}}) {
    ArtistCurve c = example_curve();
    k.edit(c);
    const Thrown thrown = invalid_argument_of([&] { validate(c); });
    EXPECT_EQ(thrown.argument, k.argument) << thrown.message;
    EXPECT_TRUE(contains(thrown.message, k.names)) << thrown.message;
    EXPECT_EQ(
        invalid_argument_of([&] { coc_artist_curve(coc.plane(0), depth.plane(0), c); }).argument,
        k.argument);
  }
}

TEST(ArtistCurve, ValidateNamesTheBadParameter) {
  auto bad = [](auto edit) {
    ArtistCurve c = example_curve();
    edit(c);
    return invalid_argument_of([&] { validate(c); }).argument;
  };
  EXPECT_EQ(bad([](ArtistCurve& c) { c.near_start_m = -1.f; }), "near_start");
  EXPECT_EQ(bad([](ArtistCurve& c) { c.near_end_m = kNaN; }), "near_end");
  EXPECT_EQ(bad([](ArtistCurve& c) { c.far_start_m = -0.5f; }), "far_start");
  EXPECT_EQ(bad([](ArtistCurve& c) { c.far_end_m = std::numeric_limits<float>::infinity(); }),
            "far_end");
  EXPECT_EQ(bad([](ArtistCurve& c) { c.near_radius_px = -2.f; }), "near_radius");
  EXPECT_EQ(bad([](ArtistCurve& c) { c.far_radius_px = kNaN; }), "far_radius");
  // Overlapping regions.
  EXPECT_EQ(bad([](ArtistCurve& c) { c.far_start_m = 2.f; }), "far_start");
  // ... are fine when one of them is disabled.
  ArtistCurve only_far = example_curve();
  only_far.far_start_m = 2.f;
  only_far.near_radius_px = 0.f;
  EXPECT_NO_THROW(validate(only_far));
  // The map validates too.
  Image depth(4, 4, 1), coc(4, 4, 1);
  ArtistCurve c = example_curve();
  c.far_radius_px = -1.f;
  EXPECT_EQ(
      invalid_argument_of([&] { coc_artist_curve(coc.plane(0), depth.plane(0), c); }).argument,
      "far_radius");
}

// ---------------------------------------------------------------------------------------------
// Registry

TEST(DofRegistry, ListsAdiAndMpadWithSummaries) {
  std::vector<std::string> names;
  for (const DofMethod& m : dof_methods()) {
    names.emplace_back(m.name);
    EXPECT_FALSE(m.summary.empty()) << m.name;
    EXPECT_FALSE(m.cost.empty()) << m.name;
    EXPECT_NE(m.run, nullptr) << m.name;
    EXPECT_EQ(&find_dof_method(m.name), &m);
  }
  EXPECT_NE(std::find(names.begin(), names.end(), "adi"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "mpad"), names.end());
  EXPECT_TRUE(find_dof_method("adi").unbounded_blur);
}

// A registry entry is a description and a kernel; `run` checks the frame and calls the kernel.
TEST(DofRegistry, EveryMethodHasAKernel) {
  for (const DofMethod& m : dof_methods()) EXPECT_NE(m.kernel, nullptr) << m.name;
}

TEST(DofRegistry, UnknownNameListsKnownMethods) {
  const Thrown t = invalid_argument_of([] { find_dof_method("nope"); });
  EXPECT_TRUE(contains(t.message, "nope"));
  EXPECT_TRUE(contains(t.message, "adi"));
  EXPECT_TRUE(contains(t.message, "mpad"));
}

// ---------------------------------------------------------------------------------------------
// Properties every diffusion method keeps

// The registered methods of the diffusion family (seed 000 §3.5, §5.3.4), which the property
// and layer tests below are about; methods of other families (ipf, a scatter: ipf_test.cpp)
// blur sharp pixels' neighbours and quantise, and are held to their own properties.
std::vector<std::reference_wrapper<const DofMethod>> diffusion_methods() {
  std::vector<std::reference_wrapper<const DofMethod>> methods;
  for (const DofMethod& m : dof_methods())
    if (m.name == "adi" || m.name == "mpad") methods.emplace_back(m);
  return methods;
}

// A colour image with HDR values and a CoC map that mixes sharp and blurred regions of
// irregular shapes, crossing tile (64 px) boundaries.
struct Case {
  Image color, coc;
};
Case mixed_case(std::ptrdiff_t width = 203, std::ptrdiff_t height = 157) {
  Case c;
  c.color = random_image(width, height, 3, 0.f, 1.f, 7);
  c.color(10, 10, 0) = 40.f;  // a highlight
  c.color(150, 100, 2) = 25.f;
  c.coc = make_coc(width, height, [](auto x, auto y) {
    const float v = 22.f * std::sin(float(x) / 17.f) * std::cos(float(y) / 13.f);
    return std::fabs(v) < 6.f ? 0.4f * v / 6.f : v;  // |v| < 6: sharp (|CoC| < 0.4 px)
  });
  return c;
}

TEST(DofMethods, DofInFocusPixelsUnchanged) {
  // The default threshold on the mixed case (sharp regions at |CoC| < 0.4), and a raised
  // threshold of 5 px on a CoC that varies continuously through it.
  struct Variant {
    Case c;
    float threshold;
  };
  Variant variants[] = {{mixed_case(), 1.f}, {mixed_case(), 5.f}};
  variants[1].c.coc = make_coc(203, 157, [](auto x, auto y) {
    return 22.f * std::sin(float(x) / 17.f) * std::cos(float(y) / 13.f);
  });
  for (const Variant& v : variants) {
    const Case& c = v.c;
    const ConstPlane coc = c.coc.plane(0);
    auto sharp = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
      return std::fabs(coc(x, y)) < v.threshold;
    };
    for (const DofMethod& method : diffusion_methods())
      for (bool skip : {true, false}) {
        DofOptions settings;
        settings.skip_in_focus = skip;
        settings.in_focus_coc_px = v.threshold;
        const Result r = run(method, c.color, c.coc, settings);
        std::ptrdiff_t interior = 0, all_sharp = 0, moved_interior = 0, moved_edge = 0,
                       blurred_moved = 0;
        for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
          for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
            bool unchanged = true;
            for (int ch = 0; ch < 3; ++ch)
              unchanged &= same_bits(r.out(x, y, ch), c.color(x, y, ch));
            if (!sharp(x, y)) {
              blurred_moved += !unchanged;
              continue;
            }
            ++all_sharp;
            const bool inner =
                (x == 0 || sharp(x - 1, y)) && (x + 1 == coc.width() || sharp(x + 1, y)) &&
                (y == 0 || sharp(x, y - 1)) && (y + 1 == coc.height() || sharp(x, y + 1));
            if (inner) {
              ++interior;
              moved_interior += !unchanged;
            } else {
              moved_edge += !unchanged;
            }
          }
        const std::string where = std::string(method.name) + (skip ? " skip" : " no skip") +
                                  ", threshold " + std::to_string(v.threshold);
        EXPECT_EQ(moved_interior, 0) << where;
        // Every sharp pixel insulates itself on its four links (coc_links takes the minimum),
        // so the sharp pixels at the edge of a blurred region keep their values too.
        EXPECT_EQ(moved_edge, 0) << where;
        EXPECT_GT(interior, 3000) << where;
        EXPECT_GT(blurred_moved, 5000) << where;  // and the rest really was blurred
        if (skip)
          std::printf(
              "[ measured ] %s: %td sharp pixels (%td interior) unchanged, %td blurred moved\n",
              where.c_str(), all_sharp, interior, blurred_moved);
      }
  }
}

TEST(DofMethods, DofSkipMatchesNoSkip) {
  // 256 x 192 (4 x 3 tiles); an out-of-focus block of 56 x 56 inside one tile: 93.6 % sharp.
  const std::ptrdiff_t width = 256, height = 192;
  const Image color = random_image(width, height, 3, 0.f, 2.f, 11);
  const Image coc = make_coc(width, height, [](auto x, auto y) {
    return (x >= 68 && x < 124 && y >= 70 && y < 126) ? 14.f : 0.f;
  });
  for (const DofMethod& method : dof_methods()) {
    DofOptions on, off;
    on.skip_in_focus = true;
    off.skip_in_focus = false;
    const Result a = run(method, color, coc, on), b = run(method, color, coc, off);
    std::ptrdiff_t differ = 0;
    float worst = 0;
    for (int ch = 0; ch < 3; ++ch)
      for (std::ptrdiff_t y = 0; y < height; ++y)
        for (std::ptrdiff_t x = 0; x < width; ++x) {
          differ += !same_bits(a.out(x, y, ch), b.out(x, y, ch));
          worst = std::max(worst, std::fabs(a.out(x, y, ch) - b.out(x, y, ch)));
        }
    EXPECT_EQ(differ, 0) << method.name << ": largest difference " << worst;
    EXPECT_GT(a.report.skipped_fraction, 0.5) << method.name;
    EXPECT_LE(a.report.skipped_fraction, 1.0);
    EXPECT_EQ(b.report.skipped_fraction, 0.0) << method.name;
    std::printf(
        "[ measured ] %s: skipped_fraction %.4f (skip) / %.4f (no skip), %td values differ\n",
        std::string(method.name).c_str(), a.report.skipped_fraction, b.report.skipped_fraction,
        differ);
  }
}

TEST(DofMethods, InPlaceGivesTheSeparateOutput) {
  // out == color: the in-place methods blur where the image lies, the others are given a copy
  // (without it they would reallocate out, the input, before reading it). A far block and a
  // near one (negative CoC), so that the layered path runs too.
  const std::ptrdiff_t width = 256, height = 192;
  const Image color = random_image(width, height, 3, 0.f, 2.f, 12);
  const Image coc = make_coc(width, height, [](auto x, auto y) {
    if (x >= 68 && x < 124 && y >= 70 && y < 126) return 9.f;
    return (x >= 150 && x < 190 && y >= 20 && y < 60) ? -6.f : 0.f;
  });
  for (const DofMethod& method : dof_methods())
    for (bool layers : {false, true}) {
      if (layers && !method.honours_layers) continue;  // refused: DofOptionsHonoured
      DofOptions settings;
      settings.layers = layers;
      const Result separate = run(method, color, coc, settings);
      Image image = color;
      DofReport report;
      report = depth_of_field(image, image, coc.plane(0), method, settings);
      const std::string where = std::string(method.name) + (layers ? " layered" : "");
      ASSERT_EQ(image.width(), width) << where;
      ASSERT_EQ(image.channels(), 3) << where;
      std::ptrdiff_t differ = 0;
      for (int ch = 0; ch < 3; ++ch)
        for (std::ptrdiff_t y = 0; y < height; ++y)
          for (std::ptrdiff_t x = 0; x < width; ++x)
            differ += !same_bits(image(x, y, ch), separate.out(x, y, ch));
      EXPECT_EQ(differ, 0) << where;
      EXPECT_EQ(report.skipped_fraction, separate.report.skipped_fraction) << where;
      EXPECT_EQ(report.layered, separate.report.layered) << where;
    }
}

TEST(DofMethods, DofConservesMass) {
  const Case c = mixed_case();
  for (const DofMethod& method : diffusion_methods()) {
    const Result r = run(method, c.color, c.coc);
    EXPECT_FALSE(r.report.layered);
    for (int ch = 0; ch < 3; ++ch) {
      const double before = channel_sum(c.color, ch), after = channel_sum(r.out, ch);
      EXPECT_NEAR(after, before, 1e-5 * before) << method.name << " channel " << ch;
      std::printf("[ measured ] %s channel %d: relative mass change %.3g\n",
                  std::string(method.name).c_str(), ch, (after - before) / before);
    }
  }
}

TEST(DofMethods, DofNoNewExtrema) {
  Case c = mixed_case();
  // Negative values too (colour spaces with negative primaries): the bound is two-sided.
  for (std::ptrdiff_t y = 0; y < 40; ++y)
    for (std::ptrdiff_t x = 60; x < 90; ++x) c.color(x, y, 1) = -0.5f - 0.01f * float(x);
  for (const DofMethod& method : diffusion_methods()) {
    const Result r = run(method, c.color, c.coc);
    for (int ch = 0; ch < 3; ++ch) {
      float lo = INFINITY, hi = -INFINITY, out_lo = INFINITY, out_hi = -INFINITY;
      for (std::ptrdiff_t y = 0; y < c.color.height(); ++y)
        for (std::ptrdiff_t x = 0; x < c.color.width(); ++x) {
          lo = std::min(lo, c.color(x, y, ch));
          hi = std::max(hi, c.color(x, y, ch));
          out_lo = std::min(out_lo, r.out(x, y, ch));
          out_hi = std::max(out_hi, r.out(x, y, ch));
        }
      EXPECT_GE(out_lo, lo) << method.name << " channel " << ch;
      EXPECT_LE(out_hi, hi) << method.name << " channel " << ch;
      EXPECT_TRUE(std::isfinite(out_lo) && std::isfinite(out_hi));
    }
  }
}

// The edge sizes (1 x 1, one row, one column, 2^k +- 1 across the 64-px tile) with and
// without layers: every output finite and within the input's range (maximum principle); without
// layers the mass of every channel kept (insulated borders).
TEST(DofMethods, EdgeSizesKeepRangeAndMass) {
  const std::pair<std::ptrdiff_t, std::ptrdiff_t> sizes[] = {
      {1, 1}, {2, 1}, {1, 2}, {2, 3}, {3, 3}, {1, 37}, {37, 1}, {63, 65}, {65, 63}, {129, 2}};
  for (const auto& [width, height] : sizes)
    for (const DofMethod& method : diffusion_methods())
      for (const bool layers : {false, true}) {
        if (layers && !method.honours_layers) continue;  // refused: DofOptionsHonoured
        SCOPED_TRACE(std::string(method.name) + " " + std::to_string(width) + " x " +
                     std::to_string(height) + (layers ? " layers" : ""));
        Case c;
        c.color = random_image(width, height, 3, 0.f, 1.f, 11);
        // Near, sharp and far stripes, and a CoC of 30 px on one-pixel-wide images.
        c.coc = make_coc(width, height, [](auto x, auto y) {
          const int band = int((x + 2 * y) % 3);
          return band == 0 ? -30.f : band == 1 ? 0.f : 12.f;
        });
        DofOptions settings;
        settings.layers = layers;
        const Result r = run(method, c.color, c.coc, settings);
        for (int ch = 0; ch < 3; ++ch) {
          float lo = INFINITY, hi = -INFINITY;
          for (std::ptrdiff_t y = 0; y < height; ++y)
            for (std::ptrdiff_t x = 0; x < width; ++x) {
              lo = std::min(lo, c.color(x, y, ch));
              hi = std::max(hi, c.color(x, y, ch));
            }
          const float slack = 1e-5f * std::max(std::fabs(lo), std::fabs(hi));
          for (std::ptrdiff_t y = 0; y < height; ++y)
            for (std::ptrdiff_t x = 0; x < width; ++x) {
              const float v = r.out(x, y, ch);
              ASSERT_TRUE(std::isfinite(v)) << "(" << x << ", " << y << ")";
              ASSERT_GE(v, lo - slack) << "(" << x << ", " << y << ")";
              ASSERT_LE(v, hi + slack) << "(" << x << ", " << y << ")";
            }
          if (!layers) {
            const double before = channel_sum(c.color, ch), after = channel_sum(r.out, ch);
            EXPECT_NEAR(after, before, 1e-5 * before) << "channel " << ch;
          }
        }
      }
}

// Per-axis variance (and covariance) of a one-channel response about its centroid.
struct Moments {
  double mass = 0, var_x = 0, var_y = 0, cov_xy = 0;
};
Moments moments(const Image& image) {
  Moments m;
  double sx = 0, sy = 0;
  for (std::ptrdiff_t y = 0; y < image.height(); ++y)
    for (std::ptrdiff_t x = 0; x < image.width(); ++x) {
      const double v = image(x, y, 0);
      m.mass += v;
      sx += v * double(x);
      sy += v * double(y);
    }
  const double cx = sx / m.mass, cy = sy / m.mass;
  for (std::ptrdiff_t y = 0; y < image.height(); ++y)
    for (std::ptrdiff_t x = 0; x < image.width(); ++x) {
      const double v = image(x, y, 0) / m.mass;
      m.var_x += v * (double(x) - cx) * (double(x) - cx);
      m.var_y += v * (double(y) - cy) * (double(y) - cy);
      m.cov_xy += v * (double(x) - cx) * (double(y) - cy);
    }
  return m;
}

TEST(DofMethods, UniformCocBlursLikeDisc) {
  // A disc of diameter D (uniform over it) has variance D^2/16 along each axis.
  const std::ptrdiff_t size = 257;
  Image impulse(size, size, 1);
  impulse(128, 128, 0) = 1.f;
  for (float diameter : {6.f, 12.f, 20.f}) {
    const Image coc = make_coc(size, size, [&](auto, auto) { return diameter; });
    const double target = double(diameter) * diameter / 16.0;
    for (const DofMethod& method : diffusion_methods()) {
      const Result r = run(method, impulse, coc);
      const Moments m = moments(r.out);
      const double tol = method.name == "adi" ? 0.02 : 0.05;
      EXPECT_NEAR(m.var_x, target, tol * target) << method.name << " D " << diameter;
      EXPECT_NEAR(m.var_y, target, tol * target) << method.name << " D " << diameter;
      EXPECT_NEAR(m.cov_xy, 0.0, 1e-3 * target) << method.name;
      EXPECT_NEAR(m.mass, 1.0, 1e-5) << method.name;
      std::printf("[ measured ] %s D=%g: var_x %.5f var_y %.5f (D^2/16 = %.5f), steps %d\n",
                  std::string(method.name).c_str(), double(diameter), m.var_x, m.var_y, target,
                  r.report.explicit_steps);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Layers: the blocking artifact of seed 000 §6.5 (fig. 6.4)

constexpr std::ptrdiff_t kLayerSize = 192, kSquare0 = 64, kSquare1 = 128;  // square [64, 128)^2
constexpr float kForegroundCoc = -16.f;

// In-focus vertical stripes (grey: R = G = B, 2 px dark 0.1 / 2 px bright 0.9) behind a pure red
// out-of-focus square. "Red excess" R - (G + B)/2 is 0 on the background, 1 on the square.
Case blocking_case() {
  Case c;
  c.color = make_image(kLayerSize, kLayerSize, 3, [](auto x, auto y, int ch) {
    const bool square = x >= kSquare0 && x < kSquare1 && y >= kSquare0 && y < kSquare1;
    if (square) return ch == 0 ? 1.f : 0.f;
    return (x / 2) % 2 ? 0.9f : 0.1f;
  });
  c.coc = make_coc(kLayerSize, kLayerSize, [](auto x, auto y) {
    const bool square = x >= kSquare0 && x < kSquare1 && y >= kSquare0 && y < kSquare1;
    return square ? kForegroundCoc : 0.f;
  });
  return c;
}

// Chebyshev distance from (x, y) to the square (0 inside).
std::ptrdiff_t distance_to_square(std::ptrdiff_t x, std::ptrdiff_t y) {
  const std::ptrdiff_t dx = std::max({kSquare0 - x, x - (kSquare1 - 1), std::ptrdiff_t(0)});
  const std::ptrdiff_t dy = std::max({kSquare0 - y, y - (kSquare1 - 1), std::ptrdiff_t(0)});
  return std::max(dx, dy);
}

float red_excess(const Image& image, std::ptrdiff_t x, std::ptrdiff_t y) {
  return image(x, y, 0) - 0.5f * (image(x, y, 1) + image(x, y, 2));
}

TEST(DofLayers, WithoutLayersSharpBackgroundInsulates) {
  const Case c = blocking_case();
  for (const DofMethod& method : diffusion_methods()) {
    const Result r = run(method, c.color, c.coc);
    EXPECT_FALSE(r.report.layered);
    std::ptrdiff_t band = 0, changed = 0;
    for (std::ptrdiff_t y = 0; y < kLayerSize; ++y)
      for (std::ptrdiff_t x = 0; x < kLayerSize; ++x) {
        if (distance_to_square(x, y) == 0) continue;
        bool same = true;
        for (int ch = 0; ch < 3; ++ch) same &= same_bits(r.out(x, y, ch), c.color(x, y, ch));
        changed += !same;
        band += distance_to_square(x, y) <= 4;
      }
    // The artifact: not one background pixel receives the foreground's blur.
    EXPECT_EQ(changed, 0) << method.name;
    EXPECT_GT(band, 4 * 4 * 64);
  }
}

TEST(DofLayers, LayersRemoveBlockingArtifact) {
  const Case c = blocking_case();
  const float d = std::fabs(kForegroundCoc);
  for (const DofMethod& method : diffusion_methods()) {
    DofOptions settings;
    settings.layers = true;
    const Result r = run(method, c.color, c.coc, settings);
    EXPECT_TRUE(r.report.layered) << method.name;

    // Mean red excess per ring at Chebyshev distance k outside the square.
    std::vector<double> ring(kLayerSize, 0.0);
    std::vector<std::ptrdiff_t> count(kLayerSize, 0);
    double far_change = 0;
    for (std::ptrdiff_t y = 0; y < kLayerSize; ++y)
      for (std::ptrdiff_t x = 0; x < kLayerSize; ++x) {
        const std::ptrdiff_t k = distance_to_square(x, y);
        if (k == 0) continue;
        ring[k] += red_excess(r.out, x, y);
        ++count[k];
        if (float(k) > 2.f * d)
          for (int ch = 0; ch < 3; ++ch)
            far_change =
                std::max(far_change, double(std::fabs(r.out(x, y, ch) - c.color(x, y, ch))));
      }
    double band = 0;
    std::ptrdiff_t band_count = 0;
    const std::ptrdiff_t quarter = std::ptrdiff_t(d / 4);
    for (std::ptrdiff_t k = 1; k <= quarter; ++k) {
      band += ring[k];
      band_count += count[k];
      ring[k] /= double(count[k]);
    }
    for (std::ptrdiff_t k = quarter + 1; k < 48; ++k) ring[k] /= double(count[k]);
    band /= double(band_count);
    // An implicit step of conductance beta = D^2/32 = 8 spreads a half-plane of foreground to
    // r^k / (1 + r) at k pixels out, r = 0.7035: a mean of 0.26 over k = 1..4. The sharp
    // background alone gives exactly 0.
    EXPECT_GT(band, 0.1) << method.name;
    // Decays with distance from the edge: strictly while the blend is well above float
    // resolution (mpad's explicit steps reach at most 32 px, and a coverage below ~1e-7 is lost
    // when added to a background value of 0.9), never rising beyond.
    for (std::ptrdiff_t k = 1; k < 2 * std::ptrdiff_t(d); ++k) {
      if (ring[k] > 1e-4) {
        EXPECT_GT(ring[k], ring[k + 1]) << method.name << " ring " << k;
      }
      EXPECT_LE(ring[k + 1], ring[k] + 1e-6) << method.name << " ring " << k;
    }
    EXPECT_LT(ring[2 * std::ptrdiff_t(d)], 0.01) << method.name;
    // Far from the square the background is (nearly) untouched.
    EXPECT_LT(far_change, 1e-3) << method.name;
    std::printf(
        "[ measured ] %s layered: band mean red excess %.4f; rings 1,2,4,8,16,32: %.4f "
        "%.4f %.4f %.4f %.5f %.2e; far max change %.2e\n",
        std::string(method.name).c_str(), band, ring[1], ring[2], ring[4], ring[8], ring[16],
        ring[32], far_change);
  }
}

TEST(DofLayers, LayeredOutputFiniteAndWithinInputRange) {
  Case cases[] = {blocking_case(), mixed_case()};
  for (Case& c : cases)
    for (const DofMethod& method : diffusion_methods()) {
      DofOptions settings;
      settings.layers = true;
      const Result r = run(method, c.color, c.coc, settings);
      EXPECT_TRUE(r.report.layered) << method.name;
      for (int ch = 0; ch < 3; ++ch) {
        float lo = INFINITY, hi = -INFINITY;
        for (std::ptrdiff_t y = 0; y < c.color.height(); ++y)
          for (std::ptrdiff_t x = 0; x < c.color.width(); ++x) {
            lo = std::min(lo, c.color(x, y, ch));
            hi = std::max(hi, c.color(x, y, ch));
          }
        const float slack = 1e-5f * std::max(std::fabs(lo), std::fabs(hi));
        std::ptrdiff_t outside = 0;
        float worst = 0;
        for (std::ptrdiff_t y = 0; y < c.color.height(); ++y)
          for (std::ptrdiff_t x = 0; x < c.color.width(); ++x) {
            const float v = r.out(x, y, ch);
            ASSERT_TRUE(std::isfinite(v)) << method.name << " (" << x << ", " << y << ")";
            const float excess = std::max(lo - v, v - hi);
            outside += excess > slack;
            worst = std::max(worst, excess);
          }
        EXPECT_EQ(outside, 0) << method.name << " channel " << ch << " range [" << lo << ", " << hi
                              << "], worst excess " << worst;
      }
    }
}

TEST(DofLayers, NoNearFieldMeansNoLayering) {
  // Layers requested but nothing in front of the focus: the plain path, identical output.
  const Case c = blocking_case();
  const Image far_coc =
      make_coc(kLayerSize, kLayerSize, [&](auto x, auto y) { return std::fabs(c.coc(x, y, 0)); });
  for (const DofMethod& method : dof_methods()) {
    // Refused (DofOptionsHonoured); `auto` asked for layers chooses among the methods that have
    // them, which may differ from its choice without.
    if (!method.honours_layers || method.name == "auto") continue;
    DofOptions layered;
    layered.layers = true;
    const Result a = run(method, c.color, far_coc, layered), b = run(method, c.color, far_coc);
    EXPECT_FALSE(a.report.layered);
    std::ptrdiff_t differ = 0;
    for (int ch = 0; ch < 3; ++ch)
      for (std::ptrdiff_t y = 0; y < kLayerSize; ++y)
        for (std::ptrdiff_t x = 0; x < kLayerSize; ++x)
          differ += !same_bits(a.out(x, y, ch), b.out(x, y, ch));
    EXPECT_EQ(differ, 0) << method.name;
  }
}

// ---------------------------------------------------------------------------------------------
// Input checking

TEST(DofInput, NanColourNamesThePixel) {
  Image color = random_image(40, 30, 3, 0.f, 1.f, 3);
  const Image coc = make_coc(40, 30, [](auto x, auto) { return float(x % 7); });
  color(17, 23, 1) = kNaN;
  const Thrown v = invalid_argument_of([&] { validate_dof_input(color, coc.plane(0)); });
  EXPECT_TRUE(contains(v.message, "pixel (17, 23)"));
  EXPECT_TRUE(contains(v.message, "channel 1"));
  for (const DofMethod& method : dof_methods())
    for (bool layers : {false, true}) {
      if (layers && !method.honours_layers) continue;  // refused: DofOptionsHonoured
      DofOptions settings;
      settings.layers = layers;
      const Thrown t = invalid_argument_of([&] { run(method, color, coc, settings); });
      EXPECT_TRUE(contains(t.message, "pixel (17, 23)")) << method.name;
    }
}

// The frame is checked before any method runs, so every method names a bad colour value as
// the colour's (the diffusion methods once named it as their operator's "src").
TEST(DofInput, EveryMethodNamesANonFiniteColourAsTheColour) {
  Image color = random_image(40, 30, 3, 0.f, 1.f, 3);
  const Image coc = make_coc(40, 30, [](auto x, auto) { return float(x % 7) - 3.f; });
  color(17, 23, 1) = kNaN;
  for (const DofMethod& method : dof_methods())
    for (bool layers : {false, true}) {
      if (layers && !method.honours_layers) continue;  // refused: DofOptionsHonoured
      DofOptions settings;
      settings.layers = layers;
      const Thrown t = invalid_argument_of([&] { run(method, color, coc, settings); });
      EXPECT_EQ(t.argument, "color") << method.name;
      EXPECT_TRUE(contains(t.message, "pixel (17, 23), channel 1")) << method.name << t.message;
    }
}

// A finite CoC whose conductance is not (|CoC| ~ 1e20 px) is named at its own pixel, with and
// without layers (the layered fill once blamed the first pixel of the frame), by every method
// that diffuses. (`auto` is left out: which method it runs depends on the measured table.)
TEST(DofInput, DiffusionNamesTheCocWhoseConductanceOverflows) {
  const Image color = random_image(70, 40, 3, 0.f, 1.f, 4);
  Image coc = make_coc(70, 40, [](auto x, auto) { return x < 35 ? -3.f : 3.f; });
  coc(66, 38, 0) = -1e20f;
  for (const char* name : {"adi", "mpad", "bokeh"})
    for (bool layers : {false, true}) {
      DofOptions settings;
      settings.layers = layers;
      const Thrown t =
          invalid_argument_of([&] { run(find_dof_method(name), color, coc, settings); });
      EXPECT_EQ(t.argument, "coc") << name;
      EXPECT_TRUE(contains(t.message, "pixel (66, 38)")) << name << " " << t.message;
    }
}

// The same refusal leaves the output as it was, also where bokeh has highlights to clamp (it
// clamps them into the output buffer, once did so before the check, and lost the caller's
// values).
TEST(DofInput, OverflowingConductanceLeavesTheOutputUntouched) {
  Image color = random_image(37, 21, 3, 0.f, 1.f, 5);
  color(10, 10, 1) = 50.f;  // a highlight for bokeh
  Image coc = make_coc(37, 21, [](auto, auto) { return 8.f; });
  coc(30, 5, 0) = 1e20f;
  const Image before = random_image(37, 21, 3, 0.f, 1.f, 9);
  for (const char* name : {"adi", "mpad", "bokeh"})
    for (bool layers : {false, true}) {
      DofOptions settings;
      settings.layers = layers;
      Image out = before;
      EXPECT_THROW(depth_of_field(out, color, coc.plane(0), find_dof_method(name), settings),
                   InvalidArgument)
          << name;
      std::ptrdiff_t changed = 0;
      for (int ch = 0; ch < 3; ++ch)
        for (std::ptrdiff_t y = 0; y < 21; ++y)
          for (std::ptrdiff_t x = 0; x < 37; ++x)
            changed += !same_bits(out(x, y, ch), before(x, y, ch));
      EXPECT_EQ(changed, 0) << name << (layers ? " layers" : "");
    }
}

// The frame is checked before a method starts: a refused input leaves the output as it was.
TEST(DofInput, RefusedInputLeavesTheOutputUntouched) {
  Image color = random_image(40, 30, 3, 0.f, 1.f, 3);
  const Image coc = make_coc(40, 30, [](auto x, auto) { return float(x % 9) - 4.f; });
  color(39, 29, 2) = kNaN;  // the last value a method would reach
  const Image before = random_image(40, 30, 3, 0.f, 1.f, 8);
  for (const DofMethod& method : dof_methods()) {
    Image out = before;
    DofReport report;
    EXPECT_THROW(depth_of_field(out, color, coc.plane(0), method, {}), InvalidArgument)
        << method.name;
    std::ptrdiff_t changed = 0;
    for (int ch = 0; ch < 3; ++ch)
      for (std::ptrdiff_t y = 0; y < 30; ++y)
        for (std::ptrdiff_t x = 0; x < 40; ++x)
          changed += !same_bits(out(x, y, ch), before(x, y, ch));
    EXPECT_EQ(changed, 0) << method.name;
  }
}

TEST(DofInput, NonFiniteCocNamesThePixel) {
  const Image color = random_image(40, 30, 3, 0.f, 1.f, 3);
  Image coc = make_coc(40, 30, [](auto, auto) { return 3.f; });
  coc(5, 29, 0) = std::numeric_limits<float>::infinity();
  const Thrown v = invalid_argument_of([&] { validate_dof_input(color, coc.plane(0)); });
  EXPECT_EQ(v.argument, "coc");
  EXPECT_TRUE(contains(v.message, "pixel (5, 29)"));
  for (const DofMethod& method : dof_methods())
    EXPECT_TRUE(
        contains(invalid_argument_of([&] { run(method, color, coc); }).message, "pixel (5, 29)"));
}

// The diffusion methods check the CoC in their conductance scan, not in a pass of its own: a
// CoC that is not finite, or so large that its conductance is not, is still named as the CoC's.
TEST(DofInput, DiffusionMethodsNameABadCocAsTheCoc) {
  const Image color = random_image(70, 40, 3, 0.f, 1.f, 4);
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), -1e20f})
    for (const char* name : {"adi", "mpad"}) {
      Image coc = make_coc(70, 40, [](auto, auto) { return 3.f; });
      coc(66, 38, 0) = bad;
      const Thrown t = invalid_argument_of([&] { run(find_dof_method(name), color, coc); });
      EXPECT_EQ(t.argument, "coc") << name << " " << bad;
      EXPECT_TRUE(contains(t.message, "pixel (66, 38)")) << name << " " << t.message;
    }
}

TEST(DofInput, CocOfWrongSizeRejected) {
  const Image color = random_image(40, 30, 3, 0.f, 1.f, 3);
  for (auto [w, h] : {std::pair{39, 30}, std::pair{40, 31}}) {
    const Image coc(w, h, 1);
    const Thrown v = invalid_argument_of([&] { validate_dof_input(color, coc.plane(0)); });
    EXPECT_EQ(v.argument, "coc");
    EXPECT_TRUE(contains(v.message, std::to_string(w) + " x " + std::to_string(h)));
    EXPECT_TRUE(contains(v.message, "40 x 30"));
    for (const DofMethod& method : dof_methods()) {
      Image out;
      DofReport report;
      EXPECT_EQ(invalid_argument_of([&] {
                  depth_of_field(out, color, coc.plane(0), method, {});
                }).argument,
                "coc")
          << method.name;
    }
  }
}

TEST(DofInput, CocInsideTheOutputRejected) {
  // A CoC that is a plane of out would be read after out is reallocated or written.
  const Image color = random_image(40, 30, 3, 0.f, 1.f, 3);
  for (const DofMethod& method : dof_methods()) {
    Image out(40, 30, 4);
    for (std::ptrdiff_t y = 0; y < 30; ++y)
      for (std::ptrdiff_t x = 0; x < 40; ++x) out(x, y, 3) = 4.f;
    DofReport report;
    const Thrown t =
        invalid_argument_of([&] { depth_of_field(out, color, out.plane(3), method, {}); });
    EXPECT_EQ(t.argument, "coc") << method.name;
    EXPECT_TRUE(contains(t.message, "output")) << method.name;
  }
}

// ---------------------------------------------------------------------------------------------
// The procedural scene

TEST(ProceduralScene, DepthColourAndLensAreUsable) {
  const std::ptrdiff_t width = 320, height = 180;
  const Scene scene = procedural_scene(width, height, 2);
  ASSERT_EQ(scene.color.width(), width);
  ASSERT_EQ(scene.color.height(), height);
  ASSERT_EQ(scene.color.channels(), 3);
  ASSERT_EQ(scene.depth.width(), width);
  ASSERT_EQ(scene.depth.height(), height);
  ASSERT_EQ(scene.depth.channels(), 1);

  float dmin = INFINITY, dmax = 0, cmin = INFINITY, cmax = -INFINITY;
  std::ptrdiff_t bad_depth = 0, bad_color = 0, hdr = 0;
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const float d = scene.depth(x, y, 0);
      bad_depth += !(std::isfinite(d) && d > 0);
      dmin = std::min(dmin, d);
      dmax = std::max(dmax, d);
      bool bright = false;
      for (int c = 0; c < 3; ++c) {
        const float v = scene.color(x, y, c);
        bad_color += !(std::isfinite(v) && v >= 0);
        cmin = std::min(cmin, v);
        cmax = std::max(cmax, v);
        bright |= v > 1.f;
      }
      hdr += bright;
    }
  EXPECT_EQ(bad_depth, 0);
  EXPECT_EQ(bad_color, 0);
  EXPECT_LT(dmin, 1.f);
  EXPECT_GT(dmax, 10.f);
  EXPECT_GT(hdr, 0);
  EXPECT_NO_THROW(validate(scene.lens));
  EXPECT_GT(scene.lens.focus_distance_m, dmin);
  EXPECT_LT(scene.lens.focus_distance_m, dmax);

  Image coc(width, height, 1);
  coc_thin_lens(coc.plane(0), scene.depth.plane(0), scene.lens);
  std::ptrdiff_t near = 0, far = 0, sharp = 0;
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const float v = coc(x, y, 0);
      near += v <= -1.f;
      far += v >= 1.f;
      sharp += std::fabs(v) < 1.f;
    }
  EXPECT_GT(near, 0);
  EXPECT_GT(far, 0);
  EXPECT_GT(sharp, 0);
  std::printf(
      "[ measured ] scene %tdx%td: depth [%.3f, %.3f] m, colour [%.3f, %.3f], %td HDR "
      "pixels, focus %.3f m; CoC near %td, far %td, sharp %td pixels\n",
      width, height, dmin, dmax, cmin, cmax, hdr, scene.lens.focus_distance_m, near, far, sharp);
}

// An option a method would ignore is refused, naming the option; the methods that honour it
// accept it, and `auto` chooses among them.
TEST(DofOptionsHonoured, EveryMethodHonoursOrRefuses) {
  const Image color = random_image(24, 16, 3, 0.f, 1.f, 5);
  const Image coc = make_coc(24, 16, [](auto x, auto) { return x < 12 ? -4.f : 6.f; });
  DofOptions layered, bladed, boosted, gained;
  layered.layers = true;
  bladed.aperture.blades = 6;
  boosted.highlight_threshold = 2.f;
  gained.highlight_gain = 3.f;
  const std::pair<const DofOptions*, const char*> asks[] = {{&layered, "layers"},
                                                            {&bladed, "aperture_blades"},
                                                            {&boosted, "highlight_threshold"},
                                                            {&gained, "highlight_gain"}};
  for (const DofMethod& method : dof_methods())
    for (const auto& [options, option] : asks) {
      SCOPED_TRACE(std::string(method.name) + " " + option);
      if (honours_options(method, *options)) {
        EXPECT_NO_THROW(run(method, color, coc, *options));
      } else {
        const Thrown t = invalid_argument_of([&] { run(method, color, coc, *options); });
        EXPECT_EQ(t.argument, option);
        EXPECT_TRUE(contains(t.message, std::string(method.name))) << t.message;
      }
    }
  EXPECT_TRUE(find_dof_method("adi").honours_layers);
  EXPECT_FALSE(find_dof_method("sat").honours_layers);
}

TEST(DofOptionsHonoured, BadLensCharacterIsRefusedNamingTheOption) {
  const Image color = random_image(8, 8, 3, 0.f, 1.f, 5);
  const Image coc = make_coc(8, 8, [](auto, auto) { return 3.f; });
  const DofMethod& adi = find_dof_method("adi");
  DofOptions options;
  options.aperture.blades = 2;
  EXPECT_EQ(invalid_argument_of([&] { run(adi, color, coc, options); }).argument,
            "aperture_blades");
  options.aperture = {.blades = 5, .rotation_deg = 0, .roundness = 1.5f};
  EXPECT_EQ(invalid_argument_of([&] { run(adi, color, coc, options); }).argument,
            "aperture_roundness");
  options.aperture = {};
  options.highlight_threshold = -1.f;
  EXPECT_EQ(invalid_argument_of([&] { run(adi, color, coc, options); }).argument,
            "highlight_threshold");
  options.highlight_threshold = INFINITY;
  options.highlight_gain = NAN;
  EXPECT_EQ(invalid_argument_of([&] { run(adi, color, coc, options); }).argument, "highlight_gain");
}

// The polygon's rim: vertices on the unit circle, blade middles at cos(pi/N); its area is the
// regular polygon's, N/2 sin(2 pi/N), counted on a fine grid.
TEST(ApertureShape, PolygonRimAndArea) {
  for (int blades : {3, 5, 6, 8}) {
    const ApertureShape shape{.blades = blades, .rotation_deg = 10, .roundness = 0};
    const float vertex = float(M_PI) / 2 + 10.f * float(M_PI) / 180.f;  // corner 0: up, turned
    EXPECT_NEAR(aperture_rim(shape, vertex), 1.f, 1e-5f) << blades;
    EXPECT_NEAR(aperture_rim(shape, vertex + float(M_PI) / float(blades)),
                std::cos(float(M_PI) / float(blades)), 1e-5f)
        << blades;
    const int n = 1000;
    long count = 0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        count += inside(shape, (2.f * float(i) + 1.f) / float(n) - 1.f,
                        (2.f * float(j) + 1.f) / float(n) - 1.f);
    const double area = 4.0 * double(count) / (double(n) * n);
    EXPECT_NEAR(area, 0.5 * blades * std::sin(2 * M_PI / blades), 2e-3) << blades;
  }
  const ApertureShape round{.blades = 6, .rotation_deg = 0, .roundness = 1};
  EXPECT_TRUE(round.is_circle());
  EXPECT_FLOAT_EQ(aperture_rim(round, 0.3f), 1.f);
  EXPECT_TRUE(inside(ApertureShape{}, 0.7f, 0.7f));
  EXPECT_FALSE(inside(ApertureShape{}, 0.72f, 0.72f));
}

// A red bar far in front of the focus (CoC -30 px) covers the left of a green subject that is
// itself slightly in front of the focus (CoC -3 px), over a far background (CoC +6 px). The
// bar's blur must spread over the subject, as the scatter reference's does: the near layer
// follows depth (near_layer.hpp), so the subject is not in the bar's layer, where the smaller
// conductance of the two would keep the bar's edge razor sharp over it.
TEST(DofLayers, NearObjectBlursOverASubjectJustInFrontOfTheFocus) {
  const std::ptrdiff_t w = 160, h = 100, edge = 60;
  Image color(w, h, 3), coc(w, h, 1);
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x) {
      const bool bar = x < edge, subject = !bar && x < 120 && y >= 20 && y < 80;
      const float rgb[3] = {bar ? 1.f : 0.f, subject ? 0.8f : 0.f, bar || subject ? 0.f : 0.6f};
      for (int c = 0; c < 3; ++c) color(x, y, c) = rgb[c];
      coc(x, y, 0) = bar ? -30.f : subject ? -3.f : 6.f;
    }
  const NearLayer near = near_layer(coc.plane(0), 1.f);
  EXPECT_TRUE(near.contains(-30.f));
  EXPECT_FALSE(near.contains(-3.f));
  DofOptions layered;
  layered.layers = true;
  const Result adi = run(find_dof_method("adi"), color, coc, layered);
  const Result scatter = run(find_dof_method("scatter"), color, coc);
  ASSERT_TRUE(adi.report.layered);
  for (std::ptrdiff_t d : {2, 4, 8}) {
    const std::ptrdiff_t x = edge + d, y = 50;
    const float red = adi.out(x, y, 0), reference = scatter.out(x, y, 0);
    EXPECT_GT(reference, 0.1f) << d;  // the reference spreads the bar this far
    EXPECT_NEAR(red, reference, 0.5f * reference) << "at " << d << " px into the subject";
  }
}

}  // namespace
}  // namespace tridiff::test
