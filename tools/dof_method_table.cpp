// Measures every registered depth-of-field method on every built-in scene — time (best of a few
// runs) and error against the scene's best reference — and writes the table that `--method
// auto` chooses from (auto.hpp; dof/data/method_table.csv). Run through
// scripts/dof_method_table.sh.
//
//   tridiff_dof_method_table [--size N] [--threads T] [--output FILE] [--method NAME]...
//
// The reference: for the ray-traced scenes (procedural, lamps), their thin-lens truth at
// kTruthSamples rays per pixel (truth.hpp), read from results/truth/ or rendered there once
// (tools/truth_cache.hpp; about a minute per scene at 1024^2 on 2 cores), scored as
// score_against_truth() does (sRGB); for the synthetic scenes, which have no lens to trace,
// the `scatter` method, scored by dof_error().
//
// Defaults: 1024 x 1024 (large enough that a frame no longer fits in the caches, as real ones
// do not), 2 threads, stdout. --method (repeatable) measures only the methods named and
// replaces their rows in the table at --output (read first; its other rows, their order and its
// comment lines are kept); --size and --threads then default to the size and threads of the
// rows they replace, so that the table stays measured alike. The scenes' CoC budgets do not scale with the frame
// (scenes.hpp), so per-pixel cost and error carry over to other sizes; the procedural scene's
// thin-lens CoC does scale, and its rows record the radius they were measured at.
#include <algorithm>
#include <chrono>
#include <iterator>
#include <sstream>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tridiff/dof/auto.hpp"
#include "tridiff/dof/quality.hpp"
#include "tridiff/dof/scenes.hpp"
#include "tridiff/dof/tiles.hpp"
#include "truth_cache.hpp"

namespace {

using namespace tridiff;

// 512 rays per pixel: the truth's own noise is ~48 dB (procedural) and ~44 dB (lamps), about
// 10 dB below every method's error against it (bench_dof.cpp measures the same).
constexpr int kTruthSamples = 512;

// The scene's reference image and how it is scored: its thin-lens truth, else `scatter`.
struct Reference {
  Image image;
  bool truth = false;
};

Reference make_reference(const DofScene& scene, const DofOptions& settings) {
  Reference reference;
  reference.truth = tools::has_truth(scene.name);
  if (reference.truth) {
    reference.image =
        tools::cached_lens_truth("results/truth", scene.name, scene.color.width(),
                                 scene.color.height(), kTruthSamples, {}, settings.threads)
            .color;
  } else {
    DofReport report;
    report = depth_of_field(reference.image, scene.color, scene.coc.plane(0),
                            find_dof_method("scatter"), settings);
  }
  return reference;
}

double run_seconds(const DofMethod& method, const DofScene& scene, const DofOptions& settings,
                   Image& out) {
  double best = 1e300;
  for (int run = 0; run < 3; ++run) {
    DofReport report;
    const auto start = std::chrono::steady_clock::now();
    report = depth_of_field(out, scene.color, scene.coc.plane(0), method, settings);
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    best = std::min(best, s);
    if (s > 2) break;  // slow methods: one run is precise enough
  }
  return best;
}

int usage() {
  std::fputs(
      "usage: tridiff_dof_method_table [--size N] [--threads T] [--output FILE] "
      "[--method NAME]...\n",
      stderr);
  return 2;
}

// The table already at `path` (empty if there is none) and its leading comment lines.
std::vector<MethodTableRow> read_table(const std::string& path, std::string& comments) {
  std::ifstream file(path);
  if (!file) return {};
  const std::string csv((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  std::istringstream lines(csv);
  for (std::string line; std::getline(lines, line) && line.rfind("#", 0) == 0;)
    comments += line + "\n";
  return parse_method_table(csv);
}

// The rows measured, put in place of the rows of the same method and scene in `table`; rows
// for a scene the table lacks are added at its end.
std::vector<MethodTableRow> replace_rows(std::vector<MethodTableRow> table,
                                         const std::vector<MethodTableRow>& measured) {
  for (const MethodTableRow& row : measured) {
    auto same = std::find_if(table.begin(), table.end(), [&](const MethodTableRow& old) {
      return old.method == row.method && old.scene == row.scene;
    });
    if (same != table.end())
      *same = row;
    else
      table.push_back(row);
  }
  return table;
}

int measure(int argc, char** argv) {
  std::ptrdiff_t size = 0;
  int threads = 0;
  std::string output;
  std::vector<std::string> only;  // --method: these methods alone
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return usage();
    if (arg == "--size")
      size = std::atol(argv[++i]);
    else if (arg == "--threads")
      threads = std::atoi(argv[++i]);
    else if (arg == "--output")
      output = argv[++i];
    else if (arg == "--method")
      only.emplace_back(find_dof_method(argv[++i]).name);
    else
      return usage();
  }
  if (std::find(only.begin(), only.end(), "auto") != only.end()) {
    std::fputs("--method auto: auto is not measured (it runs the methods of the table)\n", stderr);
    return 2;
  }
  if (!only.empty() && output.empty()) {
    std::fputs("--method replaces rows of the table at --output: give --output\n", stderr);
    return 2;
  }
  // With --method, the rows being replaced say how the table was measured.
  std::string comments;
  const std::vector<MethodTableRow> existing =
      only.empty() ? std::vector<MethodTableRow>() : read_table(output, comments);
  for (const MethodTableRow& row : existing) {
    if (std::find(only.begin(), only.end(), row.method) == only.end()) continue;
    if (size == 0) size = row.width;
    if (threads == 0) threads = row.threads;
    if (row.width != size || row.height != size || row.threads != threads)
      std::fprintf(stderr,
                   "note: the %s row of '%s' was measured at %td^2, %d threads; now %td^2, "
                   "%d threads\n",
                   row.method.c_str(), row.scene.c_str(), row.width, row.threads, size, threads);
  }
  if (size == 0) size = 1024;
  if (threads == 0) threads = 2;
  if (size < 16 || threads < 1) return usage();
  auto measured_here = [&](std::string_view name) {
    return name != "auto" &&
           (only.empty() || std::find(only.begin(), only.end(), name) != only.end());
  };

  DofOptions settings;
  settings.threads = threads;
  std::vector<MethodTableRow> rows;
  for (const DofSceneInfo& info : dof_scenes()) {
    const DofScene scene = make_dof_scene(info.name, size, size, threads);
    const TileMap tiles(scene.coc.plane(0), settings.in_focus_coc_px, TileMap::kDefaultTile, 0,
                        threads);
    const Reference reference = make_reference(scene, settings);
    for (const DofMethod& method : dof_methods()) {
      if (!measured_here(method.name)) continue;
      Image out;
      MethodTableRow row;
      row.method = std::string(method.name);
      row.scene = scene.name;
      row.width = row.height = size;
      row.threads = threads;
      row.max_radius = tiles.max_radius();
      row.has_near = tiles.has_near();
      row.work_fraction = tiles.work_fraction();
      row.seconds = run_seconds(method, scene, settings, out);
      if (reference.truth) {
        const TruthScore score = score_against_truth(out, reference.image, scene.coc.plane(0));
        row.psnr = score.psnr;
        row.ssim = score.ssim;
        row.reference = "truth";
      } else {
        const DofError error = dof_error(out, reference.image, scene.color, scene.coc.plane(0),
                                         settings.in_focus_coc_px);
        row.psnr = error.psnr;
        row.ssim = error.ssim;
        row.reference = "scatter";
      }
      std::fprintf(stderr, "%-16s %-14s %9.2f ms  PSNR %6.2f dB  SSIM %.4f  vs %s\n",
                   row.method.c_str(), row.scene.c_str(), row.seconds * 1e3, row.psnr, row.ssim,
                   row.reference.c_str());
      rows.push_back(row);
    }
  }
  std::string names;
  for (const std::string& name : only) names += (names.empty() ? "" : ", ") + name;
  const std::string measured_at =
      "(" + std::to_string(size) + "^2, " + std::to_string(threads) + " threads)";
  // Said once, however often the same methods are re-measured.
  const std::string remeasured = "# Re-measured alone: " + names + " " + measured_at + "\n";
  if (comments.find(remeasured) == std::string::npos) comments += remeasured;
  const std::string csv =
      only.empty() ? "# The measured cost and error of every DOF method on the built-in scenes "
                     "(auto.hpp).\n# Regenerate: bash scripts/dof_method_table.sh " +
                         measured_at + "\n" + format_method_table(rows)
                   : comments + format_method_table(replace_rows(existing, rows));
  if (output.empty()) {
    std::fputs(csv.c_str(), stdout);
    return 0;
  }
  // Whole or not at all: write beside the target, then rename over it.
  const std::string temporary = output + ".tmp";
  {
    std::ofstream file(temporary);
    file << csv;
    if (!file.flush()) {
      std::fprintf(stderr, "cannot write %s\n", temporary.c_str());
      std::filesystem::remove(temporary);
      return 1;
    }
  }
  std::filesystem::rename(temporary, output);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return measure(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "tridiff_dof_method_table: %s\n", error.what());
    return 2;
  }
}
