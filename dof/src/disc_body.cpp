#include "disc_body.hpp"

#include <algorithm>
#include <cassert>
#include <limits>
#include <cmath>
#include <utility>
#include <cstring>

#include "tridiff/dof/tiles.hpp"
#include "aperture_footprint.hpp"  // fold

namespace tridiff::dof_detail {
namespace {

// Tiles are gathered in blocks of kBlockRows x kBlockColumns pixels. A block's prefix sums
// cover its rows plus the largest radius above and below, and its columns plus that radius and
// two: taller and wider blocks sum fewer pixels twice, but the sums (32 bytes a pixel, for up
// to four channels) must stay in L2 while the block's tiles read them. 32 x 128 with radius 16
// is 67 rows x 169 columns, 354 KiB. (Bands of the full width, 3.5 MiB at 1920 px, made the
// gather 3.5 times slower: its reads came from L3.)
constexpr std::ptrdiff_t kBlockRows = 32, kBlockColumns = 128;

// The block holding a tile, in raster order of blocks.
std::pair<std::ptrdiff_t, std::ptrdiff_t> block_of(const Rect& tile) {
  return {tile.y / kBlockRows, tile.x / kBlockColumns};
}

// Whether the tiles within `reach` tiles of (tx, ty) are all far with CoCs in [kMinDiscCocPx,
// kMaxDiscCocPx], spanning at most kSmoothCocPx.
bool far_and_smooth_around(const TileMap& map, std::ptrdiff_t tx, std::ptrdiff_t ty,
                           std::ptrdiff_t reach, float sharp_below) {
  float lowest = INFINITY, highest = -INFINITY;
  for (std::ptrdiff_t y = std::max<std::ptrdiff_t>(ty - reach, 0);
       y <= std::min(ty + reach, map.tiles_y() - 1); ++y)
    for (std::ptrdiff_t x = std::max<std::ptrdiff_t>(tx - reach, 0);
         x <= std::min(tx + reach, map.tiles_x() - 1); ++x) {
      const TileInfo& info = map.at(x, y);
      if (info.kind != TileKind::far || !(info.min_coc >= std::max(sharp_below, kMinDiscCocPx)) ||
          !(info.max_coc <= kMaxDiscCocPx))
        return false;
      lowest = std::min(lowest, info.min_coc);
      highest = std::max(highest, info.max_coc);
    }
  return highest - lowest <= kSmoothCocPx;
}

// Where a band's prefix sums start and end: rows [first_row, first_row + rows), pixels
// [first_x, first_x + span), with everything outside the frame folded into it.
struct PrefixWindow {
  std::ptrdiff_t first_row = 0, rows = 0, first_x = 0, span = 0;
  std::ptrdiff_t length() const { return span + 1; }
};

// The smallest and the largest radius (|c| / 2) of a tile's pixels.
struct RadiusRange {
  double smallest = INFINITY, largest = 0;
};

RadiusRange radius_range(const Rect& tile, ConstPlane coc) {
  assert(tile.width <= kDiscTile);
  // Column by column first, in vector lanes: a min and a max chained over all 64 pixels cost a
  // few percent of the gather.
  float lowest[kDiscTile], highest[kDiscTile];
  std::fill_n(lowest, kDiscTile, INFINITY);
  std::fill_n(highest, kDiscTile, 0.f);
  for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y) {
    const float* c = coc.row(y) + tile.x;
    for (std::ptrdiff_t x = 0; x < tile.width; ++x) {
      const float a = std::fabs(c[x]);
      lowest[x] = a < lowest[x] ? a : lowest[x];
      highest[x] = a > highest[x] ? a : highest[x];
    }
  }
  const float smallest = *std::min_element(lowest, lowest + kDiscTile);
  const float largest = *std::max_element(highest, highest + kDiscTile);
  return {0.5 * double(smallest), 0.5 * double(largest)};
}

// A thread's buffers for the gather, reused from band to band.
struct GatherScratch {
  std::vector<double> prefix;                  // the band's row prefix sums
  std::vector<std::ptrdiff_t> columns;         // the input columns of the window's pixels
  std::vector<RadiusRange> ranges;             // the band's tiles' radii
  std::vector<double> small_rows, large_rows;  // half widths of a tile's two discs
};

// The prefix sums of `input` over `window`, a row per channel: entry i of row j, channel c is
// prefix[(j * channels + c) * length + i], the sum of the window's first i pixels of that row.
// The window is in the gather's frame: `input` itself (scale 1), or the 2 x 2 means of the
// input continued as its mirror image (scale 2: half pixel u averages input columns 2u and
// 2u + 1, folded, so that beyond the frame the half frame continues the full one's mirror
// even for odd sizes), made here from the input's rows, only where a window reaches.
// Each sum depends on the one before it: kChains rows x channels are summed side by side, so
// that the adds' latency overlaps (one chain at a time made the sums a third of the gather).
constexpr std::ptrdiff_t kChains = 8;
void row_prefix_sums(const Image& input, int scale, const PrefixWindow& window,
                     std::vector<double>& prefix, std::vector<std::ptrdiff_t>& columns) {
  const std::ptrdiff_t length = window.length();
  const int channels = input.channels();
  prefix.resize(std::size_t(window.rows * channels * length));
  // The input columns of window pixel i: columns[i * scale + k], k < scale.
  columns.resize(std::size_t(window.span * scale));
  for (std::ptrdiff_t i = 0; i < window.span * scale; ++i)
    columns[std::size_t(i)] = fold(window.first_x * scale + i, input.width());
  const std::ptrdiff_t chains = window.rows * channels;  // (row, channel) pairs, in prefix order
  for (std::ptrdiff_t first = 0; first < chains; first += kChains) {
    const std::ptrdiff_t count = std::min(kChains, chains - first);
    const float* upper[kChains];
    const float* lower[kChains];  // scale 2: the block's second row
    double* sums[kChains];
    for (std::ptrdiff_t k = 0; k < count; ++k) {
      const std::ptrdiff_t row = (window.first_row + (first + k) / channels) * scale;
      const ConstPlane plane = input.plane(int((first + k) % channels));
      upper[k] = plane.row(fold(row, input.height()));
      lower[k] = plane.row(fold(row + scale - 1, input.height()));
      sums[k] = prefix.data() + (first + k) * length;
      sums[k][0] = 0;
    }
    double sum[kChains] = {};
    const std::ptrdiff_t* at = columns.data();
    if (scale == 1) {
      for (std::ptrdiff_t i = 0; i < window.span; ++i)
        for (std::ptrdiff_t k = 0; k < count; ++k)
          sums[k][i + 1] = sum[k] += double(upper[k][at[i]]);
      continue;
    }
    for (std::ptrdiff_t i = 0; i < window.span; ++i) {
      const std::ptrdiff_t left = at[2 * i], right = at[2 * i + 1];
      for (std::ptrdiff_t k = 0; k < count; ++k)
        sums[k][i + 1] = sum[k] += 0.25 * (double(upper[k][left]) + double(upper[k][right]) +
                                           double(lower[k][left]) + double(lower[k][right]));
    }
  }
}

// The kDiscTile pixels of a tile row, one per vector lane. Written as a vector type: one
// disc row of all of them is then a few vector loads from the prefix sums (their spans, of
// one width, start at consecutive pixels).
using Lanes = double __attribute__((vector_size(kDiscTile * sizeof(double))));

inline Lanes load_lanes(const double* from) {
  Lanes values;
  std::memcpy(&values, from, sizeof values);
  return values;
}

// The integrals over [lo + i, hi + i], lane i (pixels as unit boxes, 0 <= lo <= hi inside the
// window), of a prefix-summed row: the sums at both ends, interpolated linearly.
inline Lanes span_integrals(const double* row, double lo, double hi) {
  const auto k_lo = static_cast<std::ptrdiff_t>(lo), k_hi = static_cast<std::ptrdiff_t>(hi);
  const Lanes at_lo = load_lanes(row + k_lo), next_lo = load_lanes(row + k_lo + 1);
  const Lanes at_hi = load_lanes(row + k_hi), next_hi = load_lanes(row + k_hi + 1);
  return (at_hi + (hi - double(k_hi)) * (next_hi - at_hi)) -
         (at_lo + (lo - double(k_lo)) * (next_lo - at_lo));
}

// asin x for 0 <= x <= 1, within 4.4e-8 (Abramowitz & Stegun 4.4.46, a polynomial in x times
// sqrt(1 - x)): std::asin cost a fifth of the gather.
inline double asin_unit(double x) {
  const double p =
      1.5707963050 +
      x * (-0.2145988016 +
           x * (0.0889789874 +
                x * (-0.0501743046 +
                     x * (0.0308918810 +
                          x * (-0.0170881256 + x * (0.0066700901 + x * -0.0012624911))))));
  // Less the polynomial's error at 0 (pi/2 - its constant term, 2.2e-8), so that asin 0 is 0
  // and the middle row's half width r is not widened by r² 2.2e-8.
  return 1.5707963267948966 - std::sqrt(std::max(1 - x, 0.0)) * p - 2.17948966e-8;
}

// The area of the disc of radius r between the horizontal line through its centre and the line
// t above it (0 <= t <= r): the integral of 2 sqrt(r² - s²) over [0, t]. The error of
// asin_unit, r² 4.4e-8, is 2e-4 pixels at r = 64 (kMaxDiscCocPx / 2).
inline double half_strip_area(double r, double t) {
  return t * std::sqrt(std::max(r * r - t * t, 0.0)) + r * r * asin_unit(std::min(t / r, 1.0));
}

// The half widths of the rows dy = 0 .. floor(r + 1/2) of the disc of radius r >= 1/2 (into
// `half_widths`), and their total weight (the disc's area): row dy is the span of the disc's
// area in the strip [dy - 1/2, dy + 1/2], centred. The rows hold the disc's area exactly, and a
// row enters (dy = r + 1/2) with width 0, so the average is continuous in r.
double disc_rows(double r, std::vector<double>& half_widths) {
  const auto rows = static_cast<std::ptrdiff_t>(r + 0.5);
  half_widths.resize(std::size_t(rows + 1));
  double* h = half_widths.data();
  // The areas below each row's upper edge first, in vector lanes; then their differences.
#pragma omp simd
  for (std::ptrdiff_t dy = 0; dy <= rows; ++dy)
    h[dy] = half_strip_area(r, std::min(double(dy) + 0.5, r));
  double below = h[0], weight = 2 * h[0];
  for (std::ptrdiff_t dy = 1; dy <= rows; ++dy) {
    const double above = h[dy];
    h[dy] = std::max(0.5 * (above - below), 0.0);  // 0 past the disc
    below = above;
    weight += 4 * h[dy];
  }
  return weight;
}

// The averages over the disc of radius r of the kDiscTile pixels of row y from column x0, one
// channel: rows dy and -dy share their span.
Lanes disc_averages(const double* prefix, const PrefixWindow& window, int channels, int channel,
                    std::ptrdiff_t y, std::ptrdiff_t x0, const std::vector<double>& half_widths,
                    double weight) {
  const std::ptrdiff_t row_stride = window.length() * channels;
  const double* row = prefix + (y - window.first_row) * row_stride + channel * window.length();
  const double centre = double(x0 - window.first_x) + 0.5;
  Lanes sum = span_integrals(row, centre - half_widths[0], centre + half_widths[0]);
  for (std::size_t dy = 1; dy < half_widths.size(); ++dy) {
    const double h = half_widths[dy];
    const auto offset = std::ptrdiff_t(dy) * row_stride;
    sum += span_integrals(row - offset, centre - h, centre + h) +
           span_integrals(row + offset, centre - h, centre + h);
  }
  return sum / weight;
}

// The disc averages of one tile (tile.area() values a channel, row-major, into out). Each tile
// row is gathered with the smallest and the largest radius of the tile, the lanes its pixels,
// and each pixel takes the average at its own radius interpolated linearly between the two:
// exact for constants and linear ramps (both are), and the average is smooth in r (the radii
// of a smooth tile differ by at most kSmoothCocPx / 2; a row entering at the larger radius
// holds an area of order (Δr)^(3/2) sqrt(r), 0.7 % of the disc at r = 5, Δr = 1/4, of which
// the interpolation misses a fraction). A tile of one radius is gathered once.
void gather_tile(const Rect& tile, RadiusRange range, ConstPlane coc, const PrefixWindow& window,
                 int channels, GatherScratch& scratch, float* out) {
  const std::ptrdiff_t area = tile.area();
  const double smallest = range.smallest, largest = range.largest;
  const double small_weight = disc_rows(smallest, scratch.small_rows);
  const bool uniform = largest == smallest;
  const double large_weight = uniform ? 0 : disc_rows(largest, scratch.large_rows);
  double t[kDiscTile];  // each pixel's place between the two radii
  for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y) {
    if (!uniform) {
      const float* c = coc.row(y) + tile.x;
      for (std::ptrdiff_t x = 0; x < tile.width; ++x)
        t[x] = (0.5 * std::fabs(double(c[x])) - smallest) / (largest - smallest);
    }
    for (int channel = 0; channel < channels; ++channel) {
      const Lanes at_small = disc_averages(scratch.prefix.data(), window, channels, channel, y,
                                           tile.x, scratch.small_rows, small_weight);
      float* to = out + channel * area + (y - tile.y) * tile.width;
      if (uniform) {
        for (std::ptrdiff_t x = 0; x < tile.width; ++x) to[x] = static_cast<float>(at_small[x]);
        continue;
      }
      const Lanes at_large = disc_averages(scratch.prefix.data(), window, channels, channel, y,
                                           tile.x, scratch.large_rows, large_weight);
      for (std::ptrdiff_t x = 0; x < tile.width; ++x)
        to[x] = static_cast<float>(at_small[x] + t[x] * (at_large[x] - at_small[x]));
    }
  }
}

// The disc averages of a band of tiles: their prefix sums over the rows and columns their discs
// reach, then each tile.
void gather_band(const Image& input, int scale, ConstPlane coc, const Rect* tiles,
                 std::size_t count, const std::size_t* offsets, GatherScratch& scratch,
                 float* values) {
  double radius = 0;
  std::ptrdiff_t top = tiles[0].y, bottom = top, left = tiles[0].x, right = left;
  scratch.ranges.resize(count);
  for (std::size_t t = 0; t < count; ++t) {
    const Rect& tile = tiles[t];
    scratch.ranges[t] = radius_range(tile, coc);
    radius = std::max(radius, scratch.ranges[t].largest);
    top = std::min(top, tile.y);
    bottom = std::max(bottom, tile.y + tile.height);
    left = std::min(left, tile.x);
    right = std::max(right, tile.x + kDiscTile);  // every lane, past a narrow tile too
  }
  // Rows above and below: the largest radius, rounded as the gather rounds it. Columns: that,
  // and the span's ends rounded out.
  const auto reach = static_cast<std::ptrdiff_t>(radius + 0.5);
  const std::ptrdiff_t pad = reach + 3;
  const PrefixWindow window{top - reach, bottom - top + 2 * reach + 1, left - pad,
                            right - left + 2 * pad};
  row_prefix_sums(input, scale, window, scratch.prefix, scratch.columns);
  for (std::size_t t = 0; t < count; ++t)
    gather_tile(tiles[t], scratch.ranges[t], coc, window, input.channels(), scratch,
                values + offsets[t]);
}

}  // namespace

std::ptrdiff_t DiscTiles::pixels() const {
  std::ptrdiff_t total = 0;
  for (const Rect& tile : tiles) total += tile.area();
  return total;
}

std::vector<Rect> smooth_far_tiles(ConstPlane coc, float sharp_below, int threads) {
  const TileMap map(coc, sharp_below, kDiscTile, 0, threads);
  std::vector<Rect> smooth;
  for (std::ptrdiff_t ty = 0; ty < map.tiles_y(); ++ty)
    for (std::ptrdiff_t tx = 0; tx < map.tiles_x(); ++tx) {
      const TileInfo& info = map.at(tx, ty);
      if (info.kind != TileKind::far || info.near_reach_radius > 0) continue;
      // Every pixel within R + 1 of the tile, R its largest radius.
      const auto reach_px = static_cast<std::ptrdiff_t>(std::ceil(info.max_radius)) + 1;
      const std::ptrdiff_t reach = (reach_px + kDiscTile - 1) / kDiscTile;
      if (far_and_smooth_around(map, tx, ty, reach, sharp_below))
        smooth.push_back(map.rect(tx, ty));
    }
  return smooth;
}

namespace {

// Orders tiles by block (block_of), as gather_tiles needs them.
void sort_by_block(std::vector<Rect>& tiles) {
  std::stable_sort(tiles.begin(), tiles.end(),
                   [](const Rect& a, const Rect& b) { return block_of(a) < block_of(b); });
}

// Where each tile's values start when packed in order: tile i's channel c at offsets[i] + c *
// area_i (DiscTiles). Returns the total.
std::size_t pack(const std::vector<Rect>& tiles, int channels, std::vector<std::size_t>& offsets,
                 std::size_t start = 0) {
  for (const Rect& tile : tiles) {
    offsets.push_back(start);
    start += std::size_t(tile.area() * channels);
  }
  return start;
}

// Storage for `count` floats (at least one). Above 1 MiB its pages are first touched by the
// threads that write them (allocate_zeroed_floats maps them): the values of a 4K frame's tiles
// are tens of MB, and zeroing them on one thread first cost more than a tenth of the gather.
detail::FloatStorage values_for(std::size_t count) {
  return detail::allocate_zeroed_floats(std::ptrdiff_t(std::max<std::size_t>(count, 1)));
}

// The disc averages of `count` tiles (tiles of the kDiscTile grid of the gather's frame, sorted
// by block: `input` at `scale` 1 or 2, row_prefix_sums; `coc` in that frame's pixels), into
// values + offsets[i].
void gather_tiles(const Image& input, int scale, ConstPlane coc, const Rect* tiles,
                  std::size_t count, const std::size_t* offsets, float* values, int threads) {
  // Blocks of kBlockRows x kBlockColumns pixels: a block's prefix sums are made once, for its
  // tiles together.
  std::vector<std::size_t> band_starts;
  for (std::size_t t = 0; t < count; ++t)
    if (t == 0 || block_of(tiles[t]) != block_of(tiles[t - 1])) band_starts.push_back(t);
  band_starts.push_back(count);
  const auto bands = std::ptrdiff_t(band_starts.size()) - 1;
#pragma omp parallel num_threads(threads)
  {
    GatherScratch scratch;
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t b = 0; b < bands; ++b) {
      const std::size_t first = band_starts[std::size_t(b)];
      gather_band(input, scale, coc, tiles + first, band_starts[std::size_t(b) + 1] - first,
                  offsets + first, scratch, values);
    }
  }
}

// The half-resolution gather (kHalfResRadiusPx). Full-resolution pixel x sits at x / 2 - 1/4 in
// the half frame, between half pixels floor(x / 2 - 1/4) and the next, weights 3/4 and 1/4 (x
// odd) or 1/4 and 3/4 (x even): a tile from x0 (a multiple of kDiscTile) reads half columns
// x0 / 2 - 1 .. (x0 + width) / 2, and the same for rows. Beyond the half frame the mirror
// repeats the edge pixel, which the interpolation reads by clamping.
struct HalfSpan {
  std::ptrdiff_t first, last;  // inclusive, clamped to the half frame
};
HalfSpan half_span(std::ptrdiff_t start, std::ptrdiff_t length, std::ptrdiff_t half_length) {
  return {std::max<std::ptrdiff_t>(start / 2 - 1, 0),
          std::min((start + length) / 2, half_length - 1)};
}

// The half frame's gather: the tiles of its kDiscTile grid that hold a half pixel some coarse
// tile reads, their CoC, and their disc averages.
struct HalfGather {
  std::ptrdiff_t width = 0, height = 0, tiles_x = 0, tiles_y = 0;
  std::vector<Rect> tiles;  // sorted by block, as gather_tiles needs
  Image coc;                // a diameter in half pixels
  std::vector<std::size_t> offsets;
  detail::FloatStorage values;
  std::vector<std::size_t> tile_index;  // per tile of the grid: its place in `tiles`
  static constexpr std::size_t kNotGathered = std::numeric_limits<std::size_t>::max();

  // Half pixel (x, y) of the gather, channel 0; channel c is c * plane(x, y) further.
  const float* at(std::ptrdiff_t x, std::ptrdiff_t y) const {
    const std::size_t t = tile_index[std::size_t((y / kDiscTile) * tiles_x + x / kDiscTile)];
    assert(t != kNotGathered);  // plan_half_gather marks every half pixel a tile reads
    const Rect& tile = tiles[t];
    return values.get() + offsets[t] + (y - tile.y) * tile.width + (x - tile.x);
  }
  std::ptrdiff_t plane(std::ptrdiff_t x, std::ptrdiff_t y) const {
    return tiles[tile_index[std::size_t((y / kDiscTile) * tiles_x + x / kDiscTile)]].area();
  }
};

// Tile (tx, ty) of the half frame, cut at its edges.
Rect half_tile(const HalfGather& half, std::ptrdiff_t tx, std::ptrdiff_t ty) {
  return {tx * kDiscTile, ty * kDiscTile, std::min(kDiscTile, half.width - tx * kDiscTile),
          std::min(kDiscTile, half.height - ty * kDiscTile)};
}

// The mean radius of the four full pixels of half pixel (x, y).
double block_radius(ConstPlane coc, std::ptrdiff_t x, std::ptrdiff_t y) {
  double sum = 0;
  for (std::ptrdiff_t j = 0; j < 2; ++j)
    for (std::ptrdiff_t i = 0; i < 2; ++i)
      sum += std::fabs(double(coc(fold(2 * x + i, coc.width()), fold(2 * y + j, coc.height()))));
  return sum / 8;
}

// The half disc's radius, in full pixels, for a full-resolution radius r: narrower, because the
// 2 x 2 mean and the interpolation blur too. Matching the spreads (per axis, the disc's
// variance r² / 4 against the mean's 1/3 px² and the interpolation's 3/4 px², weights 3/4 and
// 1/4 at 1/2 and 3/2 px) gives sqrt(r² - 13/3); against the exact disc on a 1/f² texture
// (d = 24 to 64 px) the error is least near sqrt(r² - 5/2), 2-7 % less rms: a disc is no bell.
// At least 1 px, so that the disc has rows (smooth_far_tiles' tiles have r >= 11.5).
double half_disc_radius(double r) { return std::sqrt(std::max(r * r - 2.5, 1.0)); }

// Which half tiles the coarse tiles read, and their CoC (the half disc's diameter in half
// pixels, numerically its radius in full ones). A read half pixel takes the mean radius of its
// four pixels; the others of its tile are gathered but never read, and take the tile's
// smallest CoC, so that the tile's radius range is the read pixels'.
void plan_half_gather(HalfGather& half, ConstPlane coc, const std::vector<Rect>& coarse,
                      int threads) {
  half.width = (coc.width() + 1) / 2;
  half.height = (coc.height() + 1) / 2;
  half.tiles_x = (half.width + kDiscTile - 1) / kDiscTile;
  half.tiles_y = (half.height + kDiscTile - 1) / kDiscTile;
  std::vector<unsigned char> read(std::size_t(half.width * half.height), 0);
  for (const Rect& tile : coarse) {
    const HalfSpan u = half_span(tile.x, tile.width, half.width);
    const HalfSpan v = half_span(tile.y, tile.height, half.height);
    for (std::ptrdiff_t y = v.first; y <= v.last; ++y)
      std::fill_n(read.begin() + y * half.width + u.first, u.last - u.first + 1, 1);
  }
  half.coc = Image(half.width, half.height, 1);
  std::vector<unsigned char> tile_read(std::size_t(half.tiles_x * half.tiles_y), 0);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t ty = 0; ty < half.tiles_y; ++ty)
    for (std::ptrdiff_t tx = 0; tx < half.tiles_x; ++tx) {
      const Rect tile = half_tile(half, tx, ty);
      float smallest = INFINITY;
      for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y)
        for (std::ptrdiff_t x = tile.x; x < tile.x + tile.width; ++x)
          if (read[std::size_t(y * half.width + x)]) {
            const auto c = static_cast<float>(half_disc_radius(block_radius(coc, x, y)));
            half.coc(x, y, 0) = c;
            smallest = std::min(smallest, c);
          }
      if (smallest == INFINITY) continue;
      for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y)
        for (std::ptrdiff_t x = tile.x; x < tile.x + tile.width; ++x)
          if (!read[std::size_t(y * half.width + x)]) half.coc(x, y, 0) = smallest;
      tile_read[std::size_t(ty * half.tiles_x + tx)] = 1;
    }
  for (std::ptrdiff_t ty = 0; ty < half.tiles_y; ++ty)
    for (std::ptrdiff_t tx = 0; tx < half.tiles_x; ++tx)
      if (tile_read[std::size_t(ty * half.tiles_x + tx)])
        half.tiles.push_back(half_tile(half, tx, ty));
  sort_by_block(half.tiles);
}

// A coarse tile's values (out, as DiscTiles packs them), interpolated from the half gather.
void interpolate_tile(const Rect& tile, const HalfGather& half, int channels, float* out) {
  // The half pixels tile.x / 2 - 1 + i, i < kPatch, of rows tile.y / 2 - 1 + j.
  constexpr std::ptrdiff_t kPatch = kDiscTile / 2 + 2;
  const HalfSpan u = half_span(tile.x, tile.width, half.width);
  const HalfSpan v = half_span(tile.y, tile.height, half.height);
  const float* from[kPatch][kPatch];
  std::ptrdiff_t plane[kPatch][kPatch];
  for (std::ptrdiff_t j = 0; j < kPatch; ++j)
    for (std::ptrdiff_t i = 0; i < kPatch; ++i) {
      const std::ptrdiff_t x = std::clamp(tile.x / 2 - 1 + i, u.first, u.last);
      const std::ptrdiff_t y = std::clamp(tile.y / 2 - 1 + j, v.first, v.last);
      from[j][i] = half.at(x, y);
      plane[j][i] = half.plane(x, y);
    }
  for (int c = 0; c < channels; ++c) {
    float patch[kPatch][kPatch];
    for (std::ptrdiff_t j = 0; j < kPatch; ++j)
      for (std::ptrdiff_t i = 0; i < kPatch; ++i) patch[j][i] = from[j][i][c * plane[j][i]];
    // Pixel tile.x + k reads patch columns (k + 1) / 2 and the next, the second with weight
    // 3/4 for even k and 1/4 for odd k (HalfSpan); the same for rows.
    for (std::ptrdiff_t y = 0; y < tile.height; ++y) {
      const float* top = patch[(y + 1) / 2];
      const float* bottom = patch[(y + 1) / 2 + 1];
      const float fy = y % 2 == 0 ? 0.75f : 0.25f;
      float* to = out + c * tile.area() + y * tile.width;
      for (std::ptrdiff_t x = 0; x < tile.width; ++x) {
        const std::ptrdiff_t i = (x + 1) / 2;
        const float fx = x % 2 == 0 ? 0.75f : 0.25f;
        const float upper = top[i] + fx * (top[i + 1] - top[i]);
        const float lower = bottom[i] + fx * (bottom[i + 1] - bottom[i]);
        to[x] = upper + fy * (lower - upper);
      }
    }
  }
}

// The coarse tiles' values (tile i at values + offsets[i]): the discs of the half frame's
// pixels, then each tile interpolated from them.
void gather_coarse(const Image& input, ConstPlane coc, const std::vector<Rect>& coarse,
                   const std::size_t* offsets, float* values, int threads) {
  HalfGather half;
  plan_half_gather(half, coc, coarse, threads);
  half.values = values_for(pack(half.tiles, input.channels(), half.offsets));
  gather_tiles(input, 2, half.coc.plane(0), half.tiles.data(), half.tiles.size(),
               half.offsets.data(), half.values.get(), threads);
  half.tile_index.assign(std::size_t(half.tiles_x * half.tiles_y), HalfGather::kNotGathered);
  for (std::size_t t = 0; t < half.tiles.size(); ++t) {
    const Rect& tile = half.tiles[t];
    half.tile_index[std::size_t((tile.y / kDiscTile) * half.tiles_x + tile.x / kDiscTile)] = t;
  }
  const auto count = std::ptrdiff_t(coarse.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t t = 0; t < count; ++t)
    interpolate_tile(coarse[std::size_t(t)], half, input.channels(),
                     values + offsets[std::size_t(t)]);
}

}  // namespace

DiscTiles gather_discs(const Image& input, ConstPlane coc, std::vector<Rect> tiles, int threads) {
  std::vector<unsigned char> is_coarse(tiles.size());
  const auto all = std::ptrdiff_t(tiles.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t t = 0; t < all; ++t)
    is_coarse[std::size_t(t)] =
        radius_range(tiles[std::size_t(t)], coc).smallest >= kHalfResRadiusPx;
  std::vector<Rect> fine, coarse;
  for (std::size_t t = 0; t < tiles.size(); ++t) (is_coarse[t] ? coarse : fine).push_back(tiles[t]);
  sort_by_block(fine);
  DiscTiles discs;
  discs.channels = input.channels();
  discs.tiles = fine;
  discs.tiles.insert(discs.tiles.end(), coarse.begin(), coarse.end());
  discs.values = values_for(pack(discs.tiles, discs.channels, discs.offsets));
  gather_tiles(input, 1, coc, fine.data(), fine.size(), discs.offsets.data(), discs.values.get(),
               threads);
  if (!coarse.empty())
    gather_coarse(input, coc, coarse, discs.offsets.data() + fine.size(), discs.values.get(),
                  threads);
  return discs;
}

namespace {

// The disc's share at pixel (x, y) of `tile` (tile (tx, ty) of the grid): its distance from the
// nearest neighbouring tile without the disc over kBlendPx, at most 1.
template <class IsDisc>
float blend_share(const IsDisc& is_disc, std::ptrdiff_t tx, std::ptrdiff_t ty, const Rect& tile,
                  std::ptrdiff_t x, std::ptrdiff_t y) {
  double nearest = kBlendPx;
  for (std::ptrdiff_t j = -1; j <= 1; ++j)
    for (std::ptrdiff_t i = -1; i <= 1; ++i) {
      if ((i == 0 && j == 0) || is_disc(tx + i, ty + j)) continue;
      const double across = i < 0 ? double(x) + 0.5 : i > 0 ? double(tile.width - x) - 0.5 : 0;
      const double down = j < 0 ? double(y) + 0.5 : j > 0 ? double(tile.height - y) - 0.5 : 0;
      nearest = std::min(nearest, std::hypot(across, down));
    }
  return static_cast<float>(nearest / kBlendPx);
}

}  // namespace

void paste_discs(Image& out, const DiscTiles& discs, int threads) {
  // Which tiles took the disc; a tile beyond the frame counts as one (nothing to blend with).
  const std::ptrdiff_t tiles_x = (out.width() + kDiscTile - 1) / kDiscTile;
  const std::ptrdiff_t tiles_y = (out.height() + kDiscTile - 1) / kDiscTile;
  std::vector<unsigned char> chosen(std::size_t(tiles_x * tiles_y), 0);
  for (const Rect& tile : discs.tiles)
    chosen[std::size_t((tile.y / kDiscTile) * tiles_x + tile.x / kDiscTile)] = 1;
  const auto is_disc = [&](std::ptrdiff_t tx, std::ptrdiff_t ty) {
    return tx < 0 || ty < 0 || tx >= tiles_x || ty >= tiles_y ||
           chosen[std::size_t(ty * tiles_x + tx)] != 0;
  };
  const auto count = std::ptrdiff_t(discs.tiles.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t t = 0; t < count; ++t) {
    const Rect& tile = discs.tiles[std::size_t(t)];
    const std::ptrdiff_t tx = tile.x / kDiscTile, ty = tile.y / kDiscTile;
    const float* values = discs.values.get() + discs.offsets[std::size_t(t)];
    bool blends = false;  // a neighbouring tile keeps the diffusion
    for (std::ptrdiff_t j = -1; j <= 1; ++j)
      for (std::ptrdiff_t i = -1; i <= 1; ++i) blends = blends || !is_disc(tx + i, ty + j);
    float share[kDiscTile];
    for (std::ptrdiff_t y = 0; y < tile.height; ++y) {
      if (blends)
        for (std::ptrdiff_t x = 0; x < tile.width; ++x)
          share[x] = blend_share(is_disc, tx, ty, tile, x, y);
      for (int c = 0; c < discs.channels; ++c) {
        const float* disc = values + (c * tile.height + y) * tile.width;
        float* to = out.plane(c).row(tile.y + y) + tile.x;
        if (!blends) {
          std::copy(disc, disc + tile.width, to);
          continue;
        }
        for (std::ptrdiff_t x = 0; x < tile.width; ++x)
          to[x] = share[x] >= 1 ? disc[x] : to[x] + share[x] * (disc[x] - to[x]);
      }
    }
  }
}

}  // namespace tridiff::dof_detail
