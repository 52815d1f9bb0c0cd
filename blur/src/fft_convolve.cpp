// Convolution through the FFT (seed 001 §3.4) and method "fft": the exact Gaussian by one
// forward and one inverse real 2D transform (single-precision FFTW), whatever sigma.
//
// A plain FFT convolves cyclically. For the replicate, mirror and zero borders the plane is
// extended by the kernel radius with the border rule (to n + 2r, fewer where the border allows:
// see padded_length), so that no output pixel reads across the wrap; for the periodic border
// the wrap is the border itself and the plane is transformed at its own size. Image pixel i
// sits at buffer index i, its extension to the left at the end of the buffer (index N - 1 for
// i = -1). Padded sizes are products of 2, 3, 5 and 7, which FFTW transforms fast.
//
// Plans are made once per (size, threads) and kept: FFTW's planner is not thread-safe, so
// planning happens under a mutex (and FFTW's own planner lock), while executing a plan on new
// arrays is safe from any number of threads.
//
// Rounding: the float transforms err by about 1e-7 of the signal's energy per coefficient. The
// plane's mean is subtracted first (where the border does not bring in zeros) so that the huge
// DC term does not dominate that error, and added back after, times the kernel's sum.
#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/kernels.hpp"

namespace tridiff {

namespace {

// ---- sizes ------------------------------------------------------------------------------

bool is_fftw_friendly(std::ptrdiff_t n) {
  for (std::ptrdiff_t p : {2, 3, 5, 7})
    while (n % p == 0) n /= p;
  return n == 1;
}

std::ptrdiff_t friendly_at_least(std::ptrdiff_t length) {
  while (!is_fftw_friendly(length)) ++length;
  return length;
}

// The transform length for a line of n pixels and a kernel radius r under `border`: the
// shortest cyclic grid on which no output pixel reads a wrong value.
// - periodic: the line's own period, n.
// - replicate: n + 2r, the extension on both sides.
// - zero: n + r. Outputs read [-r, n + r); with zeros beyond the line, a wrap lands in zeros
//   as long as the grid leaves r zeros on one side.
// - mirror: n + 2r, or 2n once that is shorter: the mirrored line is itself 2n-periodic, so
//   the cyclic convolution of the line and its reflection is the mirror border exactly.
std::ptrdiff_t padded_length(std::ptrdiff_t n, std::ptrdiff_t r, Border border) {
  switch (border) {
    case Border::periodic: return n;
    case Border::zero: return friendly_at_least(n + r);
    case Border::mirror: return 2 * n <= n + 2 * r ? 2 * n : friendly_at_least(n + 2 * r);
    case Border::replicate: break;
  }
  return friendly_at_least(n + 2 * r);
}

// ---- plans ------------------------------------------------------------------------------

// FFTW's arrays: fftwf_malloc'd, so that every buffer has the alignment the plans assume.
struct FftwFree {
  void operator()(float* p) const { fftwf_free(p); }
};
using FftwBuffer = std::unique_ptr<float, FftwFree>;

FftwBuffer allocate(std::ptrdiff_t floats) {
  auto* p = static_cast<float*>(fftwf_malloc(floats * sizeof(float)));
  if (!p) throw std::bad_alloc();
  return FftwBuffer(p);
}

// An in-place pair of plans for a real nx x ny grid: rows of 2 (nx / 2 + 1) floats, which the
// complex half-spectrum (nx / 2 + 1 values per row) overwrites.
struct Plans {
  std::ptrdiff_t nx, ny;
  fftwf_plan forward = nullptr, inverse = nullptr;

  std::ptrdiff_t complex_width() const { return nx / 2 + 1; }
  std::ptrdiff_t real_pitch() const { return 2 * complex_width(); }
  std::ptrdiff_t floats() const { return real_pitch() * ny; }

  Plans(std::ptrdiff_t nx_, std::ptrdiff_t ny_) : nx(nx_), ny(ny_) {}
  Plans(const Plans&) = delete;
  Plans& operator=(const Plans&) = delete;
  ~Plans() {
    // fftwf_make_planner_thread_safe (see plans_for) makes destroying safe without our lock.
    if (forward) fftwf_destroy_plan(forward);
    if (inverse) fftwf_destroy_plan(inverse);
  }
};

std::mutex plan_mutex;

// The plans for nx x ny on `threads` threads, made on first use. FFTW_ESTIMATE: at 4096^2
// FFTW_MEASURE saved nothing measurable here (about 1.45 s either way for three planes on one
// thread) but spent tens of seconds planning each new size.
std::shared_ptr<const Plans> plans_for(std::ptrdiff_t nx, std::ptrdiff_t ny, int threads) {
  static std::map<std::tuple<std::ptrdiff_t, std::ptrdiff_t, int>, std::shared_ptr<Plans>> cache;
  std::lock_guard lock(plan_mutex);
  static const bool initialised = [] {
    fftwf_make_planner_thread_safe();
    return fftwf_init_threads() != 0;
  }();
  auto& entry = cache[{nx, ny, threads}];
  if (entry) return entry;
  auto plans = std::make_shared<Plans>(nx, ny);
  const FftwBuffer scratch = allocate(plans->floats());
  const unsigned flags = FFTW_ESTIMATE;
  if (initialised) fftwf_plan_with_nthreads(threads);
  auto* complex = reinterpret_cast<fftwf_complex*>(scratch.get());
  plans->forward = fftwf_plan_dft_r2c_2d(static_cast<int>(ny), static_cast<int>(nx), scratch.get(),
                                         complex, flags);
  plans->inverse = fftwf_plan_dft_c2r_2d(static_cast<int>(ny), static_cast<int>(nx), complex,
                                         scratch.get(), flags);
  if (!plans->forward || !plans->inverse)
    throw Error("tridiff: FFTW could not plan a " + std::to_string(nx) + " x " +
                std::to_string(ny) + " transform");
  entry = plans;
  return entry;
}

// ---- the convolution --------------------------------------------------------------------

// The buffer index's image coordinate: i for the plane and its right/bottom extension, i - n
// (negative) for the left/top extension stored at the end.
std::ptrdiff_t coordinate_of(std::ptrdiff_t index, std::ptrdiff_t length, std::ptrdiff_t n,
                             std::ptrdiff_t r) {
  return index < n + r ? index : index - length;
}

double mean_of(ConstPlane in) {
  double sum = 0;
  for (std::ptrdiff_t y = 0; y < in.height(); ++y) {
    const float* row = in.row(y);
    for (std::ptrdiff_t x = 0; x < in.width(); ++x) sum += row[x];
  }
  return sum / (double(in.width()) * double(in.height()));
}

// buffer = `in` minus `offset`, extended with the border rule to nx x ny (see the top).
void fill(ConstPlane in, Border border, std::ptrdiff_t rx, std::ptrdiff_t ry, float offset,
          const Plans& plans, float* buffer, int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height(), pitch = plans.real_pitch();
  std::vector<std::ptrdiff_t> column(plans.nx);  // buffer column -> image column or -1
  for (std::ptrdiff_t i = 0; i < plans.nx; ++i)
    column[i] = border_index(coordinate_of(i, plans.nx, w, rx), w, border);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t j = 0; j < plans.ny; ++j) {
    float* dst = buffer + j * pitch;
    const std::ptrdiff_t y = border_index(coordinate_of(j, plans.ny, h, ry), h, border);
    if (y < 0) {
      std::fill_n(dst, plans.nx, 0.f);
      continue;
    }
    const float* src = in.row(y);
    for (std::ptrdiff_t i = 0; i < w; ++i) dst[i] = src[i] - offset;
    for (std::ptrdiff_t i = w; i < plans.nx; ++i)
      dst[i] = column[i] < 0 ? 0.f : src[column[i]] - offset;
  }
}

// spectrum *= transfer / (nx ny), transfer given per complex coefficient by `transfer(u, v)`.
template <class Transfer>
void multiply(const Plans& plans, float* buffer, Transfer&& transfer, int threads) {
  auto* spectrum = reinterpret_cast<std::complex<float>*>(buffer);
  const std::ptrdiff_t cw = plans.complex_width();
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t v = 0; v < plans.ny; ++v)
    for (std::ptrdiff_t u = 0; u < cw; ++u) spectrum[v * cw + u] *= transfer(u, v);
}

// The DFT of a 1D kernel applied as out(x) = sum_j k[j] in(x + j - r) (a correlation):
// K(u) = sum_j k[j] exp(+2 pi i u (j - r) / n), in double, divided by `scale`. The phase's
// integer product is reduced modulo n first, so every term reads one exact table entry.
std::vector<std::complex<float>> transfer_1d(std::span<const float> kernel, std::ptrdiff_t n,
                                             double scale) {
  const std::ptrdiff_t r = std::ssize(kernel) / 2;
  std::vector<std::complex<double>> twiddle(n);
  for (std::ptrdiff_t m = 0; m < n; ++m)
    twiddle[m] = std::polar(1.0, 2 * std::numbers::pi * double(m) / double(n));
  std::vector<std::complex<float>> transfer(n);
  for (std::ptrdiff_t u = 0; u < n; ++u) {
    std::complex<double> sum = 0;
    std::ptrdiff_t m = ((-r * u) % n + n) % n;  // u (j - r) mod n, for j = 0
    const std::ptrdiff_t step = u % n;
    for (float weight : kernel) {
      sum += double(weight) * twiddle[m];
      m += step;
      if (m >= n) m -= n;
    }
    transfer[u] = std::complex<float>(sum / scale);
  }
  return transfer;
}

// out = buffer + restore, cropped to the plane.
void extract(const float* buffer, const Plans& plans, float restore, Plane out, int threads) {
  const std::ptrdiff_t pitch = plans.real_pitch();
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t y = 0; y < out.height(); ++y) {
    const float* src = buffer + y * pitch;
    float* dst = out.row(y);
    for (std::ptrdiff_t x = 0; x < out.width(); ++x) dst[x] = src[x] + restore;
  }
}

double sum_of(std::span<const float> weights) {
  double sum = 0;
  for (float w : weights) sum += w;
  return sum;
}

struct Grid {
  std::shared_ptr<const Plans> plans;
  FftwBuffer buffer;
  float offset;  // subtracted from every pixel before the transform
};

// The plane, extended and transformed: what both public functions start from.
Grid forward(ConstPlane in, std::ptrdiff_t rx, std::ptrdiff_t ry, Border border, int threads) {
  const std::ptrdiff_t nx = padded_length(in.width(), rx, border);
  const std::ptrdiff_t ny = padded_length(in.height(), ry, border);
  Grid grid{plans_for(nx, ny, threads), nullptr, 0.f};
  grid.buffer = allocate(grid.plans->floats());
  // A zero border brings in zeros, which a shifted plane would turn into -offset.
  grid.offset = border == Border::zero ? 0.f : static_cast<float>(mean_of(in));
  fill(in, border, rx, ry, grid.offset, *grid.plans, grid.buffer.get(), threads);
  fftwf_execute_dft_r2c(grid.plans->forward, grid.buffer.get(),
                        reinterpret_cast<fftwf_complex*>(grid.buffer.get()));
  return grid;
}

// Back to pixels; the offset comes back multiplied by the kernel's sum, `gain`, which is what
// convolving a constant gives.
void inverse(Grid& grid, double gain, Plane out, int threads) {
  fftwf_execute_dft_c2r(grid.plans->inverse, reinterpret_cast<fftwf_complex*>(grid.buffer.get()),
                        grid.buffer.get());
  extract(grid.buffer.get(), *grid.plans, static_cast<float>(grid.offset * gain), out, threads);
}

}  // namespace

void fft_convolve_separable(Plane out, ConstPlane in, std::span<const float> kx,
                            std::span<const float> ky, Border border, int threads) {
  blur_detail::check_convolution_planes(out, in, threads);
  blur_detail::check_kernel(kx, "kx");
  blur_detail::check_kernel(ky, "ky");
  const int team = resolve_threads(threads);
  Grid grid = forward(in, std::ssize(kx) / 2, std::ssize(ky) / 2, border, team);
  const Plans& plans = *grid.plans;
  // The separable kernel's 2D transform is the product of its 1D transforms; FFTW's
  // unnormalised inverse needs 1 / (nx ny).
  const auto tx = transfer_1d(kx, plans.nx, double(plans.nx));
  const auto ty = transfer_1d(ky, plans.ny, double(plans.ny));
  multiply(
      plans, grid.buffer.get(), [&](std::ptrdiff_t u, std::ptrdiff_t v) { return tx[u] * ty[v]; },
      team);
  inverse(grid, sum_of(kx) * sum_of(ky), out, team);
}

void fft_convolve(Plane out, ConstPlane in, const Kernel2D& kernel, Border border, int threads) {
  blur_detail::check_convolution_planes(out, in, threads);
  blur_detail::check_kernel(kernel, "kernel");
  const int team = resolve_threads(threads);
  const std::ptrdiff_t rx = kernel.width / 2, ry = kernel.height / 2;
  Grid grid = forward(in, rx, ry, border, team);
  const Plans& plans = *grid.plans;
  // The kernel as a cyclic filter h(m) = k(r - m) (the correlation flipped into a
  // convolution), m taken modulo the grid, scaled by 1 / (nx ny) for the inverse. Weights
  // that wrap onto the same cell (a kernel wider than a periodic plane) add up.
  const FftwBuffer filter = allocate(plans.floats());
  std::fill_n(filter.get(), plans.floats(), 0.f);
  const double scale = 1.0 / (double(plans.nx) * double(plans.ny));
  for (std::ptrdiff_t j = 0; j < kernel.height; ++j)
    for (std::ptrdiff_t i = 0; i < kernel.width; ++i) {
      const std::ptrdiff_t mx = ((rx - i) % plans.nx + plans.nx) % plans.nx;
      const std::ptrdiff_t my = ((ry - j) % plans.ny + plans.ny) % plans.ny;
      filter.get()[my * plans.real_pitch() + mx] += static_cast<float>(kernel(i, j) * scale);
    }
  auto* filter_spectrum = reinterpret_cast<fftwf_complex*>(filter.get());
  fftwf_execute_dft_r2c(plans.forward, filter.get(), filter_spectrum);
  const auto* h = reinterpret_cast<const std::complex<float>*>(filter.get());
  const std::ptrdiff_t cw = plans.complex_width();
  multiply(
      plans, grid.buffer.get(), [&](std::ptrdiff_t u, std::ptrdiff_t v) { return h[v * cw + u]; },
      team);
  inverse(grid, sum_of(kernel.weights), out, team);
}

namespace blur_detail {

// Method "fft": the Gaussian of gaussian_radius(sigma) through fft_convolve_separable.
void run_fft_convolve(Plane out, ConstPlane in, const BlurOptions& options) {
  const std::vector<float> kernel = gaussian_kernel(options.sigma);
  fft_convolve_separable(out, in, kernel, kernel, options.border, resolve_threads(options.threads));
}

}  // namespace blur_detail

}  // namespace tridiff
