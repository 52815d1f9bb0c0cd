// Measures every registered depth-of-field method on every built-in scene — time (best of a few
// runs) and error against the scatter reference — and writes the table that `--method auto`
// chooses from (auto.hpp; dof/data/method_table.csv). Run through scripts/dof_method_table.sh.
//
//   tridiff_dof_method_table [--size N] [--threads T] [--output FILE]
//
// Defaults: 1024 x 1024 (large enough that a frame no longer fits in the caches, as real ones
// do not), 2 threads, stdout. The scenes' CoC budgets do not scale with the frame
// (scenes.hpp), so per-pixel cost and error carry over to other sizes; the procedural scene's
// thin-lens CoC does scale, and its rows record the radius they were measured at.
#include <algorithm>
#include <chrono>
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

namespace {

using namespace tridiff;

double run_seconds(const DofMethod& method, const DofScene& scene, const DofSettings& settings,
                   Image& out) {
  double best = 1e300;
  for (int run = 0; run < 3; ++run) {
    DofReport report;
    const auto start = std::chrono::steady_clock::now();
    method.run(out, scene.color, scene.coc.plane(0), settings, report);
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    best = std::min(best, s);
    if (s > 2) break;  // slow methods: one run is precise enough
  }
  return best;
}

int usage() {
  std::fputs("usage: tridiff_dof_method_table [--size N] [--threads T] [--output FILE]\n", stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::ptrdiff_t size = 1024;
  int threads = 2;
  std::string output;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return usage();
    if (arg == "--size")
      size = std::atol(argv[++i]);
    else if (arg == "--threads")
      threads = std::atoi(argv[++i]);
    else if (arg == "--output")
      output = argv[++i];
    else
      return usage();
  }
  if (size < 16 || threads < 1) return usage();

  DofSettings settings;
  settings.threads = threads;
  std::vector<MethodTableRow> rows;
  for (const DofSceneInfo& info : dof_scenes()) {
    const DofScene scene = make_dof_scene(info.name, size, size, threads);
    const TileMap tiles(scene.coc.plane(0), settings.in_focus_coc_px, TileMap::kDefaultTile, 0,
                        threads);
    Image reference;
    DofReport report;
    find_dof_method("scatter").run(reference, scene.color, scene.coc.plane(0), settings, report);
    for (const DofMethod& method : dof_methods()) {
      if (method.name == "auto") continue;
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
      const DofError error = dof_error(out, reference, scene.color, scene.coc.plane(0),
                                       settings.in_focus_coc_px);
      row.psnr = error.psnr;
      row.ssim = error.ssim;
      std::fprintf(stderr, "%-16s %-14s %9.2f ms  PSNR %6.2f dB  SSIM %.4f\n", row.method.c_str(),
                   row.scene.c_str(), row.seconds * 1e3, row.psnr, row.ssim);
      rows.push_back(row);
    }
  }
  const std::string csv =
      "# The measured cost and error of every DOF method on the built-in scenes (auto.hpp).\n"
      "# Regenerate: bash scripts/dof_method_table.sh (" +
      std::to_string(size) + "^2, " + std::to_string(threads) + " threads)\n" +
      format_method_table(rows);
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
