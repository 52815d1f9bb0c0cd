// Vector arithmetic, procedural textures and the tracers of the ray-traced scenes (scene.cpp,
// scene_lamps.cpp), for the pinhole and the thin-lens renders. Library-internal.
#pragma once

#include <cmath>
#include <cstdint>

#include "tridiff/dof/scene.hpp"

namespace tridiff {

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(float s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 normalize(Vec3 a) { return (1.f / std::sqrt(dot(a, a))) * a; }

namespace scene_texture {

// Smooth value noise in [0, 1] from an integer hash, for texture variation.
inline float hash(std::int32_t x, std::int32_t y) {
  std::uint32_t h = std::uint32_t(x) * 374761393u + std::uint32_t(y) * 668265263u;
  h = (h ^ (h >> 13)) * 1274126177u;
  return float((h ^ (h >> 16)) & 0xffffff) / float(0xffffff);
}
inline float value_noise(float u, float v) {
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
inline float texture(float u, float v) {
  return 0.5f * value_noise(u, v) + 0.3f * value_noise(2.1f * u, 2.1f * v) +
         0.2f * value_noise(4.3f * u, 4.3f * v);
}

}  // namespace scene_texture

// The procedural scene's and the lamps scene's tracers and lenses (scene.cpp, scene_lamps.cpp).
RayHit trace_procedural(Vec3 origin, Vec3 direction);
ThinLens procedural_lens();
RayHit trace_lamps(Vec3 origin, Vec3 direction);
ThinLens lamps_lens();

}  // namespace tridiff
