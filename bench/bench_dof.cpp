// Speed and error of every registered depth-of-field method on every built-in scene
// (tridiff/dof/scenes.hpp), against a plain copy of the same image, all measured in this one
// binary so that the ratios are meaningful:
//   BM_dof_copy/<W>x<H>/threads:<t>             copy of the RGB float image (the floor)
//   BM_dof_adi_traffic/<W>x<H>/threads:<t>      the data movement of one ADI step as plain
//                                               streams (adi_traffic): the adi method's floor
//   BM_dof_<method>/<W>x<H>/threads:<t>         the `procedural` scene (thin-lens CoC)
//   BM_dof_<method>/<scene>/<W>x<H>/threads:<t> the other scenes
//   BM_dof_<method>_focus/<percent>/threads:2   focus_fraction_scene(2048, 2048, percent / 100):
//                                               a compact block out of focus, the rest sharp
//   BM_dof_<method>_focus_in_place/<percent>/threads:2
//                                               the same, out == color, for the methods that
//                                               work in place (DofMethod::in_place): the tiles
//                                               in focus are not even copied. Each run blurs
//                                               the last one's output again (the work is the
//                                               same: it depends on the CoC only)
// for sizes 1024x1024, 1920x1080 (the size of issue 26's targets), 2048x2048 and 3840x2160 and
// threads 1 and 2. Each method runs with its defaults (default_settings: layers where it has
// them, as `tridiff dof` runs it). What is timed is the method alone: the scene's colour and
// CoC are made once, before timing, and cached.
// Counters:
//   copy_ratio        time / the copy time of the same image at the same thread count
//                     (the copy measured once per size and thread count, best of 5)
//   pixels_per_second, skipped (the method's DofReport::skipped_fraction),
//   work_fraction     TileMap(coc, 1 px).work_fraction(): the share of the frame in tiles that
//                     some disc reaches, what any method must compute
//   psnr_vs_scatter, ssim_vs_scatter, rmse_vs_scatter, max_error_vs_scatter, in_focus_max,
//   leakage_vs_scatter
//                     dof_error() (tridiff/dof/quality.hpp) of the method's output against the
//                     `scatter` reference with 2 threads, measured on the scene at 1024^2 once
//                     per method and scene, and reported on the rows of every size: the
//                     reference is slow, and the scenes are the same at every size (their CoC
//                     in pixels does not scale, except `procedural`'s)
//   ms <stage>        the last run's DofReport::stages, in ms (e.g. "ms body discs")
//   psnr_vs_truth, ssim_vs_truth
//                     the ray-traced scenes (procedural, lamps) only: score_against_truth()
//                     (quality.hpp: sRGB PSNR / SSIM) of the method's output on the scene at
//                     1024 x 576 against its thin-lens truth (truth.hpp) at 512 rays per pixel
//                     (noise: ~48 dB procedural, ~44 dB lamps), 2 threads. The truth is read
//                     from results/truth/ (tools/truth_cache.hpp) or rendered there once (about
//                     25 s and 60 s on 2 cores); like the scatter errors, reported on every size.
//                     TRIDIFF_BENCH_TRUTH_SAMPLES sets the rays per pixel (the quick notebook
//                     run uses 72, which must be twice a perfect square: 7x faster, its noise
//                     ~8.5 dB higher, still above every method)
// Cost guard: a method x scene x size whose one run is estimated to take more than
// kMaxRunSeconds is skipped (an error row saying so): the estimate is the 1024^2 run's time if
// it has been measured, else a 256^2 (if close to the limit, 512^2) probe's, times the pixel
// ratio. That keeps the matrix to a
// few minutes; the excluded runs are those of the methods whose cost grows with the CoC squared
// (scatter, mpad) on the large-CoC scenes at 4K.
// The ADI target of the issue: adi <= 4x the copy at 3840x2160 on 2 threads. BM_dof_adi_traffic
// is the floor of its data movement (2.5-3.2 copies on the hosts measured so far), measured
// beside it. copy_ratio divides by one best-of-5 copy per process, taken when the image is not
// in cache; BM_dof_copy's steady state can be faster (a host with a large last-level cache keeps
// part of it there: 6.2 against 7.5 ms on an Intel Xeon), so quote the ratio of BM_dof_adi's
// and BM_dof_copy's medians from the same run. (Measuring the copy again right after each
// benchmark was tried: it read 3.3x where the medians gave 4.0x, for the same reason.)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "tridiff/dof/method.hpp"
#include "tridiff/dof/quality.hpp"
#include "tridiff/dof/scene.hpp"
#include "tridiff/dof/scenes.hpp"
#include "tridiff/dof/tiles.hpp"
#include "tridiff/image/copy.hpp"
#include "truth_cache.hpp"

namespace {

using namespace tridiff;
using benchmark::Counter;

constexpr std::ptrdiff_t kErrorSize = 1024;  // errors against the reference are measured here
constexpr std::ptrdiff_t kProbeSize = 256;   // the cost guard's probe (and twice that)
constexpr double kMaxRunSeconds = 5;
constexpr std::ptrdiff_t kFocusSize = 2048;
constexpr int kFocusThreads = 2;

// A scene and its tile map, made once. `focus_percent` >= 0: focus_fraction_scene.
struct CachedScene {
  DofScene scene;
  double work_fraction = 0;
};
const CachedScene& scene(const std::string& name, std::ptrdiff_t width, std::ptrdiff_t height,
                         int focus_percent = -1) {
  static std::map<std::tuple<std::string, std::ptrdiff_t, std::ptrdiff_t, int>, CachedScene> cache;
  const auto key = std::tuple{name, width, height, focus_percent};
  auto it = cache.find(key);
  if (it == cache.end()) {
    CachedScene cached{focus_percent >= 0
                           ? focus_fraction_scene(width, height, focus_percent / 100.0)
                           : make_dof_scene(name, width, height)};
    cached.work_fraction = TileMap(cached.scene.coc.plane(0), 1.f).work_fraction();
    it = cache.emplace(key, std::move(cached)).first;
  }
  return it->second;
}

// Best of 5 copies of a width x height RGB image (the procedural scene's colour: an image never
// written reads the kernel's shared zero page, which sits in cache, and its copy measured only
// the writes, 1.1 ms at 3840 x 2160 against 2.0 for real data), cached per (size, threads).
double copy_seconds(std::ptrdiff_t width, std::ptrdiff_t height, int threads) {
  static std::map<std::tuple<std::ptrdiff_t, std::ptrdiff_t, int>, double> cache;
  auto key = std::tuple{width, height, threads};
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  const Image& src = scene("procedural", width, height).scene.color;
  Image dst(width, height, 3);
  copy_image(dst, src, threads);  // touch the pages
  double best = 1e30;
  for (int i = 0; i < 5; ++i) {
    const auto start = std::chrono::steady_clock::now();
    copy_image(dst, src, threads);
    best = std::min(
        best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return cache[key] = best;
}

void set_counters(benchmark::State& state, std::ptrdiff_t width, std::ptrdiff_t height, int threads,
                  double skipped) {
  const double iterations = double(state.iterations());
  state.counters["pixels_per_second"] =
      Counter(iterations * double(width * height), Counter::kIsRate);
  // time per iteration / copy time, as a rate counter inverted: (iterations * copy / time)^-1.
  state.counters["copy_ratio"] = Counter(iterations * copy_seconds(width, height, threads),
                                         Counter::kIsRate | Counter::kInvert);
  state.counters["skipped"] = skipped;
}

void bm_copy(benchmark::State& state, std::ptrdiff_t width, std::ptrdiff_t height, int threads) {
  copy_seconds(width, height, threads);
  const Image& src = scene("procedural", width, height).scene.color;
  Image dst(width, height, 3);
  copy_image(dst, src, threads);  // touch the pages
  for (auto _ : state) {
    copy_image(dst, src, threads);
    benchmark::ClobberMemory();
  }
  set_counters(state, width, height, threads, 0);
}

// The memory traffic of one ADI step at the speed of plain streams, with next to no
// arithmetic: the CoC read once (the adi method's activity scan), then two passes that each
// read the CoC and three planes and write three (the rows pass from the colour into out, the
// columns pass in place in out). The floor of the adi method's data movement, measured.
void adi_traffic(Image& out, const Image& color, ConstPlane coc, int threads) {
  float largest = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(max : largest)
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y) {
    const float* k = coc.row(y);
#pragma omp simd reduction(max : largest)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) largest = std::max(largest, k[x]);
  }
  const float scale = largest > 0 ? 1.f / largest : 1.f;
  for (int pass = 0; pass < 2; ++pass) {
    const Image& from = pass == 0 ? color : out;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t y = 0; y < coc.height(); ++y) {
      const float* k = coc.row(y);
      for (int c = 0; c < from.channels(); ++c) {
        const float* in = from.plane(c).row(y);
        float* to = out.plane(c).row(y);
#pragma omp simd
        for (std::ptrdiff_t x = 0; x < coc.width(); ++x) to[x] = in[x] * (k[x] * scale);
      }
    }
  }
}

void bm_adi_traffic(benchmark::State& state, std::ptrdiff_t width, std::ptrdiff_t height,
                    int threads) {
  const CachedScene& cached = scene("procedural", width, height);
  copy_seconds(width, height, threads);
  Image out(width, height, 3);
  for (auto _ : state) {
    adi_traffic(out, cached.scene.color, cached.scene.coc.plane(0), threads);
    benchmark::ClobberMemory();
  }
  set_counters(state, width, height, threads, 0);
}

// A method's options as `tridiff dof` and the Python module run it by default: with layers
// where it has them (what a user gets, and what the truth scores measure).
DofOptions default_settings(const DofMethod& method, int threads) {
  DofOptions settings;
  settings.threads = threads;
  settings.layers = method.honours_layers;
  return settings;
}

// One untimed-by-the-framework run: its output and its wall time.
double run_once(const DofMethod& method, const DofScene& s, int threads, Image& out) {
  const DofOptions settings = default_settings(method, threads);
  DofReport report;
  const auto start = std::chrono::steady_clock::now();
  report = depth_of_field(out, s.color, s.coc.plane(0), method, settings);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Seconds of one run of `method` on (name, focus_percent) at width x height with `threads`,
// estimated from the 1024^2 run when it was measured, else from a probe (cached per pixel).
using CostKey = std::tuple<std::string, std::string, int, int>;  // method, scene, percent, threads
std::map<CostKey, double>& measured_1024() {
  static std::map<CostKey, double> seconds;
  return seconds;
}
double estimated_seconds(const DofMethod& method, const std::string& name, int focus_percent,
                         std::ptrdiff_t width, std::ptrdiff_t height, int threads) {
  static std::map<CostKey, double> probes;  // seconds per pixel
  const CostKey key{std::string(method.name), name, focus_percent, threads};
  const double pixels = double(width * height);
  if (auto it = measured_1024().find(key); it != measured_1024().end())
    return it->second * pixels / double(kErrorSize * kErrorSize);
  auto probe = probes.find(key);
  if (probe == probes.end()) {
    // A small run pays a fixed cost (starting threads, faulting pages in; more on a shared
    // machine) that the pixel ratio would multiply: when the 256^2 probe alone would skip the
    // run (but not by far), a 512^2 run decides.
    double seconds_per_pixel = 0;
    for (std::ptrdiff_t size = kProbeSize; size <= 2 * kProbeSize; size *= 2) {
      Image out;
      seconds_per_pixel =
          run_once(method, scene(name, size, size, focus_percent).scene, threads, out) /
          double(size * size);
      const double estimate = seconds_per_pixel * pixels;
      if (estimate <= kMaxRunSeconds || estimate >= 10 * kMaxRunSeconds) break;
    }
    probe = probes.emplace(key, seconds_per_pixel).first;
  }
  return probe->second * pixels;
}

// `method` against the scatter reference on the scene at 1024^2, 2 threads; both cached.
const DofError& error_vs_scatter(const DofMethod& method, const std::string& name) {
  static std::map<std::pair<std::string, std::string>, DofError> errors;
  static std::map<std::string, Image> references;
  const auto key = std::pair{std::string(method.name), name};
  if (auto it = errors.find(key); it != errors.end()) return it->second;
  const DofScene& s = scene(name, kErrorSize, kErrorSize).scene;
  auto ref = references.find(name);
  if (ref == references.end()) {
    Image reference;
    run_once(find_dof_method("scatter"), s, 2, reference);
    ref = references.emplace(name, std::move(reference)).first;
  }
  Image out;
  run_once(method, s, 2, out);
  return errors[key] = dof_error(out, ref->second, s.color, s.coc.plane(0), 1.f);
}

// `method` against the thin-lens truth of the ray-traced scene `name` at kTruthWidth x
// kTruthHeight, 2 threads; the truth from the file cache, both cached in memory.
constexpr std::ptrdiff_t kTruthWidth = 1024, kTruthHeight = 576;
int truth_samples() {
  const char* value = std::getenv("TRIDIFF_BENCH_TRUTH_SAMPLES");
  const int samples = value != nullptr ? std::atoi(value) : 512;
  if (samples < 1)
    throw std::invalid_argument("TRIDIFF_BENCH_TRUTH_SAMPLES must be a positive count");
  return samples;
}
const TruthScore& score_vs_truth(const DofMethod& method, const std::string& name) {
  static std::map<std::pair<std::string, std::string>, TruthScore> scores;
  static std::map<std::string, Image> truths;
  const auto key = std::pair{std::string(method.name), name};
  if (auto it = scores.find(key); it != scores.end()) return it->second;
  auto truth = truths.find(name);
  if (truth == truths.end())
    truth = truths
                .emplace(name, tools::cached_lens_truth("results/truth", name, kTruthWidth,
                                                        kTruthHeight, truth_samples(), {}, 2)
                                   .color)
                .first;
  const DofScene& s = scene(name, kTruthWidth, kTruthHeight).scene;
  Image out;
  run_once(method, s, 2, out);
  return scores[key] = score_against_truth(out, truth->second, s.coc.plane(0));
}

// Times the method on a cached scene (focus_percent >= 0: the focus-fraction scene), after the
// cost guard; errors against scatter unless it is a focus-fraction run.
void bm_method(benchmark::State& state, const DofMethod& method, const std::string& name,
               int focus_percent, std::ptrdiff_t width, std::ptrdiff_t height, int threads) {
  const double estimate = estimated_seconds(method, name, focus_percent, width, height, threads);
  if (estimate > kMaxRunSeconds) {
    state.SkipWithError(("cost guard: one run estimated at " + std::to_string(estimate) + " s > " +
                         std::to_string(kMaxRunSeconds) + " s")
                            .c_str());
    return;
  }
  const CachedScene& cached = scene(name, width, height, focus_percent);
  copy_seconds(width, height, threads);
  const DofOptions settings = default_settings(method, threads);
  Image out(width, height, 3);
  DofReport report;
  const auto start = std::chrono::steady_clock::now();
  try {
    for (auto _ : state) {
      report = {};
      report = depth_of_field(out, cached.scene.color, cached.scene.coc.plane(0), method, settings);
      benchmark::ClobberMemory();
    }
  } catch (const std::exception& error) {
    state.SkipWithError(error.what());
    return;
  }
  if (width == kErrorSize && height == kErrorSize && state.iterations() > 0)
    measured_1024()[{std::string(method.name), name, focus_percent, threads}] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
        double(state.iterations());
  set_counters(state, width, height, threads, report.skipped_fraction);
  state.counters["work_fraction"] = cached.work_fraction;
  if (report.explicit_steps) state.counters["steps"] = report.explicit_steps;
  // The last run's stages (DofReport::stages, as `tridiff dof` prints them), in ms: where the
  // time goes, measured in the same run as the total.
  for (const DofStage& stage : report.stages)
    state.counters["ms " + stage.name] = stage.seconds * 1e3;
  if (focus_percent >= 0) return;
  // The error run at 1024^2 with 2 threads costs about the 1024^2 estimate (and the reference
  // once per scene); the guard above already admitted a run of this size or larger.
  if (estimated_seconds(method, name, -1, kErrorSize, kErrorSize, 2) > kMaxRunSeconds) return;
  const DofError& e = error_vs_scatter(method, name);
  state.counters["psnr_vs_scatter"] = e.psnr;
  state.counters["ssim_vs_scatter"] = e.ssim;
  state.counters["rmse_vs_scatter"] = e.rmse;
  state.counters["max_error_vs_scatter"] = e.max_abs;
  state.counters["in_focus_max"] = e.in_focus_max;
  state.counters["leakage_vs_scatter"] = e.leakage;
  if (!tools::has_truth(name)) return;
  const TruthScore& truth = score_vs_truth(method, name);
  state.counters["psnr_vs_truth"] = truth.psnr;
  state.counters["ssim_vs_truth"] = truth.ssim;
}

// The focus-fraction scene diffused where it lies, out == color (see the file comment).
void bm_in_place(benchmark::State& state, const DofMethod& method, int focus_percent) {
  const CachedScene& cached = scene("focus", kFocusSize, kFocusSize, focus_percent);
  copy_seconds(kFocusSize, kFocusSize, kFocusThreads);
  const DofOptions settings = default_settings(method, kFocusThreads);
  Image image = cached.scene.color;
  DofReport report;
  for (auto _ : state) {
    report = {};
    report = depth_of_field(image, image, cached.scene.coc.plane(0), method, settings);
    benchmark::ClobberMemory();
  }
  set_counters(state, kFocusSize, kFocusSize, kFocusThreads, report.skipped_fraction);
  state.counters["work_fraction"] = cached.work_fraction;
}

void register_all() {
  const std::pair<std::ptrdiff_t, std::ptrdiff_t> sizes[] = {
      {1024, 1024}, {1920, 1080}, {2048, 2048}, {3840, 2160}};
  auto add = [](const std::string& name, auto&&... args) {
    benchmark::RegisterBenchmark(name.c_str(), args...)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
  };
  for (auto [w, h] : sizes)
    for (int threads : {1, 2})
      add("BM_dof_copy/" + std::to_string(w) + "x" + std::to_string(h) +
              "/threads:" + std::to_string(threads),
          bm_copy, w, h, threads);
  for (auto [w, h] : sizes)
    for (int threads : {1, 2})
      add("BM_dof_adi_traffic/" + std::to_string(w) + "x" + std::to_string(h) +
              "/threads:" + std::to_string(threads),
          bm_adi_traffic, w, h, threads);
  // Scene by scene, 1024^2 first: its measured time replaces the probe in the 4K rows' guard.
  for (const DofSceneInfo& info : dof_scenes()) {
    const std::string name(info.name);
    const std::string part = name == "procedural" ? "/" : "/" + name + "/";
    for (auto [w, h] : sizes)
      for (int threads : {1, 2})
        for (const DofMethod& method : dof_methods())
          add("BM_dof_" + std::string(method.name) + part + std::to_string(w) + "x" +
                  std::to_string(h) + "/threads:" + std::to_string(threads),
              bm_method, method, name, -1, w, h, threads);
  }
  for (const DofMethod& method : dof_methods())
    for (int percent : {0, 10, 25, 50, 100})
      add("BM_dof_" + std::string(method.name) + "_focus/" + std::to_string(percent) +
              "/threads:" + std::to_string(kFocusThreads),
          bm_method, method, "focus", percent, kFocusSize, kFocusSize, kFocusThreads);
  for (const DofMethod& method : dof_methods())
    if (method.in_place)
      for (int percent : {0, 10, 25, 50, 100})
        add("BM_dof_" + std::string(method.name) + "_focus_in_place/" + std::to_string(percent) +
                "/threads:" + std::to_string(kFocusThreads),
            bm_in_place, method, percent);
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
