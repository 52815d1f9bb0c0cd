// The traversal that the gather methods share (issue 22; the algorithm apart from its schedule,
// as in Halide): a method is a per-pixel, per-tile or per-row kernel plus a small prepare; this
// walks the tiles that need work, copies the others at the end, and times the stages. Private
// to dof/src.
#pragma once

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"
#include "stage_clock.hpp"

namespace tridiff::dof_detail {

// Wall-clock stages of a method, into DofReport::stages in the order they end.
class Stages {
 public:
  explicit Stages(DofReport& report) : report_(report), start_(StageClock::now()) {}
  // Ends the stage that began at the last end() or restart() (or construction) as `name`.
  void end(std::string name, double earlier_seconds = 0) {
    report_.stages.push_back({std::move(name), earlier_seconds + lap()});
  }
  // The seconds since the last end(), lap() or restart(), and a new start: for a stage summed
  // over a loop.
  double lap() {
    const double seconds = seconds_since(start_);
    start_ = StageClock::now();
    return seconds;
  }
  void restart() { start_ = StageClock::now(); }

 private:
  DofReport& report_;
  StageClock::time_point start_;
};

// A span of columns [first, second) of one row.
using Span = std::pair<std::ptrdiff_t, std::ptrdiff_t>;

// The tiles of `tiles` that a method computes: those that need work, or all of them when
// skipping is off. Every kernel must compute its pixels alone (no pixel depends on another
// output pixel), so the schedule and the thread count change no bit.
class TiledGather {
 public:
  TiledGather(const TileMap& tiles, bool skip, int threads)
      : tiles_(tiles), skip_(skip), threads_(threads) {}

  const TileMap& tiles() const { return tiles_; }
  bool skip() const { return skip_; }
  bool computes(std::ptrdiff_t tx, std::ptrdiff_t ty) const {
    return !skip_ || tiles_.needs_work(tx, ty);
  }
  // The fraction of the frame copied by copy_the_rest.
  double skipped_fraction() const { return skip_ ? 1.0 - tiles_.work_fraction() : 0.0; }

  // tile(area, info) on every computed tile, OpenMP over tiles one at a time (their costs
  // differ). `tile` returns how many of its pixels it copied unchanged; the result is that sum
  // plus the pixels of the tiles left to copy_the_rest.
  template <class Tile>
  std::ptrdiff_t for_each_tile(Tile&& tile) const {
    const std::ptrdiff_t count = tiles_.tiles_x() * tiles_.tiles_y();
    std::ptrdiff_t copied = 0;
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 1) reduction(+ : copied)
    for (std::ptrdiff_t t = 0; t < count; ++t) {
      const std::ptrdiff_t tx = t % tiles_.tiles_x(), ty = t / tiles_.tiles_x();
      const Rect area = tiles_.rect(tx, ty);
      if (!computes(tx, ty)) {
        copied += area.area();
        continue;
      }
      copied += tile(area, tiles_.at(tx, ty));
    }
    return copied;
  }

  // pixel(x, y, info) on every pixel of the computed tiles, info the pixel's tile.
  template <class Pixel>
  void for_each_pixel(Pixel&& pixel) const {
    for_each_tile([&](const Rect& area, const TileInfo& info) -> std::ptrdiff_t {
      for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
        for (std::ptrdiff_t x = area.x; x < area.x + area.width; ++x) pixel(x, y, info);
      return 0;
    });
  }

  // The computed columns of row y, as runs of adjacent computed tiles; `every_tile` computes
  // the unreached tiles too.
  void spans(std::ptrdiff_t y, std::vector<Span>& runs, bool every_tile = false) const {
    runs.clear();
    const std::ptrdiff_t tile = tiles_.tile_size(), ty = y / tile;
    for (std::ptrdiff_t tx = 0; tx < tiles_.tiles_x(); ++tx) {
      if (!every_tile && !computes(tx, ty)) continue;
      const std::ptrdiff_t x0 = tx * tile, x1 = std::min(x0 + tile, tiles_.width());
      if (!runs.empty() && runs.back().second == x0)
        runs.back().second = x1;
      else
        runs.emplace_back(x0, x1);
    }
  }

  // row(y, runs, scratch) on every row with computed columns (spans above), OpenMP over rows
  // in equal blocks; `make_scratch()` gives each thread its own buffers.
  template <class MakeScratch, class Row>
  void for_each_row(MakeScratch&& make_scratch, Row&& row, bool every_tile = false) const {
#pragma omp parallel num_threads(threads_)
    {
      auto scratch = make_scratch();
      std::vector<Span> runs;
#pragma omp for schedule(static)
      for (std::ptrdiff_t y = 0; y < tiles_.height(); ++y) {
        spans(y, runs, every_tile);
        if (!runs.empty()) row(y, runs, scratch);
      }
    }
  }

  // The last step of a method: out = color on the tiles not computed (none without skipping).
  void copy_the_rest(Image& out, const Image& color) const {
    if (!skip_) return;
    for (int c = 0; c < color.channels(); ++c)
      copy_unreached_tiles(out.plane(c), color.plane(c), tiles_, threads_);
  }

 private:
  const TileMap& tiles_;
  bool skip_;
  int threads_;
};

}  // namespace tridiff::dof_detail
