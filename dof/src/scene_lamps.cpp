// The `lamps` scene: an evening street framed like the procedural scene (50 mm, full frame),
// focused at 3 m at f/1.4. Strings of small bright lamps (8-40, far above 1) hang at 6-24 m
// behind the focus in front of a lit facade at 45 m; a sign board stands at the focus; a ball
// just in front of it (its CoC -2.8 to -5 px at 1920 wide); a post and rail at 1.15 m (CoC
// -52 px at 1920) cover the ball's left part and bottom. There a near layer cut at CoC <= -1 px
// must blur the post over the slightly defocused ball, not keep its silhouette sharp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "ray_math.hpp"

namespace tridiff {
namespace {

using scene_texture::hash;
using scene_texture::texture;

constexpr float kFocus = 3.f;
constexpr float kGroundY = -1.1f, kFacadeZ = 45.f;
constexpr float kPostZ = 1.15f;
const Vec3 kLight = normalize({-0.6f, 0.7f, -0.5f});

// A ray's parameter where it reaches the plane z = `z` (infinity if it never does).
float plane_z(Vec3 origin, Vec3 dir, float z) {
  const float t = (z - origin.z) / dir.z;
  return t > 0 ? t : std::numeric_limits<float>::infinity();
}

// A facade of windows, some lit: dim light everywhere behind the lamps.
void hit_facade(Vec3 origin, Vec3 dir, RayHit& hit) {
  const float t = plane_z(origin, dir, kFacadeZ);
  if (!(t < hit.t)) return;
  const Vec3 p = origin + t * dir;
  const float column = std::floor(p.x / 3.f), floor_row = std::floor(p.y / 3.5f);
  const float u = p.x / 3.f - column, v = p.y / 3.5f - floor_row;
  const bool window = u > 0.3f && u < 0.7f && v > 0.25f && v < 0.75f;
  const float lit = hash(std::int32_t(column), std::int32_t(floor_row) + 101);
  const float grain = 0.7f + 0.3f * texture(p.x * 2, p.y * 2);
  Vec3 c{0.02f * grain, 0.02f * grain, 0.035f * grain};
  if (window && lit > 0.45f) c = (0.1f + 0.5f * lit) * Vec3{1.f, 0.7f, 0.35f};
  hit = {t, c};
}

void hit_ground(Vec3 origin, Vec3 dir, RayHit& hit) {
  if (dir.y >= 0) return;
  const float t = (kGroundY - origin.y) / dir.y;
  if (!(t < hit.t)) return;
  const Vec3 p = origin + t * dir;
  const float g = 0.025f + 0.035f * texture(p.x * 5, p.z * 5);
  hit = {t, {g, g * 0.95f, g * 0.9f}};
}

// One string of lamps across the street at depth z: bulbs every `spacing` metres, sagging in a
// parabola from `end_height` (in units of z: the image's tan) at its ends by 0.04 z, each a
// sphere of angular radius 0.0025 (about 0.9 px at 512 wide). The farther strings hang lower in
// the image, the lowest behind the sign's top edge and all behind the post.
struct LampString {
  float z, end_height, spacing;
  std::int32_t seed;
  float radius() const { return 0.0025f * z; }
  float half_width() const { return 0.5f * z; }  // beyond the frame's 0.36 z, blur included
  float height(float x) const {
    const float s = x / half_width();
    return z * (end_height - 0.04f * (1 - s * s));
  }
};

constexpr LampString kStrings[] = {
    {6.f, 0.19f, 0.42f, 1},  {8.5f, 0.15f, 0.55f, 2},  {12.f, 0.115f, 0.7f, 3},
    {17.f, 0.08f, 0.95f, 4}, {24.f, 0.045f, 1.25f, 5},
};

Vec3 lamp_color(std::int32_t index, std::int32_t seed) {
  const float power = 8.f + 32.f * hash(index, seed);
  const float kind = hash(index, seed + 50);
  if (kind < 0.12f) return power * Vec3{1.f, 0.25f, 0.15f};  // red
  if (kind < 0.2f) return power * Vec3{0.3f, 1.f, 0.45f};    // green
  if (kind < 0.28f) return power * Vec3{0.35f, 0.5f, 1.f};   // blue
  return power * Vec3{1.f, 0.72f, 0.38f};                    // warm white
}

void hit_lamp(Vec3 origin, Vec3 dir, const LampString& lamps, std::int32_t index, RayHit& hit) {
  const float x = float(index) * lamps.spacing;
  if (std::fabs(x) > lamps.half_width()) return;
  const Vec3 to_center = Vec3{x, lamps.height(x), lamps.z} - origin;
  const float a = dot(dir, dir), b = dot(dir, to_center);
  const float c = dot(to_center, to_center) - lamps.radius() * lamps.radius();
  const float disc = b * b - a * c;
  if (disc < 0) return;
  const float t = (b - std::sqrt(disc)) / a;
  if (!(t > 0 && t < hit.t)) return;
  hit = {t, lamp_color(index, lamps.seed)};
}

// Only the bulbs next to where the ray crosses the string's plane can be hit: the bulbs are far
// smaller than their spacing, so three candidates instead of every bulb of every string.
void hit_string(Vec3 origin, Vec3 dir, const LampString& lamps, RayHit& hit) {
  if (!(plane_z(origin, dir, lamps.z - lamps.radius()) < hit.t)) return;  // the bulbs' fronts
  const float t = plane_z(origin, dir, lamps.z);
  const float nearest = std::round((origin.x + t * dir.x) / lamps.spacing);
  for (float i = nearest - 1; i <= nearest + 1; ++i)
    hit_lamp(origin, dir, lamps, std::int32_t(i), hit);
}

// The subject at the focus: a sign board with rows of dark glyphs (fine detail to keep sharp).
void hit_sign(Vec3 origin, Vec3 dir, RayHit& hit) {
  const float t = plane_z(origin, dir, kFocus);
  if (!(t < hit.t)) return;
  const Vec3 p = origin + t * dir;
  if (p.x < 0.05f || p.x > 0.8f || p.y < -0.9f || p.y > 0.3f) return;
  const bool frame = p.x < 0.08f || p.x > 0.77f || p.y > 0.27f;
  const float row = std::floor(p.y / 0.06f), cell = std::floor(p.x / 0.035f);
  const float in_row = p.y / 0.06f - row, in_cell = p.x / 0.035f - cell;
  const bool glyph = in_row > 0.2f && in_row < 0.8f && in_cell > 0.15f && in_cell < 0.85f &&
                     hash(std::int32_t(cell), std::int32_t(row) + 7) > 0.45f;
  const float light = 0.5f + 0.35f * texture(p.x * 30, p.y * 30);
  Vec3 c = light * Vec3{0.85f, 0.78f, 0.6f};
  if (glyph) c = 0.15f * c;
  if (frame) c = {0.3f, 0.08f, 0.05f};
  hit = {t, c};
}

// The second subject, just in front of the focus: a striped ball from 2.60 to 2.76 m, with a
// specular glint.
void hit_ball(Vec3 origin, Vec3 dir, RayHit& hit) {
  const Vec3 center{-0.45f, -0.30f, 2.76f};
  constexpr float radius = 0.16f;
  const Vec3 to_center = center - origin;
  const float a = dot(dir, dir), b = dot(dir, to_center);
  const float disc = b * b - a * (dot(to_center, to_center) - radius * radius);
  if (disc < 0) return;
  const float t = (b - std::sqrt(disc)) / a;
  if (!(t > 0 && t < hit.t)) return;
  const Vec3 n = (1.f / radius) * (origin + t * dir - center);
  float shade = 0.08f + 0.8f * std::max(0.f, dot(n, kLight));
  shade *= 0.5f + 0.5f * (std::sin(12.f * std::atan2(n.x, n.z) + 6.f * n.y) > 0);
  const Vec3 mirror = dir - 2 * dot(dir, n) / a * n;
  const float glint = std::pow(std::max(0.f, dot(normalize(mirror), kLight)), 80.f) * 5.f;
  hit = {t, {0.2f * shade + glint, 0.55f * shade + glint, 0.6f * shade + glint}};
}

// The near object: a post from the ground up out of the frame and a rail to its left.
void hit_post(Vec3 origin, Vec3 dir, RayHit& hit) {
  const float t = plane_z(origin, dir, kPostZ);
  if (!(t < hit.t)) return;
  const Vec3 p = origin + t * dir;
  const bool post = p.x > -0.255f && p.x < -0.215f;
  const bool rail = p.x <= -0.215f && p.y > -0.185f && p.y < -0.16f;
  if (!post && !rail) return;
  const float rust = 0.7f + 0.3f * texture(p.x * 120, p.y * 120);
  hit = {t, rust * Vec3{0.16f, 0.2f, 0.13f}};
}

}  // namespace

RayHit trace_lamps(Vec3 origin, Vec3 direction) {
  RayHit hit;
  hit_facade(origin, direction, hit);
  hit_ground(origin, direction, hit);
  for (const LampString& lamps : kStrings) hit_string(origin, direction, lamps, hit);
  hit_sign(origin, direction, hit);
  hit_ball(origin, direction, hit);
  hit_post(origin, direction, hit);
  return hit;
}

ThinLens lamps_lens() {
  ThinLens lens;
  lens.focus_distance_m = kFocus;
  // At 1920 wide the CoC scale is 32.3 px: the post -52 px, the facade +30, the lamps +16-28.
  lens.f_number = 1.4f;
  return lens;
}

}  // namespace tridiff
