// The procedural scene (a camera at the origin looking down +z over a checkered floor, spheres
// at 2.5-11 m, lights on a brick wall at 18 m, a twig in front at 0.9 m), the list of built-in
// ray-traced scenes, and the pinhole render of any of them.
#include "tridiff/dof/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "ray_math.hpp"
#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

using scene_texture::texture;
using Vec = Vec3;
using Hit = RayHit;

struct Sphere {
  Vec center;
  float radius;
  Vec albedo;
  float stripes;  // stripe frequency on the surface (0: plain)
};

constexpr float kFloorY = -1.1f, kWallZ = 18.f;
const Vec kLight = normalize({-0.5f, 0.8f, -0.4f});

const Sphere kSpheres[] = {
    {{0.2f, -0.45f, 4.6f}, 0.65f, {0.75f, 0.25f, 0.12f}, 9.f},  // in focus by default
    {{-2.4f, -0.5f, 8.5f}, 0.6f, {0.15f, 0.45f, 0.8f}, 0.f},
    {{0.75f, -0.3f, 2.5f}, 0.2f, {0.2f, 0.7f, 0.25f}, 14.f},
    {{3.4f, -0.2f, 11.f}, 0.9f, {0.8f, 0.75f, 0.6f}, 5.f},
};

// Every ray starts at `origin` (a point of the lens; the pinhole's is 0). With origin 0 these
// are the former pinhole formulas value for value (0 + x is x); only where the compiler fuses
// a multiply and an add differently does the colour move, by at most 6e-6 relative (measured
// at 333 x 211; the depth is unchanged bit for bit).
//
// A ray first finds its nearest surface (each test only compares distances, in the order wall,
// floor, spheres, twig, a nearer hit replacing a farther one), and only that surface is shaded:
// shading every surface passed on the way (the wall behind everything) cost a third of the
// render. Each shade_* computes what its hit test would have, from the same t.
enum class Surface { none, wall, floor, sphere, twig };
struct Nearest {
  float t = std::numeric_limits<float>::infinity();
  Surface surface = Surface::none;
  const Sphere* sphere = nullptr;
};

void find_floor(Vec origin, Vec dir, Nearest& nearest) {
  if (dir.y >= 0) return;
  const float t = (kFloorY - origin.y) / dir.y;
  if (t < nearest.t) nearest = {t, Surface::floor};
}

Vec shade_floor(Vec origin, Vec dir, float t) {
  const Vec p = origin + t * dir;
  const bool dark = (int(std::floor(p.x * 2)) + int(std::floor(p.z * 2))) & 1;
  const float grain = 0.6f + 0.4f * texture(p.x * 6, p.z * 6);
  const float base = dark ? 0.08f : 0.55f;
  return {base * grain, base * grain * 0.95f, base * grain * 0.85f};
}

void find_wall(Vec origin, Vec dir, Nearest& nearest) {
  const float t = (kWallZ - origin.z) / dir.z;
  if (t < nearest.t) nearest = {t, Surface::wall};
}

Vec shade_wall(Vec origin, Vec dir, float t) {
  const Vec p = origin + t * dir;
  // Bricks 0.5 x 0.25 m with mortar, rows offset by half a brick.
  const float row = std::floor(p.y * 4);
  const float u = p.x * 2 + (int(row) & 1) * 0.5f;
  const bool mortar = (p.y * 4 - row) < 0.08f || (u - std::floor(u)) < 0.04f;
  const float tone = 0.5f + 0.5f * texture(std::floor(u) * 3.7f, row * 1.3f);
  Vec c = mortar ? Vec{0.35f, 0.35f, 0.33f} : Vec{0.45f * tone, 0.16f * tone, 0.1f * tone};
  // Lights: small hot dots on a grid, the highlights that show the bokeh.
  const float lx = p.x * 1.25f, ly = p.y * 1.25f - 0.3f;
  const float dx = lx - std::round(lx), dy = ly - std::round(ly);
  if (p.y > 0.2f && dx * dx + dy * dy < 0.004f) c = Vec{12.f, 9.f, 5.f};
  return c;
}

void find_sphere(Vec origin, Vec dir, const Sphere& s, Nearest& nearest) {
  const Vec to_center = s.center - origin;
  const float b = dot(dir, to_center), c = dot(to_center, to_center) - s.radius * s.radius;
  const float a = dot(dir, dir);
  const float disc = b * b - a * c;
  if (disc < 0) return;
  const float t = (b - std::sqrt(disc)) / a;
  if (t > 0 && t < nearest.t) nearest = {t, Surface::sphere, &s};
}

Vec shade_sphere(Vec origin, Vec dir, const Sphere& s, float t) {
  const float a = dot(dir, dir);
  const Vec p = origin + t * dir;
  const Vec n = (1.f / s.radius) * (p - s.center);
  float shade = 0.15f + 0.85f * std::max(0.f, dot(n, kLight));
  if (s.stripes > 0) shade *= 0.55f + 0.45f * (std::sin(s.stripes * std::atan2(n.x, n.z)) > 0);
  const Vec r = dir - 2 * dot(dir, n) / a * n;  // mirror direction: a specular glint
  const float glint = std::pow(std::max(0.f, dot(normalize(r), kLight)), 60.f) * 6.f;
  return {s.albedo.x * shade + glint, s.albedo.y * shade + glint, s.albedo.z * shade + glint};
}

// A twig close to the lens on the left: a slanted bar with leaves, the near-field object.
struct TwigPoint {
  Vec p;
  bool on_stem, on_leaf;
};
TwigPoint twig_point(Vec origin, Vec dir, float t) {
  const Vec p = origin + t * dir;
  const float along = p.y + 0.35f * p.x;  // slanted stem
  const float stem = std::abs(p.x + 0.14f - 0.12f * p.y);
  const float leaf_u = (p.x + 0.2f) * 9, leaf_v = (along - 0.02f) * 9;
  return {p, stem < 0.012f && p.y < 0.2f, leaf_u * leaf_u + 4 * leaf_v * leaf_v < 0.6f};
}

constexpr float kTwigZ = 0.9f;

void find_twig(Vec origin, Vec dir, Nearest& nearest) {
  const float t = (kTwigZ - origin.z) / dir.z;
  if (!(t < nearest.t)) return;
  const TwigPoint at = twig_point(origin, dir, t);
  if (at.on_stem || at.on_leaf) nearest = {t, Surface::twig};
}

Vec shade_twig(Vec origin, Vec dir, float t) {
  const TwigPoint at = twig_point(origin, dir, t);
  const float vein = 0.7f + 0.3f * texture(at.p.x * 80, at.p.y * 80);
  return at.on_leaf ? Vec{0.1f * vein, 0.35f * vein, 0.06f * vein} : Vec{0.2f, 0.12f, 0.05f};
}

}  // namespace

RayHit trace_procedural(Vec3 origin, Vec3 direction) {
  Nearest nearest;
  find_wall(origin, direction, nearest);
  find_floor(origin, direction, nearest);
  for (const Sphere& s : kSpheres) find_sphere(origin, direction, s, nearest);
  find_twig(origin, direction, nearest);
  const float t = nearest.t;
  switch (nearest.surface) {
    case Surface::wall: return {t, shade_wall(origin, direction, t)};
    case Surface::floor: return {t, shade_floor(origin, direction, t)};
    case Surface::sphere: return {t, shade_sphere(origin, direction, *nearest.sphere, t)};
    case Surface::twig: return {t, shade_twig(origin, direction, t)};
    case Surface::none: break;
  }
  return {};
}

ThinLens procedural_lens() {
  ThinLens lens;
  lens.focus_distance_m = kSpheres[0].center.z - kSpheres[0].radius;
  lens.f_number = 1.8f;  // a fast lens: a shallow depth of field worth looking at
  return lens;
}

namespace {

constexpr std::array<std::string_view, 2> kSceneNames{"procedural", "lamps"};

}  // namespace

std::span<const std::string_view> ray_traced_scene_names() { return kSceneNames; }

RayTracedScene find_ray_traced_scene(std::string_view name) {
  if (name == "procedural") return {"procedural", procedural_lens(), trace_procedural};
  if (name == "lamps") return {"lamps", lamps_lens(), trace_lamps};
  throw InvalidArgument(
      "scene", "unknown ray-traced scene '" + std::string(name) + "' (known: procedural, lamps)");
}

Scene render_pinhole(const RayTracedScene& traced, std::ptrdiff_t width, std::ptrdiff_t height,
                     int supersample, int threads) {
  if (supersample < 1)
    throw InvalidArgument("supersample", "must be >= 1, got " + std::to_string(supersample));
  Scene scene;
  scene.color.reset(width, height, 3);
  scene.depth.reset(width, height, 1);
  scene.lens = traced.lens;
  // Pinhole: a pixel spans sensor_width / (focal_length * width) on the z = 1 plane.
  const float pixel = scene.lens.sensor_width_mm / (scene.lens.focal_length_mm * float(width));
  const float weight = 1.f / float(supersample * supersample);
  const Vec origin{0, 0, 0};
  const int team = resolve_threads(threads);
#pragma omp parallel for num_threads(team) schedule(dynamic, 8)
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      auto ray = [&](float sx, float sy) {
        return Vec{(float(x) + sx - 0.5f * float(width)) * pixel,
                   (0.5f * float(height) - float(y) - sy) * pixel, 1.f};
      };
      Vec sum{0, 0, 0};
      for (int j = 0; j < supersample; ++j)
        for (int i = 0; i < supersample; ++i) {
          const float sx = (float(i) + 0.5f) / float(supersample);
          const float sy = (float(j) + 0.5f) / float(supersample);
          sum = sum + traced.trace(origin, ray(sx, sy)).color;
        }
      scene.color(x, y, 0) = weight * sum.x;
      scene.color(x, y, 1) = weight * sum.y;
      scene.color(x, y, 2) = weight * sum.z;
      scene.depth(x, y, 0) = traced.trace(origin, ray(0.5f, 0.5f)).t;  // the ray's z is 1
    }
  return scene;
}

Scene ray_traced_scene(std::string_view name, std::ptrdiff_t width, std::ptrdiff_t height,
                       int threads) {
  return render_pinhole(find_ray_traced_scene(name), width, height, 2, threads);
}

Scene procedural_scene(std::ptrdiff_t width, std::ptrdiff_t height, int threads) {
  return ray_traced_scene("procedural", width, height, threads);
}

Scene lamps_scene(std::ptrdiff_t width, std::ptrdiff_t height, int threads) {
  return ray_traced_scene("lamps", width, height, threads);
}

}  // namespace tridiff
