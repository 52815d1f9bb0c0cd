// Summed-area tables built as parallel prefix scans, and the box filter through them with the
// exact replicate border. See sat.hpp for the two tables and why the float one is tiled.
#include "tridiff/blur/sat.hpp"
#include "tridiff/threads.hpp"

#include <algorithm>
#include <string>

namespace tridiff {

namespace {

void check_input(ConstPlane in) {
  if (in.width() < 1 || in.height() < 1 || !in.data()) throw InvalidArgument("in", "is empty");
}

// The prefix sum P(i) = x[clamp 0] + ... + x[clamp i] of a line of n pixels extended by the
// replicate border, continued below i = 0 so that P(b) - P(a - 1) is the sum over [a, b] for
// any a <= b: P(-1) = 0 and P(i) = (i + 1) x[0] for i < 0; past the end the last pixel repeats.
// As a combination w0 T(p0) + w1 T(p1) of table prefixes (p >= -1, T(-1) = 0), using
// x[n - 1] = T(n - 1) - T(n - 2).
struct ExtendedPrefix {
  std::ptrdiff_t p0, p1;
  double w0, w1;
};

ExtendedPrefix extended_prefix(std::ptrdiff_t i, std::ptrdiff_t n) {
  if (i < 0) return {0, -1, static_cast<double>(i + 1), 0.0};
  if (i < n) return {i, -1, 1.0, 0.0};
  const double repeats = static_cast<double>(i - (n - 1));
  return {n - 1, n - 2, 1 + repeats, -repeats};
}

// The 2D extended prefix: the replicate extension is separable, so it is the tensor product of
// the two 1D combinations (at most four lookups).
template <class Table>
double extended_at(const Table& t, const ExtendedPrefix& px, const ExtendedPrefix& py) {
  double sum = px.w0 * py.w0 * t.at(px.p0, py.p0);
  if (px.w1 != 0) sum += px.w1 * py.w0 * t.at(px.p1, py.p0);
  if (py.w1 != 0) {
    sum += px.w0 * py.w1 * t.at(px.p0, py.p1);
    if (px.w1 != 0) sum += px.w1 * py.w1 * t.at(px.p1, py.p1);
  }
  return sum;
}

template <class Table>
double replicate_sum(const Table& t, std::ptrdiff_t x0, std::ptrdiff_t y0, std::ptrdiff_t x1,
                     std::ptrdiff_t y1) {
  const std::ptrdiff_t w = t.width(), h = t.height();
  const ExtendedPrefix left = extended_prefix(x0 - 1, w), right = extended_prefix(x1, w);
  const ExtendedPrefix top = extended_prefix(y0 - 1, h), bottom = extended_prefix(y1, h);
  return extended_at(t, right, bottom) - extended_at(t, left, bottom) - extended_at(t, right, top) +
         extended_at(t, left, top);
}

template <class Table>
void box_filter(const Table& t, Plane out, std::ptrdiff_t rx, std::ptrdiff_t ry, int threads) {
  const std::ptrdiff_t w = t.width(), h = t.height();
  if (out.width() != w || out.height() != h)
    throw InvalidArgument("out", "size differs from the table's");
  if (rx < 0 || ry < 0) throw InvalidArgument("radius", "must be >= 0");
  threads = resolve_threads(threads);
  const double inv_area = 1.0 / (double(2 * rx + 1) * double(2 * ry + 1));
  // Columns whose box lies inside the image horizontally: [inner_x0, inner_x1).
  const std::ptrdiff_t inner_x0 = std::min(rx, w), inner_x1 = std::max(inner_x0, w - rx);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t y = 0; y < h; ++y) {
    float* o = out.row(y);
    const auto general = [&](std::ptrdiff_t x) {
      o[x] = static_cast<float>(replicate_sum(t, x - rx, y - ry, x + rx, y + ry) * inv_area);
    };
    for (std::ptrdiff_t x = 0; x < inner_x0; ++x) general(x);
    if (y - ry >= 0 && y + ry < h) {
      // The common case: four plain lookups (eq. 2.3).
      const std::ptrdiff_t top = y - ry - 1, bottom = y + ry;
      for (std::ptrdiff_t x = inner_x0; x < inner_x1; ++x)
        o[x] = static_cast<float>((t.at(x + rx, bottom) - t.at(x - rx - 1, bottom) -
                                   t.at(x + rx, top) + t.at(x - rx - 1, top)) *
                                  inv_area);
    } else {
      for (std::ptrdiff_t x = inner_x0; x < inner_x1; ++x) general(x);
    }
    for (std::ptrdiff_t x = inner_x1; x < w; ++x) general(x);
  }
}

}  // namespace

// Rows then columns: each row's prefix sum is independent (parallel over rows); then each row
// adds the one above, which is sequential down a column but independent across columns
// (parallel over strips of columns, vectorised along the row). Every entry is summed in the
// same order whatever the thread count.
SummedAreaTable::SummedAreaTable(ConstPlane in, int threads) {
  check_input(in);
  threads = resolve_threads(threads);
  width_ = in.width();
  height_ = in.height();
  stride_ = width_ + 1;
  table_.assign((height_ + 1) * stride_, 0.0);
  const std::ptrdiff_t w = width_, h = height_;
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      const float* src = in.row(y);
      double* dst = table_.data() + (y + 1) * stride_ + 1;
      double sum = 0;
      for (std::ptrdiff_t x = 0; x < w; ++x) dst[x] = sum += src[x];
    }
    // 512 doubles (4 KiB) a strip: the row above stays in L1.
    constexpr std::ptrdiff_t kStrip = 512;
    const std::ptrdiff_t strips = (w + kStrip - 1) / kStrip;
#pragma omp for schedule(static)
    for (std::ptrdiff_t s = 0; s < strips; ++s) {
      const std::ptrdiff_t x0 = 1 + s * kStrip, x1 = std::min(x0 + kStrip, w + 1);
      for (std::ptrdiff_t y = 2; y <= h; ++y) {
        double* row = table_.data() + y * stride_;
        const double* above = row - stride_;
#pragma omp simd
        for (std::ptrdiff_t x = x0; x < x1; ++x) row[x] += above[x];
      }
    }
  }
}

double SummedAreaTable::replicate_box_sum(std::ptrdiff_t x0, std::ptrdiff_t y0, std::ptrdiff_t x1,
                                          std::ptrdiff_t y1) const {
  return replicate_sum(*this, x0, y0, x1, y1);
}

namespace {

// One band of tile rows of the tiled table, independently of the others: the tile means, the
// local tables, and T relative to the band (rows y0.. only) along the tile columns' left
// edges and along the band's last row (`bottom`, width doubles).
struct TiledBand {
  ConstPlane in;
  std::ptrdiff_t tile, tiles_x;
  float* local;
  double* mean;    // this band's tiles
  double* left;    // left[tx * height + y]
  double* bottom;  // width
};

void build_tiled_band(const TiledBand& b, std::ptrdiff_t y0) {
  const std::ptrdiff_t w = b.in.width(), h = b.in.height();
  const std::ptrdiff_t y1 = std::min(y0 + b.tile, h);
  // The tile means, so that each local table holds deviations from its tile's mean: exactly 0
  // on a constant tile, and small on a smooth one.
  std::fill_n(b.mean, b.tiles_x, 0.0);
  for (std::ptrdiff_t y = y0; y < y1; ++y) {
    const float* row = b.in.row(y);
    for (std::ptrdiff_t x = 0; x < w; ++x) b.mean[x / b.tile] += row[x];
  }
  for (std::ptrdiff_t tx = 0; tx < b.tiles_x; ++tx) {
    const std::ptrdiff_t tile_width = std::min(b.tile, w - tx * b.tile);
    b.mean[tx] /= double(tile_width) * double(y1 - y0);
  }
  // column[x]: the sum over the tile's columns x0..x and the band's rows y0..y, in double.
  std::vector<double> column(w, 0.0);
  for (std::ptrdiff_t y = y0; y < y1; ++y) {
    const float* row = b.in.row(y);
    double left_of_tile = 0;  // the band's sum over all columns left of the tile, rows y0..y
    for (std::ptrdiff_t tx = 0; tx < b.tiles_x; ++tx) {
      const std::ptrdiff_t x0 = tx * b.tile, x1 = std::min(x0 + b.tile, w);
      b.left[tx * h + y] = left_of_tile;
      double run = 0;
      for (std::ptrdiff_t x = x0; x < x1; ++x) {
        run += row[x];
        column[x] += run;
        const double area = double(x - x0 + 1) * double(y - y0 + 1);
        b.local[y * w + x] = static_cast<float>(column[x] - b.mean[tx] * area);
      }
      if (y == y1 - 1)
        for (std::ptrdiff_t x = x0; x < x1; ++x) b.bottom[x] = left_of_tile + column[x];
      left_of_tile += column[x1 - 1];
    }
  }
}

}  // namespace

// A blocked two-level scan: bands of tile rows are scanned independently (parallel), the exact
// T above each band is a short sequential scan over the bands' last rows, and a last parallel
// pass turns the band-relative left edges into absolute ones.
TiledFloatSummedAreaTable::TiledFloatSummedAreaTable(ConstPlane in, int threads) {
  check_input(in);
  threads = resolve_threads(threads);
  width_ = in.width();
  height_ = in.height();
  tiles_x_ = (width_ + kTile - 1) / kTile;
  tiles_y_ = (height_ + kTile - 1) / kTile;
  local_.assign(width_ * height_, 0.f);
  mean_.assign(tiles_x_ * tiles_y_, 0.0);
  top_.assign(tiles_y_ * width_, 0.0);
  left_.assign(tiles_x_ * height_, 0.0);
  corner_.assign(tiles_x_ * tiles_y_, 0.0);
  const std::ptrdiff_t w = width_, h = height_, tx_count = tiles_x_, ty_count = tiles_y_;
  std::vector<double> bottoms(ty_count * w);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t ty = 0; ty < ty_count; ++ty)
    build_tiled_band({in, kTile, tx_count, local_.data(), mean_.data() + ty * tx_count,
                      left_.data(), bottoms.data() + ty * w},
                     ty * kTile);
  for (std::ptrdiff_t ty = 1; ty < ty_count; ++ty) {
    double* top = top_.data() + ty * w;
    const double* above = top - w;
    const double* bottom = bottoms.data() + (ty - 1) * w;
#pragma omp simd
    for (std::ptrdiff_t x = 0; x < w; ++x) top[x] = above[x] + bottom[x];
  }
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t ty = 0; ty < ty_count; ++ty) {
    const std::ptrdiff_t y0 = ty * kTile, y1 = std::min(y0 + kTile, h);
    for (std::ptrdiff_t tx = 1; tx < tx_count; ++tx) {
      const double above_left = top_[ty * w + tx * kTile - 1];
      corner_[ty * tx_count + tx] = above_left;
      for (std::ptrdiff_t y = y0; y < y1; ++y) left_[tx * h + y] += above_left;
    }
  }
}

double TiledFloatSummedAreaTable::replicate_box_sum(std::ptrdiff_t x0, std::ptrdiff_t y0,
                                                    std::ptrdiff_t x1, std::ptrdiff_t y1) const {
  return replicate_sum(*this, x0, y0, x1, y1);
}

void sat_box_filter(Plane out, const SummedAreaTable& table, std::ptrdiff_t radius_x,
                    std::ptrdiff_t radius_y, int threads) {
  box_filter(table, out, radius_x, radius_y, threads);
}

void sat_box_filter(Plane out, const TiledFloatSummedAreaTable& table, std::ptrdiff_t radius_x,
                    std::ptrdiff_t radius_y, int threads) {
  box_filter(table, out, radius_x, radius_y, threads);
}

}  // namespace tridiff
