// The lens as the user points it (issue 26): focusing at a pixel's depth, an in-focus range,
// and the pictures of what the methods see (views.hpp), each against numbers worked out by hand
// or a closed form evaluated apart from the library's formula.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "test_util.hpp"
#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/views.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// ---------------------------------------------------------------------------------------------
// focus_depth_at

// A depth step: 1.5 m left of column 10, 6 m from it on.
Image step_depth() {
  return make_image(20, 9, 1, [](auto x, auto, int) { return x < 10 ? 1.5f : 6.f; });
}

TEST(LensFocusDepthAt, MedianPicksTheSideOfTheEdgeThePixelIsOn) {
  const Image depth = step_depth();
  // Column 9's 5 x 5 window holds columns 7..11: three of 1.5 m, two of 6 m.
  EXPECT_EQ(focus_depth_at(depth.plane(0), 9, 4), 1.5f);
  // Column 10's holds 8..12: two of 1.5 m, three of 6 m.
  EXPECT_EQ(focus_depth_at(depth.plane(0), 10, 4), 6.f);
  // Far from the edge, and at the frame's corners (the window clipped).
  EXPECT_EQ(focus_depth_at(depth.plane(0), 0, 0), 1.5f);
  EXPECT_EQ(focus_depth_at(depth.plane(0), 19, 8), 6.f);
  // A 1 x 1 window is the pixel itself.
  EXPECT_EQ(focus_depth_at(depth.plane(0), 9, 4, 1), 1.5f);
}

TEST(LensFocusDepthAt, InvalidDepthsAreLeftOutOfTheMedian) {
  // 3 x 3 frame, window 3 around the centre: every pixel. Valid: 2, 4, 7 (median 4).
  Image depth(3, 3, 1);
  const float values[9] = {kNaN, 2.f, 0.f, kInf, -1.f, 7.f, 4.f, kNaN, 0.f};
  for (int i = 0; i < 9; ++i) depth(i % 3, i / 3, 0) = values[i];
  EXPECT_EQ(focus_depth_at(depth.plane(0), 1, 1, 3), 4.f);
  // An even count (2, 4, 7, 9): the lower middle value, the nearer surface.
  depth(0, 0, 0) = 9.f;
  EXPECT_EQ(focus_depth_at(depth.plane(0), 1, 1, 3), 4.f);
}

TEST(LensFocusDepthAt, RefusesAPixelOutsideAnEmptyWindowAndAnEvenWindow) {
  const Image depth = step_depth();
  EXPECT_EQ(invalid_argument_of([&] { focus_depth_at(depth.plane(0), 20, 0); }).argument, "pixel");
  EXPECT_EQ(invalid_argument_of([&] { focus_depth_at(depth.plane(0), 0, -1); }).argument, "pixel");
  EXPECT_EQ(invalid_argument_of([&] { focus_depth_at(depth.plane(0), 3, 3, 4); }).argument,
            "window");
  Image holes = make_image(8, 8, 1, [](auto x, auto, int) { return x < 5 ? 0.f : 3.f; });
  // Columns 0..4 invalid: the window around column 1 (columns 0..3) has nothing valid...
  const Thrown empty = invalid_argument_of([&] { focus_depth_at(holes.plane(0), 1, 4); });
  EXPECT_EQ(empty.argument, "depth");
  EXPECT_TRUE(contains(empty.message, "5 x 5 window around pixel (1, 4)"));
  // ...the one around column 3 reaches column 5.
  EXPECT_EQ(focus_depth_at(holes.plane(0), 3, 4), 3.f);
}

// ---------------------------------------------------------------------------------------------
// The in-focus range of the thin lens

// Seed 000 eq. 3.2 in long double, signed, for a lens focused at `focus_m`: the on-sensor
// diameter A f (d - d_f) / (d (d_f - f)), A = f / N, in pixels of an image `width` wide.
long double thin_lens_px(long double d, long double focus_m, const ThinLens& lens,
                         std::ptrdiff_t width) {
  const long double f = lens.focal_length_mm / 1000.0L, aperture = f / lens.f_number;
  const long double on_sensor_m = aperture * f * (d - focus_m) / (d * (focus_m - f));
  return on_sensor_m * 1000.0L / lens.sensor_width_mm * static_cast<long double>(width);
}

// The range's closed form: 0 inside [near, far], the lens focused at near in front of it and
// at far behind it.
long double range_px(long double d, const ThinLens& lens, std::ptrdiff_t width) {
  if (d < lens.focus_near_m) return thin_lens_px(d, lens.focus_near_m, lens, width);
  if (d > lens.focus_far_m) return thin_lens_px(d, lens.focus_far_m, lens, width);
  return 0.0L;
}

ThinLens range_lens(float near_m, float far_m) {
  ThinLens lens{50.f, 2.f, 3.2f, 36.f, 1e30f};
  lens.focus_near_m = near_m;
  lens.focus_far_m = far_m;
  return lens;
}

TEST(ThinLensFocusRange, MatchesTheClosedFormOutsideAndIsZeroInside) {
  const std::ptrdiff_t width = 1920;
  int checked = 0;
  for (const ThinLens lens : {range_lens(2.f, 5.f), range_lens(0.4f, 0.6f), range_lens(8.f, 8.f)})
    for (float d = 0.06f; d < 1e4f; d *= 1.013f) {
      const long double expected = range_px(d, lens, width);
      const float got = coc_thin_lens(d, lens, width);
      if (d >= lens.focus_near_m && d <= lens.focus_far_m) {
        EXPECT_EQ(got, 0.f) << "d " << d;
        continue;
      }
      // Float: a few roundings of the far-field CoC, the scale of both sides' formulas.
      const double scale = double(std::fabs(thin_lens_px(1e12L, lens.focus_near_m, lens, width)));
      EXPECT_NEAR(got, double(expected), 1e-5 * std::max(std::fabs(double(expected)), scale))
          << "range [" << lens.focus_near_m << ", " << lens.focus_far_m << "], d " << d;
      EXPECT_EQ(std::signbit(got), d < lens.focus_near_m) << "d " << d;
      ++checked;
    }
  EXPECT_GT(checked, 1000);
}

TEST(ThinLensFocusRange, ContinuousAtBothEnds) {
  const ThinLens lens = range_lens(2.f, 5.f);
  EXPECT_EQ(coc_thin_lens(2.f, lens, 1920), 0.f);
  EXPECT_EQ(coc_thin_lens(5.f, lens, 1920), 0.f);
  // One float step outside each end: the CoC is a tiny fraction of a pixel.
  EXPECT_LT(std::fabs(coc_thin_lens(std::nextafter(2.f, 0.f), lens, 1920)), 1e-4f);
  EXPECT_LT(std::fabs(coc_thin_lens(std::nextafter(5.f, 10.f), lens, 1920)), 1e-4f);
  // And a known value on each side: 1 m is eq. 3.2 focused at 2 m, 10 m focused at 5 m.
  // 1 m: A f (1 - 2) / (1 (2 - 0.05)) = -0.025 * 0.05 / 1.95 m = -0.000641 m on the sensor,
  // * 1000 / 36 * 1920 = -34.19 px; 10 m: 0.025 * 0.05 * 5 / (10 * 4.95) * 1e3 / 36 * 1920.
  EXPECT_NEAR(coc_thin_lens(1.f, lens, 1920), -0.025 * 0.05 / 1.95 * 1e3 / 36 * 1920, 1e-3);
  EXPECT_NEAR(coc_thin_lens(10.f, lens, 1920), 0.025 * 0.05 * 5 / 49.5 * 1e3 / 36 * 1920, 1e-3);
}

TEST(ThinLensFocusRange, MapAgreesWithTheSingleValueToTheBit) {
  const std::ptrdiff_t width = 333, height = 4;
  Image depth = make_image(width, height, 1, [](auto x, auto y, int) {
    return 0.06f * std::pow(1.03f, float(x)) * (1.f + 0.1f * float(y));
  });
  depth(7, 0, 0) = 2.f;  // both ends exactly
  depth(8, 0, 0) = 5.f;
  for (const ThinLens lens : {range_lens(2.f, 5.f), ThinLens{}}) {
    Image coc(width, height, 1);
    coc_thin_lens(coc.plane(0), depth.plane(0), lens, 2);
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x)
        ASSERT_TRUE(same_bits(coc(x, y, 0), coc_thin_lens(depth(x, y, 0), lens, width)))
            << x << ", " << y;
  }
}

TEST(ThinLensFocusRange, ValidateNamesTheBadEnd) {
  EXPECT_NO_THROW(validate(range_lens(2.f, 5.f)));
  EXPECT_NO_THROW(validate(range_lens(3.f, 3.f)));  // a range of one distance: a focus
  EXPECT_EQ(invalid_argument_of([] { validate(range_lens(5.f, 2.f)); }).argument, "focus_far");
  EXPECT_EQ(invalid_argument_of([] { validate(range_lens(0.f, 2.f)); }).argument, "focus_near");
  EXPECT_EQ(invalid_argument_of([] { validate(range_lens(2.f, 0.f)); }).argument, "focus_far");
  EXPECT_EQ(invalid_argument_of([] { validate(range_lens(-1.f, 2.f)); }).argument, "focus_near");
  EXPECT_EQ(invalid_argument_of([] { validate(range_lens(2.f, kNaN)); }).argument, "focus_far");
  // At or inside the focal length (50 mm): no real image.
  const Thrown inside = invalid_argument_of([] { validate(range_lens(0.05f, 2.f)); });
  EXPECT_EQ(inside.argument, "focus_near");
  EXPECT_TRUE(contains(inside.message, "focal length"));
  // The single focus distance is not used with a range, so not refused either.
  ThinLens lens = range_lens(2.f, 5.f);
  lens.focus_distance_m = 0.f;
  EXPECT_NO_THROW(validate(lens));
}

// ---------------------------------------------------------------------------------------------
// Views

// One row of CoC values (in_focus 1): near, the near threshold itself, just inside it, sharp,
// just inside the far threshold, far.
const std::vector<float> kRowCoc = {-5.f, -1.f, -0.99f, 0.f, 0.99f, 2.5f, 5.f};

Image row_coc() {
  return make_image(std::ptrdiff_t(kRowCoc.size()), 2, 1,
                    [](auto x, auto, int) { return kRowCoc[std::size_t(x)]; });
}

void expect_colour(const Image& picture, std::ptrdiff_t x, std::ptrdiff_t y, float r, float g,
                   float b) {
  ASSERT_EQ(picture.channels(), 3);
  EXPECT_FLOAT_EQ(picture(x, y, 0), r) << "pixel " << x << ", " << y;
  EXPECT_FLOAT_EQ(picture(x, y, 1), g) << "pixel " << x << ", " << y;
  EXPECT_FLOAT_EQ(picture(x, y, 2), b) << "pixel " << x << ", " << y;
}

TEST(DofViews, CocViewIsBlueNearRedFarScaledByTheLargest) {
  const Image coc = row_coc();
  const Image picture = dof_view(DofView::coc, Image(7, 2, 3), coc.plane(0), {});
  expect_colour(picture, 0, 1, 0.f, 0.25f, 1.f);    // -5 of 5
  expect_colour(picture, 3, 0, 0.f, 0.f, 0.f);      // 0
  expect_colour(picture, 5, 0, 0.5f, 0.125f, 0.f);  // 2.5 of 5
  expect_colour(picture, 6, 0, 1.f, 0.25f, 0.f);    // 5 of 5
}

TEST(DofViews, FocalPlaneIsNearInFocusOrFarByTheInFocusSetting) {
  const Image coc = row_coc();
  DofOptions options;
  options.in_focus_coc_px = 1.f;
  const Image picture = dof_view(DofView::focal_plane, Image(7, 2, 3), coc.plane(0), options);
  for (std::ptrdiff_t x : {0, 1}) expect_colour(picture, x, 0, 0.f, 0.f, 1.f);
  for (std::ptrdiff_t x : {2, 3, 4}) expect_colour(picture, x, 1, 0.f, 1.f, 0.f);
  for (std::ptrdiff_t x : {5, 6}) expect_colour(picture, x, 0, 1.f, 0.f, 0.f);
  // A wider in-focus band takes in 2.5 px.
  options.in_focus_coc_px = 3.f;
  const Image wide = dof_view(DofView::focal_plane, Image(7, 2, 3), coc.plane(0), options);
  expect_colour(wide, 5, 0, 0.f, 1.f, 0.f);
  expect_colour(wide, 0, 0, 0.f, 0.f, 1.f);
}

TEST(DofViews, LayersShowTheNearLayerMask) {
  const Image coc = row_coc();
  const Image mask = near_layer_mask(coc.plane(0), {});
  // The near field holds -5 and -1, two depths more than an octave apart: the layer is the
  // nearer one (near_layer.hpp), the -1 px pixel blurs with the background.
  const float expected[7] = {1, 0, 0, 0, 0, 0, 0};
  for (std::ptrdiff_t x = 0; x < 7; ++x) EXPECT_EQ(mask(x, 1, 0), expected[x]) << x;
  // Within an octave the near field is one depth: all of it is the layer.
  Image one_depth = row_coc();
  one_depth(1, 0, 0) = one_depth(1, 1, 0) = -3.f;
  EXPECT_EQ(near_layer_mask(one_depth.plane(0), {})(1, 1, 0), 1.f);
  const Image picture = dof_view(DofView::layers, Image(7, 2, 3), coc.plane(0), {});
  expect_colour(picture, 0, 0, 1.f, 1.f, 1.f);
  expect_colour(picture, 1, 0, 0.f, 0.f, 0.f);
  expect_colour(picture, 6, 0, 0.f, 0.f, 0.f);
}

// 96 x 32: three 32 px tiles. A far pixel (CoC 5, radius 2.5: reaches ceil(3) = 3 px) at x = 34
// reaches the left tile's last columns (31 >= 34 - 3), not the right tile; the right tile is
// all sharp.
TEST(DofViews, TilesDarkenTheSkippedTilesOfTheInput) {
  const Image color = make_image(96, 32, 3, [](auto, auto, int c) { return 0.6f - 0.2f * c; });
  Image coc(96, 32, 1);
  coc(34, 16, 0) = 5.f;
  DofOptions options;
  const Image picture = dof_view(DofView::tiles, color, coc.plane(0), options);
  expect_colour(picture, 0, 0, 0.6f, 0.4f, 0.2f);      // left: reached from x = 34
  expect_colour(picture, 50, 20, 0.6f, 0.4f, 0.2f);    // middle: holds the far pixel
  expect_colour(picture, 95, 31, 0.15f, 0.1f, 0.05f);  // right: skipped, a quarter
  // Moved to x = 35 the disc stops at x = 32: the left tile is skipped too.
  coc(34, 16, 0) = 0.f;
  coc(35, 16, 0) = 5.f;
  expect_colour(dof_view(DofView::tiles, color, coc.plane(0), options), 0, 0, 0.15f, 0.1f, 0.05f);
  // --no-skip: nothing is skipped, the input as it is (clamped to [0, 1]).
  options.skip_in_focus = false;
  Image bright = color;
  bright(95, 0, 0) = 7.f;
  const Image all = dof_view(DofView::tiles, bright, coc.plane(0), options);
  expect_colour(all, 95, 31, 0.6f, 0.4f, 0.2f);
  expect_colour(all, 95, 0, 1.f, 0.4f, 0.2f);
}

TEST(DofViews, UnknownViewAndBadCocAreRefused) {
  EXPECT_EQ(dof_view_named("focal-plane"), DofView::focal_plane);
  const Thrown unknown = invalid_argument_of([] { dof_view_named("depth"); });
  EXPECT_EQ(unknown.argument, "view");
  EXPECT_TRUE(contains(unknown.message, "coc, focal-plane, layers or tiles"));
  Image coc(4, 4, 1);
  coc(1, 2, 0) = kNaN;
  EXPECT_EQ(invalid_argument_of([&] {
              dof_view(DofView::coc, Image(4, 4, 3), coc.plane(0), {});
            }).argument,
            "coc");
}

}  // namespace
}  // namespace tridiff::test
