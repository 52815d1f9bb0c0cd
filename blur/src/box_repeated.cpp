// Repeated box filtering (seed 001 §3.8) with the box widths of Wells / Kovesi, and the
// separable running-sum engine shared with the extended box (box_extended.cpp).
//
// Layout as in iir_deriche.cpp: columns are filtered in strips of kLanes columns, one SIMD lane
// a column, all passes of a strip done while it sits in L2 (two 16-column buffers of 4096 rows
// are 512 KiB); rows are transposed 16 at a time into the same layout, all passes run, and
// transposed back. So the image is read and written once for the columns and once for the
// rows, whatever the number of passes.
#include <algorithm>
#include <cmath>
#include <string>

#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/box.hpp"
#include "tridiff/solvers/solve.hpp"
#include "row_blocks.hpp"

namespace tridiff {

double box_variance(std::ptrdiff_t width) { return (double(width) * double(width) - 1) / 12; }

std::vector<std::ptrdiff_t> box_widths(double sigma, int passes) {
  if (!std::isfinite(sigma) || sigma < 0) throw InvalidArgument("sigma", "must be finite and >= 0");
  if (passes < 1) throw InvalidArgument("passes", "must be >= 1");
  const double n = passes, target = 12 * sigma * sigma;  // 12 sigma^2 = sum of (w^2 - 1)
  auto lower = static_cast<std::ptrdiff_t>(std::floor(std::sqrt(target / n + 1)));
  if (lower % 2 == 0) --lower;
  const double wl = static_cast<double>(lower);
  // m boxes of width wl and n - m of wl + 2 sum to target when
  // m (wl^2 - 1) + (n - m) ((wl + 2)^2 - 1) = target.
  const double ideal_m = (target - n * wl * wl - 4 * n * wl - 3 * n) / (-4 * wl - 4);
  const auto m = std::clamp<std::ptrdiff_t>(std::lround(ideal_m), 0, passes);
  std::vector<std::ptrdiff_t> widths(passes, lower + 2);
  std::fill_n(widths.begin(), m, lower);
  return widths;
}

std::vector<BoxPass> plain_box_passes(double sigma, int passes) {
  std::vector<BoxPass> result;
  for (std::ptrdiff_t width : box_widths(sigma, passes)) result.push_back({(width - 1) / 2, 0});
  return result;
}

namespace {

constexpr int kLanes = 16;  // one AVX-512 vector of floats

// Samples [lo, hi) of a line, by their logical index (negative: before the image).
struct Range {
  std::ptrdiff_t lo, hi;
};

// One pass along kLanes interleaved lines (sample j of lane l at src[(j - in.lo) * ss + l]),
// writing samples out.lo..out.hi - 1 into dst, which must not overlap src. A running sum over
// the window [i - r, i + r]; the extended box adds alpha times the two samples just outside
// it. Reads outside `in` take its edge sample: the replicate border for the first pass; later
// passes are given enough margin that they never read outside.
template <bool kExtended>
void pass_lanes(const float* src, std::ptrdiff_t ss, Range in, float* dst, std::ptrdiff_t ds,
                Range out, const BoxPass& pass) {
  const std::ptrdiff_t r = pass.radius;
  const float alpha = static_cast<float>(pass.end_weight);
  const float norm = static_cast<float>(1 / (2.0 * double(r) + 1 + 2 * pass.end_weight));
  const auto at = [&](std::ptrdiff_t j) {
    return src + (std::clamp(j, in.lo, in.hi - 1) - in.lo) * ss;
  };
  float sum[kLanes];
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) sum[l] = 0;
  for (std::ptrdiff_t k = out.lo - r; k <= out.lo + r; ++k) {
    const float* x = at(k);
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) sum[l] += x[l];
  }
  for (std::ptrdiff_t i = out.lo; i < out.hi; ++i) {
    const float* enter = at(i + r + 1);  // joins the window at i + 1
    const float* leave = at(i - r);      // leaves it at i + 1
    float* y = dst + (i - out.lo) * ds;
    if constexpr (kExtended) {
      const float* before = at(i - r - 1);
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) {
        y[l] = norm * (sum[l] + alpha * (before[l] + enter[l]));
        sum[l] += enter[l] - leave[l];
      }
    } else {
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) {
        y[l] = norm * sum[l];
        sum[l] += enter[l] - leave[l];
      }
    }
  }
}

void run_pass(const float* src, std::ptrdiff_t ss, Range in, float* dst, std::ptrdiff_t ds,
              Range out, const BoxPass& pass) {
  if (pass.end_weight != 0)
    pass_lanes<true>(src, ss, in, dst, ds, out, pass);
  else
    pass_lanes<false>(src, ss, in, dst, ds, out, pass);
}

void copy_lanes(const float* src, std::ptrdiff_t ss, float* dst, std::ptrdiff_t ds,
                std::ptrdiff_t n) {
  for (std::ptrdiff_t i = 0; i < n; ++i) std::copy_n(src + i * ss, kLanes, dst + i * ds);
}

// How far past each end of the line pass k must compute so that the passes after it never
// read past what it computed: the sum of their reach (radius + 1). Clamping every pass at the
// image edge instead would not be the replicate border of the combined kernel (at a corner the
// error against the Gaussian nearly doubles).
std::vector<std::ptrdiff_t> margins(std::span<const BoxPass> passes) {
  std::vector<std::ptrdiff_t> m(passes.size(), 0);
  for (std::size_t k = passes.size(); k-- > 1;) m[k - 1] = m[k] + passes[k].radius + 1;
  return m;
}

// Scratch for one thread: two lane buffers, for the line with its widest margins. They are
// the thread's buffers kept from call to call (row_blocks.hpp), so taking them is cheap even
// once per block.
struct LaneScratch {
  float* a;
  float* b;
  LaneScratch(std::ptrdiff_t n, std::span<const BoxPass> passes) {
    const std::ptrdiff_t margin = passes.empty() ? 0 : margins(passes).front();
    const auto floats = static_cast<std::size_t>((n + 2 * margin) * kLanes);
    a = blur_detail::scratch(blur_detail::kFreeScratchSlot, floats);
    b = blur_detail::scratch(blur_detail::kFreeScratchSlot + 1, floats);
  }
};

// All passes along kLanes lines of n samples: src -> a -> b -> a ... -> dst. src and dst may
// be the same (the first pass reads src before the last writes dst).
void run_passes(const float* src, std::ptrdiff_t ss, float* dst, std::ptrdiff_t ds,
                std::ptrdiff_t n, std::span<const BoxPass> passes, LaneScratch& scratch) {
  const Range line{0, n};
  if (passes.empty()) {
    if (src != dst) copy_lanes(src, ss, dst, ds, n);
    return;
  }
  if (passes.size() == 1 && src == dst) {
    run_pass(src, ss, line, scratch.a, kLanes, line, passes[0]);
    copy_lanes(scratch.a, kLanes, dst, ds, n);
    return;
  }
  const std::vector<std::ptrdiff_t> margin = margins(passes);
  const float* current = src;
  std::ptrdiff_t current_stride = ss;
  Range current_range = line;
  for (std::size_t k = 0; k < passes.size(); ++k) {
    const bool final_pass = k + 1 == passes.size();
    float* target = final_pass ? dst : (k % 2 == 0 ? scratch.a : scratch.b);
    const std::ptrdiff_t target_stride = final_pass ? ds : kLanes;
    const Range target_range{-margin[k], n + margin[k]};
    run_pass(current, current_stride, current_range, target, target_stride, target_range,
             passes[k]);
    current = target;
    current_stride = target_stride;
    current_range = target_range;
  }
}

// Columns: strips of kLanes columns straight from `in` to `out`; a last partial strip goes
// through a padded copy.
void filter_columns(ConstPlane in, Plane out, std::span<const BoxPass> passes, int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height();
  const std::ptrdiff_t strips = (w + kLanes - 1) / kLanes;
#pragma omp parallel num_threads(threads)
  {
    LaneScratch scratch(h, passes);
    std::vector<float> pad;
#pragma omp for schedule(static)
    for (std::ptrdiff_t s = 0; s < strips; ++s) {
      const std::ptrdiff_t x0 = s * kLanes, lanes = std::min<std::ptrdiff_t>(kLanes, w - x0);
      if (lanes == kLanes) {
        run_passes(in.row(0) + x0, in.pitch(), out.row(0) + x0, out.pitch(), h, passes, scratch);
        continue;
      }
      pad.assign(h * kLanes, 0.f);
      for (std::ptrdiff_t y = 0; y < h; ++y)
        std::copy_n(in.row(y) + x0, lanes, pad.data() + y * kLanes);
      run_passes(pad.data(), kLanes, pad.data(), kLanes, h, passes, scratch);
      for (std::ptrdiff_t y = 0; y < h; ++y)
        std::copy_n(pad.data() + y * kLanes, lanes, out.row(y) + x0);
    }
  }
}

// Rows, in place: kLanes rows at a time in lane order (row_blocks.hpp), all passes run there.
void filter_rows(Plane plane, std::span<const BoxPass> passes, int threads) {
  blur_detail::for_each_row_block<kLanes>(plane, threads, [&](float* lanes, std::ptrdiff_t w) {
    LaneScratch scratch(w, passes);
    run_passes(lanes, kLanes, lanes, kLanes, w, passes, scratch);
  });
}

}  // namespace

void box_passes(Plane out, ConstPlane in, std::span<const BoxPass> passes, int threads) {
  if (in.width() < 1 || in.height() < 1 || !in.data()) throw InvalidArgument("in", "is empty");
  if (out.width() != in.width() || out.height() != in.height())
    throw InvalidArgument("out", "size differs from in");
  if (threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
  std::vector<BoxPass> effective;  // identity passes (radius 0, no end weights) dropped
  for (const BoxPass& p : passes) {
    if (p.radius < 0 || !(p.end_weight >= 0 && p.end_weight <= 1))
      throw InvalidArgument("passes", "need radius >= 0 and end_weight in [0, 1]");
    if (p.radius > 0 || p.end_weight > 0) effective.push_back(p);
  }
  const int resolved = resolve_threads(threads);
  filter_columns(in, out, effective, resolved);
  filter_rows(out, effective, resolved);
}

namespace blur_detail {

void run_box(Plane out, ConstPlane in, const BlurOptions& options) {
  box_passes(out, in, plain_box_passes(options.sigma, kDefaultBoxPasses),
             resolve_threads(options.threads));
}

}  // namespace blur_detail

}  // namespace tridiff
