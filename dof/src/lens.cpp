// The CoC models of lens.hpp.
#include "tridiff/dof/lens.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

void require_positive(float value, const char* name) {
  if (!(value > 0) || !std::isfinite(value))
    throw InvalidArgument(name, "must be finite and > 0, got " + std::to_string(value));
}

void require_non_negative(float value, const char* name) {
  if (!(value >= 0) || !std::isfinite(value))
    throw InvalidArgument(name, "must be finite and >= 0, got " + std::to_string(value));
}

template <class Model>
void coc_map(Plane coc, ConstPlane depth, int threads, Model model) {
  if (coc.width() != depth.width() || coc.height() != depth.height())
    throw InvalidArgument("coc", "size differs from the depth map");
  const int team = resolve_threads(threads);
#pragma omp parallel for num_threads(team) schedule(static)
  for (std::ptrdiff_t y = 0; y < depth.height(); ++y) {
    const float* d = depth.row(y);
    float* c = coc.row(y);
#pragma omp simd
    for (std::ptrdiff_t x = 0; x < depth.width(); ++x) c[x] = model(d[x]);
  }
}

// Linear ramp from 0 at `zero` to 1 at `full`.
float ramp(float distance, float zero, float full) {
  return std::clamp((distance - zero) / (full - zero), 0.f, 1.f);
}

}  // namespace

void validate(const ThinLens& lens) {
  require_positive(lens.focal_length_mm, "focal_length");
  require_positive(lens.f_number, "f_number");
  require_positive(lens.sensor_width_mm, "sensor_width");
  require_non_negative(lens.max_coc_px, "max_coc");
  require_positive(lens.focus_distance_m, "focus");
  if (lens.focus_distance_m * 1000.f <= lens.focal_length_mm)
    throw InvalidArgument("focus", "the focus distance " + std::to_string(lens.focus_distance_m) +
                                       " m must exceed the focal length (" +
                                       std::to_string(lens.focal_length_mm) + " mm)");
}

void validate(const ArtistCurve& curve) {
  require_non_negative(curve.near_start_m, "near_start");
  require_non_negative(curve.near_end_m, "near_end");
  require_non_negative(curve.far_start_m, "far_start");
  require_non_negative(curve.far_end_m, "far_end");
  require_non_negative(curve.near_radius_px, "near_radius");
  require_non_negative(curve.far_radius_px, "far_radius");
  // A region with a radius must have a ramp: an empty or reversed one would blur nothing,
  // silently. A radius of 0 is how a region is turned off.
  if (curve.near_radius_px > 0 && !(curve.near_end_m > curve.near_start_m))
    throw InvalidArgument("near_end", "must be beyond near_start (" +
                                          std::to_string(curve.near_start_m) +
                                          " m) when near_radius is > 0, got " +
                                          std::to_string(curve.near_end_m) + " m");
  if (curve.far_radius_px > 0 && !(curve.far_end_m > curve.far_start_m))
    throw InvalidArgument(
        "far_end", "must be beyond far_start (" + std::to_string(curve.far_start_m) +
                       " m) when far_radius is > 0, got " + std::to_string(curve.far_end_m) + " m");
  const bool near = curve.near_radius_px > 0;
  const bool far = curve.far_radius_px > 0;
  if (near && far && curve.far_start_m < curve.near_end_m)
    throw InvalidArgument("far_start", "the far region must start at or after near_end");
}

namespace {

// Seed 000 eq. 3.2 folded into c = scale * (1 - focus / d): the on-sensor diameter
// A f |d - d_f| / (d (d_f - f)), A = f / N, in pixels and signed (negative in front of the
// focus). One formula for the single value and the map, so that both agree to the last bit.
struct ThinLensFold {
  float scale, focus, max_coc;
  ThinLensFold(const ThinLens& lens, std::ptrdiff_t image_width_px) {
    const double f = lens.focal_length_mm * 1e-3, focus_m = lens.focus_distance_m;
    scale = float((f / lens.f_number) * f / (focus_m - f) * 1e3 / lens.sensor_width_mm *
                  double(image_width_px));
    focus = float(focus_m);
    max_coc = lens.max_coc_px;
  }
  float operator()(float distance_m) const {
    const float signed_coc = scale * (1.f - focus / distance_m);
    // Written out rather than std::clamp (whose references keep GCC 12 from vectorising).
    const float low = signed_coc < -max_coc ? -max_coc : signed_coc;
    return low > max_coc ? max_coc : low;
  }
};

}  // namespace

float coc_thin_lens(float distance_m, const ThinLens& lens, std::ptrdiff_t image_width_px) {
  return ThinLensFold(lens, image_width_px)(distance_m);
}

float coc_artist_curve(float distance_m, const ArtistCurve& curve) {
  const bool near = curve.near_end_m > curve.near_start_m && curve.near_radius_px > 0;
  const bool far = curve.far_end_m > curve.far_start_m && curve.far_radius_px > 0;
  if (near && distance_m < curve.near_end_m)
    return -2.f * curve.near_radius_px *
           (1.f - ramp(distance_m, curve.near_start_m, curve.near_end_m));
  if (far && distance_m > curve.far_start_m)
    return 2.f * curve.far_radius_px * ramp(distance_m, curve.far_start_m, curve.far_end_m);
  return 0.f;
}

void coc_thin_lens(Plane coc, ConstPlane depth, const ThinLens& lens, int threads) {
  validate(lens);
  coc_map(coc, depth, threads, ThinLensFold(lens, depth.width()));
}

void coc_artist_curve(Plane coc, ConstPlane depth, const ArtistCurve& curve, int threads) {
  validate(curve);
  coc_map(coc, depth, threads, [&](float d) { return coc_artist_curve(d, curve); });
}

}  // namespace tridiff
