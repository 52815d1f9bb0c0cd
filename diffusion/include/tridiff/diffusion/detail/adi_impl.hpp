// The ADI passes, written once for every source of link conductances (a LinkField, or a
// per-pixel value mapped to a conductance as the solve reads it).
//
// A band of kTile rows (or columns) is one SIMD batch of diffusion-form solves, one lane per
// row (column). Every colour plane is a right-hand side of the same factorisation (up to
// kMaxRhs at a time), so the division and the conductances are paid once per pixel, not once
// per plane. Inside a band only the runs of tiles with a non-zero link are solved; the rest
// is copied.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "tridiff/solvers/detail/subnormals.hpp"
#include "tridiff/solvers/solve.hpp"

namespace tridiff::adi_detail {

inline constexpr std::ptrdiff_t kTile = LinkField::kTile;
inline constexpr int kLanes = int(kTile);  // one band is one batch
static_assert(kLanes == detail::kLanes<float>);
// Right-hand sides solved together (an RGB image in one group). Measured, columns pass of
// 3840 x 2160 RGB: 15 ms for the three planes together, 17-18 ms one at a time. At 64 lanes
// the forward sweep's state then no longer fits the vector registers and spills to L1.
inline constexpr int kMaxRhs = 3;
inline constexpr std::ptrdiff_t kBlock = detail::kTransposeBlock;
// Columns of the rows pass's batch transposed into lanes at a time, and rows solved side by
// side in the rows pass and columns in the columns pass (a band is solved in groups of them).
// Measured on 3840 x 2160 RGB, 2 threads, two hosts:
// - an AMD EPYC with fast memory (copy of the frame 2.1 ms): rows 32 lanes with blocks of 16
//   columns 6.6 ms, of 32 columns 7.3, of 64 7.7; rows 16 lanes about as fast as 32; columns
//   32 and 64 lanes the same.
// - an Intel Xeon with slow memory (copy 6.1-7.3 ms; a 512-bit division every 8 cycles, one
//   16 x 16 transpose every 47): rows 32 lanes with blocks of 16 columns 17-18 ms, 16 lanes
//   with blocks of 16 14-15 ms, with blocks of 32 11.3-11.8, of 64 12.0-12.3; columns 64
//   lanes 14.7 ms, 32 lanes 11.3-12.0, 16 lanes 14.3. At 64 lanes the three right-hand
//   sides' state no longer fits the 32 vector registers (the sweeps alone, in L1: 3.3 cycles
//   a pixel at 64 lanes, 2.4 at 32), and 16 rows of four planes are half the streams of 32
//   for the memory system to follow.
inline constexpr std::ptrdiff_t kRowBlock = 32;
inline constexpr std::ptrdiff_t kRowLanes = 16, kColumnLanes = 32;
// Rows of a column band swept between two requests for the rows a block ahead.
inline constexpr std::ptrdiff_t kChunk = 4;
static_assert(kBlock % kChunk == 0);

enum class Direction { Rows, Columns };

// Planes of one image (or one plane on its own): plane c, row y at data + c * plane_stride +
// y * pitch.
template <class T>
struct PlaneStack {
  T* data;
  std::ptrdiff_t width, height, pitch, plane_stride;
  int count;
  T* row(int c, std::ptrdiff_t y) const { return data + c * plane_stride + y * pitch; }
};

// A run of pixels [begin, end) along a band that forms one independent system.
struct Segment {
  std::ptrdiff_t begin, end;
};

// The runs of active tiles of one band, as pixel ranges. A run of tiles [t0, t1] covers the
// links t0*kTile ... (t1+1)*kTile - 1, so its system spans pixels t0*kTile ... (t1+1)*kTile; the
// links on either side are zero (they lie in inactive tiles or outside the image), so the
// systems are exactly decoupled from the pixels around them.
inline void find_segments(const std::vector<std::uint8_t>& active, std::ptrdiff_t extent, bool skip,
                          std::vector<Segment>& segments) {
  segments.clear();
  if (!skip) {
    segments.push_back({0, extent});
    return;
  }
  const auto tiles = std::ptrdiff_t(active.size());
  for (std::ptrdiff_t t = 0; t < tiles;) {
    if (!active[t]) {
      ++t;
      continue;
    }
    const std::ptrdiff_t first = t;
    while (t < tiles && active[t]) ++t;
    segments.push_back({first * kTile, std::min(extent, t * kTile + 1)});
  }
}

// What one thread keeps between bands (and calls: the pages stay mapped).
struct BandScratch {
  std::vector<Segment> segments;
  std::vector<std::uint8_t> active;
  std::vector<float> work, zeros, sink;
  float* floats(std::size_t count) {
    if (work.size() < count) work.resize(count);
    return work.data();
  }
  // A row of zeros, and a row to write into and never read, as long as an image row (and the
  // 16 floats a masked vector access may span past it).
  const float* zero_row(std::ptrdiff_t width) {
    if (zeros.size() < std::size_t(width + 16)) zeros.assign(width + 16, 0.f);
    return zeros.data();
  }
  float* sink_row(std::ptrdiff_t width) {
    if (sink.size() < std::size_t(width + 16)) sink.resize(width + 16);
    return sink.data();
  }
};

// Runs body(band, scratch) for every band in parallel; the first error (by band) is rethrown.
template <class Body>
void for_each_band(std::ptrdiff_t bands, int threads, Body&& body) {
  std::exception_ptr error;
  std::ptrdiff_t error_band = std::numeric_limits<std::ptrdiff_t>::max();
  std::mutex guard;
#pragma omp parallel num_threads(threads) if (threads > 1 && bands > 1)
  {
    static thread_local BandScratch scratch;
    const detail::SubnormalsAsZero flush;  // see subnormals.hpp
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t band = 0; band < bands; ++band) {
      try {
        body(band, scratch);
      } catch (...) {
        std::lock_guard<std::mutex> lock(guard);
        if (band < error_band) {
          error_band = band;
          error = std::current_exception();
        }
      }
    }
  }
  if (error) std::rethrow_exception(error);
}

[[noreturn]] inline void throw_not_finite(std::ptrdiff_t x, std::ptrdiff_t y) {
  throw InvalidArgument(
      "src", "pixel (" + std::to_string(x) + ", " + std::to_string(y) + "): is not finite");
}

// dst[0, n) = src[0, n); throws naming the pixel if a value is not finite (the solves check
// the pixels they solve; this is the check of the ones they skip).
inline void copy_finite(float* dst, const float* src, std::ptrdiff_t n, std::ptrdiff_t x0,
                        std::ptrdiff_t y) {
  // The copy first (memmove), then the check of the copy while it is in L1, in 64 independent
  // sums (one sum would wait on its own additions): the ADI DOF at 2048^2 entirely in focus,
  // into a separate image, 2 threads, 3 alternating runs: 3.4-3.9 ms with the check in the
  // copy loop, 3.1-3.3 ms so.
  std::copy(src, src + n, dst);
  constexpr int kSums = 64;
  float probe[kSums] = {};  // sums of 0 * value: zero unless a value is NaN or infinite
  std::ptrdiff_t i = 0;
  for (; i + kSums <= n; i += kSums)
#pragma omp simd
    for (int j = 0; j < kSums; ++j) probe[j] += 0.f * dst[i + j];
  for (; i < n; ++i) probe[0] += 0.f * dst[i];
  float any = 0;
  for (int j = 0; j < kSums; ++j) any += probe[j];
  if (any == 0) return;
  for (std::ptrdiff_t i = 0; i < n; ++i)
    if (!std::isfinite(src[i])) throw_not_finite(x0 + i, y);
}

// A solve found a non-finite value somewhere in the rectangle [x0, x1) x [y0, y1) of src
// (the sources check their conductances before any solve): names the first, row by row.
[[noreturn]] inline void throw_first_bad_pixel(const PlaneStack<const float>& src,
                                               std::ptrdiff_t x0, std::ptrdiff_t x1,
                                               std::ptrdiff_t y0, std::ptrdiff_t y1) {
  for (std::ptrdiff_t y = y0; y < y1; ++y)
    for (std::ptrdiff_t x = x0; x < x1; ++x)
      for (int c = 0; c < src.count; ++c)
        if (!std::isfinite(src.row(c, y)[x])) throw_not_finite(x, y);
  throw NumericalError(-1, -1, "a diffusion solve failed on valid input");  // not reached
}

// Fetches the cache lines of [p, p + count) into L2 ahead of their use.
inline void prefetch_span(const float* p, std::ptrdiff_t count) {
  for (std::ptrdiff_t i = 0; i < count; i += 16) __builtin_prefetch(p + i, 0, 2);
}

// The W rows of a band of `count` rows from y0 in one plane, as row pointers; the lanes
// past the band's last row point at `spare` (a row of zeros to read, or one nobody reads to
// write).
template <int W, class T>
void band_rows(T* first_row, std::ptrdiff_t pitch, std::ptrdiff_t count, T* spare, T* rows[W]) {
  for (std::ptrdiff_t l = 0; l < W; ++l) rows[l] = l < count ? first_row + l * pitch : spare;
}

inline std::size_t row_scratch_floats(std::ptrdiff_t n) {
  return std::size_t(detail::diffusion_lanes_workspace<float>(n, kLanes, kMaxRhs) +
                     (kRowBlock + 1) * kLanes * (1 + kMaxRhs));
}

// The rows pass of planes [c0, c0 + Rhs) over one segment of a band of `count` rows from y0.
// Blocks of kBlock columns of the band's rows are transposed into lanes in L1, straight from
// the image (each row prefetched ahead), and the solution goes back the same way.
template <int W, int Rhs, class Source>
void solve_row_segment(const Source& source, const PlaneStack<float>& dst,
                       const PlaneStack<const float>& src, int c0, std::ptrdiff_t y0,
                       std::ptrdiff_t count, Segment s, BandScratch& scratch) {
  const std::ptrdiff_t n = s.end - s.begin;
  float* work = scratch.floats(row_scratch_floats(n));
  float* links = work + detail::diffusion_lanes_workspace<float>(n, W, Rhs);
  float* block = links + (kRowBlock + 1) * W;  // Rhs planes of kRowBlock rows of lanes
  const float* in[Rhs][W];
  float* out[Rhs][W];
  for (int c = 0; c < Rhs; ++c) {
    band_rows<W>(src.row(c0 + c, y0), src.pitch, count, scratch.zero_row(src.width), in[c]);
    band_rows<W>(dst.row(c0 + c, y0), dst.pitch, count, scratch.sink_row(src.width), out[c]);
  }
  detail::DiffusionLanes<float, W, Rhs> sweep(n, work);
  for (std::ptrdiff_t begin = 0; begin < n; begin += kRowBlock) {
    const std::ptrdiff_t columns = std::min(n, begin + kRowBlock) - begin;
    source.template row_link_lanes<W>(y0, count, s.begin + begin, columns,
                                      scratch.zero_row(src.width), links);
    for (int c = 0; c < Rhs; ++c)
      detail::gather_into_lanes<float, W>(in[c], s.begin + begin, columns,
                                          block + c * kRowBlock * W, s.end);
    sweep.forward(begin, begin + columns, links, W, block, W, kRowBlock * W);
  }
  if (!sweep.healthy()) throw_first_bad_pixel(src, s.begin, s.end, y0, y0 + count);
  for (std::ptrdiff_t begin = (n - 1) / kRowBlock * kRowBlock; begin >= 0; begin -= kRowBlock) {
    const std::ptrdiff_t columns = std::min(n, begin + kRowBlock) - begin;
    sweep.backward(begin, begin + columns, block, W, kRowBlock * W);
    for (int c = 0; c < Rhs; ++c)
      detail::scatter_from_lanes<float, W>(block + c * kRowBlock * W, columns, out[c],
                                           s.begin + begin, true);
  }
  detail::finish_streaming_stores();
}

// The columns pass of planes [c0, c0 + Rhs) over one segment of a band of `count` columns
// from x0. A full band is solved in place in the image (its lanes are contiguous); a partial
// one (the right edge) through a copy padded with zeros.
template <int W, int Rhs, class Source>
void solve_column_segment(const Source& source, const PlaneStack<float>& dst,
                          const PlaneStack<const float>& src, int c0, std::ptrdiff_t x0,
                          std::ptrdiff_t count, Segment s, float* scratch) {
  const std::ptrdiff_t n = s.end - s.begin;
  float* work = scratch;
  float* block_beta = work + detail::diffusion_lanes_workspace<float>(n, W, Rhs);
  float* padded = block_beta + (kBlock + 1) * W;  // partial bands: n rows of Rhs planes of W lanes
  const bool full = count == W;
  if (!full)
    for (std::ptrdiff_t i = 0; i < n; ++i)
      for (int c = 0; c < Rhs; ++c) {
        float* to = padded + (i * Rhs + c) * W;
        const float* from = src.row(c0 + c, s.begin + i) + x0;
        std::copy(from, from + count, to);
        std::fill(to + count, to + W, 0.f);
      }
  detail::DiffusionLanes<float, W, Rhs> sweep(n, work);
  for (std::ptrdiff_t begin = 0; begin < n; begin += kBlock) {
    const std::ptrdiff_t end = std::min(n, begin + kBlock);
    source.column_links(s.begin + begin, end - begin, x0, count, W, block_beta);
    if (full) {
      // The eliminated values go straight to dst, in the rows the solution will overwrite.
      // Should a value of src be bad, the first bad pixel by rows still holds a non-finite
      // value there (NaN and infinity carry down each column), and the pixels before it in
      // its column hold finite ones, so the search of src below names the same pixel when dst
      // is src. (Through an L1 block copied once found valid, as before: the columns pass of
      // 3840 x 2160 RGB on an Intel Xeon took 12.7 against 11.5 ms on 2 threads, 27.2 against
      // 23.9 on one.)
      // The sweep goes kChunk rows at a time, each chunk fetching the rows one block below
      // it: the hardware prefetchers do not follow a walk down the image 256 bytes a row, and
      // a whole block's lines requested at once stall on the misses in flight (the ADI DOF,
      // 3840 x 2160 RGB, 2 threads: 18.5 -> 16.7 ms with a block at once; the columns pass
      // alone, 9.7 ms with chunks of a block, 9.0 of 8 rows, 8.7 of 4 rows).
      for (std::ptrdiff_t chunk = begin; chunk < end; chunk += kChunk) {
        const std::ptrdiff_t chunk_end = std::min(end, chunk + kChunk);
        for (std::ptrdiff_t i = chunk + kBlock; i < std::min(n, chunk_end + kBlock); ++i) {
          source.prefetch_column(s.begin + i, x0, count);
          for (int c = 0; c < Rhs; ++c) prefetch_span(src.row(c0 + c, s.begin + i) + x0, count);
        }
        sweep.forward_to(chunk, chunk_end, block_beta + (chunk - begin) * W, W,
                         src.row(c0, s.begin + chunk) + x0, src.pitch, src.plane_stride,
                         dst.row(c0, s.begin + chunk) + x0, dst.pitch, dst.plane_stride);
      }
    } else
      sweep.forward(begin, end, block_beta, W, padded + begin * Rhs * W, Rhs * W, W);
  }
  if (!sweep.healthy()) throw_first_bad_pixel(src, x0, x0 + count, s.begin, s.end);
  if (full) {
    // Up the band a chunk at a time, each fetching the rows one block above it.
    for (std::ptrdiff_t begin = (n - 1) / kChunk * kChunk; begin >= 0; begin -= kChunk) {
      for (std::ptrdiff_t i = std::max<std::ptrdiff_t>(0, begin - kBlock);
           i < std::max<std::ptrdiff_t>(0, begin - kBlock + kChunk); ++i)
        for (int c = 0; c < Rhs; ++c) prefetch_span(dst.row(c0 + c, s.begin + i) + x0, W);
      float* x = dst.row(c0, s.begin + begin) + x0;
      sweep.backward_from(begin, std::min(n, begin + kChunk), x, dst.pitch, dst.plane_stride, x,
                          dst.pitch, dst.plane_stride);
    }
    return;
  }
  sweep.backward(0, n, padded, Rhs * W, W);
  for (std::ptrdiff_t i = 0; i < n; ++i)
    for (int c = 0; c < Rhs; ++c) {
      const float* from = padded + (i * Rhs + c) * W;
      std::copy(from, from + count, dst.row(c0 + c, s.begin + i) + x0);
    }
}

inline std::size_t column_scratch_floats(std::ptrdiff_t n) {
  return std::size_t(detail::diffusion_lanes_workspace<float>(n, kLanes, kMaxRhs) +
                     (kBlock + 1) * kLanes + n * kMaxRhs * kLanes);
}

// Calls solve<Rhs>(c0) for planes [c0, c0 + Rhs), in groups of at most kMaxRhs.
template <class Solve>
void for_each_plane_group(int planes, Solve&& solve) {
  for (int c0 = 0; c0 < planes; c0 += kMaxRhs) {
    const int group = std::min(kMaxRhs, planes - c0);
    if (group == 3)
      solve.template operator()<3>(c0);
    else if (group == 2)
      solve.template operator()<2>(c0);
    else
      solve.template operator()<1>(c0);
  }
  static_assert(kMaxRhs == 3);
}

// One pass over every plane of the stacks (dst may be src).
//
// Source provides:
//   void activity(Direction, std::ptrdiff_t band, std::vector<std::uint8_t>& active): per tile
//     along the band, whether it may hold a non-zero link in that direction (a tile marked
//     inactive must have none);
//   template <int W> void row_link_lanes(std::ptrdiff_t y0, std::ptrdiff_t count,
//     std::ptrdiff_t x0, std::ptrdiff_t columns, const float* zero_row, float* lanes):
//     lanes[k * W + l] = the link (x0 + k, y0 + l)-(x0 + k + 1, y0 + l) for k < columns, zero
//     at the border and for l >= count (zero_row: a row of zeros as long as the image's);
//     lanes has room for columns + 1 rows of W;
//   void column_links(std::ptrdiff_t y0, std::ptrdiff_t rows, std::ptrdiff_t x0,
//     std::ptrdiff_t count, std::ptrdiff_t lanes, float* out): out[r * lanes + l] = the link
//     (x0 + l, y0 + r)-(x0 + l, y0 + r + 1) for r < rows, zero at the border and for
//     l >= count; out has room for rows + 1 rows;
//   void prefetch_column(std::ptrdiff_t y, std::ptrdiff_t x0, std::ptrdiff_t count): fetches
//     what column_links will read of row y for columns [x0, x0 + count).
// Every conductance a source gives is finite and >= 0 (checked when it was made).
template <class Source>
DiffusionReport run_pass(Direction direction, const PlaneStack<float>& dst,
                         const PlaneStack<const float>& src, const Source& source,
                         const DiffusionOptions& options) {
  const bool rows = direction == Direction::Rows;
  const std::ptrdiff_t width = src.width, height = src.height;
  const std::ptrdiff_t bands = ((rows ? height : width) + kTile - 1) / kTile;
  const std::ptrdiff_t length = rows ? width : height;  // of one system
  const bool in_place = dst.data == src.data;
  std::vector<std::ptrdiff_t> solved(bands, 0);

  for_each_band(
      bands, resolve_threads(options.threads), [&](std::ptrdiff_t band, BandScratch& scratch) {
        const std::ptrdiff_t first = band * kTile;  // first row (rows) or column (columns)
        const std::ptrdiff_t count = std::min(kTile, (rows ? height : width) - first);
        source.activity(direction, band, scratch.active);
        find_segments(scratch.active, length, options.skip_inactive, scratch.segments);
        // Copies pixels [from, to) along every system of the band (the parts not solved).
        auto copy_span = [&](std::ptrdiff_t from, std::ptrdiff_t to) {
          if (in_place || to <= from) return;
          for (int c = 0; c < src.count; ++c) {
            if (rows)
              for (std::ptrdiff_t y = first; y < first + count; ++y)
                copy_finite(dst.row(c, y) + from, src.row(c, y) + from, to - from, from, y);
            else
              for (std::ptrdiff_t y = from; y < to; ++y)
                copy_finite(dst.row(c, y) + first, src.row(c, y) + first, count, first, y);
          }
        };
        std::ptrdiff_t copied_to = 0;
        for (const Segment& s : scratch.segments) {
          copy_span(copied_to, s.begin);
          const std::ptrdiff_t n = s.end - s.begin;
          if (rows) {
            for (std::ptrdiff_t sub = 0; sub < count; sub += kRowLanes)
              for_each_plane_group(src.count, [&]<int Rhs>(int c0) {
                solve_row_segment<kRowLanes, Rhs>(source, dst, src, c0, first + sub,
                                                  std::min(kRowLanes, count - sub), s, scratch);
              });
          } else {
            float* work = scratch.floats(column_scratch_floats(n));
            for (std::ptrdiff_t sub = 0; sub < count; sub += kColumnLanes)
              for_each_plane_group(src.count, [&]<int Rhs>(int c0) {
                solve_column_segment<kColumnLanes, Rhs>(source, dst, src, c0, first + sub,
                                                        std::min(kColumnLanes, count - sub), s,
                                                        work);
              });
          }
          solved[band] += n * count * src.count;
          copied_to = s.end;
        }
        copy_span(copied_to, length);
      });
  DiffusionReport report{width * height * src.count, 0};
  for (std::ptrdiff_t s : solved) report.pixels_solved += s;
  return report;
}

inline void require_same_size(std::ptrdiff_t width, std::ptrdiff_t height, ConstPlane other,
                              const char* what) {
  if (other.width() != width || other.height() != height)
    throw InvalidArgument(what, "is " + std::to_string(other.width()) + " x " +
                                    std::to_string(other.height()) + ", the source is " +
                                    std::to_string(width) + " x " + std::to_string(height));
}

inline PlaneStack<const float> stack_of(const Image& image) {
  return {image.data(),  image.width(),        image.height(),
          image.pitch(), image.plane_stride(), image.channels()};
}
inline PlaneStack<float> stack_of(Image& image) {
  return {image.data(),  image.width(),        image.height(),
          image.pitch(), image.plane_stride(), image.channels()};
}

// Both passes over every channel: rows from src into dst, then columns in place in dst.
template <class Source>
DiffusionReport run_adi(Image& dst, const Image& src, const Source& source,
                        const DiffusionOptions& options) {
  if (&dst != &src && (dst.width() != src.width() || dst.height() != src.height() ||
                       dst.channels() != src.channels()))
    dst.reset(src.width(), src.height(), src.channels());
  DiffusionReport report = run_pass(Direction::Rows, stack_of(dst), stack_of(src), source, options);
  if (options.progress) options.progress(0.5);
  const Image& rows_done = dst;
  report += run_pass(Direction::Columns, stack_of(dst), stack_of(rows_done), source, options);
  if (options.progress) options.progress(1.0);
  return report;
}

// Conductance per pixel, to_link(value(x, y)); a link conducts the smaller of its two ends.
template <class ToLink>
class PixelConductance {
 public:
  // Checks every conductance and finds the tiles that hold one, in one pass over `value` in
  // memory order (both passes share the result; the columns pass would otherwise scan
  // 64-pixel-wide strips).
  PixelConductance(ConstPlane value, ToLink to_link, int threads)
      : value_(value),
        to_link_(to_link),
        tiles_x_((value.width() + kTile - 1) / kTile),
        tiles_y_((value.height() + kTile - 1) / kTile),
        conducting_(tiles_x_ * tiles_y_, 0) {
    bool bad = false;
// clang-format off
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(dynamic, 1) \
    reduction(|| : bad) if (tiles_y_ > 1)
    // clang-format on
    for (std::ptrdiff_t ty = 0; ty < tiles_y_; ++ty) bad = scan_tile_row(ty) || bad;
    if (bad) throw_bad_conductance(value_, to_link_);  // names the first bad pixel
  }

  void activity(Direction direction, std::ptrdiff_t band, std::vector<std::uint8_t>& active) const {
    const bool rows = direction == Direction::Rows;
    active.resize(rows ? tiles_x_ : tiles_y_);
    for (std::ptrdiff_t t = 0; t < std::ptrdiff_t(active.size()); ++t)
      active[t] = rows ? conducting_[band * tiles_x_ + t] : conducting_[t * tiles_x_ + band];
  }

  template <int W>
  void row_link_lanes(std::ptrdiff_t y0, std::ptrdiff_t count, std::ptrdiff_t x0,
                      std::ptrdiff_t columns, const float* zero_row, float* lanes) const {
    const float* rows[W];
    adi_detail::band_rows<W>(value_.row(y0), value_.pitch(), count, zero_row, rows);
    // The conductances of columns [x0, x0 + columns] (the last one for the block's last link),
    // as far as the image goes.
    const std::ptrdiff_t known = std::min(columns + 1, value_.width() - x0);
    detail::gather_into_lanes<float, W>(rows, x0, known, lanes, value_.width());
#pragma omp simd
    for (std::ptrdiff_t i = 0; i < known * W; ++i) lanes[i] = to_link_(lanes[i]);
    for (std::ptrdiff_t k = 0; k < columns; ++k) {
      float* here = lanes + k * W;
      const bool has_link = k + 1 < known;
#pragma omp simd
      for (int l = 0; l < W; ++l)
        here[l] = has_link && l < count ? std::min(here[l], here[l + W]) : 0.f;
    }
  }

  void prefetch_column(std::ptrdiff_t y, std::ptrdiff_t x0, std::ptrdiff_t count) const {
    prefetch_span(value_.row(y) + x0, count);
  }

  // Whether tile (tx, ty) holds a conductance other than zero.
  bool conducting(std::ptrdiff_t tx, std::ptrdiff_t ty) const {
    return conducting_[ty * tiles_x_ + tx] != 0;
  }
  const ToLink& to_link() const { return to_link_; }

  void column_links(std::ptrdiff_t y0, std::ptrdiff_t rows, std::ptrdiff_t x0, std::ptrdiff_t count,
                    std::ptrdiff_t lanes, float* out) const {
    // The conductances of rows [y0, y0 + rows] (the last one for the block's last link), as
    // far as the image goes: each pixel's once, not once per link.
    const std::ptrdiff_t known = std::min(rows + 1, value_.height() - y0);
    for (std::ptrdiff_t r = 0; r < known; ++r) {
      const float* v = value_.row(y0 + r) + x0;
      float* k = out + r * lanes;
#pragma omp simd
      for (std::ptrdiff_t l = 0; l < count; ++l) k[l] = to_link_(v[l]);
    }
    for (std::ptrdiff_t r = 0; r < rows; ++r) {
      float* here = out + r * lanes;
      if (r + 1 < known) {
#pragma omp simd
        for (std::ptrdiff_t l = 0; l < count; ++l) here[l] = std::min(here[l], here[l + lanes]);
        std::fill(here + count, here + lanes, 0.f);
      } else {
        std::fill(here, here + lanes, 0.f);  // the bottom border
      }
    }
  }

 private:
  // Marks the tiles of tile row ty that hold a conductance other than zero (a tile marked
  // inactive then has no link); returns whether a conductance is negative or not finite.
  // Each tile keeps 16 lanes of bits, reduced once per tile row: reducing them once per image
  // row made this scan cost three times a read of the plane.
  bool scan_tile_row(std::ptrdiff_t ty) {
    // On the bit patterns: +0 and -0 are the zeros; a valid conductance is below the
    // pattern of +infinity; anything else with the sign bit is negative or NaN.
    constexpr std::uint32_t kInfinity = 0x7f800000u, kNegativeZero = 0x80000000u;
    constexpr int kWidth = 16;
    constexpr std::ptrdiff_t kScanAhead = 512;
    static_assert(kTile % kWidth == 0);
    const std::ptrdiff_t width = value_.width();
    thread_local std::vector<std::uint32_t> seen;  // tiles_x_ x kWidth lanes
    seen.assign(std::size_t(tiles_x_ * kWidth), 0u);
    std::uint32_t bad[kWidth] = {};
    for (std::ptrdiff_t y = ty * kTile; y < std::min(value_.height(), (ty + 1) * kTile); ++y) {
      const float* v = value_.row(y);
      for (std::ptrdiff_t x0 = 0; x0 < width; x0 += kWidth) {
        // The conductances first, then the bits: in one loop GCC 12 kept to_link's branch
        // and did not vectorise.
        // 2 KiB ahead: the hardware prefetchers of some hosts do not keep one stream fed
        // (an Intel Xeon, 3840 x 2160, 2 threads: 2.2 -> 1.2 ms; 1 KiB or 4 KiB the same).
        __builtin_prefetch(v + x0 + kScanAhead);
        const int lanes = int(std::min<std::ptrdiff_t>(kWidth, width - x0));
        float link[kWidth] = {};
        if (lanes == kWidth) {
#pragma omp simd
          for (int l = 0; l < kWidth; ++l) link[l] = to_link_(v[x0 + l]);
        } else {
          for (int l = 0; l < lanes; ++l) link[l] = to_link_(v[x0 + l]);
        }
        std::uint32_t* bits = seen.data() + x0 / kTile * kWidth;
#pragma omp simd
        for (int l = 0; l < kWidth; ++l) {
          const auto k = std::bit_cast<std::uint32_t>(link[l]);
          bits[l] |= k & ~kNegativeZero;
          bad[l] |= std::uint32_t(k >= kInfinity && k != kNegativeZero);
        }
      }
    }
    for (std::ptrdiff_t tx = 0; tx < tiles_x_; ++tx) {
      std::uint32_t bits = 0;
      for (int l = 0; l < kWidth; ++l) bits |= seen[tx * kWidth + l];
      conducting_[ty * tiles_x_ + tx] = bits != 0;
    }
    std::uint32_t any_bad = 0;
    for (int l = 0; l < kWidth; ++l) any_bad |= bad[l];
    return any_bad != 0;
  }

  ConstPlane value_;
  ToLink to_link_;
  std::ptrdiff_t tiles_x_, tiles_y_;
  std::vector<std::uint8_t> conducting_;  // per tile, row-major
};

// to_link scaled by a constant factor (the isotropic step's share of the conductance).
template <class ToLink>
struct ScaledLink {
  ToLink to_link;
  float scale;
  float operator()(float value) const { return scale * to_link(value); }
};

}  // namespace tridiff::adi_detail

#include "tridiff/diffusion/detail/diagonal_impl.hpp"

namespace tridiff {

template <class ToLink>
DiffusionReport diffuse_adi(Image& dst, const Image& src, ConstPlane value, ToLink to_link,
                            const DiffusionOptions& options) {
  adi_detail::require_same_size(src.width(), src.height(), value, "value");
  return adi_detail::run_adi(
      dst, src, adi_detail::PixelConductance<ToLink>(value, to_link, options.threads), options);
}

}  // namespace tridiff

namespace tridiff {

template <class ToLink>
DiffusionReport diffuse_isotropic(Image& dst, const Image& src, ConstPlane value, ToLink to_link,
                                  const DiffusionOptions& options) {
  adi_detail::require_same_size(src.width(), src.height(), value, "value");
  const adi_detail::ScaledLink<ToLink> half{to_link, 0.5f}, quarter{to_link, 0.25f};
  const adi_detail::PixelConductance<adi_detail::ScaledLink<ToLink>> axes(value, half,
                                                                          options.threads);
  DiffusionOptions quiet = options;
  quiet.progress = nullptr;
  DiffusionReport report = adi_detail::run_adi(dst, src, axes, quiet);
  if (options.progress) options.progress(0.5);
  const auto conducting = [&](std::ptrdiff_t tx, std::ptrdiff_t ty) {
    return axes.conducting(tx, ty);
  };
  for (const int slope : {+1, -1})
    report += adi_detail::run_diagonal_pass(adi_detail::stack_of(dst), value, quarter, conducting,
                                            slope, options);
  if (options.progress) options.progress(1.0);
  return report;
}

}  // namespace tridiff
