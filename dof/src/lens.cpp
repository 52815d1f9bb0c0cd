// The CoC models of lens.hpp.
#include "tridiff/dof/lens.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

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

bool uses_focus_range(const ThinLens& lens) {
  return lens.focus_near_m != 0.f || lens.focus_far_m != 0.f;
}

void validate_focus_range(const ThinLens& lens) {
  require_positive(lens.focus_near_m, "focus_near");
  require_positive(lens.focus_far_m, "focus_far");
  if (lens.focus_near_m * 1000.f <= lens.focal_length_mm)
    throw InvalidArgument("focus_near", "the near end of the in-focus range, " +
                                            std::to_string(lens.focus_near_m) +
                                            " m, must exceed the focal length (" +
                                            std::to_string(lens.focal_length_mm) + " mm)");
  if (lens.focus_near_m > lens.focus_far_m)
    throw InvalidArgument("focus_far", "the far end of the in-focus range, " +
                                           std::to_string(lens.focus_far_m) +
                                           " m, is nearer than its near end, " +
                                           std::to_string(lens.focus_near_m) + " m");
}

}  // namespace

void validate(const ThinLens& lens) {
  require_positive(lens.focal_length_mm, "focal_length");
  require_positive(lens.f_number, "f_number");
  require_positive(lens.sensor_width_mm, "sensor_width");
  require_non_negative(lens.max_coc_px, "max_coc");
  if (uses_focus_range(lens)) {
    validate_focus_range(lens);
    return;
  }
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

// The factor of (1 - d_f / d) in the CoC, pixels: A f / (d_f - f), A = f / N, on the sensor.
float thin_lens_scale(const ThinLens& lens, float focus_m, std::ptrdiff_t image_width_px) {
  const double f = lens.focal_length_mm * 1e-3;
  return float((f / lens.f_number) * f / (double(focus_m) - f) * 1e3 / lens.sensor_width_mm *
               double(image_width_px));
}

// Seed 000 eq. 3.2 folded into c = scale * (1 - focus / d): the on-sensor diameter
// A f |d - d_f| / (d (d_f - f)), A = f / N, in pixels and signed (negative in front of the
// focus). One formula for the single value and the map, so that both agree to the last bit.
// An in-focus range focuses at its near end for nearer depths and at its far end for farther
// ones; a single focus distance is the range [d_f, d_f], computed exactly as before the range.
struct ThinLensFold {
  float near_scale, far_scale, near, far, max_coc;
  ThinLensFold(const ThinLens& lens, std::ptrdiff_t image_width_px) {
    const bool range = uses_focus_range(lens);
    near = range ? lens.focus_near_m : lens.focus_distance_m;
    far = range ? lens.focus_far_m : lens.focus_distance_m;
    near_scale = thin_lens_scale(lens, near, image_width_px);
    far_scale = thin_lens_scale(lens, far, image_width_px);
    max_coc = lens.max_coc_px;
  }
  float operator()(float distance_m) const {
    // Inside the range the focus is the depth itself: 1 - d / d is exactly 0 (a NaN stays NaN).
    const float focus = distance_m < near ? near : distance_m > far ? far : distance_m;
    const float scale = distance_m < near ? near_scale : far_scale;
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

float focus_depth_at(ConstPlane depth, std::ptrdiff_t x, std::ptrdiff_t y, int window) {
  if (x < 0 || y < 0 || x >= depth.width() || y >= depth.height())
    throw InvalidArgument("pixel", "(" + std::to_string(x) + ", " + std::to_string(y) +
                                       ") is outside the " + std::to_string(depth.width()) + " x " +
                                       std::to_string(depth.height()) + " depth map");
  if (window < 1 || window % 2 == 0)
    throw InvalidArgument("window", "must be odd and >= 1, got " + std::to_string(window));
  const std::ptrdiff_t reach = window / 2;
  std::vector<float> valid;
  valid.reserve(std::size_t(window) * std::size_t(window));
  for (std::ptrdiff_t v = std::max<std::ptrdiff_t>(0, y - reach);
       v <= std::min(depth.height() - 1, y + reach); ++v)
    for (std::ptrdiff_t u = std::max<std::ptrdiff_t>(0, x - reach);
         u <= std::min(depth.width() - 1, x + reach); ++u)
      if (std::isfinite(depth(u, v)) && depth(u, v) > 0) valid.push_back(depth(u, v));
  if (valid.empty())
    throw InvalidArgument("depth", "no finite depth > 0 in the " + std::to_string(window) + " x " +
                                       std::to_string(window) + " window around pixel (" +
                                       std::to_string(x) + ", " + std::to_string(y) + ")");
  const auto lower_middle = valid.begin() + std::ptrdiff_t(valid.size() - 1) / 2;
  std::nth_element(valid.begin(), lower_middle, valid.end());
  return *lower_middle;
}

}  // namespace tridiff
