// One tile classification of a CoC map, shared by every depth-of-field method (issue 5, "skip
// what a scene doesn't need"): per tile the range of the signed CoC, whether the tile holds near,
// far or only sharp pixels, and how far the blur of the tiles around it reaches into it. A method
// copies the tiles that nothing reaches, sizes its gather to the largest disc that can reach a
// tile, and leaves out a pass the whole frame does not need (no near pixel: no near pass).
//
// Sign convention (as everywhere in dof/): a CoC c is a signed diameter in pixels, negative in
// front of the focus. A pixel is sharp when |c| < in_focus_coc_px; its blur radius is |c| / 2.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff {

enum class TileKind : unsigned char {
  sharp = 0,  // every pixel of the tile is sharp
  far = 1,    // some pixel is out of focus behind the focus, none in front
  near = 2,   // some pixel is out of focus in front of the focus, none behind
  mixed = 3,  // both near and far pixels
};

struct TileInfo {
  float min_coc = 0, max_coc = 0;  // signed range over the tile's pixels
  float max_radius = 0;            // max |c| / 2 over the tile's out-of-focus pixels (0: none)
  Rect blurred;                    // the bounding box of those pixels (empty: none)
  // The largest radius of any out-of-focus pixel in the frame whose disc (radius r around it,
  // rounded out to whole pixels) overlaps this tile; this tile's own pixels included. 0: no disc
  // reaches the tile, so every method's output there is its input.
  float reach_radius = 0;
  float near_reach_radius = 0;  // the same over near (c < 0) pixels only
  TileKind kind = TileKind::sharp;
};

// The CoC (px) from which a pixel counts as out of focus for the gather and scatter methods:
// the setting, but never below one pixel (a disc under one pixel is a point).
inline float sharp_below_px(float in_focus_coc_px) { return std::max(1.f, in_focus_coc_px); }

// The one definition of "in focus" for every DOF method and the tile classification: a signed
// CoC c (finite) is sharp when |c| < sharp_below; otherwise it is near (in front of the focus,
// c <= -sharp_below) or far (c >= sharp_below). The gather and scatter methods and TileMap use
// sharp_below_px(DofOptions::in_focus_coc_px); the diffusion methods the setting itself (their
// conductance vanishes continuously, so a sub-pixel threshold means something to them).
struct FocusTest {
  float sharp_below = 1.f;
  bool is_sharp(float c) const { return std::abs(c) < sharp_below; }
  bool is_near(float c) const { return c <= -sharp_below; }
  bool is_far(float c) const { return c >= sharp_below; }
};

class TileMap {
 public:
  static constexpr std::ptrdiff_t kDefaultTile = 32;

  // Classifies `coc` (finite; check with validate_coc first) in tile x tile squares (the last
  // row and column of tiles may be smaller). A disc of radius r reaches ceil(r + 1/2) +
  // margin_px pixels from its centre: the 1/2 covers an anti-aliased rim, the margin what a
  // method's filters add beyond the disc (a 3 x 3 blur, bilinear upsampling from half
  // resolution). OpenMP over tile rows with `threads` (0: all).
  TileMap(ConstPlane coc, float in_focus_coc_px, std::ptrdiff_t tile = kDefaultTile,
          std::ptrdiff_t margin_px = 0, int threads = 0);

  std::ptrdiff_t tile_size() const { return tile_; }
  std::ptrdiff_t tiles_x() const { return tiles_x_; }
  std::ptrdiff_t tiles_y() const { return tiles_y_; }
  std::ptrdiff_t width() const { return width_; }
  std::ptrdiff_t height() const { return height_; }
  float in_focus_coc_px() const { return in_focus_; }
  FocusTest focus() const { return {in_focus_}; }  // the predicate the tiles were classified by

  const TileInfo& at(std::ptrdiff_t tx, std::ptrdiff_t ty) const {
    return info_[std::size_t(ty * tiles_x_ + tx)];
  }
  // The tile holding pixel (x, y).
  const TileInfo& of_pixel(std::ptrdiff_t x, std::ptrdiff_t y) const {
    return at(x / tile_, y / tile_);
  }
  // The pixels of tile (tx, ty).
  Rect rect(std::ptrdiff_t tx, std::ptrdiff_t ty) const;

  // Whether some disc reaches the tile: a method must compute it (false: copy the input).
  bool needs_work(std::ptrdiff_t tx, std::ptrdiff_t ty) const {
    return at(tx, ty).reach_radius > 0;
  }

  // Whole-frame summaries: a pass that no pixel needs is not run.
  bool has_near() const { return has_near_; }
  bool has_far() const { return has_far_; }
  float max_radius() const { return max_radius_; }  // max |c| / 2 over out-of-focus pixels
  // Fraction of the frame's pixels in tiles that need work (the "out-of-focus fraction" that
  // the benchmarks plot cost against).
  double work_fraction() const { return work_fraction_; }

 private:
  std::ptrdiff_t width_, height_, tile_, tiles_x_, tiles_y_;
  float in_focus_;
  std::vector<TileInfo> info_;
  bool has_near_ = false, has_far_ = false;
  float max_radius_ = 0;
  double work_fraction_ = 0;
};

// Copies `in` to `out` (same size) on the tiles that need no work; the other tiles are left as
// they are. Every method's last step. `threads`: 0 = all cores.
void copy_unreached_tiles(Plane out, ConstPlane in, const TileMap& tiles, int threads = 0);

}  // namespace tridiff
