// Summed-area tables (seed 001 §2.1, Crow 1984): T(x, y) = the sum of in(x', y') over x' <= x,
// y' <= y, so that the sum over any rectangle takes four lookups (eq. 2.3). Two tables:
//
//  - SummedAreaTable: T in double. 8 bytes a pixel; its rounding is negligible at any image
//    size (entries < 2^53 ulp-wise: a 16k x 16k image of ones sums to 2^28).
//  - TiledFloatSummedAreaTable: the float variant. A plain float table loses precision as T
//    grows with the pixels above-left (seed 003, "Limitations": at 4096 x 4096 an entry reaches
//    1.6e7 and its float ulp is 1, so a 3 x 3 box sum is lost). Subtracting one global offset
//    (the image mean) only fixes constant or stationary images: a half-black half-white image
//    still grows entries to W H / 4. So we keep per-tile local tables: in each 32 x 32 tile a
//    float table of the tile's own rectangle sums minus the tile mean times the area (bounded
//    by 1024 x the tile's range whatever the image size, and exactly 0 on a constant tile),
//    plus in double the exact T along every tile's top row and left column (the "offsets in a
//    separate, lower resolution table" of seed 003). An entry is rebuilt exactly in double from
//    those; its only error is the float rounding of one local value. 4.5 bytes a pixel.
//
// Both are built as parallel scans with OpenMP: a fixed work split, so the result does not
// depend on the thread count.
//
// Lookups take x in [-1, width) and y in [-1, height); row and column -1 are zero. Sums over
// rectangles reaching outside the image follow the replicate border exactly (the edge pixel
// repeats), which is not the same as clamping the rectangle to the image.
#pragma once

#include <cstddef>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff {

class SummedAreaTable {
 public:
  SummedAreaTable() = default;
  // The table of `in`; threads 0 means all cores.
  explicit SummedAreaTable(ConstPlane in, int threads = 0);

  std::ptrdiff_t width() const { return width_; }
  std::ptrdiff_t height() const { return height_; }

  // T(x, y), x in [-1, width), y in [-1, height).
  double at(std::ptrdiff_t x, std::ptrdiff_t y) const {
    return table_[(y + 1) * stride_ + (x + 1)];
  }
  // Sum over [x0, x1] x [y0, y1] (inclusive, any integers with x0 <= x1 and y0 <= y1) of the
  // image extended by the replicate border.
  double replicate_box_sum(std::ptrdiff_t x0, std::ptrdiff_t y0, std::ptrdiff_t x1,
                           std::ptrdiff_t y1) const;

 private:
  std::ptrdiff_t width_ = 0, height_ = 0, stride_ = 0;  // stride_ = width_ + 1
  std::vector<double> table_;  // (height + 1) x (width + 1): a zero row and column in front
};

class TiledFloatSummedAreaTable {
 public:
  static constexpr std::ptrdiff_t kTile = 32;

  TiledFloatSummedAreaTable() = default;
  explicit TiledFloatSummedAreaTable(ConstPlane in, int threads = 0);

  std::ptrdiff_t width() const { return width_; }
  std::ptrdiff_t height() const { return height_; }

  // T(x, y) rebuilt in double, x in [-1, width), y in [-1, height).
  double at(std::ptrdiff_t x, std::ptrdiff_t y) const {
    if (x < 0 || y < 0) return 0;
    const std::ptrdiff_t tx = x / kTile, ty = y / kTile, tile = ty * tiles_x_ + tx;
    const double area = double(x - tx * kTile + 1) * double(y - ty * kTile + 1);
    return top_[ty * width_ + x] + left_[tx * height_ + y] - corner_[tile] + mean_[tile] * area +
           local_[y * width_ + x];
  }
  double replicate_box_sum(std::ptrdiff_t x0, std::ptrdiff_t y0, std::ptrdiff_t x1,
                           std::ptrdiff_t y1) const;

 private:
  std::ptrdiff_t width_ = 0, height_ = 0, tiles_x_ = 0, tiles_y_ = 0;
  std::vector<float> local_;    // per tile: its own rectangle sums minus mean x area
  std::vector<double> mean_;    // per tile
  std::vector<double> top_;     // tile row ty: T(x, y0 - 1) for every x (y0 = ty * kTile)
  std::vector<double> left_;    // tile column tx: T(x0 - 1, y) for every y (x0 = tx * kTile)
  std::vector<double> corner_;  // per tile: T(x0 - 1, y0 - 1)
};

// out(x, y) = the mean of the (2 radius_x + 1) x (2 radius_y + 1) box around (x, y) of the
// table's image, replicate border (boxes may be wider than the image). `out` has the table's
// size. Any radius >= 0. For a box size varying per pixel, use replicate_box_sum directly.
void sat_box_filter(Plane out, const SummedAreaTable& table, std::ptrdiff_t radius_x,
                    std::ptrdiff_t radius_y, int threads = 0);
void sat_box_filter(Plane out, const TiledFloatSummedAreaTable& table, std::ptrdiff_t radius_x,
                    std::ptrdiff_t radius_y, int threads = 0);

}  // namespace tridiff
