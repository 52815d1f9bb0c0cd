// The built-in ray-traced scenes (colour and depth), so that depth of field can be shown and
// measured with nothing to download: `procedural` (textured surfaces at several depths, a
// foreground object, bright highlights) and `lamps` (an evening scene, many small lamps far
// behind the focus, a subject at the focus, a second just in front of it and a near post partly
// over that one). Each is a tracer of rays plus the lens it was made for: a pinhole render gives
// the sharp colour the DOF methods blur; truth.hpp renders the same scene through the thin lens.
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <string_view>

#include "tridiff/dof/lens.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct Scene {
  Image color;    // linear light, RGB; highlights exceed 1
  Image depth;    // distance along the optical axis, metres, one channel
  ThinLens lens;  // the camera the scene was rendered for
};

struct Vec3 {
  float x = 0, y = 0, z = 0;
};

// What a ray origin + t direction sees first: its t (infinity: nothing) and the radiance there.
struct RayHit {
  float t = std::numeric_limits<float>::infinity();
  Vec3 color;
};

// A scene as a ray tracer sees it. Camera space: the lens centre (or pinhole) at the origin,
// looking down +z, +x right, +y up; metres. Every ray's direction has z = 1 (so that t is the
// depth gained; the built-in scenes' glints assume a direction of about unit length). `trace`
// is called from many threads at once.
struct RayTracedScene {
  std::string name;
  ThinLens lens;  // focal length, sensor width, f-number and focus the scene is framed for
  std::function<RayHit(Vec3 origin, Vec3 direction)> trace;
};

// The built-in scenes' names: "procedural", "lamps".
std::span<const std::string_view> ray_traced_scene_names();
// The scene called `name` (InvalidArgument listing the known names otherwise).
RayTracedScene find_ray_traced_scene(std::string_view name);

// The scene through a pinhole at the origin: pixel (x, y) spans sensor_width / (focal_length *
// width) on the z = 1 plane, image centre on the axis. Colour: the mean of supersample^2 rays
// at a regular grid of points in the pixel; depth: the z of the first hit of the ray through
// the pixel centre.
Scene render_pinhole(const RayTracedScene& scene, std::ptrdiff_t width, std::ptrdiff_t height,
                     int supersample = 2, int threads = 0);

// render_pinhole of the built-in scene `name` (2 x 2 samples per pixel).
Scene ray_traced_scene(std::string_view name, std::ptrdiff_t width, std::ptrdiff_t height,
                       int threads = 0);

// ray_traced_scene("procedural", ...): a checkered floor, spheres at 2.5-11 m (focus on the
// nearest large one), lights on a brick wall at 18 m, a twig at 0.9 m; f/1.8.
Scene procedural_scene(std::ptrdiff_t width, std::ptrdiff_t height, int threads = 0);

// ray_traced_scene("lamps", ...): focus 3 m, f/1.4; see scene_lamps.cpp.
Scene lamps_scene(std::ptrdiff_t width, std::ptrdiff_t height, int threads = 0);

}  // namespace tridiff
