// The built-in DOF test scenes: procedural colour and CoC, one function per scene.
#include "tridiff/dof/scenes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/scene.hpp"
#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

using Rgb = std::array<float, 3>;

struct Sample {
  Rgb color;
  float coc;
};

float hash01(std::int32_t x, std::int32_t y, std::uint32_t seed) {
  std::uint32_t h =
      std::uint32_t(x) * 374761393u + std::uint32_t(y) * 668265263u + seed * 2246822519u;
  h = (h ^ (h >> 13)) * 1274126177u;
  return float((h ^ (h >> 16)) & 0xffffff) / float(0xffffff);
}

float value_noise(double u, double v, std::uint32_t seed) {
  const double fu = std::floor(u), fv = std::floor(v);
  const auto iu = std::int32_t(fu), iv = std::int32_t(fv);
  float su = float(u - fu), sv = float(v - fv);
  su = su * su * (3 - 2 * su);
  sv = sv * sv * (3 - 2 * sv);
  const float top = hash01(iu, iv, seed) + su * (hash01(iu + 1, iv, seed) - hash01(iu, iv, seed));
  const float bottom =
      hash01(iu, iv + 1, seed) + su * (hash01(iu + 1, iv + 1, seed) - hash01(iu, iv + 1, seed));
  return top + sv * (bottom - top);
}

// A tinted texture at (u, v) in units of the frame's short side: checks 1/24 of it wide broken
// up by value noise at 1/48 and 1/12, values in [0.2, 0.95] x tint. Detail at the scale of a
// 4-64 px blur at 1024^2, so that any blur visibly changes it.
Rgb textured(double u, double v, Rgb tint, std::uint32_t seed) {
  const auto check_x = std::int64_t(std::floor(u * 24)), check_y = std::int64_t(std::floor(v * 24));
  const bool check = ((check_x + check_y) & 1) != 0;
  const float noise =
      0.6f * value_noise(u * 48, v * 48, seed) + 0.4f * value_noise(u * 12, v * 12, seed + 1);
  const float grey = 0.2f + 0.5f * noise + (check ? 0.25f : 0.f);
  return {tint[0] * grey, tint[1] * grey, tint[2] * grey};
}

// The frame and its coordinates: pixel centres in units of the short side (u, v) and as
// fractions of the frame (fx, fy).
struct Frame {
  std::ptrdiff_t width, height;
  double side;
  double u(std::ptrdiff_t x) const { return (double(x) + 0.5) / side; }
  double v(std::ptrdiff_t y) const { return (double(y) + 0.5) / side; }
  double fx(std::ptrdiff_t x) const { return (double(x) + 0.5) / double(width); }
  double fy(std::ptrdiff_t y) const { return (double(y) + 0.5) / double(height); }
};

template <class PixelFn>
DofScene paint(std::string name, std::ptrdiff_t width, std::ptrdiff_t height, int threads,
               PixelFn pixel) {
  DofScene scene{std::move(name), Image(width, height, 3), Image(width, height, 1)};
  const Frame frame{width, height, double(std::min(width, height))};
  const int team = resolve_threads(threads);
#pragma omp parallel for num_threads(team) schedule(static)
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const Sample s = pixel(frame, x, y);
      for (int c = 0; c < 3; ++c) scene.color(x, y, c) = s.color[std::size_t(c)];
      scene.coc(x, y, 0) = s.coc;
    }
  return scene;
}

// 000 fig. 6.3: a disc in front of the focus, blurred (CoC -24 px), over a sharp background.
Sample foreground_blur(const Frame& f, std::ptrdiff_t x, std::ptrdiff_t y) {
  const double du = f.u(x) - 0.5 * double(f.width) / f.side,
               dv = f.v(y) - 0.5 * double(f.height) / f.side;
  if (du * du + dv * dv < 0.28 * 0.28)
    return {textured(f.u(x) + 0.3, f.v(y), {0.25f, 0.55f, 0.95f}, 7), -24.f};
  return {textured(f.u(x), f.v(y), {0.95f, 0.8f, 0.55f}, 3), 0.f};
}

// 000 fig. 6.2: a sharp, saturated red cross in front of a background blurred behind the focus
// (CoC +24 px). A method that gathers without a depth test pulls the red into the background.
Sample sharp_foreground(const Frame& f, std::ptrdiff_t x, std::ptrdiff_t y) {
  const double dx = std::fabs(f.fx(x) - 0.5), dy = std::fabs(f.fy(y) - 0.5);
  const bool cross = (dx < 0.06 && dy < 0.35) || (dy < 0.06 && dx < 0.35);
  if (cross) {
    const float grain = 0.75f + 0.25f * value_noise(f.u(x) * 48, f.v(y) * 48, 11);
    return {{grain, 0.02f, 0.01f}, 0.f};
  }
  return {textured(f.u(x), f.v(y), {0.55f, 0.8f, 0.95f}, 5), 24.f};
}

// |CoC| >= 32 px over 90% of the frame: a far background (+40 px), a near block (-36 px) and a
// sharp vertical strip (8% of the frame), with depth edges between all three.
Sample large_coc(const Frame& f, std::ptrdiff_t x, std::ptrdiff_t y) {
  const double fx = f.fx(x), fy = f.fy(y);
  if (fx >= 0.6 && fx < 0.68) return {textured(f.u(x), f.v(y), {0.95f, 0.95f, 0.9f}, 13), 0.f};
  if (fx >= 0.1 && fx < 0.45 && fy >= 0.2 && fy < 0.8)
    return {textured(f.u(x), f.v(y), {0.3f, 0.9f, 0.4f}, 17), -36.f};
  return {textured(f.u(x), f.v(y), {0.9f, 0.5f, 0.35f}, 19), 40.f};
}

// A tilted textured plane (a floor seen from above): CoC +28 px at the top (far) falling
// linearly through 0 at mid-height to -28 px at the bottom (near).
Sample depth_gradient(const Frame& f, std::ptrdiff_t x, std::ptrdiff_t y) {
  return {textured(f.u(x), f.v(y), {0.85f, 0.85f, 0.85f}, 23),
          static_cast<float>(28.0 - 56.0 * f.fy(y))};
}

// Bokeh: points of 5-20 (far above 1) on a dark background, all 20 px behind the focus. One
// point per cell of 1/8 of the short side, jittered; at least the pixel holding it is lit.
Sample highlights(const Frame& f, std::ptrdiff_t x, std::ptrdiff_t y) {
  const double cell = f.side / 8;
  const auto i = std::int32_t(std::floor((double(x) + 0.5) / cell)),
             j = std::int32_t(std::floor((double(y) + 0.5) / cell));
  const double px = (double(i) + 0.25 + 0.5 * hash01(i, j, 29)) * cell,
               py = (double(j) + 0.25 + 0.5 * hash01(i, j, 31)) * cell;
  const double dx = double(x) + 0.5 - px, dy = double(y) + 0.5 - py;
  const bool lit = (std::floor(px) == double(x) && std::floor(py) == double(y)) ||
                   dx * dx + dy * dy <= (f.side / 400) * (f.side / 400);
  if (lit) {
    const float power = 5.f + 15.f * hash01(i, j, 37);
    return {{power, power * 0.75f, power * 0.45f}, 20.f};
  }
  return {textured(f.u(x), f.v(y), {0.08f, 0.06f, 0.1f}, 41), 20.f};
}

constexpr std::array kScenes{
    DofSceneInfo{"foreground-blur",
                 "a blurred near disc must spread over the sharp background (000 fig. 6.3)"},
    DofSceneInfo{"sharp-foreground",
                 "a sharp red cross must not leak into the blurred background (000 fig. 6.2)"},
    DofSceneInfo{"large-coc", "|CoC| >= 32 px over 90% of the frame, near/far/sharp edges"},
    DofSceneInfo{"depth-gradient", "a tilted plane: CoC +28 px to -28 px, smoothly through 0"},
    DofSceneInfo{"highlights", "points of 5-20 on a dark blurred background: bokeh discs"},
    DofSceneInfo{"procedural", "the procedural scene with its thin-lens CoC: everything at once"},
    DofSceneInfo{"lamps",
                 "many lamps far behind the focus, a near post over a subject just in "
                 "front of it: bokeh and the near layer's edge"},
};

void require_size(std::ptrdiff_t width, std::ptrdiff_t height) {
  if (width < 1 || height < 1)
    throw InvalidArgument("size", std::to_string(width) + " x " + std::to_string(height) +
                                      " (a scene needs at least 1 x 1)");
}

}  // namespace

std::span<const DofSceneInfo> dof_scenes() { return kScenes; }

DofScene make_dof_scene(std::string_view name, std::ptrdiff_t width, std::ptrdiff_t height,
                        int threads) {
  require_size(width, height);
  const std::string id(name);
  if (name == "foreground-blur") return paint(id, width, height, threads, foreground_blur);
  if (name == "sharp-foreground") return paint(id, width, height, threads, sharp_foreground);
  if (name == "large-coc") return paint(id, width, height, threads, large_coc);
  if (name == "depth-gradient") return paint(id, width, height, threads, depth_gradient);
  if (name == "highlights") return paint(id, width, height, threads, highlights);
  if (name == "procedural" || name == "lamps") {
    Scene scene = ray_traced_scene(name, width, height, threads);
    DofScene out{id, std::move(scene.color), Image(width, height, 1)};
    coc_thin_lens(out.coc.plane(0), scene.depth.plane(0), scene.lens, threads);
    return out;
  }
  std::string known;
  for (const DofSceneInfo& info : kScenes)
    known += (known.empty() ? "" : ", ") + std::string(info.name);
  throw InvalidArgument("scene", "unknown scene '" + id + "' (known: " + known + ")");
}

DofScene focus_fraction_scene(std::ptrdiff_t width, std::ptrdiff_t height, double fraction) {
  require_size(width, height);
  if (!(fraction >= 0 && fraction <= 1))
    throw InvalidArgument("fraction", std::to_string(fraction) + " is not in [0, 1]");
  const double scale = std::sqrt(fraction);
  const auto block_w = std::ptrdiff_t(std::lround(scale * double(width))),
             block_h = std::ptrdiff_t(std::lround(scale * double(height)));
  return paint("focus-" + std::to_string(fraction), width, height, 0,
               [&](const Frame& f, std::ptrdiff_t x, std::ptrdiff_t y) {
                 return Sample{textured(f.u(x), f.v(y), {0.9f, 0.85f, 0.7f}, 43),
                               x < block_w && y < block_h ? 16.f : 0.f};
               });
}

}  // namespace tridiff
