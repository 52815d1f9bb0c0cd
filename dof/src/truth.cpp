// The thin-lens truth of truth.hpp: stratified aperture and pixel samples, one deterministic
// random stream per pixel, rays from the lens to the pinhole's focal-plane points.
#include "tridiff/dof/truth.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>
#include <utility>

#include "aperture_boundary.hpp"
#include "ray_math.hpp"
#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

constexpr int kSteps = 1024;  // angles per sector in the table of a polygon's cumulative area

// splitmix64: a good, tiny generator; seeded per pixel, so no pixel depends on the schedule.
class PixelRandom {
 public:
  PixelRandom(std::uint64_t seed, std::ptrdiff_t x, std::ptrdiff_t y)
      : state_(seed * 0x9e3779b97f4a7c15ull ^ (std::uint64_t(x) << 32) ^ std::uint64_t(y)) {
    next();
  }
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  float uniform() { return float(next() >> 40) * 0x1p-24f; }  // [0, 1)
  int below(int n) { return int((next() >> 33) % std::uint64_t(n)); }

 private:
  std::uint64_t state_;
};

int strata_of(int samples) {
  const int side = int(std::lround(std::sqrt(double(samples))));
  if (samples < 1 || side * side != samples)
    throw InvalidArgument("samples", "must be a perfect square >= 1 (s x s aperture strata), got " +
                                         std::to_string(samples));
  return side;
}

// Concentric map of the square [0, 1)^2 onto the unit disc (Shirley and Chiu 1997): area- and
// nearly shape-preserving, so that the strata stay compact.
std::array<float, 2> concentric_disc(float a, float b) {
  const float sx = 2 * a - 1, sy = 2 * b - 1;
  if (sx == 0 && sy == 0) return {0, 0};
  constexpr float kQuarter = std::numbers::pi_v<float> / 4;
  float r, angle;
  if (std::fabs(sx) > std::fabs(sy)) {
    r = sx;
    angle = kQuarter * (sy / sx);
  } else {
    r = sy;
    angle = 2 * kQuarter - kQuarter * (sx / sy);
  }
  return {r * std::cos(angle), r * std::sin(angle)};
}

// The pixel's random pairing of its aperture strata with its pixel-area strata (Fisher-Yates).
void shuffle(std::vector<int>& order, PixelRandom& random) {
  std::iota(order.begin(), order.end(), 0);
  for (int i = int(order.size()) - 1; i > 0; --i)
    std::swap(order[std::size_t(i)], order[std::size_t(random.below(i + 1))]);
}

}  // namespace

// A point Q at depth d seen through the lens point L lands on the focal plane z = d_f at
// F = Q d_f / d + L (1 - d_f / d): as L sweeps an aperture of diameter D, F sweeps a disc of
// diameter D |1 - d_f / d| around the pinhole image of Q. A pixel of the pinhole framing spans
// p d_f there, p = sensor_width / (f W), so the blur is D |1 - d_f / d| / (p d_f) pixels.
// coc_thin_lens is scale (1 - d_f / d) with scale = A f / (d_f - f) W / sensor_width (seed 000
// eq. 3.2: the sensor at f d_f / (d_f - f), not at f). Equal for D = scale p d_f =
// A d_f / (d_f - f): the real lens's magnification f / (d_f - f) against the pinhole's f / d_f.
double effective_aperture_m(const ThinLens& lens) {
  validate(lens);
  const double f = lens.focal_length_mm * 1e-3, focus = lens.focus_distance_m;
  return (f / lens.f_number) * focus / (focus - f);
}

ApertureSampler::ApertureSampler(const ApertureShape& shape) : shape_(shape) {
  validate(shape);
  if (shape.blades == 0 || shape.roundness == 1) return;
  // The area of a sector up to angle phi is the integral of R(phi)^2 / 2 (trapezoids).
  const float sector = 2 * std::numbers::pi_v<float> / float(shape.blades);
  area_below_.assign(kSteps + 1, 0.f);
  double area = 0, previous = 0.5 * std::pow(aperture_radius_in_sector(shape, 0), 2.f);
  for (int k = 1; k <= kSteps; ++k) {
    const double r = aperture_radius_in_sector(shape, sector * float(k) / kSteps);
    const double here = 0.5 * r * r;
    area += 0.5 * (previous + here) * sector / kSteps;
    area_below_[std::size_t(k)] = float(area);
    previous = here;
  }
  for (float& value : area_below_) value /= float(area);
}

std::array<float, 2> ApertureSampler::operator()(float a, float b) const {
  if (area_below_.empty()) return concentric_disc(a, b);
  return polygon(a, b);
}

std::array<float, 2> ApertureSampler::polygon(float a, float b) const {
  const int blades = shape_.blades;
  const int index = std::min(int(b * float(blades)), blades - 1);
  const float fraction = b * float(blades) - float(index);  // how far into the sector's area
  const auto above = std::upper_bound(area_below_.begin(), area_below_.end(), fraction);
  const auto k = std::clamp<std::ptrdiff_t>(above - area_below_.begin(), 1, kSteps);
  const float low = area_below_[std::size_t(k - 1)], high = area_below_[std::size_t(k)];
  const float step = high > low ? (fraction - low) / (high - low) : 0.f;
  const float sector = 2 * std::numbers::pi_v<float> / float(blades);
  const float phi = sector * (float(k - 1) + step) / kSteps;
  const float corner =
      std::numbers::pi_v<float> / 2 + shape_.rotation_deg * std::numbers::pi_v<float> / 180;
  const float angle = corner + sector * float(index) + phi;
  const float r = aperture_radius_in_sector(shape_, phi) * std::sqrt(a);
  return {r * std::cos(angle), r * std::sin(angle)};
}

Image render_thin_lens(const RayTracedScene& scene, std::ptrdiff_t width, std::ptrdiff_t height,
                       const LensRenderOptions& options) {
  const int strata = strata_of(options.samples);
  const ApertureSampler sampler(options.aperture);
  Image out(width, height, 3);
  const ThinLens& lens = scene.lens;
  const float radius = float(0.5 * effective_aperture_m(lens));
  const float focus = lens.focus_distance_m;
  // The pinhole's framing (render_pinhole): a pixel spans this on the z = 1 plane.
  const float pixel = lens.sensor_width_mm / (lens.focal_length_mm * float(width));
  const int team = resolve_threads(options.threads);
#pragma omp parallel num_threads(team)
  {
    std::vector<int> pixel_stratum(std::size_t(options.samples));
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        PixelRandom random(options.seed, x, y);
        shuffle(pixel_stratum, random);
        double sum[3] = {0, 0, 0};
        for (int k = 0; k < options.samples; ++k) {
          const float a = (float(k % strata) + random.uniform()) / float(strata);
          const float b = (float(k / strata) + random.uniform()) / float(strata);
          const int p = pixel_stratum[std::size_t(k)];
          const float sx = (float(p % strata) + random.uniform()) / float(strata);
          const float sy = (float(p / strata) + random.uniform()) / float(strata);
          const auto [u, v] = sampler(a, b);
          const Vec3 on_focal_plane{(float(x) + sx - 0.5f * float(width)) * pixel * focus,
                                    (0.5f * float(height) - float(y) - sy) * pixel * focus, focus};
          const Vec3 on_lens{radius * u, radius * v, 0.f};
          // z = 1, as the pinhole's rays (RayTracedScene::trace).
          const Vec3 direction = (1.f / focus) * (on_focal_plane - on_lens);
          const Vec3 color = scene.trace(on_lens, direction).color;
          sum[0] += color.x;
          sum[1] += color.y;
          sum[2] += color.z;
        }
        for (int c = 0; c < 3; ++c) out(x, y, c) = float(sum[c] / options.samples);
      }
  }
  return out;
}

LensTruth lens_truth_halves(std::string_view name, std::ptrdiff_t width, std::ptrdiff_t height,
                            int samples, const ApertureShape& aperture, int threads) {
  if (samples < 2 || samples % 2 != 0 ||
      std::lround(std::sqrt(samples / 2.0)) * std::lround(std::sqrt(samples / 2.0)) != samples / 2)
    throw InvalidArgument("samples",
                          "the truth's rays per pixel must be twice a perfect square "
                          "(2, 8, 18, 32, ..., 512), got " +
                              std::to_string(samples));
  const RayTracedScene scene = find_ray_traced_scene(name);
  LensRenderOptions options{samples / 2, aperture, 1, threads};
  LensTruth truth;
  truth.half_a = render_thin_lens(scene, width, height, options);
  options.seed = 2;
  truth.half_b = render_thin_lens(scene, width, height, options);
  truth.color.reset(width, height, 3);
  for (int c = 0; c < 3; ++c)
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x)
        truth.color(x, y, c) = 0.5f * (truth.half_a(x, y, c) + truth.half_b(x, y, c));
  return truth;
}

Image lens_truth(std::string_view name, std::ptrdiff_t width, std::ptrdiff_t height, int samples,
                 const ApertureShape& aperture, int threads) {
  return lens_truth_halves(name, width, height, samples, aperture, threads).color;
}

}  // namespace tridiff
