// Circle-of-confusion models: the physical thin lens (seed 000 eq. 3.2) and the artist's
// piecewise-linear curve (seed 002 §28.5.3). Both give a signed CoC diameter in pixels:
// negative in front of the focus (near field), positive behind it (far field).
#pragma once

#include "tridiff/image/image.hpp"

namespace tridiff {

struct ThinLens {
  float focal_length_mm = 50.f;
  float f_number = 2.8f;
  float focus_distance_m = 3.2f;
  float sensor_width_mm = 36.f;  // full frame; the image width maps onto it
  float max_coc_px = 64.f;       // |CoC| is clamped to this (a blur budget, as in seed 000 §5.2)
  // An in-focus range, metres (both 0: unused, the lens focuses at focus_distance_m alone).
  // Depths in [focus_near_m, focus_far_m] are sharp; nearer ones blur as if the lens focused
  // at focus_near_m, farther ones as if it focused at focus_far_m, so the CoC is continuous at
  // both ends. When the range is used, focus_distance_m is not (nor validated).
  float focus_near_m = 0.f, focus_far_m = 0.f;
};

// Seed 002 §28.5.3: blur radii at the near and far ends, falling linearly to zero across
// [near_start, near_end] and rising across [far_start, far_end]; distances in metres. A
// region with a zero radius has no blur, so artists can blur only the foreground or only the
// background; a region with a radius needs end beyond start (validate() refuses an empty or
// reversed one, which would blur nothing). coc_artist_curve(distance, curve) alone does not
// validate: a degenerate region there gives no blur.
struct ArtistCurve {
  float near_start_m = 0.f, near_end_m = 0.f;
  float far_start_m = 0.f, far_end_m = 0.f;
  float near_radius_px = 0.f, far_radius_px = 0.f;
};

// Throws InvalidArgument naming the bad parameter.
void validate(const ThinLens& lens);
void validate(const ArtistCurve& curve);

// Signed CoC diameter in pixels of a point at `distance_m` for an image `image_width_px` wide.
// Thin lens: c = A f |d - d_f| / (d (d_f - f)) on the sensor, A = f / N (seed 000 eq. 3.2
// rewritten), scaled by pixels per millimetre of sensor; with an in-focus range, d_f is its
// near end in front of it, its far end behind it, and c = 0 inside it.
float coc_thin_lens(float distance_m, const ThinLens& lens, std::ptrdiff_t image_width_px);
float coc_artist_curve(float distance_m, const ArtistCurve& curve);

// The CoC map of a depth map (linear distance in metres, every value finite and > 0).
void coc_thin_lens(Plane coc, ConstPlane depth, const ThinLens& lens, int threads = 0);
void coc_artist_curve(Plane coc, ConstPlane depth, const ArtistCurve& curve, int threads = 0);

// The depth to focus on when the user points at pixel (x, y): the median of the valid depths
// (finite and > 0) in the `window` x `window` square around it (odd, clipped to the frame), so
// that a pixel on or next to an edge, or a stray bad value, focuses on the surface the pixel
// belongs to (the majority of its window) rather than on the edge's other side or on an
// average that lies on neither. With an even count, the lower (nearer) of the two middle
// values: a tie between two surfaces focuses on the nearer one, the usual subject.
// InvalidArgument naming "pixel" (outside the frame), "window" (not odd and >= 1) or "depth"
// (no valid depth in the window).
inline constexpr int kFocusWindow = 5;
float focus_depth_at(ConstPlane depth, std::ptrdiff_t x, std::ptrdiff_t y,
                     int window = kFocusWindow);

}  // namespace tridiff
