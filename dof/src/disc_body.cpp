#include "disc_body.hpp"

#include <algorithm>
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

// The prefix sums of `input` over `window`, the channels in groups of kGroup (the last padded
// with zeros): entry i of row j, group g is prefix[((j * groups + g) * length + i) * kGroup ...],
// the sums of the window's first i pixels of that row, a group's channels side by side so that
// one read of a span's end brings them all.
constexpr int kGroup = 4;

int channel_groups(int channels) { return (channels + kGroup - 1) / kGroup; }

void row_prefix_sums(const Image& input, const PrefixWindow& window, std::vector<double>& prefix) {
  const std::ptrdiff_t width = input.width(), length = window.length();
  const int channels = input.channels(), groups = channel_groups(channels);
  prefix.resize(std::size_t(window.rows * groups * length * kGroup));
  for (std::ptrdiff_t j = 0; j < window.rows; ++j) {
    const std::ptrdiff_t y = fold(window.first_row + j, input.height());
    for (int g = 0; g < groups; ++g) {
      const float* source[kGroup] = {};
      for (int c = 0; c < kGroup && g * kGroup + c < channels; ++c)
        source[c] = input.plane(g * kGroup + c).row(y);
      double* sums = prefix.data() + (j * groups + g) * length * kGroup;
      double sum[kGroup] = {};
      std::fill(sums, sums + kGroup, 0.0);
      for (std::ptrdiff_t i = 0; i < window.span; ++i) {
        const std::ptrdiff_t x = fold(window.first_x + i, width);
        for (int c = 0; c < kGroup; ++c)
          sums[(i + 1) * kGroup + c] = sum[c] += source[c] ? double(source[c][x]) : 0.0;
      }
    }
  }
}

// A channel group's values, in one vector register. Written as a vector type because GCC 12,
// left to itself, vectorised the loop over the disc's rows instead (two rows at a time, every
// read a gather) and ran 3.5 times slower.
using Group = double __attribute__((vector_size(kGroup * sizeof(double))));

inline Group load_group(const double* from) {
  Group values;
  std::memcpy(&values, from, sizeof values);
  return values;
}

// The integral over [lo, hi] (pixels as unit boxes, lo <= hi inside the window) of one channel
// group's prefix-summed row: the sums at both ends, interpolated linearly.
inline Group span_integral(const double* row, double lo, double hi) {
  const auto k_lo = static_cast<std::ptrdiff_t>(lo), k_hi = static_cast<std::ptrdiff_t>(hi);
  const Group at_lo = load_group(row + k_lo * kGroup),
              next_lo = load_group(row + (k_lo + 1) * kGroup);
  const Group at_hi = load_group(row + k_hi * kGroup),
              next_hi = load_group(row + (k_hi + 1) * kGroup);
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

// The disc averages at n <= kDiscTile pixels of row y, at columns xs[0 .. n), written to
// to[c * stride + i], the block's prefix sums made. Row dy of a disc of radius r (r >= 1/2) is
// the span of the disc's area in the strip [dy - 1/2, dy + 1/2], centred: the rows hold the
// disc's area exactly, and a row enters (dy = r + 1/2) with width 0, so the average is
// continuous in r. Rows dy and -dy share their span. The half widths are computed first, the
// pixels in vector lanes (`half_widths`, row dy's at [dy * kDiscTile ...]; unused lanes repeat
// the first pixel), then each pixel's reads.
void gather_points(ConstPlane coc, std::ptrdiff_t y, const std::ptrdiff_t* xs, std::ptrdiff_t n,
                   const std::vector<double>& prefix, const PrefixWindow& window, int channels,
                   std::vector<double>& half_widths, float* to, std::ptrdiff_t stride) {
  const int groups = channel_groups(channels);
  const std::ptrdiff_t group_stride = window.length() * kGroup, row_stride = group_stride * groups;
  double radius[kDiscTile], below[kDiscTile], weight[kDiscTile];
  double largest = 0;
  for (std::ptrdiff_t i = 0; i < kDiscTile; ++i) {
    radius[i] = 0.5 * std::fabs(double(coc(xs[i < n ? i : 0], y)));
    largest = std::max(largest, radius[i]);
  }
  const auto reach = static_cast<std::ptrdiff_t>(largest + 0.5);
  half_widths.resize(std::size_t((reach + 1) * kDiscTile));
  double* widths = half_widths.data();
#pragma omp simd
  for (std::ptrdiff_t i = 0; i < kDiscTile; ++i) {
    below[i] = half_strip_area(radius[i], std::min(0.5, radius[i]));
    widths[i] = below[i];
    weight[i] = 2 * below[i];
  }
  for (std::ptrdiff_t dy = 1; dy <= reach; ++dy) {
#pragma omp simd
    for (std::ptrdiff_t i = 0; i < kDiscTile; ++i) {
      const double above = half_strip_area(radius[i], std::min(double(dy) + 0.5, radius[i]));
      const double h = std::max(0.5 * (above - below[i]), 0.0);  // 0 past the disc
      below[i] = above;
      widths[dy * kDiscTile + i] = h;
      weight[i] += 4 * h;
    }
  }
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const double centre = double(xs[i] - window.first_x) + 0.5;
    const auto rows = static_cast<std::ptrdiff_t>(radius[i] + 0.5);
    for (int g = 0; g < groups; ++g) {
      const double* row = prefix.data() + (y - window.first_row) * row_stride + g * group_stride;
      Group sum = span_integral(row, centre - widths[i], centre + widths[i]);
      for (std::ptrdiff_t dy = 1; dy <= rows; ++dy) {
        const double h = widths[dy * kDiscTile + i];
        sum += span_integral(row - dy * row_stride, centre - h, centre + h) +
               span_integral(row + dy * row_stride, centre - h, centre + h);
      }
      for (int c = 0; c < kGroup && g * kGroup + c < channels; ++c)
        to[(g * kGroup + c) * stride + i] = static_cast<float>(sum[c] / weight[i]);
    }
  }
}

// The samples of a sparse tile: every kSparseStep pixels from its corner, through the corner of
// the next tile (kSparseSamples a side).
constexpr std::ptrdiff_t kSparseStep = 2, kSparseSamples = kDiscTile / kSparseStep + 1;

// Whether a tile is gathered at kSparseSamples² points and interpolated bilinearly: a whole
// tile, not on the frame's last row or column of tiles, whose radii are all kSparseRadius or
// more. A disc of radius r passes 2 J1(a) / a of a texture of wavelength λ, a = 2 π r / λ; at the
// shortest wavelength the interpolation misses, 2 kSparseStep = 4 px, and r >= 8 that is below
// 0.03 (and falling as r^-3/2), against 0.07 at r = 4.
constexpr double kSparseRadius = 8;
bool is_sparse(const Rect& tile, ConstPlane coc) {
  if (tile.width != kDiscTile || tile.height != kDiscTile || tile.x + kDiscTile >= coc.width() ||
      tile.y + kDiscTile >= coc.height())
    return false;
  for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y)
    for (std::ptrdiff_t x = tile.x; x < tile.x + tile.width; ++x)
      if (!(0.5 * std::fabs(double(coc(x, y))) >= kSparseRadius)) return false;
  return true;
}

// The disc averages of one tile (tile.area() values a channel, row-major, into out).
void gather_tile(const Rect& tile, ConstPlane coc, const std::vector<double>& prefix,
                 const PrefixWindow& window, int channels, std::vector<double>& half_widths,
                 std::vector<float>& samples, float* out) {
  const std::ptrdiff_t area = tile.area();
  std::ptrdiff_t xs[kDiscTile];
  if (!is_sparse(tile, coc)) {
    for (std::ptrdiff_t i = 0; i < tile.width; ++i) xs[i] = tile.x + i;
    for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y)
      gather_points(coc, y, xs, tile.width, prefix, window, channels, half_widths,
                    out + (y - tile.y) * tile.width, area);
    return;
  }
  constexpr std::ptrdiff_t kCount = kSparseSamples * kSparseSamples;
  samples.resize(std::size_t(kCount * channels));
  for (std::ptrdiff_t i = 0; i < kSparseSamples; ++i) xs[i] = tile.x + i * kSparseStep;
  for (std::ptrdiff_t j = 0; j < kSparseSamples; ++j)
    gather_points(coc, tile.y + j * kSparseStep, xs, kSparseSamples, prefix, window, channels,
                  half_widths, samples.data() + j * kSparseSamples, kCount);
  for (int c = 0; c < channels; ++c) {
    const float* grid = samples.data() + c * kCount;
    for (std::ptrdiff_t y = 0; y < kDiscTile; ++y) {
      const std::ptrdiff_t j = y / kSparseStep;
      const float fy = float(y % kSparseStep) / float(kSparseStep);
      for (std::ptrdiff_t x = 0; x < kDiscTile; ++x) {
        const std::ptrdiff_t i = x / kSparseStep;
        const float fx = float(x % kSparseStep) / float(kSparseStep);
        const float* cell = grid + j * kSparseSamples + i;
        const float top = cell[0] + fx * (cell[1] - cell[0]);
        const float bottom =
            cell[kSparseSamples] + fx * (cell[kSparseSamples + 1] - cell[kSparseSamples]);
        out[c * area + y * kDiscTile + x] = top + fy * (bottom - top);
      }
    }
  }
}

// The disc averages of a band of tiles: their prefix sums over the rows and columns their discs
// reach, then each tile.
void gather_band(const Image& input, ConstPlane coc, const Rect* tiles, std::size_t count,
                 const std::size_t* offsets, std::vector<double>& prefix,
                 std::vector<double>& half_widths, std::vector<float>& samples, float* values) {
  float radius = 0;
  std::ptrdiff_t top = tiles[0].y, bottom = top, left = tiles[0].x, right = left;
  for (std::size_t t = 0; t < count; ++t) {
    const Rect& tile = tiles[t];
    for (std::ptrdiff_t y = tile.y; y < tile.y + tile.height; ++y)
      for (std::ptrdiff_t x = tile.x; x < tile.x + tile.width; ++x)
        radius = std::max(radius, 0.5f * std::fabs(coc(x, y)));
    top = std::min(top, tile.y);
    bottom = std::max(bottom, tile.y + tile.height);
    left = std::min(left, tile.x);
    right = std::max(right, tile.x + tile.width);
  }
  // Rows above and below: the largest radius, rounded as the gather rounds it, plus 1/2 for the
  // samples of a sparse tile in the next tile's corner (whose CoC may be kSmoothCocPx larger),
  // which also needs a row and a column more.
  const auto reach = static_cast<std::ptrdiff_t>(radius + 0.5f + 0.5f * kSmoothCocPx);
  const std::ptrdiff_t pad = reach + 3;  // columns: the span's ends, rounded out
  const PrefixWindow window{top - reach, bottom - top + 2 * reach + 1, left - pad,
                            right - left + 2 * pad};
  row_prefix_sums(input, window, prefix);
  for (std::size_t t = 0; t < count; ++t)
    gather_tile(tiles[t], coc, prefix, window, input.channels(), half_widths, samples,
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

DiscTiles gather_discs(const Image& input, ConstPlane coc, std::vector<Rect> tiles, int threads) {
  DiscTiles discs;
  discs.channels = input.channels();
  discs.tiles = std::move(tiles);
  std::stable_sort(discs.tiles.begin(), discs.tiles.end(),
                   [](const Rect& a, const Rect& b) { return block_of(a) < block_of(b); });
  std::size_t total = 0;
  for (const Rect& tile : discs.tiles) {
    discs.offsets.push_back(total);
    total += std::size_t(tile.area() * discs.channels);
  }
  discs.values.resize(total);
  // Blocks of kBlockRows x kBlockColumns pixels: a block's prefix sums are made once, for its
  // tiles together.
  std::vector<std::size_t> band_starts;
  for (std::size_t t = 0; t < discs.tiles.size(); ++t)
    if (t == 0 || block_of(discs.tiles[t]) != block_of(discs.tiles[t - 1]))
      band_starts.push_back(t);
  band_starts.push_back(discs.tiles.size());
  const auto bands = std::ptrdiff_t(band_starts.size()) - 1;
#pragma omp parallel num_threads(threads)
  {
    std::vector<double> prefix, half_widths;
    std::vector<float> samples;
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t b = 0; b < bands; ++b) {
      const std::size_t first = band_starts[std::size_t(b)];
      gather_band(input, coc, discs.tiles.data() + first, band_starts[std::size_t(b) + 1] - first,
                  discs.offsets.data() + first, prefix, half_widths, samples, discs.values.data());
    }
  }
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
    const float* values = discs.values.data() + discs.offsets[std::size_t(t)];
    bool blends = false;  // a neighbouring tile keeps the diffusion
    for (std::ptrdiff_t j = -1; j <= 1; ++j)
      for (std::ptrdiff_t i = -1; i <= 1; ++i) blends = blends || !is_disc(tx + i, ty + j);
    float share[kDiscTile];
    for (std::ptrdiff_t y = 0; y < tile.height; ++y) {
      for (std::ptrdiff_t x = 0; x < tile.width; ++x)
        share[x] = blends ? blend_share(is_disc, tx, ty, tile, x, y) : 1.f;
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
