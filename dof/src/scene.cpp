// The procedural scene: a pinhole camera at the origin looking down +z over a checkered
// floor, spheres at 2.5-11 m, lights on a brick wall at 18 m, a twig in front at 0.9 m.
#include "tridiff/dof/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

struct Vec {
  float x, y, z;
};
Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec operator-(Vec a, Vec b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec operator*(float s, Vec a) { return {s * a.x, s * a.y, s * a.z}; }
float dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec normalize(Vec a) { return (1.f / std::sqrt(dot(a, a))) * a; }

// Smooth value noise in [0, 1] from an integer hash, for texture variation.
float hash(std::int32_t x, std::int32_t y) {
  std::uint32_t h = std::uint32_t(x) * 374761393u + std::uint32_t(y) * 668265263u;
  h = (h ^ (h >> 13)) * 1274126177u;
  return float((h ^ (h >> 16)) & 0xffffff) / float(0xffffff);
}
float value_noise(float u, float v) {
  const float fu = std::floor(u), fv = std::floor(v);
  const auto iu = std::int32_t(fu), iv = std::int32_t(fv);
  float su = u - fu, sv = v - fv;
  su = su * su * (3 - 2 * su);
  sv = sv * sv * (3 - 2 * sv);
  const float top = hash(iu, iv) + su * (hash(iu + 1, iv) - hash(iu, iv));
  const float bottom = hash(iu, iv + 1) + su * (hash(iu + 1, iv + 1) - hash(iu, iv + 1));
  return top + sv * (bottom - top);
}
// Three octaves: a 1/f-like texture.
float texture(float u, float v) {
  return 0.5f * value_noise(u, v) + 0.3f * value_noise(2.1f * u, 2.1f * v) +
         0.2f * value_noise(4.3f * u, 4.3f * v);
}

struct Sphere {
  Vec center;
  float radius;
  Vec albedo;
  float stripes;  // stripe frequency on the surface (0: plain)
};

struct Hit {
  float t = std::numeric_limits<float>::infinity();
  Vec color{0, 0, 0};
};

constexpr float kFloorY = -1.1f, kWallZ = 18.f;
const Vec kLight = normalize({-0.5f, 0.8f, -0.4f});

const Sphere kSpheres[] = {
    {{0.2f, -0.45f, 4.6f}, 0.65f, {0.75f, 0.25f, 0.12f}, 9.f},  // in focus by default
    {{-2.4f, -0.5f, 8.5f}, 0.6f, {0.15f, 0.45f, 0.8f}, 0.f},
    {{0.75f, -0.3f, 2.5f}, 0.2f, {0.2f, 0.7f, 0.25f}, 14.f},
    {{3.4f, -0.2f, 11.f}, 0.9f, {0.8f, 0.75f, 0.6f}, 5.f},
};

void hit_floor(Vec dir, Hit& hit) {
  if (dir.y >= 0) return;
  const float t = kFloorY / dir.y;
  if (!(t < hit.t)) return;
  const Vec p = t * dir;
  const bool dark = (int(std::floor(p.x * 2)) + int(std::floor(p.z * 2))) & 1;
  const float grain = 0.6f + 0.4f * texture(p.x * 6, p.z * 6);
  const float base = dark ? 0.08f : 0.55f;
  hit = {t, {base * grain, base * grain * 0.95f, base * grain * 0.85f}};
}

void hit_wall(Vec dir, Hit& hit) {
  const float t = kWallZ / dir.z;
  if (!(t < hit.t)) return;
  const Vec p = t * dir;
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
  hit = {t, c};
}

void hit_sphere(Vec dir, const Sphere& s, Hit& hit) {
  const float b = dot(dir, s.center), c = dot(s.center, s.center) - s.radius * s.radius;
  const float a = dot(dir, dir);
  const float disc = b * b - a * c;
  if (disc < 0) return;
  const float t = (b - std::sqrt(disc)) / a;
  if (!(t > 0 && t < hit.t)) return;
  const Vec p = t * dir;
  const Vec n = (1.f / s.radius) * (p - s.center);
  float shade = 0.15f + 0.85f * std::max(0.f, dot(n, kLight));
  if (s.stripes > 0) shade *= 0.55f + 0.45f * (std::sin(s.stripes * std::atan2(n.x, n.z)) > 0);
  const Vec r = dir - 2 * dot(dir, n) / a * n;  // mirror direction: a specular glint
  const float glint = std::pow(std::max(0.f, dot(normalize(r), kLight)), 60.f) * 6.f;
  hit = {t, {s.albedo.x * shade + glint, s.albedo.y * shade + glint, s.albedo.z * shade + glint}};
}

// A twig close to the lens on the left: a slanted bar with leaves, the near-field object.
void hit_twig(Vec dir, Hit& hit) {
  const float z = 0.9f, t = z / dir.z;
  if (!(t < hit.t)) return;
  const Vec p = t * dir;
  const float along = p.y + 0.35f * p.x;  // slanted stem
  const float stem = std::abs(p.x + 0.14f - 0.12f * p.y);
  const bool on_stem = stem < 0.012f && p.y < 0.2f;
  const float leaf_u = (p.x + 0.2f) * 9, leaf_v = (along - 0.02f) * 9;
  const bool on_leaf = leaf_u * leaf_u + 4 * leaf_v * leaf_v < 0.6f;
  if (!on_stem && !on_leaf) return;
  const float vein = 0.7f + 0.3f * texture(p.x * 80, p.y * 80);
  hit = {t, on_leaf ? Vec{0.1f * vein, 0.35f * vein, 0.06f * vein} : Vec{0.2f, 0.12f, 0.05f}};
}

Hit trace(Vec dir) {
  Hit hit;
  hit_wall(dir, hit);
  hit_floor(dir, hit);
  for (const Sphere& s : kSpheres) hit_sphere(dir, s, hit);
  hit_twig(dir, hit);
  return hit;
}

}  // namespace

Scene procedural_scene(std::ptrdiff_t width, std::ptrdiff_t height, int threads) {
  Scene scene;
  scene.color.reset(width, height, 3);
  scene.depth.reset(width, height, 1);
  scene.lens = ThinLens{};
  scene.lens.focus_distance_m = kSpheres[0].center.z - kSpheres[0].radius;
  scene.lens.f_number = 1.8f;  // a fast lens: a shallow depth of field worth looking at
  // Pinhole: a pixel spans sensor_width / (focal_length * width) on the z = 1 plane.
  const float pixel = scene.lens.sensor_width_mm / (scene.lens.focal_length_mm * float(width));
  const int team = resolve_threads(threads);
#pragma omp parallel for num_threads(team) schedule(dynamic, 8)
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      auto ray = [&](float sx, float sy) {
        return Vec{(float(x) + sx - 0.5f * float(width)) * pixel,
                   (0.5f * float(height) - float(y) - sy) * pixel, 1.f};
      };
      Vec sum{0, 0, 0};
      for (float sy : {0.25f, 0.75f})
        for (float sx : {0.25f, 0.75f}) sum = sum + trace(ray(sx, sy)).color;
      scene.color(x, y, 0) = 0.25f * sum.x;
      scene.color(x, y, 1) = 0.25f * sum.y;
      scene.color(x, y, 2) = 0.25f * sum.z;
      scene.depth(x, y, 0) = trace(ray(0.5f, 0.5f)).t;
    }
  return scene;
}

}  // namespace tridiff
