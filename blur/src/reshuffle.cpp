// Reshuffling (Porikli 2008; seed 001 §3.7.1, Algorithm 3.2, single output access), method
// "reshuffle": the sampled Gaussian of the exact reference (radius ceil(6 sigma)) applied
// separably, rows then columns, through its unique weights and linkage sets.
//
// Loop order: Algorithm 3.2 loops pixel, unique weight, link. Here the pixel loop is innermost
// over a whole output row (weight, link, x), which vectorises; each output pixel still gets
// sum_i w_i (linkage sum), accumulated in a row buffer and written to the image once. The
// linkage sums are float (a handful of inputs each), the weighted accumulation double, so the
// result stays within ~1e-6 of the exact convolution even for hundreds of unique weights.
#include "tridiff/blur/reshuffle.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "tridiff/blur/reference.hpp"

namespace tridiff {

std::ptrdiff_t ReshuffledKernel::taps() const {
  std::ptrdiff_t count = 0;
  for (const auto& set : links) count += static_cast<std::ptrdiff_t>(set.size());
  return count;
}

namespace {

void check_kernel_shape(std::span<const double> kernel, std::ptrdiff_t width, std::ptrdiff_t height,
                        int levels) {
  if (kernel.empty()) throw InvalidArgument("kernel", "is empty");
  if (width < 1 || width % 2 == 0)
    throw InvalidArgument(
        "width", "must be odd and >= 1 (the kernel is centred), got " + std::to_string(width));
  if (height < 1 || height % 2 == 0)
    throw InvalidArgument(
        "height", "must be odd and >= 1 (the kernel is centred), got " + std::to_string(height));
  if (static_cast<std::ptrdiff_t>(kernel.size()) != width * height)
    throw InvalidArgument("kernel", "has " + std::to_string(kernel.size()) +
                                        " weights, width x height is " +
                                        std::to_string(width * height));
  for (double w : kernel)
    if (!std::isfinite(w)) throw InvalidArgument("kernel", "has a non-finite weight");
  if (levels < 0) throw InvalidArgument("levels", "must be >= 0 (0: exact weights)");
}

// Every weight rounded to a multiple of max|w| / levels; levels = 0 leaves them as they are.
std::vector<double> quantised(std::span<const double> kernel, int levels) {
  std::vector<double> out(kernel.begin(), kernel.end());
  if (levels == 0) return out;
  double largest = 0;
  for (double w : kernel) largest = std::max(largest, std::abs(w));
  const double step = largest / levels;
  for (double& w : out) w = step > 0 ? std::round(w / step) * step : 0.0;
  return out;
}

void check_planes(ConstPlane in, ConstPlane out, int threads) {
  if (in.width() < 1 || in.height() < 1 || !in.data()) throw InvalidArgument("in", "is empty");
  if (out.width() != in.width() || out.height() != in.height())
    throw InvalidArgument("out", "size differs from in");
  if (threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
}

// `line` extended by `pad` pixels on each side by the border rule (zero border: 0).
void extend_line(const float* line, std::ptrdiff_t n, std::ptrdiff_t pad, Border border,
                 float* extended) {
  for (std::ptrdiff_t i = -pad; i < n + pad; ++i) {
    const std::ptrdiff_t j = border_index(i, n, border);
    extended[i + pad] = j < 0 ? 0.f : line[j];
  }
}

// The single-output step for one output row of `width` pixels: acc = sum_i w_i sum_links
// source(link)[x]. source(link) is the input row (already offset by the link's dx) a link
// reads, or null for a row beyond a zero border.
template <class SourceOf>
void reshuffled_row(const ReshuffledKernel& kernel, std::ptrdiff_t width, const SourceOf& source_of,
                    std::vector<float>& sum, std::vector<double>& acc, float* out) {
  acc.assign(width, 0.0);
  for (std::size_t i = 0; i < kernel.weights.size(); ++i) {
    sum.assign(width, 0.f);
    for (const ReshuffledKernel::Link& link : kernel.links[i]) {
      const float* src = source_of(link);
      if (!src) continue;
      for (std::ptrdiff_t x = 0; x < width; ++x) sum[x] += src[x];
    }
    const double w = kernel.weights[i];
    for (std::ptrdiff_t x = 0; x < width; ++x) acc[x] += w * sum[x];
  }
  for (std::ptrdiff_t x = 0; x < width; ++x) out[x] = static_cast<float>(acc[x]);
}

// Rows of `in` into `out` with a 1D kernel read along x (links' dx).
void filter_rows(ConstPlane in, Plane out, const ReshuffledKernel& kernel, Border border,
                 int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height(), pad = kernel.radius_x;
#pragma omp parallel num_threads(threads)
  {
    std::vector<float> extended(w + 2 * pad), sum;
    std::vector<double> acc;
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      extend_line(in.row(y), w, pad, border, extended.data());
      const auto source_of = [&](const ReshuffledKernel::Link& link) {
        return extended.data() + pad + link.dx;
      };
      reshuffled_row(kernel, w, source_of, sum, acc, out.row(y));
    }
  }
}

// Columns of `in` into `out` with a 1D kernel read along y (the links' dx used as dy).
void filter_columns(ConstPlane in, Plane out, const ReshuffledKernel& kernel, Border border,
                    int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height();
#pragma omp parallel num_threads(threads)
  {
    std::vector<float> sum;
    std::vector<double> acc;
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      const auto source_of = [&](const ReshuffledKernel::Link& link) -> const float* {
        const std::ptrdiff_t j = border_index(y + link.dx, h, border);
        return j < 0 ? nullptr : in.row(j);
      };
      reshuffled_row(kernel, w, source_of, sum, acc, out.row(y));
    }
  }
}

}  // namespace

ReshuffledKernel reshuffle_kernel(std::span<const double> kernel, std::ptrdiff_t width,
                                  std::ptrdiff_t height, int levels) {
  check_kernel_shape(kernel, width, height, levels);
  const std::vector<double> weights = quantised(kernel, levels);
  const std::ptrdiff_t cx = width / 2, cy = height / 2;
  // Grouping by the exact double value: equal weights share one multiplication.
  std::map<double, std::vector<ReshuffledKernel::Link>> sets;
  for (std::ptrdiff_t j = 0; j < height; ++j)
    for (std::ptrdiff_t i = 0; i < width; ++i)
      if (const double w = weights[j * width + i]; w != 0)
        sets[w].push_back({cx - i, cy - j});  // convolution: the input lies opposite the tap
  if (sets.empty())
    throw InvalidArgument(levels ? "levels" : "kernel",
                          levels ? "quantises every weight to zero" : "is all zero");
  ReshuffledKernel out;
  out.radius_x = cx;
  out.radius_y = cy;
  for (auto& [w, links] : sets) {
    out.weights.push_back(w);
    out.links.push_back(std::move(links));
  }
  return out;
}

void reshuffle_filter(Plane out, ConstPlane in, const ReshuffledKernel& kernel, Border border,
                      int threads) {
  check_planes(in, out, threads);
  if (kernel.weights.empty() || kernel.weights.size() != kernel.links.size())
    throw InvalidArgument("kernel", "is empty (make it with reshuffle_kernel)");
  const std::ptrdiff_t w = in.width(), h = in.height();
  const std::ptrdiff_t px = kernel.radius_x, py = kernel.radius_y, pw = w + 2 * px;
  // The input extended by the kernel's half-sizes, so that links need no bounds checks.
  std::vector<float> padded(pw * (h + 2 * py));
  for (std::ptrdiff_t y = -py; y < h + py; ++y) {
    const std::ptrdiff_t j = border_index(y, h, border);
    if (j < 0) continue;  // zero border: the row stays 0
    extend_line(in.row(j), w, px, border, padded.data() + (y + py) * pw);
  }
  const int team = resolve_threads(threads);
#pragma omp parallel num_threads(team)
  {
    std::vector<float> sum;
    std::vector<double> acc;
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      const auto source_of = [&](const ReshuffledKernel::Link& link) -> const float* {
        return padded.data() + (y + py + link.dy) * pw + px + link.dx;
      };
      reshuffled_row(kernel, w, source_of, sum, acc, out.row(y));
    }
  }
}

void reshuffle_filter_separable(Plane out, ConstPlane in, const ReshuffledKernel& kernel,
                                Border border, int threads) {
  check_planes(in, out, threads);
  if (kernel.weights.empty() || kernel.weights.size() != kernel.links.size())
    throw InvalidArgument("kernel", "is empty (make it with reshuffle_kernel)");
  if (kernel.radius_y != 0)
    throw InvalidArgument("kernel", "must be 1D (height 1) for the separable filter");
  const int team = resolve_threads(threads);
  Image rows(in.width(), in.height(), 1);
  filter_rows(in, rows.plane(0), kernel, border, team);
  filter_columns(rows.plane(0), out, kernel, border, team);
}

namespace blur_detail {
void run_reshuffle(Plane out, ConstPlane in, const BlurOptions& options) {
  const std::vector<double> gaussian =
      sampled_gaussian(options.sigma, reference_radius(options.sigma));
  const ReshuffledKernel kernel =
      reshuffle_kernel(gaussian, static_cast<std::ptrdiff_t>(gaussian.size()), 1);
  reshuffle_filter_separable(out, in, kernel, options.border, options.threads);
}
}  // namespace blur_detail

}  // namespace tridiff
