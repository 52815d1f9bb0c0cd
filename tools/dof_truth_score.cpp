// Scores every registered DOF method against the thin-lens truth (tridiff/dof/truth.hpp) of the
// ray-traced scenes: each method blurs the pinhole colour with the thin-lens CoC map, and its
// output is compared with the scene rendered through the lens itself (sRGB PSNR / SSIM overall,
// in focus, defocused, near depth edges; quality.hpp's TruthScore), and with `scatter`.
//
//   tridiff_dof_truth_score [--scene NAME]... [--width W] [--height H] [--samples N]
//                           [--supersample S] [--threads T] [--cache DIR]
//                           [--blades B --rotation DEG --roundness R]
//
// Defaults: both scenes (procedural, lamps), 512 x 288, kDefaultTruthSamples rays per pixel,
// 2 threads, cache results/truth (tools/truth_cache.hpp). Run through scripts/dof_truth_table.sh.
// The methods get the pinhole colour at S x S rays per pixel (default 16), not make_dof_scene's
// 2 x 2: the truth averages each pixel's area, and 2 x 2 alone is 32.5 dB from that average on
// both scenes (33 dB over the lamps scene's sharp sign), a floor that would hide the methods'
// own errors. The row "input 2x2" is that colour, unblurred, against the truth.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tridiff/dof/method.hpp"
#include "tridiff/dof/quality.hpp"
#include "tridiff/dof/scene.hpp"
#include "tridiff/dof/scenes.hpp"
#include "truth_cache.hpp"

namespace {

using namespace tridiff;

struct Settings {
  std::vector<std::string> scenes;
  std::ptrdiff_t width = 512, height = 288;
  int samples = kDefaultTruthSamples;
  int supersample = 16;
  int threads = 2;
  std::string cache = "results/truth";
  ApertureShape aperture;
};

int usage() {
  std::fputs(
      "usage: tridiff_dof_truth_score [--scene NAME]... [--width W] [--height H] [--samples N]\n"
      "                               [--supersample S] [--threads T] [--cache DIR]\n"
      "                               [--blades B] [--rotation DEG] [--roundness R]\n",
      stderr);
  return 2;
}

bool parse(int argc, char** argv, Settings& settings) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return false;
    const char* value = argv[++i];
    if (arg == "--scene")
      settings.scenes.emplace_back(value);
    else if (arg == "--width")
      settings.width = std::atol(value);
    else if (arg == "--height")
      settings.height = std::atol(value);
    else if (arg == "--samples")
      settings.samples = std::atoi(value);
    else if (arg == "--supersample")
      settings.supersample = std::atoi(value);
    else if (arg == "--threads")
      settings.threads = std::atoi(value);
    else if (arg == "--cache")
      settings.cache = value;
    else if (arg == "--blades")
      settings.aperture.blades = std::atoi(value);
    else if (arg == "--rotation")
      settings.aperture.rotation_deg = float(std::atof(value));
    else if (arg == "--roundness")
      settings.aperture.roundness = float(std::atof(value));
    else
      return false;
  }
  if (settings.scenes.empty())
    for (std::string_view name : ray_traced_scene_names()) settings.scenes.emplace_back(name);
  return settings.width >= 1 && settings.height >= 1 && settings.threads >= 1 &&
         settings.supersample >= 1;
}

// One method's output and its wall time (best of two runs when one is fast).
struct Run {
  Image out;
  double seconds = 0;
};
Run run(const DofMethod& method, const DofScene& scene, const DofOptions& options) {
  Run result{Image(), 1e300};
  for (int attempt = 0; attempt < 2; ++attempt) {
    const auto start = std::chrono::steady_clock::now();
    DofReport report = depth_of_field(result.out, scene.color, scene.coc.plane(0), method, options);
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.seconds = std::min(result.seconds, s);
    if (s > 0.5) break;
  }
  return result;
}

void print_header() {
  std::printf("%-18s %9s | %6s %6s | %6s %6s | %6s %6s | %6s %6s | %9s\n", "method", "ms", "PSNR",
              "SSIM", "focus", "SSIM", "defoc", "SSIM", "edges", "SSIM", "vs scatter");
}

void print_row(const std::string& name, double ms, const TruthScore& s, double vs_scatter) {
  std::printf("%-18s %9.1f | %6.2f %6.4f | %6.2f %6.4f | %6.2f %6.4f | %6.2f %6.4f | %9.2f\n",
              name.c_str(), ms, s.psnr, s.ssim, s.psnr_in_focus, s.ssim_in_focus, s.psnr_defocused,
              s.ssim_defocused, s.psnr_edges, s.ssim_edges, vs_scatter);
}

// The largest |CoC| of the scene's depth without the clamp at max_coc_px (the truth has none).
float largest_coc(const std::string& name, std::ptrdiff_t width, std::ptrdiff_t height,
                  int threads) {
  Scene scene = ray_traced_scene(name, width, height, threads);
  scene.lens.max_coc_px = 1e6f;
  Image coc(width, height, 1);
  coc_thin_lens(coc.plane(0), scene.depth.plane(0), scene.lens, threads);
  float largest = 0;
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) largest = std::max(largest, std::fabs(coc(x, y, 0)));
  return largest;
}

void score_scene(const std::string& name, const Settings& settings) {
  const tools::CachedTruth truth =
      tools::cached_lens_truth(settings.cache, name, settings.width, settings.height,
                               settings.samples, settings.aperture, settings.threads);
  const DofScene coarse = make_dof_scene(name, settings.width, settings.height, settings.threads);
  DofScene scene = coarse;
  scene.color = render_pinhole(find_ray_traced_scene(name), settings.width, settings.height,
                               settings.supersample, settings.threads)
                    .color;
  const ConstPlane coc = scene.coc.plane(0);
  std::printf(
      "\n## %s %tdx%td, truth %d rays/pixel, aperture %s (%s, rendered in %.1f s); "
      "input %dx%d rays/pixel\n",
      name.c_str(), settings.width, settings.height, settings.samples,
      tools::aperture_tag(settings.aperture).c_str(),
      truth.from_cache ? "from the cache" : "rendered now", truth.render_seconds,
      settings.supersample, settings.supersample);
  std::printf("truth noise: PSNR between its halves %.2f dB -> truth vs exact ~%.2f dB (sRGB)\n",
              truth.halves_psnr, truth.halves_psnr + 6.02);
  if (!truth.from_cache)
    std::printf("cache file (half-float EXR) vs the render: %.2f dB\n", truth.cache_psnr);
  const TruthScore input = score_against_truth(scene.color, truth.color, coc);
  std::printf(
      "regions: in focus %td, defocused %td, edges %td px; largest |CoC| %.1f px "
      "(methods clamp at %.0f)\n",
      input.in_focus_pixels, input.defocused_pixels, input.edge_pixels,
      double(largest_coc(name, settings.width, settings.height, settings.threads)),
      double(ThinLens{}.max_coc_px));
  DofOptions options;
  options.threads = settings.threads;
  const Run scatter = run(find_dof_method("scatter"), scene, options);
  auto vs_scatter = [&](const Image& out) {
    return dof_error(out, scatter.out, scene.color, coc, options.in_focus_coc_px).psnr;
  };
  print_header();
  print_row("input (no blur)", 0, input, vs_scatter(scene.color));
  print_row("input 2x2", 0, score_against_truth(coarse.color, truth.color, coc),
            vs_scatter(coarse.color));
  for (const DofMethod& method : dof_methods()) {
    const Run result = run(method, scene, options);
    print_row(std::string(method.name), result.seconds * 1e3,
              score_against_truth(result.out, truth.color, coc), vs_scatter(result.out));
  }
  // Every method that has a near layer, with it.
  DofOptions layered = options;
  layered.layers = true;
  for (const DofMethod& method : dof_methods()) {
    if (!method.honours_layers || method.name == "auto") continue;
    const Run result = run(method, scene, layered);
    print_row(std::string(method.name) + " layers=true", result.seconds * 1e3,
              score_against_truth(result.out, truth.color, coc), vs_scatter(result.out));
  }
}

}  // namespace

int main(int argc, char** argv) {
  Settings settings;
  if (!parse(argc, argv, settings)) return usage();
  try {
    std::printf(
        "# DOF methods against the thin-lens truth: sRGB PSNR (dB) / SSIM; focus: |CoC| < "
        "1 px, edges: within the blur radius + 3 px of a CoC jump > 1 px, defoc: the "
        "rest; vs scatter: dof_error PSNR (clipped linear)\n");
    for (const std::string& name : settings.scenes) score_scene(name, settings);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "tridiff_dof_truth_score: %s\n", error.what());
    return 1;
  }
  return 0;
}
