// The thin-lens truth (tridiff/dof/truth.hpp) cached on disk, for the programs that score DOF
// methods against it (tools/dof_truth_score.cpp, bench/bench_dof.cpp): rendered once per scene,
// size, sample count and aperture under results/truth/, then read back.
//
// Files: <dir>/<scene>_<W>x<H>_<samples>_<aperture>_<fingerprint>.exr and a .txt beside it with
// the PSNR between the truth's two halves (its noise). The fingerprint hashes a tiny pinhole
// render and the lens of the scene, so that a changed scene is rendered again, not read stale. write_image stores OpenEXR as half floats (10-bit
// mantissa, relative step 2^-11); in the sRGB score that is ~80 dB, far below the truth's own
// noise (the tool prints the measured round trip when it writes).
#pragma once

#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>

#include "tridiff/dof/quality.hpp"
#include "tridiff/dof/truth.hpp"
#include "tridiff/image/io.hpp"

namespace tridiff::tools {

struct CachedTruth {
  Image color;
  double halves_psnr = std::numeric_limits<double>::quiet_NaN();  // sRGB, between the halves
  double render_seconds = 0;  // when rendered now, or as recorded in the cache
  double cache_psnr = std::numeric_limits<double>::infinity();  // the written file vs the render
  bool from_cache = false;
};

// Whether `scene` is one of the ray-traced scenes, the ones that have a thin-lens truth.
inline bool has_truth(std::string_view scene) {
  for (std::string_view traced : ray_traced_scene_names())
    if (traced == scene) return true;
  return false;
}

inline std::string aperture_tag(const ApertureShape& shape) {
  if (shape.blades == 0) return "circle";
  char tag[64];
  std::snprintf(tag, sizeof tag, "%dblades-%gdeg-%ground", shape.blades, double(shape.rotation_deg),
                double(shape.roundness));
  return tag;
}

// FNV-1a of the scene's lens and of its pinhole render at 32 x 18 (colour and depth bits).
inline std::string scene_fingerprint(const std::string& name) {
  const RayTracedScene traced = find_ray_traced_scene(name);
  const Scene tiny = render_pinhole(traced, 32, 18, 1, 1);
  std::uint64_t hash = 14695981039346656037ull;
  auto add = [&](float value) {
    hash = (hash ^ std::bit_cast<std::uint32_t>(value)) * 1099511628211ull;
  };
  const ThinLens& lens = traced.lens;
  for (float value :
       {lens.focal_length_mm, lens.f_number, lens.focus_distance_m, lens.sensor_width_mm})
    add(value);
  for (const Image* image : {&tiny.color, &tiny.depth})
    for (int c = 0; c < image->channels(); ++c)
      for (std::ptrdiff_t y = 0; y < image->height(); ++y)
        for (std::ptrdiff_t x = 0; x < image->width(); ++x) add((*image)(x, y, c));
  char text[17];
  std::snprintf(text, sizeof text, "%08x", unsigned(hash ^ (hash >> 32)));
  return text;
}

inline std::string truth_cache_path(const std::string& dir, const std::string& scene,
                                    std::ptrdiff_t width, std::ptrdiff_t height, int samples,
                                    const ApertureShape& aperture) {
  return dir + "/" + scene + "_" + std::to_string(width) + "x" + std::to_string(height) + "_" +
         std::to_string(samples) + "_" + aperture_tag(aperture) + "_" + scene_fingerprint(scene) +
         ".exr";
}

// sRGB PSNR of a against b over the whole frame (the regions do not matter here).
inline double srgb_psnr(const Image& a, const Image& b) {
  const Image no_coc(a.width(), a.height(), 1);
  return score_against_truth(a, b, no_coc.plane(0)).psnr;
}

// The truth from the cache if it is there, else rendered (and its noise measured) and stored.
inline CachedTruth cached_lens_truth(const std::string& dir, const std::string& scene,
                                     std::ptrdiff_t width, std::ptrdiff_t height, int samples,
                                     const ApertureShape& aperture, int threads) {
  const std::string path = truth_cache_path(dir, scene, width, height, samples, aperture);
  const std::string notes = path.substr(0, path.size() - 4) + ".txt";
  CachedTruth truth;
  if (std::filesystem::exists(path) && std::filesystem::exists(notes)) {
    ReadOptions options;
    options.encoding = ColorEncoding::Linear;
    truth.color = read_color(path, options).pixels;
    std::ifstream file(notes);
    std::string key;
    file >> key >> truth.halves_psnr >> key >> truth.render_seconds;
    truth.from_cache = true;
    return truth;
  }
  const auto start = std::chrono::steady_clock::now();
  LensTruth rendered = lens_truth_halves(scene, width, height, samples, aperture, threads);
  truth.render_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  truth.halves_psnr = srgb_psnr(rendered.half_a, rendered.half_b);
  std::filesystem::create_directories(dir);
  write_image(path, rendered.color);
  ReadOptions options;
  options.encoding = ColorEncoding::Linear;
  truth.color = read_color(path, options).pixels;
  truth.cache_psnr = srgb_psnr(truth.color, rendered.color);
  std::ofstream(notes) << "halves_psnr_srgb " << truth.halves_psnr << "\nrender_seconds "
                       << truth.render_seconds << "\n";
  return truth;
}

}  // namespace tridiff::tools
