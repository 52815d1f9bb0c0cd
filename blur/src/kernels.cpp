// Kernels and spatial convolution (seed 001 §3.2, §3.3; seed 000 §3.3.1, §5.3.2).
//
// Both convolutions stream the image row by row through a per-thread ring of prepared rows:
// for the separable one the ring holds rows already filtered along x (the column pass then
// sums 2r + 1 of them), for the 2D one it holds border-padded input rows. The separable ring is
// 2r + 8 rows of the image width (368 KiB at width 4096, sigma 2), or of a narrower panel of
// columns when that would not fit in L2, so the only full-size traffic is reading `in` once
// and writing `out` once: no full-size temporary. The column pass works on 8 output rows at a
// time in x strips that fit L1, two rows per sweep sharing their loads. Borders are handled
// once per row, when the row is padded (x) or picked (y); the inner loops have no branches.
//
// Measured at 4096^2 x 3 planes on the shared 2-core AVX-512 machine, one thread, CPU time:
// sigma 2 (23 taps) about 80 ms, where OpenCV's cv::GaussianBlur (17 taps) took 125-170 ms
// and a plain copy 10 ms; sigma 8 (87 taps) about 215 ms.

#include "tridiff/blur/kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "tridiff/blur/reference.hpp"

namespace tridiff {

// ---- kernels ----------------------------------------------------------------------------

std::ptrdiff_t gaussian_radius(double sigma) { return gaussian_radius(sigma, kGaussianTailMass); }

std::ptrdiff_t gaussian_radius(double sigma, double tail_mass) {
  if (!(tail_mass > 0 && tail_mass < 1))
    throw InvalidArgument("tail_mass", "must lie in (0, 1), got " + std::to_string(tail_mass));
  const std::ptrdiff_t max_radius = reference_radius(sigma);  // also checks sigma
  const std::vector<double> full = sampled_gaussian(sigma, max_radius);
  // full is normalised over [-max_radius, max_radius], whose own tail beyond is < 2e-9: the
  // mass outside [-r, r] is 1 - (sum inside), accumulated from the outside in for accuracy.
  double tail = 0;
  std::ptrdiff_t r = max_radius;
  while (r > 1) {
    const double dropped = tail + full[0 + (max_radius - r)] + full[max_radius + r];
    if (dropped > tail_mass) break;
    tail = dropped;
    --r;
  }
  return r;
}

std::vector<float> gaussian_kernel(double sigma, std::ptrdiff_t radius) {
  const std::vector<double> weights = sampled_gaussian(sigma, radius);  // checks its arguments
  return {weights.begin(), weights.end()};
}

std::vector<float> gaussian_kernel(double sigma) {
  return gaussian_kernel(sigma, gaussian_radius(sigma));
}

std::vector<float> triangle_kernel(std::ptrdiff_t size) {
  if (size < 1 || size % 2 == 0)
    throw InvalidArgument("size", "must be odd and >= 1, got " + std::to_string(size));
  const std::ptrdiff_t middle = (size + 1) / 2, radius = size / 2;
  const double norm = 1.0 / (double(middle) * double(middle));
  std::vector<float> kernel(size);
  for (std::ptrdiff_t k = -radius; k <= radius; ++k)
    kernel[k + radius] = static_cast<float>((middle - std::abs(k)) * norm);
  return kernel;
}

std::vector<float> bilinear_box_kernel() { return {0.f, 0.5f, 0.5f}; }

Kernel2D outer_product(std::span<const float> kx, std::span<const float> ky) {
  blur_detail::check_kernel(kx, "kx");
  blur_detail::check_kernel(ky, "ky");
  Kernel2D kernel{
      static_cast<std::ptrdiff_t>(kx.size()), static_cast<std::ptrdiff_t>(ky.size()), {}};
  kernel.weights.reserve(kx.size() * ky.size());
  for (float wy : ky)
    for (float wx : kx) kernel.weights.push_back(static_cast<float>(double(wx) * double(wy)));
  return kernel;
}

Kernel2D gaussian_kernel_2d(double sigma) {
  const std::vector<float> k = gaussian_kernel(sigma);
  return outer_product(k, k);
}

Kernel2D bilinear_box_kernel_2d() {
  const std::vector<float> k = bilinear_box_kernel();
  return outer_product(k, k);
}

// ---- argument checks --------------------------------------------------------------------

namespace blur_detail {

void check_convolution_planes(ConstPlane out, ConstPlane in, int threads) {
  if (in.width() < 1 || in.height() < 1 || !in.data()) throw InvalidArgument("in", "is empty");
  if (out.width() != in.width() || out.height() != in.height() || !out.data())
    throw InvalidArgument(
        "out", "is " + std::to_string(out.width()) + " x " + std::to_string(out.height()) +
                   ", in is " + std::to_string(in.width()) + " x " + std::to_string(in.height()));
  const float* in_end = in.row(in.height() - 1) + in.width();
  const float* out_end = out.row(out.height() - 1) + out.width();
  if (in.data() < out_end && out.data() < in_end) throw InvalidArgument("out", "overlaps in");
  if (threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
}

namespace {
void check_weights(std::span<const float> weights, const char* name) {
  for (float w : weights)
    if (!std::isfinite(w)) throw InvalidArgument(name, "has a weight that is not finite");
}
}  // namespace

void check_kernel(std::span<const float> kernel, const char* name) {
  if (kernel.empty()) throw InvalidArgument(name, "is empty");
  if (kernel.size() % 2 == 0)
    throw InvalidArgument(
        name, "must have odd length (2r + 1, centred), got " + std::to_string(kernel.size()));
  check_weights(kernel, name);
}

void check_kernel(const Kernel2D& kernel, const char* name) {
  if (kernel.width < 1 || kernel.height < 1 || kernel.weights.empty())
    throw InvalidArgument(name, "is empty");
  if (kernel.width % 2 == 0 || kernel.height % 2 == 0)
    throw InvalidArgument(name, "must be odd in both directions (centred), got " +
                                    std::to_string(kernel.width) + " x " +
                                    std::to_string(kernel.height));
  if (static_cast<std::ptrdiff_t>(kernel.weights.size()) != kernel.width * kernel.height)
    throw InvalidArgument(name, "has " + std::to_string(kernel.weights.size()) +
                                    " weights, width x height is " +
                                    std::to_string(kernel.width * kernel.height));
  check_weights(kernel.weights, name);
}

}  // namespace blur_detail

// ---- the summation kernel ---------------------------------------------------------------

namespace {

// Pixels per block of the inner loops: four AVX-512 vectors of accumulators.
constexpr std::ptrdiff_t kBlock = 64;

std::ptrdiff_t round_up(std::ptrdiff_t n, std::ptrdiff_t to) { return (n + to - 1) / to * to; }

// A kernel flattened to taps, each tap reading its own source line; a kernel symmetric about
// its middle (k[t] == k[n - 1 - t]) is folded so that each pair of taps costs one add and one
// multiply-add.
struct Taps {
  std::vector<float> weights;
  bool symmetric = false;

  explicit Taps(std::span<const float> k) : weights(k.begin(), k.end()) {
    symmetric = std::equal(weights.begin(), weights.end(), weights.rbegin());
  }
  std::ptrdiff_t size() const { return static_cast<std::ptrdiff_t>(weights.size()); }
};

// Four vectors of accumulators, written with GCC's vector extension: with `omp simd` GCC 12
// vectorised the tap loop (gathers) and kept the accumulators in memory, 10x slower. Lowered
// to AVX-512 with -march=native, to pairs of narrower vectors otherwise.
typedef float Vec __attribute__((vector_size(64)));
constexpr int kLanes = sizeof(Vec) / sizeof(float);
constexpr int kVecs = kBlock / kLanes;

// acc[v] += the taps [t0, t1) (pairs of mirrored taps when `folded`) at x0 + v kLanes. The
// taps are the outer loop so that each tap reads contiguous vectors; the accumulators stay in
// registers. Folding adds the mirrored samples first: half the multiplications.
inline void add_taps(Vec* acc, const float* const* src, const Taps& taps, std::ptrdiff_t x0,
                     std::ptrdiff_t t0, std::ptrdiff_t t1, bool folded) {
  const std::ptrdiff_t n = taps.size();
  const float* k = taps.weights.data();
  Vec a, b;
  for (std::ptrdiff_t t = t0; t < t1; ++t) {
    const float* pa = src[t] + x0;
    const float* pb = src[n - 1 - t] + x0;
    const float kt = k[t];
    for (int v = 0; v < kVecs; ++v) {
      std::memcpy(&a, pa + v * kLanes, sizeof a);
      if (folded) {
        std::memcpy(&b, pb + v * kLanes, sizeof b);
        a += b;
      }
      acc[v] += kt * a;
    }
  }
}

// Sums of many taps are formed in chunks of max(64, sqrt(taps)) added to the total, so that
// float rounding grows like 2 sqrt(taps) rather than taps (a 2D Gaussian of sigma 16 has 29241).
std::ptrdiff_t tap_chunk(std::ptrdiff_t taps) {
  return std::max<std::ptrdiff_t>(64, static_cast<std::ptrdiff_t>(std::sqrt(double(taps))) + 1);
}

// out[l] = sum_t k[t] src[t][x0 + l], l in [0, kBlock).
inline void sum_block(const float* const* src, const Taps& taps, std::ptrdiff_t x0, float* out) {
  const std::ptrdiff_t n = taps.size();
  const bool folded = taps.symmetric;
  const std::ptrdiff_t terms = folded ? n / 2 : n, chunk = tap_chunk(terms);
  Vec acc[kVecs];
  for (int v = 0; v < kVecs; ++v) acc[v] = Vec{} + 0.f;
  if (terms <= chunk) {
    add_taps(acc, src, taps, x0, 0, terms, folded);
  } else {
    for (std::ptrdiff_t t0 = 0; t0 < terms; t0 += chunk) {
      Vec part[kVecs];
      for (int v = 0; v < kVecs; ++v) part[v] = Vec{} + 0.f;
      add_taps(part, src, taps, x0, t0, std::min(terms, t0 + chunk), folded);
      for (int v = 0; v < kVecs; ++v) acc[v] += part[v];
    }
  }
  // The middle tap last, in the same order as sum_pair_block: a row comes out bit for bit the
  // same whichever of the two computes it (which one does depends on the thread count).
  if (folded)
    for (int v = 0; v < kVecs; ++v) {
      Vec centre;
      std::memcpy(&centre, src[n / 2] + x0 + v * kLanes, sizeof centre);
      acc[v] += taps.weights[n / 2] * centre;
    }
  std::memcpy(out, acc, sizeof acc);
}

// dst[x] = sum_t k[t] src[t][x] for x in [begin, end), begin a multiple of kBlock. Sources
// must be readable up to round_up(end, kBlock); only [begin, end) is written.
void weighted_sum(const float* const* src, const Taps& taps, float* dst, std::ptrdiff_t begin,
                  std::ptrdiff_t end) {
  // Whole blocks are stored straight into dst; a last partial block goes through `acc` (a
  // variable-length memcpy per block is a libc call: it once took a quarter of the time).
  std::ptrdiff_t x0 = begin;
  for (; x0 + kBlock <= end; x0 += kBlock) sum_block(src, taps, x0, dst + x0);
  if (x0 < end) {
    alignas(64) float acc[kBlock];
    sum_block(src, taps, x0, acc);
    std::memcpy(dst + x0, acc, (end - x0) * sizeof(float));
  }
}

// Whether two adjacent output rows can share their loads (sum_pair_block): a symmetric kernel
// summed in one chunk.
bool pairs_rows(const Taps& taps) {
  return taps.symmetric && taps.size() / 2 <= tap_chunk(taps.size() / 2);
}

// Two adjacent output rows of the column pass at once, for a pairs_rows kernel of radius r:
// rows[0, 2r + 2) are the input rows, out0 sums rows[0, 2r], out1 rows[1, 2r + 1]. Row t + 1
// of one output's left half is row t of the other's, and likewise on the right, so each input
// vector is loaded once for both: r + 1 loads per output vector instead of 2r + 1.
inline void sum_pair_block(const float* const* rows, const Taps& taps, std::ptrdiff_t x0,
                           float* out0, float* out1) {
  const std::ptrdiff_t r = taps.size() / 2;
  const float* k = taps.weights.data();
  // All kVecs vectors advance together: 2 kVecs independent accumulator chains hide the
  // multiply-add latency (one vector at a time left the loop waiting on two chains).
  Vec lo[kVecs], hi[kVecs], acc0[kVecs], acc1[kVecs];
  for (int v = 0; v < kVecs; ++v) {
    std::memcpy(&lo[v], rows[0] + x0 + v * kLanes, sizeof(Vec));          // out0's left end
    std::memcpy(&hi[v], rows[2 * r + 1] + x0 + v * kLanes, sizeof(Vec));  // out1's right end
    acc0[v] = acc1[v] = Vec{} + 0.f;
  }
  for (std::ptrdiff_t t = 0; t < r; ++t) {
    const float* next_lo = rows[t + 1] + x0;
    const float* next_hi = rows[2 * r - t] + x0;
    const float kt = k[t];
    for (int v = 0; v < kVecs; ++v) {
      Vec a, b;
      std::memcpy(&a, next_lo + v * kLanes, sizeof a);
      std::memcpy(&b, next_hi + v * kLanes, sizeof b);
      acc0[v] += kt * (lo[v] + b);  // rows t and 2r - t
      acc1[v] += kt * (a + hi[v]);  // rows t + 1 and 2r + 1 - t
      lo[v] = a;
      hi[v] = b;
    }
  }
  for (int v = 0; v < kVecs; ++v) {
    acc0[v] += k[r] * lo[v];  // row r
    acc1[v] += k[r] * hi[v];  // row r + 1
  }
  std::memcpy(out0, acc0, sizeof acc0);
  std::memcpy(out1, acc1, sizeof acc1);
}

// weighted_sum for two adjacent rows (see sum_pair_block).
void weighted_sum_pair(const float* const* rows, const Taps& taps, float* dst0, float* dst1,
                       std::ptrdiff_t begin, std::ptrdiff_t end) {
  std::ptrdiff_t x0 = begin;
  for (; x0 + kBlock <= end; x0 += kBlock) sum_pair_block(rows, taps, x0, dst0 + x0, dst1 + x0);
  if (x0 < end) {
    alignas(64) float acc0[kBlock], acc1[kBlock];
    sum_pair_block(rows, taps, x0, acc0, acc1);
    std::memcpy(dst0 + x0, acc0, (end - x0) * sizeof(float));
    std::memcpy(dst1 + x0, acc1, (end - x0) * sizeof(float));
  }
}

// `row` of `in` extended by `radius` pixels each side with the border rule, into
// padded[0, w + 2 radius); the rest of `padded` (slack for whole blocks) is left alone.
void pad_row(const float* row, std::ptrdiff_t w, std::ptrdiff_t radius, Border border,
             float* padded) {
  std::memcpy(padded + radius, row, w * sizeof(float));
  for (std::ptrdiff_t i = -radius; i < 0; ++i) {
    const std::ptrdiff_t j = border_index(i, w, border);
    padded[i + radius] = j < 0 ? 0.f : row[j];
  }
  for (std::ptrdiff_t i = w; i < w + radius; ++i) {
    const std::ptrdiff_t j = border_index(i, w, border);
    padded[i + radius] = j < 0 ? 0.f : row[j];
  }
}

// Columns [x_begin - radius, x_begin + count + radius) of `row` (w pixels), the ones outside
// the image taken with the border rule, into padded[0, count + 2 radius).
void pad_segment(const float* row, std::ptrdiff_t w, std::ptrdiff_t x_begin, std::ptrdiff_t count,
                 std::ptrdiff_t radius, Border border, float* padded) {
  const std::ptrdiff_t first = x_begin - radius, last = x_begin + count + radius;  // [first, last)
  const std::ptrdiff_t inside_begin = std::max<std::ptrdiff_t>(first, 0);
  const std::ptrdiff_t inside_end = std::min(last, w);
  if (inside_begin < inside_end)
    std::memcpy(padded + (inside_begin - first), row + inside_begin,
                (inside_end - inside_begin) * sizeof(float));
  auto from_border = [&](std::ptrdiff_t i) {
    const std::ptrdiff_t j = border_index(i, w, border);
    padded[i - first] = j < 0 ? 0.f : row[j];
  };
  for (std::ptrdiff_t i = first; i < std::min(last, std::ptrdiff_t{0}); ++i) from_border(i);
  for (std::ptrdiff_t i = std::max(first, w); i < last; ++i) from_border(i);
}

// A ring of `count` prepared rows for the padded row indices of one stripe, each of `stride`
// floats. Row i (a padded index, may lie outside the image) is prepared once, by `prepare`,
// when first asked for; asking for rows in increasing order keeps the last `count` available.
class RowRing {
 public:
  RowRing(std::ptrdiff_t count, std::ptrdiff_t stride)
      : count_(count), stride_(stride), rows_(count * stride, 0.f) {}

  template <class Prepare>
  void advance_to(std::ptrdiff_t last, Prepare&& prepare) {
    for (; next_ <= last; ++next_) prepare(next_, slot(next_));
  }
  void start_at(std::ptrdiff_t first) { next_ = first; }
  float* slot(std::ptrdiff_t i) {
    return rows_.data() + ((i % count_) + count_) % count_ * stride_;
  }

 private:
  std::ptrdiff_t count_, stride_, next_ = 0;
  std::vector<float> rows_;
};

// Rows [0, h) split into `stripes` contiguous stripes: stripe s is [first(s), first(s + 1)).
std::ptrdiff_t stripe_start(std::ptrdiff_t s, std::ptrdiff_t stripes, std::ptrdiff_t h) {
  return h * s / stripes;
}

// Output rows per group of the column pass.
constexpr std::ptrdiff_t kRowGroup = 8;

// The width of the x strips of the column pass: `rows` ring rows of it fill about 24 KiB, most
// of a 32 KiB L1, in whole blocks.
std::ptrdiff_t column_strip(std::ptrdiff_t rows) {
  constexpr std::ptrdiff_t kL1Floats = 24 * 1024 / sizeof(float);
  return std::max<std::ptrdiff_t>(1, kL1Floats / rows / kBlock) * kBlock;
}

// The width of the column panels of the separable convolution: its ring (`ring_rows` rows of
// the panel) should stay within about 512 KiB, half of a 1 MiB L2; the image width is split
// into equal panels (whole blocks) no wider than that. At sigma 2 a 4096 wide image is one
// panel; at sigma 8 (ring of 94 rows) four of 1024, each recomputing 2r halo columns.
std::ptrdiff_t panel_width(std::ptrdiff_t w, std::ptrdiff_t ring_rows) {
  constexpr std::ptrdiff_t kL2Floats = 512 * 1024 / sizeof(float);
  const std::ptrdiff_t widest = std::max<std::ptrdiff_t>(4 * kBlock, kL2Floats / ring_rows);
  const std::ptrdiff_t panels = (w + widest - 1) / widest;
  return round_up((w + panels - 1) / panels, kBlock);
}

int stripe_count(int threads, std::ptrdiff_t h) {
  return static_cast<int>(std::min<std::ptrdiff_t>(threads, h));
}

}  // namespace

// ---- separable convolution --------------------------------------------------------------

void convolve_separable(Plane out, ConstPlane in, std::span<const float> kx,
                        std::span<const float> ky, Border border, int threads) {
  blur_detail::check_convolution_planes(out, in, threads);
  blur_detail::check_kernel(kx, "kx");
  blur_detail::check_kernel(ky, "ky");
  const int team = resolve_threads(threads);
  const std::ptrdiff_t w = in.width(), h = in.height();
  const std::ptrdiff_t rx = std::ssize(kx) / 2, ry = std::ssize(ky) / 2;
  const Taps taps_x(kx), taps_y(ky);
  const std::ptrdiff_t ring_rows = 2 * ry + kRowGroup;
  const std::ptrdiff_t panel = panel_width(w, ring_rows);  // a multiple of kBlock
  const int stripes = stripe_count(team, h);
  const std::ptrdiff_t strip = column_strip(ring_rows);
  const bool pair_rows = pairs_rows(taps_y);

#pragma omp parallel for num_threads(team) schedule(static, 1)
  for (int s = 0; s < stripes; ++s) {
    std::vector<float> padded(panel + 2 * rx, 0.f);
    std::vector<const float*> src(kx.size());
    for (std::ptrdiff_t t = 0; t < taps_x.size(); ++t) src[t] = padded.data() + t;
    std::vector<const float*> column_src(ring_rows);
    RowRing ring(ring_rows, panel);
    const std::ptrdiff_t y0 = stripe_start(s, stripes, h), y1 = stripe_start(s + 1, stripes, h);
    for (std::ptrdiff_t x0 = 0; x0 < w; x0 += panel) {
      const std::ptrdiff_t width = std::min(panel, w - x0);
      // The row pass: padded row index i is input row border_index(i), filtered along x.
      auto filter_row = [&](std::ptrdiff_t i, float* dst) {
        const std::ptrdiff_t j = border_index(i, h, border);
        if (j < 0) {
          std::fill_n(dst, panel, 0.f);
          return;
        }
        pad_segment(in.row(j), w, x0, width, rx, border, padded.data());
        weighted_sum(src.data(), taps_x, dst, 0, width);
      };
      // The column pass, kRowGroup output rows at a time, strip by strip across the panel:
      // the ring rows a strip reads stay in L1 for the whole group.
      ring.start_at(y0 - ry);
      for (std::ptrdiff_t y = y0; y < y1; y += kRowGroup) {
        const std::ptrdiff_t rows = std::min(kRowGroup, y1 - y);
        ring.advance_to(y + rows - 1 + ry, filter_row);
        // Output row y + g reads rows y + g - ry .. y + g + ry: column_src[g, g + 2 ry].
        for (std::ptrdiff_t i = 0; i < rows + 2 * ry; ++i) column_src[i] = ring.slot(y - ry + i);
        for (std::ptrdiff_t x = 0; x < width; x += strip) {
          const std::ptrdiff_t x_end = std::min(x + strip, width);
          std::ptrdiff_t g = 0;
          if (pair_rows)
            for (; g + 1 < rows; g += 2)
              weighted_sum_pair(column_src.data() + g, taps_y, out.row(y + g) + x0,
                                out.row(y + g + 1) + x0, x, x_end);
          for (; g < rows; ++g)
            weighted_sum(column_src.data() + g, taps_y, out.row(y + g) + x0, x, x_end);
        }
      }
    }
  }
}

// ---- 2D convolution ---------------------------------------------------------------------

void convolve_2d(Plane out, ConstPlane in, const Kernel2D& kernel, Border border, int threads) {
  blur_detail::check_convolution_planes(out, in, threads);
  blur_detail::check_kernel(kernel, "kernel");
  const int team = resolve_threads(threads);
  const std::ptrdiff_t w = in.width(), h = in.height();
  const std::ptrdiff_t rx = kernel.width / 2, ry = kernel.height / 2;
  const Taps taps(kernel.weights);
  const std::ptrdiff_t stride = round_up(w, kBlock) + 2 * rx;
  const int stripes = stripe_count(team, h);

#pragma omp parallel for num_threads(team) schedule(static, 1)
  for (int s = 0; s < stripes; ++s) {
    std::vector<const float*> src(kernel.weights.size());
    RowRing ring(2 * ry + 1, stride);
    auto pad = [&](std::ptrdiff_t i, float* dst) {
      const std::ptrdiff_t j = border_index(i, h, border);
      if (j < 0)
        std::fill_n(dst, stride, 0.f);
      else
        pad_row(in.row(j), w, rx, border, dst);
    };
    const std::ptrdiff_t y0 = stripe_start(s, stripes, h), y1 = stripe_start(s + 1, stripes, h);
    ring.start_at(y0 - ry);
    for (std::ptrdiff_t y = y0; y < y1; ++y) {
      ring.advance_to(y + ry, pad);
      // Tap (i, j) reads padded row y + j - ry from column x + i.
      for (std::ptrdiff_t j = 0; j < kernel.height; ++j) {
        const float* row = ring.slot(y - ry + j);
        for (std::ptrdiff_t i = 0; i < kernel.width; ++i) src[j * kernel.width + i] = row + i;
      }
      weighted_sum(src.data(), taps, out.row(y), 0, w);
    }
  }
}

}  // namespace tridiff
