// The diagonal passes of the isotropic diffusion step (diffuse_isotropic in adi.hpp): the
// same backward-Euler solves as the rows and columns passes, along the lines x - y = s
// (down-right, slope +1) or x + y = s (down-left, slope -1).
//
// A band is kDiagonalLanes neighbouring lines. At image row y its pixels are contiguous (the
// band's lanes move one pixel sideways per row), so a band is gathered row by row into a strip
// of lanes, solved by the lanes sweep of the columns pass, and scattered back. Lanes outside the
// frame hold zeros with no links: systems of their own that change nothing.
//
// A diagonal link joins (x, y) and (x + slope, y + 1). It conducts the smallest conductance of
// the 2 x 2 block it crosses: its two ends and the two pixels beside it, (x + slope, y) and
// (x, y + 1). With its ends alone, a link would step over a one-pixel-wide diagonal line of
// sharp pixels (the line's two pixels beside the link are not its ends), and a blurred
// background would leak through a thin sharp foreground.
#pragma once

#include <algorithm>
#include <vector>

namespace tridiff::adi_detail {

inline constexpr int kDiagonalLanes = 32;
inline constexpr std::ptrdiff_t kDiagonalBlock = 32;  // rows gathered and swept at a time

struct DiagonalBand {
  std::ptrdiff_t s0;  // the band's first line
  int slope;          // +1: pixel (s + y, y) of line s; -1: pixel (s - y, y)
  std::ptrdiff_t x(std::ptrdiff_t lane, std::ptrdiff_t y) const {
    return slope > 0 ? s0 + lane + y : s0 + lane - y;
  }
};

// Rows [y0, y1) where some lane of the band lies in a frame of width x height.
inline std::pair<std::ptrdiff_t, std::ptrdiff_t> band_rows(const DiagonalBand& band,
                                                           std::ptrdiff_t width,
                                                           std::ptrdiff_t height) {
  const std::ptrdiff_t first = band.s0, last = band.s0 + kDiagonalLanes - 1;
  if (band.slope > 0)  // 0 <= s + y < width
    return {std::max<std::ptrdiff_t>(0, -last), std::min(height, width - first)};
  return {std::max<std::ptrdiff_t>(0, first - width + 1), std::min(height, last + 1)};  // s - y
}

// Per tile row t of the band's rows: whether a tile of the frame that the band (and a pixel on
// either side) crosses in those rows conducts. A band tile that does not has no link.
template <class Conducting>
void diagonal_activity(const DiagonalBand& band, std::ptrdiff_t width, std::ptrdiff_t height,
                       const Conducting& conducting, std::vector<std::uint8_t>& active) {
  const std::ptrdiff_t tiles_y = (height + kTile - 1) / kTile;
  active.assign(std::size_t(tiles_y), 0);
  for (std::ptrdiff_t t = 0; t < tiles_y; ++t) {
    const std::ptrdiff_t ya = t * kTile, yb = std::min(height, ya + kTile) - 1;
    const std::ptrdiff_t xs[] = {band.x(0, ya), band.x(0, yb), band.x(kDiagonalLanes - 1, ya),
                                 band.x(kDiagonalLanes - 1, yb)};
    const std::ptrdiff_t x0 = std::max<std::ptrdiff_t>(0, *std::min_element(xs, xs + 4) - 1);
    const std::ptrdiff_t x1 = std::min(width - 1, *std::max_element(xs, xs + 4) + 1);
    for (std::ptrdiff_t tx = x0 / kTile; tx <= x1 / kTile && x0 <= x1; ++tx)
      if (conducting(tx, t)) {
        active[std::size_t(t)] = 1;
        break;
      }
  }
}

// The lanes [first, last) of a band row that lie in [0, width), for a band row whose lane 0
// is at x: the band's lanes are contiguous and increasing in x on every row.
struct LaneSpan {
  int first, last;
  LaneSpan(std::ptrdiff_t x, int lanes, std::ptrdiff_t width)
      : first(int(std::clamp<std::ptrdiff_t>(-x, 0, lanes))),
        last(int(std::clamp<std::ptrdiff_t>(width - x, 0, lanes))) {}
};

// What one band solves, a block of rows at a time.
template <class ToLink>
struct DiagonalStrip {
  const PlaneStack<float>& image;
  ConstPlane value;
  const ToLink& to_link;
  DiagonalBand band;

  // k[r * (W + 2) + 1 + l] = the conductance of lane l (-1 .. W) in row y0 + r, for `rows`
  // rows (zero outside the frame). Returns the number of lanes 0 .. W-1 in the frame.
  std::ptrdiff_t conductances(std::ptrdiff_t y0, std::ptrdiff_t rows, float* k) const {
    constexpr int W = kDiagonalLanes;
    std::ptrdiff_t in_frame = 0;
    for (std::ptrdiff_t r = 0; r < rows; ++r) {
      prefetch(y0 + r + kDiagonalBlock, -1, 0);
      const std::ptrdiff_t x = band.x(-1, y0 + r);
      const LaneSpan span(x, W + 2, image.width);
      float* out = k + r * (W + 2);
      const float* v = value.row(y0 + r) + x;
      std::fill(out, out + span.first, 0.f);
#pragma omp simd
      for (int l = span.first; l < span.last; ++l) out[l] = to_link(v[l]);
      std::fill(out + span.last, out + W + 2, 0.f);
      in_frame += std::clamp(span.last, 1, W + 1) - std::clamp(span.first, 1, W + 1);
    }
    return in_frame;
  }

  // links[r * W + l]: the link of lane l from row begin + r to the next, from the conductances
  // k of rows begin .. end (end included when it is a row of the system, below `stop`).
  void links(const float* k, std::ptrdiff_t rows, bool last_has_next, float* links) const {
    constexpr int W = kDiagonalLanes;
    const int side = band.slope;  // (x + slope, y) is lane l + slope; (x, y + 1) lane l - slope
    for (std::ptrdiff_t r = 0; r < rows; ++r) {
      float* out = links + r * W;
      if (r + 1 == rows && !last_has_next) {
        std::fill(out, out + W, 0.f);
        continue;
      }
      const float* here = k + r * (W + 2) + 1;
      const float* next = here + W + 2;
#pragma omp simd
      for (int l = 0; l < W; ++l)
        out[l] = std::min(std::min(here[l], next[l]), std::min(here[l + side], next[l - side]));
    }
  }

  // Fetches what conductances() (c0 < 0) or gather() of planes [c0, c0 + planes) will read of
  // row y: a walk down a diagonal is not a stream the hardware prefetchers follow.
  void prefetch(std::ptrdiff_t y, int c0, int planes) const {
    if (y >= image.height) return;
    const std::ptrdiff_t x = std::clamp<std::ptrdiff_t>(band.x(-1, y), 0, image.width - 1);
    const std::ptrdiff_t count = std::min<std::ptrdiff_t>(kDiagonalLanes + 2, image.width - x);
    if (c0 < 0) prefetch_span(value.row(y) + x, count);
    for (int c = std::max(c0, 0); c < c0 + planes; ++c) prefetch_span(image.row(c, y) + x, count);
  }

  template <int Rhs>
  void gather(int c0, std::ptrdiff_t y0, std::ptrdiff_t rows, float* strip) const {
    constexpr int W = kDiagonalLanes;
    for (std::ptrdiff_t r = 0; r < rows; ++r) {
      const std::ptrdiff_t x = band.x(0, y0 + r);
      const LaneSpan span(x, W, image.width);
      for (int c = 0; c < Rhs; ++c) {
        const float* from = image.row(c0 + c, y0 + r) + x;
        float* to = strip + (r * Rhs + c) * W;
        if (span.first == 0 && span.last == W) {  // the lanes in the frame: a vector copy
#pragma omp simd
          for (int l = 0; l < W; ++l) to[l] = from[l];
          continue;
        }
        std::fill(to, to + span.first, 0.f);
        std::copy(from + span.first, from + span.last, to + span.first);
        std::fill(to + span.last, to + W, 0.f);
      }
    }
  }

  template <int Rhs>
  void scatter(int c0, std::ptrdiff_t y0, std::ptrdiff_t rows, const float* strip) const {
    constexpr int W = kDiagonalLanes;
    for (std::ptrdiff_t r = 0; r < rows; ++r) {
      const std::ptrdiff_t x = band.x(0, y0 + r);
      const LaneSpan span(x, W, image.width);
      for (int c = 0; c < Rhs; ++c) {
        const float* from = strip + (r * Rhs + c) * W;
        float* to = image.row(c0 + c, y0 + r) + x;
        if (span.first == 0 && span.last == W) {
#pragma omp simd
          for (int l = 0; l < W; ++l) to[l] = from[l];
          continue;
        }
        std::copy(from + span.first, from + span.last, to + span.first);
      }
    }
  }
};

// Solves rows [a, e) of the band's lines, planes [c0, c0 + Rhs), in blocks of rows: each block
// gathered into lanes, swept forward; then back up, each block swept backward and scattered.
// k: conductances of the rows [a, e); `scratch` the block buffers and the sweep's workspace.
template <int Rhs, class ToLink>
void solve_diagonal_segment(const DiagonalStrip<ToLink>& strip, int c0, std::ptrdiff_t a,
                            std::ptrdiff_t e, const float* k, float* scratch) {
  constexpr int W = kDiagonalLanes;
  const std::ptrdiff_t n = e - a;
  float* links = scratch;
  float* block = links + kDiagonalBlock * W;
  float* work = block + kDiagonalBlock * Rhs * W;
  detail::DiffusionLanes<float, W, Rhs> sweep(n, work);
  for (std::ptrdiff_t begin = 0; begin < n; begin += kDiagonalBlock) {
    const std::ptrdiff_t rows = std::min(kDiagonalBlock, n - begin);
    strip.links(k + begin * (W + 2), rows, begin + rows < n, links);
    for (std::ptrdiff_t r = 0; r < rows; ++r)
      strip.prefetch(a + begin + r + kDiagonalBlock, c0, Rhs);
    strip.template gather<Rhs>(c0, a + begin, rows, block);
    sweep.forward(begin, begin + rows, links, W, block, Rhs * W, W);
  }
  // The pass diffuses what the rows and columns passes made of finite values: a convex
  // combination of them, finite too.
  if (!sweep.healthy())
    throw NumericalError(-1, -1, "a diagonal diffusion solve failed on valid input");
  for (std::ptrdiff_t begin = (n - 1) / kDiagonalBlock * kDiagonalBlock; begin >= 0;
       begin -= kDiagonalBlock) {
    const std::ptrdiff_t rows = std::min(kDiagonalBlock, n - begin);
    sweep.backward(begin, begin + rows, block, Rhs * W, W);
    strip.template scatter<Rhs>(c0, a + begin, rows, block);
  }
}

// One diagonal pass in place over every plane of `image`, the conductance of a pixel
// to_link(value(x, y)). conducting(tx, ty): whether tile (tx, ty) holds a conductance other
// than zero.
template <class ToLink, class Conducting>
DiffusionReport run_diagonal_pass(const PlaneStack<float>& image, ConstPlane value,
                                  const ToLink& to_link, const Conducting& conducting, int slope,
                                  const DiffusionOptions& options) {
  constexpr int W = kDiagonalLanes;
  const std::ptrdiff_t width = image.width, height = image.height;
  const std::ptrdiff_t bands = (width + height - 1 + W - 1) / W;
  const std::ptrdiff_t first_line = slope > 0 ? -(height - 1) : 0;
  std::vector<std::ptrdiff_t> solved(std::size_t(bands), 0);
  for_each_band(bands, resolve_threads(options.threads), [&](std::ptrdiff_t b, BandScratch& s) {
    const DiagonalStrip<ToLink> strip{image, value, to_link, {first_line + b * W, slope}};
    const auto [y0, y1] = band_rows(strip.band, width, height);
    if (y1 <= y0) return;
    diagonal_activity(strip.band, width, height, conducting, s.active);
    find_segments(s.active, height, options.skip_inactive, s.segments);
    for (const Segment& segment : s.segments) {
      const std::ptrdiff_t a = std::max(y0, segment.begin), e = std::min(y1, segment.end);
      if (e - a < 2) continue;  // one row: no link
      const std::ptrdiff_t n = e - a;
      float* k = s.floats(std::size_t(n * (W + 2) + kDiagonalBlock * W * (1 + kMaxRhs) +
                                      detail::diffusion_lanes_workspace<float>(n, W, kMaxRhs)));
      solved[std::size_t(b)] += strip.conductances(a, n, k) * image.count;
      for_each_plane_group(image.count, [&]<int Rhs>(int c0) {
        solve_diagonal_segment<Rhs>(strip, c0, a, e, k, k + n * (W + 2));
      });
    }
  });
  DiffusionReport report{width * height * image.count, 0};
  for (std::ptrdiff_t n : solved) report.pixels_solved += n;
  return report;
}

}  // namespace tridiff::adi_detail
