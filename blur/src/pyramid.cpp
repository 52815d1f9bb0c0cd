// Pyramid blur (seed 001 §3.5): analysis down-sampling, an optional smoothing at the coarsest
// level, then biquadratic B-spline up-sampling. See pyramid.hpp for the geometry and borders.
//
// Each step is separable and done one output row at a time: the vertical taps are summed into
// a per-thread row buffer (contiguous, vectorisable), padded with the replicate border on both
// sides, and the horizontal taps read from that buffer. No image-sized scratch is needed; the
// only allocations are the coarse levels (1/3 of the input together), made once per call.
#include "tridiff/blur/pyramid.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace tridiff {

namespace {

// The analysis filters are all symmetric 4-tap filters per axis: coarse pixel j takes
// outer * (f[2j - 1] + f[2j + 2]) + inner * (f[2j] + f[2j + 1]). The 2x2 box has outer = 0.
struct AnalysisTaps {
  float outer, inner;
};

AnalysisTaps analysis_taps(PyramidFilter filter) {
  switch (filter) {
    case PyramidFilter::box2: return {0.f, 0.5f};
    case PyramidFilter::box4: return {0.25f, 0.25f};
    case PyramidFilter::quasi: return {13.f / 64, 19.f / 64};
  }
  throw InvalidArgument("filter", "unknown pyramid filter");
}

// Floor division by 2 for any sign (grid indices of the margins are negative).
std::ptrdiff_t floor_half(std::ptrdiff_t i) { return i >= 0 ? i / 2 : -((1 - i) / 2); }

// The grid indices [lo, hi) of one axis of one level that are stored. Level 0 is the input,
// [0, n). Beyond the stored range the level of the replicate-extended image is constant and
// equal to the stored end pixel, so clamping an index to [lo, hi) reads the exact value.
struct Range {
  std::ptrdiff_t lo, hi;
  std::ptrdiff_t size() const { return hi - lo; }
  std::ptrdiff_t clamp(std::ptrdiff_t i) const { return std::clamp<std::ptrdiff_t>(i, lo, hi - 1); }
  Range widened(std::ptrdiff_t by) const { return {lo - by, hi + by}; }
};

// The stored range of the next coarser level. Coarse pixel j reads fine pixels 2j - 1 to
// 2j + 2: it equals the left far-field value once 2j + 2 <= fine.lo, the right one once
// 2j - 1 >= fine.hi - 1. Storing down to the first such pixel on each side keeps clamping
// exact; the margins settle at 2 to 3 pixels a side whatever the level. These ranges also
// cover every coarse pixel the up-sampling of [fine.lo, fine.hi) reads
// (floor(fine.lo / 2) - 1 to ceil(fine.hi / 2)), so the synthesis never clamps.
Range coarser(Range fine) { return {floor_half(fine.lo - 2), -floor_half(-fine.hi) + 1}; }

// A level of the pyramid: its stored pixels, grid index (x, y) at image(x - x.lo, y - y.lo).
struct Level {
  Range x, y;
  Image image;
  Level(Range x_range, Range y_range)
      : x(x_range), y(y_range), image(x_range.size(), y_range.size(), 1) {}
  Plane plane() { return image.plane(0); }
  float* row(std::ptrdiff_t grid_y) { return image.plane(0).row(grid_y - y.lo); }
};

// A read-only view of a level or of the input, addressed by grid index with clamping.
struct GridView {
  ConstPlane plane;
  Range x, y;
  // Row `grid_y` (clamped), shifted so that element [grid_x] is column grid_x.
  const float* row(std::ptrdiff_t grid_y) const { return plane.row(y.clamp(grid_y) - y.lo) - x.lo; }
};

// A row buffer addressed by grid index over [range.lo - pad, range.hi + pad), the stored
// part filled by the caller and the padding by replicate_edges().
class PaddedRow {
 public:
  PaddedRow(Range range, std::ptrdiff_t pad)
      : storage_(range.size() + 2 * pad), range_(range), pad_(pad) {}
  // Element [i] is grid index i.
  float* at_grid() { return storage_.data() + pad_ - range_.lo; }
  void replicate_edges() {
    float* v = at_grid();
    for (std::ptrdiff_t k = 1; k <= pad_; ++k) {
      v[range_.lo - k] = v[range_.lo];
      v[range_.hi - 1 + k] = v[range_.hi - 1];
    }
  }

 private:
  std::vector<float> storage_;
  Range range_;
  std::ptrdiff_t pad_;
};

// coarse = analysis filter of fine, down-sampled by 2, over coarse's stored range.
void down_sample(const GridView& fine, Level& coarse, AnalysisTaps taps, int threads) {
  const float outer = taps.outer, inner = taps.inner;
  const Range fx = fine.x;
  const std::ptrdiff_t x_lo = coarse.x.lo, x_hi = coarse.x.hi;
#pragma omp parallel num_threads(threads)
  {
    // The horizontal taps reach fine columns 2 x_lo - 1 to 2 x_hi; beyond the fine range
    // (by up to 3, more when the coarse level is widened for smoothing) they read padding.
    const std::ptrdiff_t pad =
        std::max({std::ptrdiff_t{1}, fx.lo - (2 * x_lo - 1), 2 * x_hi - (fx.hi - 1)});
    PaddedRow buffer(fx, pad);
    float* v = buffer.at_grid();
#pragma omp for schedule(static)
    for (std::ptrdiff_t j = coarse.y.lo; j < coarse.y.hi; ++j) {
      const float* r0 = fine.row(2 * j - 1);
      const float* r1 = fine.row(2 * j);
      const float* r2 = fine.row(2 * j + 1);
      const float* r3 = fine.row(2 * j + 2);
      if (outer == 0.f) {
#pragma omp simd
        for (std::ptrdiff_t x = fx.lo; x < fx.hi; ++x) v[x] = inner * (r1[x] + r2[x]);
      } else {
#pragma omp simd
        for (std::ptrdiff_t x = fx.lo; x < fx.hi; ++x)
          v[x] = outer * (r0[x] + r3[x]) + inner * (r1[x] + r2[x]);
      }
      buffer.replicate_edges();
      float* out = coarse.row(j) - x_lo;
      for (std::ptrdiff_t i = x_lo; i < x_hi; ++i) {
        const float* f = v + 2 * i;
        out[i] = outer * (f[-1] + f[2]) + inner * (f[0] + f[1]);
      }
    }
  }
}

// fine = biquadratic B-spline up-sampling of coarse over the grid ranges (fx, fy), written to
// `fine` (pixel (fx.lo, fy.lo) at fine(0, 0)). Fine pixel 2j takes 3/4 of coarse j and 1/4 of
// coarse j - 1, fine pixel 2j + 1 takes 3/4 of coarse j and 1/4 of coarse j + 1 (the quadratic
// B-spline evaluated a quarter coarse pixel either side of the coarse centre).
void up_sample(const GridView& coarse, Plane fine, Range fx, Range fy, int threads) {
#pragma omp parallel num_threads(threads)
  {
    PaddedRow buffer(coarse.x, 1);
    float* v = buffer.at_grid();
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = fy.lo; y < fy.hi; ++y) {
      const std::ptrdiff_t j = floor_half(y);
      const float* near_row = coarse.row(j);
      const float* far_row = coarse.row(y - 2 * j ? j + 1 : j - 1);
#pragma omp simd
      for (std::ptrdiff_t x = coarse.x.lo; x < coarse.x.hi; ++x)
        v[x] = 0.75f * near_row[x] + 0.25f * far_row[x];
      buffer.replicate_edges();
      float* out = fine.row(y - fy.lo) - fx.lo;
      for (std::ptrdiff_t x = fx.lo; x < fx.hi; ++x) {
        const std::ptrdiff_t i = floor_half(x);
        out[x] = 0.75f * v[i] + 0.25f * v[x - 2 * i ? i + 1 : i - 1];
      }
    }
  }
}

// One pass of [a, 1 - 2a, a] down the columns of `in` into `out`, clamped at the edges.
void smooth_columns(ConstPlane in, Plane out, float a, int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height();
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t y = 0; y < h; ++y) {
    const float* up = in.row(std::max<std::ptrdiff_t>(y - 1, 0));
    const float* mid = in.row(y);
    const float* down = in.row(std::min(y + 1, h - 1));
    float* o = out.row(y);
#pragma omp simd
    for (std::ptrdiff_t x = 0; x < w; ++x) o[x] = mid[x] + a * (up[x] + down[x] - 2 * mid[x]);
  }
}

// One pass of [a, 1 - 2a, a] along the rows of `in` into `out`, clamped at the edges.
void smooth_rows(ConstPlane in, Plane out, float a, int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height();
#pragma omp parallel num_threads(threads)
  {
    PaddedRow buffer({0, w}, 1);
    float* v = buffer.at_grid();
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      std::copy_n(in.row(y), w, v);
      buffer.replicate_edges();
      float* o = out.row(y);
#pragma omp simd
      for (std::ptrdiff_t x = 0; x < w; ++x) o[x] = v[x] + a * (v[x - 1] + v[x + 1] - 2 * v[x]);
    }
  }
}

// The passes of the 3-tap smoothing for a variance sigma^2: each adds 2a <= 1/2.
int smoothing_passes(double sigma) { return static_cast<int>(std::ceil(sigma * sigma / 0.5)); }

// Smooths `plane` in place by a separable filter of variance sigma^2 per axis: passes of the
// 3-tap [a, 1 - 2a, a] (variance 2a each), a <= 1/4 so that every pass is a non-negative,
// monotone low-pass; a few passes are already close to a Gaussian. Each pass spreads the
// non-constant part by one pixel, so the clamped edges are exact when the plane has
// smoothing_passes(sigma) pixels of constant far field on each side.
void smooth(Plane plane, double sigma, int threads) {
  const int passes = smoothing_passes(sigma);
  if (passes == 0) return;
  const float a = static_cast<float>(sigma * sigma / (2 * passes));
  Image scratch(plane.width(), plane.height(), 1);
  for (int p = 0; p < passes; ++p) {
    smooth_columns(plane, scratch.plane(0), a, threads);
    smooth_rows(scratch.plane(0), plane, a, threads);
  }
}

GridView view_of(Level& level) { return {level.plane(), level.x, level.y}; }

// dst = src over dst's stored range, reading src with clamping.
void fill_clamped(const GridView& src, Level& dst) {
  for (std::ptrdiff_t y = dst.y.lo; y < dst.y.hi; ++y) {
    const float* in = src.row(y);
    float* out = dst.row(y) - dst.x.lo;
    for (std::ptrdiff_t x = dst.x.lo; x < dst.x.hi; ++x) out[x] = in[src.x.clamp(x)];
  }
}

// No pyramid: only the smoothing, on a copy of the input widened by its far-field margin.
void smooth_only(ConstPlane in, Plane out, double sigma, int threads) {
  const int passes = smoothing_passes(sigma);
  const GridView input{in, {0, in.width()}, {0, in.height()}};
  Level padded(input.x.widened(passes), input.y.widened(passes));
  fill_clamped(input, padded);
  smooth(padded.plane(), sigma, threads);
  copy_plane(out, padded.plane().sub({passes, passes, in.width(), in.height()}));
}

// 2^30 pixels per coarsest pixel is far beyond any image; the bound keeps 2^levels finite.
constexpr int kMaxLevels = 30;

bool overlap(ConstPlane a, ConstPlane b) {
  const float* a_end = a.row(a.height() - 1) + a.width();
  const float* b_end = b.row(b.height() - 1) + b.width();
  return a.data() < b_end && b.data() < a_end;
}

void check_arguments(ConstPlane in, ConstPlane out, int levels, double coarse_sigma, Border border,
                     int threads) {
  if (in.width() < 1 || in.height() < 1 || !in.data()) throw InvalidArgument("in", "is empty");
  if (out.width() != in.width() || out.height() != in.height() || !out.data())
    throw InvalidArgument("out", "size differs from in");
  if (overlap(in, out)) throw InvalidArgument("out", "overlaps in");
  if (levels < 0 || levels > kMaxLevels)
    throw InvalidArgument(
        "levels", std::to_string(levels) + " is not in [0, " + std::to_string(kMaxLevels) + "]");
  if (!std::isfinite(coarse_sigma) || coarse_sigma < 0)
    throw InvalidArgument("coarse_sigma", "must be finite and >= 0");
  if (border != Border::replicate)
    throw InvalidArgument("border", std::string(border_name(border)) +
                                        " is not supported by the pyramid blur (replicate only)");
  if (threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
}

// The effective sigma of 1 to 5 levels, measured with effective_sigma() (relative precision
// 1e-4) on quality_test_set(1024), the 5 patterns fitted jointly. Near sqrt((v_a + 3/4)
// (4^L - 1) / 3), the phase-averaged standard deviation (v_a: the analysis filter's variance,
// 1/4, 5/4 and 17/16), but 2-5% above it: the L1 fit weighs the kernel's shape, not only its
// second moment. The first entry is also each method's min_sigma in the registry.
constexpr int kMeasuredLevels = 5;
constexpr double kSigmaBox2[kMeasuredLevels] = {1.0472, 2.2838, 4.6990, 9.4181, 18.5702};
constexpr double kSigmaBox4[kMeasuredLevels] = {1.5029, 3.2460, 6.5983, 13.2547, 26.5699};
constexpr double kSigmaQuasi[kMeasuredLevels] = {1.4138, 3.0811, 6.2593, 12.5643, 25.1758};

const double* measured_sigmas(PyramidFilter filter) {
  switch (filter) {
    case PyramidFilter::box2: return kSigmaBox2;
    case PyramidFilter::box4: return kSigmaBox4;
    case PyramidFilter::quasi: return kSigmaQuasi;
  }
  throw InvalidArgument("filter", "unknown pyramid filter");
}

}  // namespace

std::string_view pyramid_filter_name(PyramidFilter filter) {
  switch (filter) {
    case PyramidFilter::box2: return "box2";
    case PyramidFilter::box4: return "box4";
    case PyramidFilter::quasi: return "quasi";
  }
  return "unknown";
}

void pyramid_blur(Plane out, ConstPlane in, PyramidFilter filter, int levels, double coarse_sigma,
                  Border border, int threads) {
  check_arguments(in, out, levels, coarse_sigma, border, threads);
  const AnalysisTaps taps = analysis_taps(filter);
  const int team = resolve_threads(threads);
  if (levels == 0) return smooth_only(in, out, coarse_sigma, team);

  // Level l (1 <= l <= levels) lives in pyramid[l - 1]. The coarsest is widened by the
  // smoothing's passes so that its clamped edges stay exact (see smooth). On the way up, level
  // l's analysis values are no longer needed once level l + 1 exists, so the up-sampled level
  // l overwrites them; the last up-sampling writes straight into `out`.
  const GridView input{in, {0, in.width()}, {0, in.height()}};
  std::vector<Level> pyramid;
  pyramid.reserve(levels);
  Range x = input.x, y = input.y;
  for (int l = 1; l <= levels; ++l) {
    x = coarser(x), y = coarser(y);
    const std::ptrdiff_t margin = l == levels ? smoothing_passes(coarse_sigma) : 0;
    pyramid.emplace_back(x.widened(margin), y.widened(margin));
  }

  down_sample(input, pyramid[0], taps, team);
  for (int l = 1; l < levels; ++l) down_sample(view_of(pyramid[l - 1]), pyramid[l], taps, team);
  smooth(pyramid.back().plane(), coarse_sigma, team);
  for (int l = levels - 1; l >= 1; --l) {
    Level& fine = pyramid[l - 1];
    up_sample(view_of(pyramid[l]), fine.plane(), fine.x, fine.y, team);
  }
  up_sample(view_of(pyramid[0]), out, input.x, input.y, team);
}

void pyramid_blur(Plane out, ConstPlane in, PyramidFilter filter, int levels, Border border,
                  int threads) {
  pyramid_blur(out, in, filter, levels, 0.0, border, threads);
}

double pyramid_sigma(PyramidFilter filter, int levels) {
  if (levels < 1) throw InvalidArgument("levels", "must be >= 1");
  const double* measured = measured_sigmas(filter);
  if (levels <= kMeasuredLevels) return measured[levels - 1];
  const double growth = (std::pow(4.0, levels) - 1) / (std::pow(4.0, kMeasuredLevels) - 1);
  return measured[kMeasuredLevels - 1] * std::sqrt(growth);
}

PyramidPlan pyramid_plan(PyramidFilter filter, double sigma) {
  const double smallest = pyramid_sigma(filter, 1);
  if (!std::isfinite(sigma) || sigma < smallest)
    throw InvalidArgument("sigma", "must be finite and >= " + std::to_string(smallest) +
                                       ", the sigma of one " +
                                       std::string(pyramid_filter_name(filter)) + " pyramid level");
  PyramidPlan plan;
  // Sigma roughly doubles per level: this loop runs about log2(sigma) times.
  while (pyramid_sigma(filter, plan.levels + 1) <= sigma) ++plan.levels;
  const double level_sigma = pyramid_sigma(filter, plan.levels);
  const double missing = std::max(0.0, sigma * sigma - level_sigma * level_sigma);
  plan.coarse_sigma = std::sqrt(missing / std::pow(4.0, plan.levels));
  return plan;
}

void pyramid_blur_sigma(Plane out, ConstPlane in, PyramidFilter filter, double sigma, Border border,
                        int threads) {
  const PyramidPlan plan = pyramid_plan(filter, sigma);
  pyramid_blur(out, in, filter, plan.levels, plan.coarse_sigma, border, threads);
}

namespace blur_detail {

void run_pyramid_box2(Plane out, ConstPlane in, const BlurOptions& options) {
  pyramid_blur_sigma(out, in, PyramidFilter::box2, options.sigma, options.border, options.threads);
}
void run_pyramid_box4(Plane out, ConstPlane in, const BlurOptions& options) {
  pyramid_blur_sigma(out, in, PyramidFilter::box4, options.sigma, options.border, options.threads);
}
void run_pyramid_quasi(Plane out, ConstPlane in, const BlurOptions& options) {
  pyramid_blur_sigma(out, in, PyramidFilter::quasi, options.sigma, options.border, options.threads);
}

}  // namespace blur_detail

}  // namespace tridiff
