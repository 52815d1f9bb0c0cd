// Lens character (issue 26): the scatter reference's shaped bokeh and highlight boost, and the
// `bokeh` method (adi body + highlight sprites). Shapes are checked against the aperture's own
// inside() test and the polygon's area formula; energies against the input's, by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <cstdio>
#include <memory>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "test_util.hpp"
#include "tridiff/dof/method.hpp"
#include "disc_body.hpp"  // dof/src: the smooth tiles

namespace tridiff {
namespace {

using testing_util::make_coc;
using testing_util::random_image;

constexpr std::ptrdiff_t kSize = 81, kCentre = 40;
constexpr float kPoint = 1000.f;

Image filled(std::ptrdiff_t width, std::ptrdiff_t height, int channels, float value) {
  return testing_util::make_image(width, height, channels, [=](auto, auto, int) { return value; });
}

Image run(std::string_view method, const Image& color, const Image& coc,
          const DofOptions& settings = {}) {
  Image out;
  depth_of_field(out, color, coc.plane(0), find_dof_method(method), settings);
  return out;
}

// A black frame, one bright pixel at (x, y) in every channel, a uniform CoC.
struct Point {
  Image color, coc;
};
Point bright_point(float coc_px, std::ptrdiff_t x = kCentre, std::ptrdiff_t y = kCentre) {
  Point p{filled(kSize, kSize, 3, 0.f), make_coc(kSize, kSize, [=](auto, auto) { return coc_px; })};
  for (int c = 0; c < 3; ++c) p.color(x, y, c) = kPoint;
  return p;
}

double channel_sum(const Image& image, int c) {
  double sum = 0;
  for (std::ptrdiff_t y = 0; y < image.height(); ++y)
    for (std::ptrdiff_t x = 0; x < image.width(); ++x) sum += image(x, y, c);
  return sum;
}

DofOptions bladed(int blades, float rotation_deg = 0) {
  DofOptions settings;
  settings.aperture = {.blades = blades, .rotation_deg = rotation_deg, .roundness = 0};
  return settings;
}

// Whether offset (dx, dy) (y down) lies in the aperture scaled to circumradius `radius`.
bool in_shape(const ApertureShape& shape, double radius, std::ptrdiff_t dx, std::ptrdiff_t dy) {
  return inside(shape, float(double(dx) / radius), float(-double(dy) / radius));
}

// CoC 31 px and 6 blades: the splat is the hexagon of circumradius 15.5 — nonzero a pixel
// inside its rim, zero a pixel outside, its area (energy / plateau) the hexagon's
// 3 sqrt(3) / 2 r^2 = 624.2 px^2.
TEST(ApertureScatter, SixBladesSplatTheHexagon) {
  const Point p = bright_point(31.f);
  const DofOptions settings = bladed(6);
  const Image out = run("scatter", p.color, p.coc, settings);
  const double radius = 15.5;
  std::ptrdiff_t inside_checked = 0, outside_checked = 0;
  for (std::ptrdiff_t dy = -kCentre; dy <= kCentre; ++dy)
    for (std::ptrdiff_t dx = -kCentre; dx <= kCentre; ++dx) {
      const float v = out(kCentre + dx, kCentre + dy, 0);
      if (in_shape(settings.aperture, radius - 1, dx, dy)) {
        EXPECT_GT(v, 0.f) << dx << ", " << dy;
        ++inside_checked;
      } else if (!in_shape(settings.aperture, radius + 1, dx, dy)) {
        EXPECT_EQ(v, 0.f) << dx << ", " << dy;
        ++outside_checked;
      }
    }
  EXPECT_GT(inside_checked, 500);
  EXPECT_GT(outside_checked, 5000);
  const double area = kPoint / double(out(kCentre, kCentre, 0));
  const double hexagon = 1.5 * std::sqrt(3.0) * radius * radius;
  EXPECT_NEAR(area / hexagon, 1.0, 0.03) << area;
}

// A shaped splat conserves the point's energy. At the frame's border the folded splats of a
// uniform CoC tile the frame only for a shape symmetric under the axis reflections (the hexagon
// with a vertex on the x axis): scatter's layer normalisation rescales the others there.
TEST(ApertureScatter, ShapedSplatConservesEnergy) {
  const Point p = bright_point(31.f);
  for (int blades : {3, 5, 6, 8}) {
    const Image out = run("scatter", p.color, p.coc, bladed(blades, 17));
    EXPECT_NEAR(channel_sum(out, 1), kPoint, 1e-5 * kPoint) << blades;
  }
  const Point corner = bright_point(31.f, 3, 5);
  const Image out = run("scatter", corner.color, corner.coc, bladed(6, 0));
  EXPECT_NEAR(channel_sum(out, 1), kPoint, 1e-5 * kPoint);
}

// Rotating the aperture by 90 degrees counter-clockwise rotates the splat so on the screen:
// offset (dx, dy) (y down) moves to (dy, -dx).
TEST(ApertureScatter, RotationRotatesTheSplat) {
  const Point p = bright_point(31.f);
  const Image upright = run("scatter", p.color, p.coc, bladed(5, 0));
  const Image turned = run("scatter", p.color, p.coc, bladed(5, 90));
  float largest = 0, worst = 0;
  for (std::ptrdiff_t dy = -20; dy <= 20; ++dy)
    for (std::ptrdiff_t dx = -20; dx <= 20; ++dx) {
      const float a = upright(kCentre + dx, kCentre + dy, 0);
      largest = std::max(largest, a);
      worst = std::max(worst, std::fabs(a - turned(kCentre + dy, kCentre - dx, 0)));
    }
  EXPECT_LT(worst, 1e-5f * largest);
  // Unturned, corner 0 of the pentagon points up (to smaller rows), a blade faces down.
  EXPECT_GT(upright(kCentre, kCentre - 14, 0), 0.f);
  EXPECT_EQ(upright(kCentre, kCentre + 14, 0), 0.f);
}

// Four blades at 45 degrees are the axis-aligned square (corners at (±11, ±11) of the
// circumradius 15.5); at 0 degrees the diamond, which misses those corners.
TEST(ApertureScatter, FourBladesAt45DegreesAreTheUprightSquare) {
  const Point p = bright_point(31.f);
  const Image square = run("scatter", p.color, p.coc, bladed(4, 45));
  const Image diamond = run("scatter", p.color, p.coc, bladed(4, 0));
  for (const std::ptrdiff_t sx : {-10, 10})
    for (const std::ptrdiff_t sy : {-10, 10}) {
      EXPECT_GT(square(kCentre + sx, kCentre + sy, 0), 0.f);
      EXPECT_EQ(diamond(kCentre + sx, kCentre + sy, 0), 0.f);
    }
  EXPECT_EQ(square(kCentre + 14, kCentre, 0), 0.f);
  EXPECT_GT(diamond(kCentre + 14, kCentre, 0), 0.f);
}

// A ring kernel image: 1 for 10 <= r <= 14 (r from the centre of a 31 x 31 image).
Image ring(std::ptrdiff_t size, double inner, double outer) {
  Image kernel(size, size, 1);
  const double centre = 0.5 * double(size - 1);
  for (std::ptrdiff_t y = 0; y < size; ++y)
    for (std::ptrdiff_t x = 0; x < size; ++x) {
      const double r = std::hypot(double(x) - centre, double(y) - centre);
      kernel(x, y, 0) = r >= inner && r <= outer ? 1.f : 0.f;
    }
  return kernel;
}

// At CoC 31 a 31 x 31 kernel maps pixel to pixel: the splat is the kernel over its sum.
TEST(ApertureScatter, KernelImageIsReproducedAtItsOwnSize) {
  const Point p = bright_point(31.f);
  const Image kernel = ring(31, 10, 14);
  DofOptions settings;
  settings.aperture_image = std::make_shared<const Image>(kernel);
  const Image out = run("scatter", p.color, p.coc, settings);
  const double kernel_sum = channel_sum(kernel, 0);
  for (std::ptrdiff_t y = 0; y < 31; ++y)
    for (std::ptrdiff_t x = 0; x < 31; ++x)
      ASSERT_NEAR(out(kCentre - 15 + x, kCentre - 15 + y, 2), kPoint * kernel(x, y, 0) / kernel_sum,
                  1e-6 * kPoint)
          << x << ", " << y;
  EXPECT_NEAR(channel_sum(out, 2), kPoint, 1e-5 * kPoint);
}

// Shrunk by 2 (a 62 x 62 ring at CoC 31), every output pixel is the mean of a 2 x 2 block.
TEST(ApertureScatter, KernelImageShrinksByBoxFilter) {
  const Point p = bright_point(31.f);
  const Image kernel = ring(62, 20, 28);
  DofOptions settings;
  settings.aperture_image = std::make_shared<const Image>(kernel);
  const Image out = run("scatter", p.color, p.coc, settings);
  const double kernel_sum = channel_sum(kernel, 0);
  for (std::ptrdiff_t y = 0; y < 31; ++y)
    for (std::ptrdiff_t x = 0; x < 31; ++x) {
      const double block = kernel(2 * x, 2 * y, 0) + kernel(2 * x + 1, 2 * y, 0) +
                           kernel(2 * x, 2 * y + 1, 0) + kernel(2 * x + 1, 2 * y + 1, 0);
      ASSERT_NEAR(out(kCentre - 15 + x, kCentre - 15 + y, 0), kPoint * block / kernel_sum,
                  1e-6 * kPoint)
          << x << ", " << y;
    }
}

TEST(ApertureScatter, BadKernelImageIsRefusedNamingIt) {
  const Point p = bright_point(9.f);
  Image negative = ring(9, 2, 3), not_finite = ring(9, 2, 3), dark = filled(9, 9, 1, 0.f);
  negative(4, 4, 0) = -1.f;
  not_finite(1, 2, 0) = NAN;
  for (const Image* kernel : {&negative, &not_finite, &dark}) {
    DofOptions settings;
    settings.aperture_image = std::make_shared<const Image>(*kernel);
    for (const char* method : {"scatter", "bokeh"}) {
      try {
        run(method, p.color, p.coc, settings);
        ADD_FAILURE() << method << ": not refused";
      } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.argument(), "aperture_image") << method;
      }
    }
  }
}

// Highlight boost, by hand: (4, 2, 1) over threshold 1 with gain 3 is scaled by
// (1 + 3 (4 - 1)) / 4 = 2.5, so the splat carries (10, 5, 2.5); the circle as well.
TEST(ApertureScatter, HighlightBoostScalesTheExcessKeepingHue) {
  Point p = bright_point(15.f);
  p.color(kCentre, kCentre, 0) = 4.f;
  p.color(kCentre, kCentre, 1) = 2.f;
  p.color(kCentre, kCentre, 2) = 1.f;
  DofOptions settings;
  settings.highlight_threshold = 1.f;
  settings.highlight_gain = 3.f;
  const Image out = run("scatter", p.color, p.coc, settings);
  EXPECT_NEAR(channel_sum(out, 0), 10.0, 1e-5);
  EXPECT_NEAR(channel_sum(out, 1), 5.0, 1e-5);
  EXPECT_NEAR(channel_sum(out, 2), 2.5, 1e-5);
}

// A dark frame with three bright points at CoC 20 px and six blades: `bokeh` makes the same
// hexagons as scatter and keeps every channel's energy.
struct Lamps {
  Image color, coc;
};
Lamps dark_frame_with_lamps() {
  Lamps f{filled(96, 96, 3, 0.01f), make_coc(96, 96, [](auto, auto) { return 20.f; })};
  f.color(20, 24, 0) = 200.f;
  f.color(60, 30, 1) = 120.f;
  f.color(40, 70, 2) = 300.f;
  f.color(40, 70, 0) = 50.f;
  return f;
}

TEST(DofBokeh, SpritesKeepEnergyAndMatchScatter) {
  const Lamps f = dark_frame_with_lamps();
  const DofOptions settings = bladed(6, 10);
  const Image bokeh = run("bokeh", f.color, f.coc, settings);
  const Image scatter = run("scatter", f.color, f.coc, settings);
  double peak = 0, worst = 0, squared = 0;
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(channel_sum(bokeh, c) / channel_sum(f.color, c), 1.0, 1e-3) << c;
    for (std::ptrdiff_t y = 0; y < 96; ++y)
      for (std::ptrdiff_t x = 0; x < 96; ++x) {
        peak = std::max(peak, double(scatter(x, y, c)));
        const double e = double(bokeh(x, y, c)) - double(scatter(x, y, c));
        worst = std::max(worst, std::fabs(e));
        squared += e * e;
      }
  }
  const double psnr = 10 * std::log10(peak * peak / (squared / (3 * 96 * 96)));
  std::printf("[ measured ] bokeh vs scatter, three lamps: max %.4g of peak %.4g, PSNR %.1f dB\n",
              worst, peak, psnr);
  EXPECT_LT(worst, 0.02 * peak);
  EXPECT_GT(psnr, 45.0);
}

// The round aperture's sprite, which counts each row's fully covered run and evaluates only
// the rim, against the disc by brute force: weight max(0, min(1, d/2 + 1/2 - |(dx, dy)|)) over
// the whole square, normalised, mirror-folded at the border. The sprite is bokeh's output less
// bokeh's on the frame with the highlight at what the body keeps (kBodyKeeps = 1/4 of the
// threshold 1: the point of 1000 keeps 0.25 in the body, 999.75 in the sprite; that frame has
// no highlight, so it is the body). Diameters with rims through whole pixels (11: outer 6, so
// (3, 4) has coverage exactly 1), tiny and large; points inside, at a corner and an edge.
TEST(DofBokeh, RoundSpriteIsTheDiscByBruteForce) {
  constexpr std::ptrdiff_t kFrame = 96;
  constexpr float kBodyKeeps = 0.25f;  // method_bokeh.cpp
  const float kExcess = kPoint - kBodyKeeps;
  for (const float diameter : {11.f, 1.5f, 4.f, 20.3f, 63.f})
    for (const auto& [px, py] : {std::pair{48, 40}, std::pair{2, 1}, std::pair{90, 47}}) {
      const Image coc = make_coc(kFrame, kFrame, [=](auto, auto) { return diameter; });
      Image color = filled(kFrame, kFrame, 3, 0.f), clamped = color;
      for (int c = 0; c < 3; ++c) {
        color(px, py, c) = kPoint;
        clamped(px, py, c) = kBodyKeeps;
      }
      const Image bokeh = run("bokeh", color, coc), body = run("bokeh", clamped, coc);
      const double outer = 0.5 * diameter + 0.5;
      const auto reach = std::ptrdiff_t(std::ceil(outer));
      std::vector<double> expected(std::size_t(kFrame * kFrame), 0.0);
      double total = 0;
      for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy)
        for (std::ptrdiff_t dx = -reach; dx <= reach; ++dx)
          total += std::max(0.0, std::min(1.0, outer - std::hypot(double(dx), double(dy))));
      const auto fold = [](std::ptrdiff_t x) {
        return x < 0 ? -1 - x : x >= kFrame ? 2 * kFrame - 1 - x : x;
      };
      for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy)
        for (std::ptrdiff_t dx = -reach; dx <= reach; ++dx) {
          const double cover = std::min(1.0, outer - std::hypot(double(dx), double(dy)));
          if (cover > 0)
            expected[std::size_t(fold(py + dy) * kFrame + fold(px + dx))] +=
                kExcess * cover / total;
        }
      double worst = 0;
      for (std::ptrdiff_t y = 0; y < kFrame; ++y)
        for (std::ptrdiff_t x = 0; x < kFrame; ++x)
          for (int c = 0; c < 3; ++c) {
            const double sprite = double(bokeh(x, y, c)) - double(body(x, y, c));
            worst = std::max(worst, std::fabs(sprite - expected[std::size_t(y * kFrame + x)]));
          }
      EXPECT_LT(worst, 1e-5 * kExcess) << "diameter " << diameter << " at " << px << ", " << py;
    }
}

// Below the threshold everywhere (values in [0, 1), the automatic threshold 1): no sprite, so
// the aperture's shape changes no bit (the body is shapeless).
TEST(DofBokeh, WithoutHighlightsTheShapeChangesNoBit) {
  const Image color = random_image(70, 50, 3, 0.f, 1.f, 7);
  const Image coc = make_coc(70, 50, [](auto x, auto y) { return float((x + y) % 23) - 9.f; });
  for (bool layers : {false, true}) {
    DofOptions settings;
    settings.layers = layers;
    const Image round = run("bokeh", color, coc, settings);
    DofOptions shaped = settings;
    shaped.aperture.blades = 7;
    const Image bokeh = run("bokeh", color, coc, shaped);
    EXPECT_EQ(testing_util::differing_bits(round, bokeh), 0) << layers;
  }
}

// A texture with the power spectrum of natural images, 1/f^2 (the same energy in every octave
// of spatial frequency): value noise, bilinearly interpolated, one layer per octave of equal
// amplitude, spacings 128 down to 2 px; clamped to [0, 0.99], below the automatic highlight
// threshold (1), so that bokeh is its body alone.
Image natural_texture(std::ptrdiff_t n, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<double> sum(std::size_t(n * n), 0.0);
  int octaves = 0;
  for (std::ptrdiff_t spacing = 128; spacing >= 2; spacing /= 2, ++octaves) {
    const std::ptrdiff_t cells = n / spacing + 2;
    std::vector<double> grid(std::size_t(cells * cells));
    for (double& g : grid) g = unit(random);
    for (std::ptrdiff_t y = 0; y < n; ++y)
      for (std::ptrdiff_t x = 0; x < n; ++x) {
        const std::ptrdiff_t ix = x / spacing, iy = y / spacing;
        const double fx = double(x % spacing) / spacing, fy = double(y % spacing) / spacing;
        const auto at = [&](std::ptrdiff_t i, std::ptrdiff_t j) {
          return grid[std::size_t(j * cells + i)];
        };
        const double top = at(ix, iy) * (1 - fx) + at(ix + 1, iy) * fx;
        const double bottom = at(ix, iy + 1) * (1 - fx) + at(ix + 1, iy + 1) * fx;
        sum[std::size_t(y * n + x)] += top * (1 - fy) + bottom * fy;
      }
  }
  return testing_util::make_image(n, n, 1, [&](auto x, auto y, int) {
    return float(std::clamp(0.5 + 0.5 * sum[std::size_t(y * n + x)] / std::sqrt(double(octaves)),
                            0.0, 0.99));
  });
}

// The thin lens's disc, by brute force: the coverage of each pixel (a unit square) by the disc
// of diameter d about the pixel's centre, from 32 x 32 samples in the square, normalised; rows
// and columns beyond the frame folded as a mirror (edge pixel repeated), as scatter's are.
struct BruteDisc {
  struct Tap {
    std::ptrdiff_t dx, dy;
    double weight;
  };
  std::vector<Tap> taps;
  explicit BruteDisc(double diameter) {
    const double r = 0.5 * diameter;
    const auto reach = std::ptrdiff_t(std::ceil(r + 1));
    double total = 0;
    for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy)
      for (std::ptrdiff_t dx = -reach; dx <= reach; ++dx) {
        int inside = 0;
        for (int j = 0; j < 32; ++j)
          for (int i = 0; i < 32; ++i)
            inside += std::hypot(double(dx) + (i + 0.5) / 32 - 0.5,
                                 double(dy) + (j + 0.5) / 32 - 0.5) <= r;
        if (inside > 0) taps.push_back({dx, dy, double(inside)});
        total += inside;
      }
    for (Tap& tap : taps) tap.weight /= total;
  }
  double average(const Image& image, std::ptrdiff_t x, std::ptrdiff_t y) const {
    const auto fold = [](std::ptrdiff_t i, std::ptrdiff_t n) {
      while (i < 0 || i >= n) i = i < 0 ? -1 - i : 2 * n - 1 - i;
      return i;
    };
    double sum = 0;
    for (const Tap& tap : taps)
      sum += tap.weight *
             double(image(fold(x + tap.dx, image.width()), fold(y + tap.dy, image.height()), 0));
    return sum;
  }
};

// Where the CoC is smooth and far (disc_body.hpp), bokeh's body is the lens's disc: on a 1/f^2
// texture with a uniform CoC, every pixel (borders included) against BruteDisc. Each row of
// the gather holds the disc's exact area in its strip, but as a centred span, so the rim's
// pixels differ from their true coverage, by a share that falls as 1/d: measured max 1.2e-2,
// 3.2e-3, 2.8e-3, 1.6e-3 and rms 2.3e-3, 8.3e-4, 7.4e-4, 3.5e-4 for d = 4, 5.3, 7, 16, on
// values in [0, 1]. The bound is 0.06 / d (max), and a quarter of that (rms). Wider discs are
// gathered at half resolution (the next test).
TEST(DofBokeh, SmoothFarFieldIsTheDiscByBruteForce) {
  constexpr std::ptrdiff_t kFrame = 96;
  const Image texture = natural_texture(kFrame, 11);
  for (const float diameter : {4.f, 5.3f, 7.f, 16.f}) {
    const Image coc = make_coc(kFrame, kFrame, [=](auto, auto) { return diameter; });
    const Image out = run("bokeh", texture, coc);
    const BruteDisc disc(diameter);
    double worst = 0, squares = 0;
    for (std::ptrdiff_t y = 0; y < kFrame; ++y)
      for (std::ptrdiff_t x = 0; x < kFrame; ++x) {
        const double error = std::fabs(out(x, y, 0) - disc.average(texture, x, y));
        worst = std::max(worst, error);
        squares += error * error;
      }
    const double rms = std::sqrt(squares / double(kFrame * kFrame));
    std::printf("[ measured ] CoC %g px: max %.2e, rms %.2e against the disc\n", diameter, worst,
                rms);
    const double bound = 0.06 / diameter;
    EXPECT_LT(worst, bound) << "CoC " << diameter;
    EXPECT_LT(rms, bound / 4) << "CoC " << diameter;
  }
}

// From kHalfResRadiusPx the disc is gathered from the input's 2 x 2 means and interpolated
// back (disc_body.cpp): each pixel against the disc of its own diameter by brute force, on the
// same texture, borders included. Uniform CoCs; a frame of odd width and height (its half
// frame's last column and row average an edge pixel with its mirror image, and its tiles are
// narrow; folding the half frame as a frame of its own measured 2.6e-2 here); a ramp with a
// step within a tile; and a ramp from below the threshold to above it, so that full and half
// resolution tiles meet. Measured max 5.5e-3, 4.2e-3, 2.3e-3 for d = 24, 31.3, 48 (rms 1.3e-3,
// 8.7e-4, 5.0e-4), 4.4e-3 (8.6e-4) for the odd frame, 6.1e-3 (1.3e-3) for the ramp, 5.8e-3
// (9.4e-4) across the threshold: 5-10 times the full resolution's error at the same size. Bound: 0.2 / d (max), 0.05 / d (rms), d the
// smallest. A half pixel has one radius, its four pixels' mean, so columns alternating by
// 0.95 px all take the disc between the two (measured max 9.5e-3, rms 2.0e-3): bound twice.
TEST(DofBokeh, WideDiscsAtHalfResolutionAreNearTheDisc) {
  const Image texture = natural_texture(96, 17);
  struct Case {
    const char* name;
    std::ptrdiff_t width, height;
    std::function<float(std::ptrdiff_t)> diameter;  // of the column
    double slack = 1;                               // times the bounds
  };
  const float smallest = 2 * float(dof_detail::kHalfResRadiusPx);
  const std::vector<Case> cases = {
      {"uniform", 96, 96, [=](auto) { return smallest; }},
      {"uniform", 96, 96, [](auto) { return 31.3f; }},
      {"uniform", 96, 96, [](auto) { return 48.f; }},
      {"odd frame", 93, 71, [](auto) { return 30.f; }},
      {"ramp", 96, 96,
       [=](std::ptrdiff_t x) { return smallest + 0.8f * float(x) / 96 + (x >= 44 ? 0.1f : 0.f); }},
      {"ramp across the threshold", 96, 96,
       [=](std::ptrdiff_t x) { return smallest - 0.4f + 0.8f * float(x) / 96; }},
      {"alternating", 96, 96, [=](std::ptrdiff_t x) { return smallest + (x % 2 ? 0.95f : 0.f); },
       2},
  };
  for (const Case& c : cases) {
    const Image crop = testing_util::make_image(
        c.width, c.height, 1, [&](auto x, auto y, int) { return texture(x, y, 0); });
    const Image coc = make_coc(c.width, c.height, [&](auto x, auto) { return c.diameter(x); });
    const std::vector<Rect> tiles = dof_detail::smooth_far_tiles(coc.plane(0), 1.f, 2);
    ASSERT_EQ(tiles.size(), std::size_t(((c.width + 7) / 8) * ((c.height + 7) / 8))) << c.name;
    const Image out = run("bokeh", crop, coc);
    std::map<float, BruteDisc> discs;
    double worst = 0, squares = 0;
    for (std::ptrdiff_t y = 0; y < c.height; ++y)
      for (std::ptrdiff_t x = 0; x < c.width; ++x) {
        const float d = c.diameter(x);
        const BruteDisc& disc = discs.try_emplace(d, d).first->second;
        const double error = std::fabs(out(x, y, 0) - disc.average(crop, x, y));
        worst = std::max(worst, error);
        squares += error * error;
      }
    const double rms = std::sqrt(squares / double(c.width * c.height));
    const float d = c.diameter(0);
    std::printf("[ measured ] %s, CoC %g px: max %.2e, rms %.2e against each disc\n", c.name, d,
                worst, rms);
    EXPECT_LT(worst, c.slack * 0.2 / d) << c.name << " " << d;
    EXPECT_LT(rms, c.slack * 0.05 / d) << c.name << " " << d;
  }
}

// The same where the CoC varies within a tile, each pixel against the disc of its own diameter:
// a ramp along x (0.8 px over the frame) with a step of 0.1 px between columns 43 and 44,
// inside a tile; and the widest spread a smooth tile may hold, columns alternating between d
// and d + 0.95. The gather interpolates between a tile's smallest and largest radius
// (disc_body.cpp); measured max 5.0e-3, rms 9.9e-4 for the ramp from 5.6, 2.5e-3 and 5.6e-4
// from 12, and 1.6e-3, 3.1e-4 alternating from 9. Bound as above, 0.06 / d (max) and a
// quarter of it (rms).
TEST(DofBokeh, SmoothFarFieldIsEachPixelsOwnDisc) {
  constexpr std::ptrdiff_t kFrame = 96;
  const Image texture = natural_texture(kFrame, 7);
  struct Case {
    float base;
    bool alternating;
  };
  for (const Case& c : {Case{5.6f, false}, Case{12.f, false}, Case{9.f, true}}) {
    const auto diameter = [=](std::ptrdiff_t x) {
      if (c.alternating) return c.base + (x % 2 == 1 ? 0.95f : 0.f);
      return c.base + 0.8f * float(x) / float(kFrame) + (x >= 44 ? 0.1f : 0.f);
    };
    const Image coc = make_coc(kFrame, kFrame, [&](auto x, auto) { return diameter(x); });
    ASSERT_EQ(dof_detail::smooth_far_tiles(coc.plane(0), 1.f, 2).size(),
              std::size_t(kFrame / dof_detail::kDiscTile * kFrame / dof_detail::kDiscTile));
    const Image out = run("bokeh", texture, coc);
    double worst = 0, squares = 0;
    for (std::ptrdiff_t x = 0; x < kFrame; ++x) {
      const BruteDisc disc(diameter(x));
      for (std::ptrdiff_t y = 0; y < kFrame; ++y) {
        const double error = std::fabs(out(x, y, 0) - disc.average(texture, x, y));
        worst = std::max(worst, error);
        squares += error * error;
      }
    }
    const double rms = std::sqrt(squares / double(kFrame * kFrame));
    std::printf("[ measured ] CoC %g px and up%s: max %.2e, rms %.2e against each disc\n", c.base,
                c.alternating ? " (alternating)" : "", worst, rms);
    EXPECT_LT(worst, 0.06 / c.base) << "CoC " << c.base;
    EXPECT_LT(rms, 0.015 / c.base) << "CoC " << c.base;
  }
}

// The gather's prefix sums are made per block of 32 x 128 pixels (disc_body.cpp), each with its
// own window: CoC steps on the block boundaries (x = 128 and 256, y = 32 and 64; 0.5 and 0.4 px,
// within the smooth bound together) must not show. Every pixel against its own disc by brute
// force, bound 0.06 / d as above; measured max 4.3e-3, rms 6.5e-4.
TEST(DofBokeh, SmoothFarFieldIsTheDiscAcrossBlocks) {
  constexpr std::ptrdiff_t kWidth = 272, kHeight = 72;
  const Image texture = natural_texture(kWidth, 13);  // square; the first kHeight rows used
  const auto diameter = [](std::ptrdiff_t x, std::ptrdiff_t y) {
    return 7.f + (x >= 128 && x < 256 ? 0.5f : 0.f) + (y >= 32 && y < 64 ? 0.4f : 0.f);
  };
  Image crop(kWidth, kHeight, 1);
  for (std::ptrdiff_t y = 0; y < kHeight; ++y)
    for (std::ptrdiff_t x = 0; x < kWidth; ++x) crop(x, y, 0) = texture(x, y, 0);
  const Image coc = make_coc(kWidth, kHeight, diameter);
  ASSERT_EQ(dof_detail::smooth_far_tiles(coc.plane(0), 1.f, 2).size(),
            std::size_t(kWidth / dof_detail::kDiscTile * kHeight / dof_detail::kDiscTile));
  const Image out = run("bokeh", crop, coc);
  std::map<float, BruteDisc> discs;
  double worst = 0, squares = 0;
  for (std::ptrdiff_t y = 0; y < kHeight; ++y)
    for (std::ptrdiff_t x = 0; x < kWidth; ++x) {
      const float d = diameter(x, y);
      const BruteDisc& disc = discs.try_emplace(d, d).first->second;
      const double error = std::fabs(out(x, y, 0) - disc.average(crop, x, y));
      worst = std::max(worst, error);
      squares += error * error;
    }
  const double rms = std::sqrt(squares / double(kWidth * kHeight));
  std::printf("[ measured ] across blocks: max %.2e, rms %.2e against each disc\n", worst, rms);
  EXPECT_LT(worst, 0.06 / 7);
  EXPECT_LT(rms, 0.015 / 7);
}

// The gather's invariants, exact up to float rounding: a constant stays constant, and a linear
// ramp (x and y) is unchanged away from the borders (the disc is symmetric), for CoCs that vary
// within the smooth bound, not only for a uniform one.
TEST(DofBokeh, SmoothFarFieldKeepsConstantsAndRamps) {
  constexpr std::ptrdiff_t kFrame = 128;
  const Image constant = filled(kFrame, kFrame, 2, 0.37f);
  const Image ramp = testing_util::make_image(kFrame, kFrame, 1, [](auto x, auto y, int) {
    return 0.2f + 0.004f * float(x) + 0.002f * float(y);
  });
  // At full resolution, and at half (a diameter from 2 kHalfResRadiusPx up): the 2 x 2 means
  // of a ramp are the ramp at their centres, and the interpolation is exact on it.
  for (const float base : {9.f, 2 * float(dof_detail::kHalfResRadiusPx) + 6}) {
    const Image coc = make_coc(kFrame, kFrame, [=](auto x, auto y) {
      return base + 0.45f * float(std::sin(0.05 * double(x) + 0.03 * double(y)));
    });
    ASSERT_EQ(dof_detail::smooth_far_tiles(coc.plane(0), 1.f, 2).size(),
              std::size_t(kFrame / dof_detail::kDiscTile * kFrame / dof_detail::kDiscTile));
    const Image flat = run("bokeh", constant, coc);
    const Image ramped = run("bokeh", ramp, coc);
    // The ramp folds at the borders: compare beyond the largest radius.
    const auto margin = std::ptrdiff_t(base / 2) + 3;
    double flat_error = 0, ramp_error = 0;
    for (std::ptrdiff_t y = 0; y < kFrame; ++y)
      for (std::ptrdiff_t x = 0; x < kFrame; ++x) {
        for (int c = 0; c < 2; ++c)
          flat_error = std::max(flat_error, double(std::fabs(flat(x, y, c) - 0.37f)));
        if (x >= margin && y >= margin && x < kFrame - margin && y < kFrame - margin)
          ramp_error = std::max(ramp_error, double(std::fabs(ramped(x, y, 0) - ramp(x, y, 0))));
      }
    EXPECT_LT(flat_error, 1e-6) << "CoC " << base;
    EXPECT_LT(ramp_error, 2e-6) << "CoC " << base;
  }
}

// Which tiles take the disc: checked pixel by pixel against the rule, on a far field of CoC 10
// with a sharp square, a far step of 3 px, and a near pixel whose disc reaches into the far
// field. For every pixel p of a chosen tile, every pixel within ceil(r_p) + 1 (a square) is far
// with a CoC within kSmoothCocPx of p's, and no near pixel's disc (its radius + 1) reaches p.
// Tiles far from all three are chosen.
TEST(DofBokeh, DiscTilesAreOnlyWhereTheCocIsSmooth) {
  constexpr std::ptrdiff_t kFrame = 160;
  Image coc = make_coc(kFrame, kFrame, [](auto x, auto) { return x < 120 ? 10.f : 13.f; });
  for (std::ptrdiff_t y = 40; y < 48; ++y)
    for (std::ptrdiff_t x = 40; x < 48; ++x) coc(x, y, 0) = 0.f;
  coc(20, 140, 0) = -30.f;
  const std::vector<Rect> tiles = dof_detail::smooth_far_tiles(coc.plane(0), 1.f, 2);
  ASSERT_FALSE(tiles.empty());
  std::vector<bool> chosen(std::size_t(kFrame * kFrame), false);
  for (const Rect& tile : tiles)
    for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y)
      for (std::ptrdiff_t x = tile.x; x < tile.x + tile.width; ++x) {
        chosen[std::size_t(y * kFrame + x)] = true;
        const float c = coc(x, y, 0);
        const auto reach = std::ptrdiff_t(std::ceil(0.5f * c)) + 1;
        for (std::ptrdiff_t v = std::max<std::ptrdiff_t>(y - reach, 0);
             v <= std::min(y + reach, kFrame - 1); ++v)
          for (std::ptrdiff_t u = std::max<std::ptrdiff_t>(x - reach, 0);
               u <= std::min(x + reach, kFrame - 1); ++u) {
            ASSERT_GE(coc(u, v, 0), 1.f) << x << ", " << y << " reads " << u << ", " << v;
            ASSERT_LE(std::fabs(coc(u, v, 0) - c), dof_detail::kSmoothCocPx) << x << ", " << y;
          }
        ASSERT_GT(std::hypot(double(x - 20), double(y - 140)), 16.0) << x << ", " << y;
      }
  // A CoC above kMaxDiscCocPx keeps the diffusion: its prefix sums would grow as its square.
  const Image huge = make_coc(64, 64, [](auto, auto) { return 300.f; });
  EXPECT_TRUE(dof_detail::smooth_far_tiles(huge.plane(0), 1.f, 2).empty());
  // Far from the square, the step and the near pixel: chosen.
  for (const auto& [x, y] :
       {std::pair{8, 8}, std::pair{100, 100}, std::pair{70, 150}, std::pair{150, 20}})
    EXPECT_TRUE(chosen[std::size_t(y * kFrame + x)]) << x << ", " << y;
}

// The blend of the disc tiles into the diffusion around them, checked on the weights alone: the
// disc values of an all-ones image pasted over a zero body give each pixel its share, which
// must be min(1, d / kBlendPx), d the distance from the pixel's centre to the nearest of the
// 8 neighbouring tiles that did not take the disc (tiles beyond the frame count as disc
// tiles), computed here from the tile set.
TEST(DofBokeh, DiscTilesBlendIntoTheDiffusionOverKBlendPx) {
  constexpr std::ptrdiff_t kFrame = 96;
  // Far CoC 10, except a sharp pixel whose neighbourhood keeps the diffusion.
  Image coc = make_coc(kFrame, kFrame, [](auto, auto) { return 10.f; });
  coc(50, 45, 0) = 0.f;
  const std::vector<Rect> tiles = dof_detail::smooth_far_tiles(coc.plane(0), 1.f, 2);
  const Image ones = filled(kFrame, kFrame, 1, 1.f);
  const dof_detail::DiscTiles discs = dof_detail::gather_discs(ones, coc.plane(0), tiles, 2);
  Image out = filled(kFrame, kFrame, 1, 0.f);
  dof_detail::paste_discs(out, discs, 2);
  constexpr std::ptrdiff_t kTiles = kFrame / dof_detail::kDiscTile;
  std::vector<bool> disc(std::size_t(kTiles * kTiles), false);
  for (const Rect& tile : tiles)
    disc[std::size_t((tile.y / dof_detail::kDiscTile) * kTiles + tile.x / dof_detail::kDiscTile)] =
        true;
  std::ptrdiff_t blended = 0;
  for (std::ptrdiff_t y = 0; y < kFrame; ++y)
    for (std::ptrdiff_t x = 0; x < kFrame; ++x) {
      const std::ptrdiff_t tx = x / dof_detail::kDiscTile, ty = y / dof_detail::kDiscTile;
      if (!disc[std::size_t(ty * kTiles + tx)]) {
        ASSERT_EQ(out(x, y, 0), 0.f) << x << ", " << y;
        continue;
      }
      double nearest = dof_detail::kBlendPx;
      for (std::ptrdiff_t j = -1; j <= 1; ++j)
        for (std::ptrdiff_t i = -1; i <= 1; ++i) {
          const std::ptrdiff_t nx = tx + i, ny = ty + j;
          if (nx < 0 || ny < 0 || nx >= kTiles || ny >= kTiles ||
              disc[std::size_t(ny * kTiles + nx)])
            continue;
          // From the pixel's centre to the neighbouring tile's square.
          const double x0 = double(nx * dof_detail::kDiscTile),
                       y0 = double(ny * dof_detail::kDiscTile);
          const double px = double(x) + 0.5, py = double(y) + 0.5;
          const double across = std::max({x0 - px, px - (x0 + dof_detail::kDiscTile), 0.0});
          const double down = std::max({y0 - py, py - (y0 + dof_detail::kDiscTile), 0.0});
          nearest = std::min(nearest, std::hypot(across, down));
        }
      const double share = nearest / dof_detail::kBlendPx;
      blended += share < 1;
      ASSERT_NEAR(out(x, y, 0), share, 1e-6) << x << ", " << y;
    }
  EXPECT_GT(blended, 100);  // the test saw blending
}

// The body's blur where the CoC is not smooth (here it alternates by 1.2 px between 8 x 8
// blocks, so no tile takes the disc), on that texture, against the thin-lens disc of the mean
// CoC by brute force: with its conductance fitted to the disc's transfer function
// (kBodySpread, method_bokeh.cpp) it is nearer the disc than adi, whose blur only has the
// disc's variance (theory, 1/f^2 spectrum and a uniform CoC: 2.2 dB less squared error).
// Away from the borders (adi insulates them, the disc would fold).
TEST(DofBokeh, BodyIsNearerTheDiscThanAdiOnNaturalTexture) {
  constexpr std::ptrdiff_t kFrame = 256, kMargin = 40;
  const Image texture = natural_texture(kFrame, 5);
  for (const float diameter : {8.f, 16.f, 32.f}) {
    const Image coc = make_coc(kFrame, kFrame, [=](auto x, auto y) {
      return diameter + ((x / 8 + y / 8) % 2 == 0 ? 0.6f : -0.6f);
    });
    ASSERT_TRUE(dof_detail::smooth_far_tiles(coc.plane(0), 1.f, 2).empty());
    const Image body = run("bokeh", texture, coc), adi = run("adi", texture, coc);
    const BruteDisc disc(diameter);
    double body_error = 0, adi_error = 0;
    for (std::ptrdiff_t y = kMargin; y < kFrame - kMargin; ++y)
      for (std::ptrdiff_t x = kMargin; x < kFrame - kMargin; ++x) {
        const double lens = disc.average(texture, x, y);
        body_error += std::pow(body(x, y, 0) - lens, 2);
        adi_error += std::pow(adi(x, y, 0) - lens, 2);
      }
    const double gain_db = 10 * std::log10(adi_error / body_error);
    std::printf("[ measured ] CoC %g px: body %.2f dB nearer the disc than adi\n", diameter,
                gain_db);
    EXPECT_GT(gain_db, 1.5) << "CoC " << diameter;
  }
}

// Each strip of rows takes its highlights in the same order whichever thread takes it: the
// thread count changes no bit.
TEST(DofBokeh, ThreadCountChangesNoBit) {
  const Lamps f = dark_frame_with_lamps();
  DofOptions one = bladed(6), two = bladed(6);
  one.threads = 1;
  two.threads = 2;
  EXPECT_EQ(testing_util::differing_bits(run("bokeh", f.color, f.coc, one),
                                         run("bokeh", f.color, f.coc, two)),
            0);
}

// The round aperture's sprites add the rows' fully visible runs as steps, summed once a row
// (method_bokeh.cpp, SpriteStrip): 40 lamps over a 160 x 120 frame, a quarter within 3 px of
// the left or right border and a quarter of the top or bottom (their columns and rows fold),
// across the strips of 16 rows, each
// lamp's sprite the disc of its own CoC (16-22 px, slow enough that every sprite shows in
// full), against the sum of the lamps' discs by brute force as in the test above; and the
// thread count changes no bit (the strips go to whichever thread is free). Measured max
// error 4.8e-7 of a peak of 6.
TEST(DofBokeh, RoundSpritesAreTheirDiscsAcrossStripsAndBorders) {
  constexpr std::ptrdiff_t kWidth = 160, kHeight = 120;
  constexpr float kBodyKeeps = 0.25f;  // method_bokeh.cpp
  const auto diameter = [](std::ptrdiff_t x, std::ptrdiff_t y) {
    return 16.f + 6.f * float(x + y) / float(kWidth + kHeight);
  };
  const Image coc = make_coc(kWidth, kHeight, diameter);
  Image color = filled(kWidth, kHeight, 3, 0.f), clamped = color;
  std::vector<double> expected(std::size_t(3 * kWidth * kHeight), 0.0);
  std::mt19937 random(5);
  for (int i = 0; i < 40; ++i) {
    // A quarter of the lamps within 3 px of the left or right border, a quarter of the top or
    // bottom.
    std::ptrdiff_t x = std::uniform_int_distribution<std::ptrdiff_t>(0, kWidth - 1)(random);
    std::ptrdiff_t y = std::uniform_int_distribution<std::ptrdiff_t>(0, kHeight - 1)(random);
    if (i % 4 == 0) x = i % 8 == 0 ? x % 3 : kWidth - 1 - x % 3;
    if (i % 4 == 1) y = i % 8 == 1 ? y % 3 : kHeight - 1 - y % 3;
    const int c = i % 3;
    if (color(x, y, c) > 0) continue;  // one lamp a pixel and channel
    color(x, y, c) = 50.f + 10.f * float(i);
    clamped(x, y, c) = kBodyKeeps;
    const double outer = 0.5 * double(diameter(x, y)) + 0.5;
    const auto reach = std::ptrdiff_t(std::ceil(outer));
    double total = 0;
    for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy)
      for (std::ptrdiff_t dx = -reach; dx <= reach; ++dx)
        total += std::max(0.0, std::min(1.0, outer - std::hypot(double(dx), double(dy))));
    const auto fold = [](std::ptrdiff_t i, std::ptrdiff_t n) {
      return i < 0 ? -1 - i : i >= n ? 2 * n - 1 - i : i;
    };
    for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy)
      for (std::ptrdiff_t dx = -reach; dx <= reach; ++dx) {
        const double cover = std::min(1.0, outer - std::hypot(double(dx), double(dy)));
        if (cover > 0)
          expected[std::size_t((c * kHeight + fold(y + dy, kHeight)) * kWidth +
                               fold(x + dx, kWidth))] +=
              double(color(x, y, c) - kBodyKeeps) * cover / total;
      }
  }
  const Image bokeh = run("bokeh", color, coc), body = run("bokeh", clamped, coc);
  double peak = 0, worst = 0;
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < kHeight; ++y)
      for (std::ptrdiff_t x = 0; x < kWidth; ++x) {
        const double want = expected[std::size_t((c * kHeight + y) * kWidth + x)];
        peak = std::max(peak, want);
        worst = std::max(worst, std::fabs(double(bokeh(x, y, c)) - double(body(x, y, c)) - want));
      }
  std::printf("[ measured ] 40 round sprites against their discs: max error %.2g of peak %.3g\n",
              worst, peak);
  EXPECT_LT(worst, 1e-5 * peak);
  for (const int threads : {1, 3}) {
    DofOptions settings;
    settings.threads = threads;
    EXPECT_EQ(testing_util::differing_bits(run("bokeh", color, coc, settings), bokeh), 0)
        << threads << " threads";
  }
}

// Between the runs of a row no run is open, and there the steps' sum is reset to exactly 0: a
// sharp column (CoC 0, value 0) between the runs of large round sprites on either side of it
// (runs in other blocks of 16 pixels than the column's, so they take the steps; three lamps
// of different values on each side, so that the steps do not cancel exactly) stays 0, bit
// for bit.
TEST(DofBokeh, SharpPixelsBetweenRoundSpritesStayBitForBit) {
  constexpr std::ptrdiff_t kWidth = 128, kHeight = 64;
  Lamps f{filled(kWidth, kHeight, 3, 0.2f),
          make_coc(kWidth, kHeight, [](auto x, auto) { return x == 48 ? 0.f : 30.f; })};
  for (std::ptrdiff_t y = 0; y < kHeight; ++y)
    for (int c = 0; c < 3; ++c) f.color(48, y, c) = 0.f;
  for (int i = 0; i < 3; ++i) {
    f.color(20 + 4 * i, 30, 1) = 300.f + 170.f * float(i);
    f.color(86 + 4 * i, 30, 1) = 410.f + 130.f * float(i);
  }
  for (const int threads : {1, 2}) {
    DofOptions settings;
    settings.threads = threads;
    const Image out = run("bokeh", f.color, f.coc, settings);
    for (std::ptrdiff_t y = 0; y < kHeight; ++y)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(out(48, y, c), 0.f) << y << ", channel " << c;
    EXPECT_GT(out(40, 30, 1), 1.f);  // the sprites landed beside it
    EXPECT_GT(out(80, 30, 1), 1.f);
  }
}

// A sprite hidden by a near object in one strip of rows only (rows 16-31, x >= 48) and seen
// in full in the strips above and below it: the strip's test of full visibility must look at
// its own rows (a test that kept the rows' minima of the strip before would add the sprite
// over the near object). The near object's pixels get nothing of it; with the object gone
// from those rows, the same pixels get their share.
TEST(DofBokeh, SpriteHiddenInOneStripOnly) {
  constexpr std::ptrdiff_t kFrame = 96;
  Lamps f{filled(kFrame, kFrame, 3, 0.f),
          make_coc(kFrame, kFrame, [](auto, auto) { return 40.f; })};
  f.color(44, 24, 0) = f.color(44, 24, 1) = f.color(44, 24, 2) = 1000.f;
  const Image near = make_coc(
      kFrame, kFrame, [](auto x, auto y) { return x >= 48 && y >= 16 && y < 32 ? -12.f : 40.f; });
  DofOptions settings;
  settings.threads = 1;
  const Image open = run("bokeh", f.color, f.coc, settings);
  const Image hidden = run("bokeh", f.color, near, settings);
  double open_part = 0, hidden_part = 0;
  for (std::ptrdiff_t y = 16; y < 32; ++y)
    for (std::ptrdiff_t x = 56; x < 64; ++x) {
      open_part += open(x, y, 1);
      hidden_part += hidden(x, y, 1);
    }
  EXPECT_GT(open_part, 10.0);
  EXPECT_LT(hidden_part, 0.01 * open_part);
}

// Images of any number of channels (here 5, each the same lamp) take the round sprite's steps
// channel by channel: every channel's output is the same.
TEST(DofBokeh, RoundSpritesOfFiveChannels) {
  constexpr std::ptrdiff_t kFrame = 64;
  Image color = filled(kFrame, kFrame, 5, 0.1f);
  for (int c = 0; c < 5; ++c) color(30, 33, c) = 800.f;
  const Image coc = make_coc(kFrame, kFrame, [](auto, auto) { return 24.f; });
  const Image out = run("bokeh", color, coc);
  EXPECT_GT(out(30, 33, 0), 0.5f);
  for (std::ptrdiff_t y = 0; y < kFrame; ++y)
    for (std::ptrdiff_t x = 0; x < kFrame; ++x)
      for (int c = 1; c < 5; ++c) ASSERT_EQ(out(x, y, c), out(x, y, 0)) << x << ", " << y;
}

// A near object (CoC -12) over the right part of a far lamp's sprite (CoC +20) hides that part;
// the left part is as without it. With the hexagon (every pixel on the per-pixel path) and the
// round aperture (the runs it may hide on the vectorised path, the others as steps).
TEST(DofBokeh, NearObjectOccludesTheSprite) {
  Lamps f{filled(96, 96, 3, 0.f), make_coc(96, 96, [](auto, auto) { return 20.f; })};
  f.color(44, 48, 0) = f.color(44, 48, 1) = f.color(44, 48, 2) = 1000.f;
  const Image coc_near = make_coc(96, 96, [](auto x, auto) { return x >= 48 ? -12.f : 20.f; });
  for (const DofOptions& aperture : {bladed(6), DofOptions{}}) {
    const Image open = run("bokeh", f.color, f.coc, aperture);
    const Image hidden = run("bokeh", f.color, coc_near, aperture);
    double open_left = 0, hidden_left = 0, open_right = 0, hidden_right = 0;
    for (std::ptrdiff_t y = 0; y < 96; ++y)
      for (std::ptrdiff_t x = 0; x < 96; ++x) {
        (x < 48 ? open_left : open_right) += open(x, y, 1);
        (x < 48 ? hidden_left : hidden_right) += hidden(x, y, 1);
      }
    const int blades = aperture.aperture.blades;
    EXPECT_GT(open_right, 250.0) << blades;  // the part right of x = 47.5 (about 40 %)
    EXPECT_LT(hidden_right, 0.01 * open_right) << blades;
    EXPECT_NEAR(hidden_left / open_left, 1.0, 0.01) << blades;
  }
}

// A gain that overflows a float on a highlight is refused, naming it, by both methods that
// boost (an infinite excess would spread inf, and 0 x inf = NaN on hidden pixels).
TEST(DofBokeh, OverflowingGainIsRefused) {
  Lamps f{filled(32, 32, 3, 0.f), make_coc(32, 32, [](auto, auto) { return 8.f; })};
  f.color(10, 12, 0) = 1e10f;
  DofOptions settings;
  settings.highlight_threshold = 1;
  settings.highlight_gain = 1e30f;
  for (const char* method : {"bokeh", "scatter"}) {
    const auto thrown =
        testing_util::invalid_argument_of([&] { run(method, f.color, f.coc, settings); });
    EXPECT_EQ(thrown.argument, "highlight_gain") << method;
    EXPECT_TRUE(testing_util::contains(thrown.message, "pixel (10, 12)")) << method;
  }
  settings.highlight_gain = 1e20f;  // 1e30: finite
  EXPECT_NO_THROW(run("bokeh", f.color, f.coc, settings));
}

// Splats that would take too long (64 x 64 pixels of CoC 10^4 px: 3.2e11 weights) are refused at
// once, the largest CoC and its pixel named; bokeh splats only its highlights, so the same CoC
// over a dim frame with one light runs.
TEST(DofBokeh, SplatsThatWouldNotEndAreRefused) {
  Lamps f{filled(64, 64, 3, 4.f), make_coc(64, 64, [](auto, auto) { return 1e4f; })};
  f.coc(5, 7, 0) = -1.2e4f;
  for (const char* method : {"bokeh", "scatter"}) {
    const auto thrown = testing_util::invalid_argument_of([&] { run(method, f.color, f.coc, {}); });
    EXPECT_EQ(thrown.argument, "coc") << method;
    EXPECT_TRUE(testing_util::contains(thrown.message, "12000 px, at pixel (5, 7)"))
        << method << ": " << thrown.message;
  }
  Image dim = filled(64, 64, 3, 0.5f);
  dim(20, 20, 0) = 4.f;
  f.coc(20, 20, 0) = 500.f;  // one sprite of 2e5 weights
  EXPECT_NO_THROW(run("bokeh", dim, f.coc, {}));
  EXPECT_EQ(testing_util::invalid_argument_of([&] { run("scatter", dim, f.coc, {}); }).argument,
            "coc");
}

}  // namespace
}  // namespace tridiff
