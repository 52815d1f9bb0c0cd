// A physical truth for depth of field: a ray-traced scene (scene.hpp) rendered through the thin
// lens itself, every ray started at a point of the aperture. What every DOF method approximates
// from the pinhole image and its CoC map; unlike them it sees behind the edge of a blurred
// foreground. It does not clamp the blur at ThinLens::max_coc_px.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "tridiff/dof/aperture.hpp"
#include "tridiff/dof/scene.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

// The diameter (metres) of the disc on the lens plane z = 0 that rays start from, A d_f /
// (d_f - f) with A = f / N: with it a point at depth d is blurred over exactly
// |coc_thin_lens(d)| pixels of the pinhole framing (truth.cpp derives it).
double effective_aperture_m(const ThinLens& lens);

// Uniform points of an aperture shape from points of the unit square, so that stratified points
// of the square give stratified points of the shape: the circle by the concentric map (Shirley
// and Chiu 1997); a polygon (rounded or not) sector by sector, the angle from the inverse of
// its cumulative area, the radius sqrt(a) times the boundary's.
class ApertureSampler {
 public:
  explicit ApertureSampler(const ApertureShape& shape);  // validate(shape) first
  // The point (u, v) of the shape, unit-disc coordinates, for (a, b) in [0, 1)^2.
  std::array<float, 2> operator()(float a, float b) const;

 private:
  std::array<float, 2> polygon(float a, float b) const;
  ApertureShape shape_;
  std::vector<float> area_below_;  // cumulative area of a sector at kSteps + 1 equal angles
};

struct LensRenderOptions {
  int samples = 256;       // rays per pixel, a perfect square s^2: s x s aperture strata
  ApertureShape aperture;  // the circle by default
  std::uint64_t seed = 1;  // the same seed gives the same image, whatever the thread count
  int threads = 0;         // 0: all cores
};

// `scene` through its thin lens at width x height: per pixel, `samples` rays from jittered
// strata of the aperture to points of the focal plane z = focus_distance_m that the pinhole
// maps into the pixel (jittered strata of the pixel, paired with the aperture's at random).
// The pinhole render's framing exactly; mean colour, linear light.
Image render_thin_lens(const RayTracedScene& scene, std::ptrdiff_t width, std::ptrdiff_t height,
                       const LensRenderOptions& options = {});

// The truth and its noise: two renders of samples / 2 rays per pixel with disjoint random
// streams (seeds 1 and 2) and their mean, the truth (samples rays per pixel).
struct LensTruth {
  Image color;
  Image half_a, half_b;
};

// Rays per pixel of the truth by default (2 x 32^2). The PSNR between the two halves (sRGB,
// measured on 2 cores): 48.4 dB procedural, 43.7 lamps at 512 x 288; 53.2 and 48.2 at
// 1920 x 1080. The truth, their mean, is about 6 dB closer to the exact image than the halves
// are to each other (each half's noise variance s^2, their difference's 2 s^2, the mean's
// s^2 / 2: a factor 4), so 54-59 dB and 50-54 dB: 10 dB and more above the best method's PSNR
// against it, overall and in every region but in focus (tools/dof_truth_score.cpp).
inline constexpr int kDefaultTruthSamples = 2048;

// The built-in scene `name` (scene.hpp) through its lens with `samples` rays per pixel
// (samples / 2 a perfect square: 2, 8, 18, 32, ..., 512, ...; InvalidArgument otherwise).
LensTruth lens_truth_halves(std::string_view scene, std::ptrdiff_t width, std::ptrdiff_t height,
                            int samples = kDefaultTruthSamples, const ApertureShape& aperture = {},
                            int threads = 0);
Image lens_truth(std::string_view scene, std::ptrdiff_t width, std::ptrdiff_t height,
                 int samples = kDefaultTruthSamples, const ApertureShape& aperture = {},
                 int threads = 0);

}  // namespace tridiff
