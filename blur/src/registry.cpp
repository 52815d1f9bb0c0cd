// The registry of blur methods (one line per method) and the argument checks every method
// shares.
#include <cmath>
#include <string>
#include <vector>

#include "tridiff/blur/blur.hpp"

namespace tridiff {
namespace blur_detail {
// One declaration per method file (blur/src/<method>.cpp).
void run_iir_deriche(Plane, ConstPlane, const BlurOptions&);
void run_gaussian_fir(Plane, ConstPlane, const BlurOptions&);
void run_iir_decimated(Plane, ConstPlane, const BlurOptions&);
void run_diffusion_explicit(Plane, ConstPlane, const BlurOptions&);
void run_diffusion_implicit(Plane, ConstPlane, const BlurOptions&);
void run_convolve_direct(Plane, ConstPlane, const BlurOptions&);
void run_convolve_separable(Plane, ConstPlane, const BlurOptions&);
void run_fft_convolve(Plane, ConstPlane, const BlurOptions&);
void run_kosloff(Plane, ConstPlane, const BlurOptions&);
void run_reshuffle(Plane, ConstPlane, const BlurOptions&);
void run_box(Plane, ConstPlane, const BlurOptions&);
void run_box_extended(Plane, ConstPlane, const BlurOptions&);
void run_box_sat(Plane, ConstPlane, const BlurOptions&);
void run_pyramid_box2(Plane, ConstPlane, const BlurOptions&);
void run_pyramid_box4(Plane, ConstPlane, const BlurOptions&);
void run_pyramid_quasi(Plane, ConstPlane, const BlurOptions&);
}  // namespace blur_detail

namespace {

constexpr BorderSet kReplicateZero{Border::replicate, Border::zero};
constexpr BorderSet kAllBorders{Border::replicate, Border::mirror, Border::zero, Border::periodic};

const std::vector<BlurMethod>& registry() {
  static const std::vector<BlurMethod> methods{
      {.name = "direct",
       .summary = "2D convolution with the 2D sampled Gaussian, every tap summed (seed 001 §3.2)",
       .exact = true,
       .max_error = 2e-6,
       .min_sigma = 0.25,
       .max_sigma = 16.0,
       .borders = kAllBorders,
       .cost = "O(pixels sigma^2): (2r + 1)^2 taps, r ~ 5.3 sigma; quadratic, hence max sigma 16",
       .run = blur_detail::run_convolve_direct},
      {.name = "separable",
       .summary = "sampled Gaussian as a row pass then a column pass (seed 001 §3.3); fastest for "
                  "small sigma",
       .exact = true,
       .max_error = 2e-6,
       .min_sigma = 0.25,
       .max_sigma = 128.0,
       .borders = kAllBorders,
       .cost = "O(pixels sigma): 2 (2r + 1) taps, r ~ 5.3 sigma",
       .run = blur_detail::run_convolve_separable},
      {.name = "fft",
       .summary = "sampled Gaussian through single-precision FFTs of the border-padded plane (seed "
                  "001 §3.4)",
       .exact = true,
       .max_error = 2e-6,
       .min_sigma = 0.25,
       .max_sigma = 128.0,
       .borders = kAllBorders,
       .cost = "O(N log N), N the plane padded by up to 2r (r ~ 5.3 sigma): almost flat in sigma",
       .run = blur_detail::run_fft_convolve},
      {.name = "gaussian-fir",
       .summary = "the sampled Gaussian cut at a tail of 2e-4 (r ~ 3.7 sigma), columns then rows "
                  "in strips of 16 rows, the rows transposed into lanes; for small sigma",
       .exact = false,
       .max_error = 5e-4,
       .min_sigma = 0.5,
       .max_sigma = 3.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels sigma): 2 (r + 1) multiply-adds and 2 r additions per pixel",
       .run = blur_detail::run_gaussian_fir},
      {.name = "iir-deriche",
       .summary =
           "recursive Gaussian, Deriche's 4th-order causal + anticausal filters (Deriche 1993)",
       .exact = false,
       .max_error = 5e-4,
       .min_sigma = 1.0,
       .max_sigma = 1024.0,
       .borders = kReplicateZero,
       .cost = "O(pixels), independent of sigma",
       .run = blur_detail::run_iir_deriche},
      {.name = "iir-decimated",
       .summary =
           "the recursive Gaussian on the plane decimated by f = 2^k <= sigma / 2 (binomial [1 4 6 "
           "4 1] per level, at most 16), brought back with a cubic B-spline; for sigma >= 4",
       .exact = false,
       .max_error = 5e-4,
       .min_sigma = 4.0,
       .max_sigma = 1024.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels), independent of sigma: the recursion on pixels / f^2, a decimation and "
               "an up-sampling of the plane",
       .run = blur_detail::run_iir_decimated},
      {.name = "diffusion-explicit",
       .summary = "heat diffusion, ceil(2 sigma^2) forward-Euler steps of c <= 1/4 (seed 001 §3.9)",
       .exact = false,
       .max_error = 0.26,
       .min_sigma = 0.5,
       .max_sigma = 16.0,
       .borders = BorderSet{Border::mirror},
       .cost = "O(pixels sigma^2)",
       .run = blur_detail::run_diffusion_explicit},
      {.name = "diffusion-implicit",
       .summary = "heat diffusion, 4 ADI steps of tridiagonal solves along rows and columns",
       .exact = false,
       .max_error = 0.12,
       .min_sigma = 1.0,
       .max_sigma = 1024.0,
       .borders = BorderSet{Border::mirror},
       .cost = "O(pixels), independent of sigma",
       .run = blur_detail::run_diffusion_implicit},
      {.name = "kosloff",
       .summary = "polynomial spreading: the tent of eq. 3.17 (fractional half-width), spread and "
                  "integrated twice in double, exact replicate borders (Kosloff; seed 001 §3.6.2)",
       .exact = false,
       .max_error = 0.09,
       .min_sigma = 0.5,
       .max_sigma = 1024.0,
       .borders = kReplicateZero,
       .cost = "O(pixels), independent of sigma: 5 taps + 2 running sums per pixel and pass",
       .run = blur_detail::run_kosloff},
      {.name = "reshuffle",
       .summary = "the sampled Gaussian through unique weights and linkage sets, single-output "
                  "algorithm, rows then columns (Porikli 2008; seed 001 §3.7)",
       .exact = true,
       .max_error = 2e-6,
       .min_sigma = 0.25,
       .max_sigma = 64.0,
       .borders = kAllBorders,
       .cost = "O(pixels sigma): per pass 2r + 1 additions and r + 1 multiplications, r = ceil(6 "
               "sigma)",
       .run = blur_detail::run_reshuffle},
      {.name = "box",
       .summary = "3 box passes, odd widths by the ideal-widths rule (Wells; Kovesi), running sums "
                  "along columns and rows (seed 001 §3.8)",
       .exact = false,
       .max_error = 0.1,
       .min_sigma = 2.0,
       .max_sigma = 1024.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels), independent of sigma: 3 running sums per pixel and direction",
       .run = blur_detail::run_box},
      {.name = "box-extended",
       .summary = "3 extended boxes: width 2r + 1 plus fractional end weights, variance exactly "
                  "sigma^2 (Gwosdek et al. 2011)",
       .exact = false,
       .max_error = 0.055,
       .min_sigma = 1.0,
       .max_sigma = 1024.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels), independent of sigma: 3 running sums per pixel and direction",
       .run = blur_detail::run_box_extended},
      {.name = "box-sat",
       .summary = "the 3 boxes of 'box', each a 2D box mean from a double summed-area table (seed "
                  "001 §2.1, §3.8)",
       .exact = false,
       .max_error = 0.1,
       .min_sigma = 2.0,
       .max_sigma = 128.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels), independent of sigma: a table build and 4 lookups per pixel and pass, "
               "on the image padded by the boxes' reach (~3 sigma each side; hence max sigma 128)",
       .run = blur_detail::run_box_sat},
      {.name = "pyramid-box2",
       .summary =
           "pyramid: 2x2 box down-sampling, biquadratic B-spline up-sampling, a 3-tap smoothing at "
           "the coarsest level between levels; exact replicate borders (seed 001 §3.5)",
       .exact = false,
       .max_error = 0.2,
       .min_sigma = 1.05,
       .max_sigma = 64.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels), independent of sigma: ~1.3 down + up-samplings of the plane",
       .run = blur_detail::run_pyramid_box2},
      {.name = "pyramid-box4",
       .summary =
           "pyramid: 4x4 box down-sampling, biquadratic B-spline up-sampling, a 3-tap smoothing at "
           "the coarsest level between levels; exact replicate borders (seed 001 §3.5)",
       .exact = false,
       .max_error = 0.15,
       .min_sigma = 1.51,
       .max_sigma = 64.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels), independent of sigma: ~1.3 down + up-samplings of the plane",
       .run = blur_detail::run_pyramid_box4},
      {.name = "pyramid-quasi",
       .summary = "pyramid: Kraus's quasi-convolution down-sampling (eq. 3.15), biquadratic "
                  "B-spline up-sampling, a 3-tap smoothing at the coarsest level between levels; "
                  "exact replicate borders (seed 001 §3.5)",
       .exact = false,
       .max_error = 0.1,
       .min_sigma = 1.42,
       .max_sigma = 64.0,
       .borders = BorderSet{Border::replicate},
       .cost = "O(pixels), independent of sigma: ~1.3 down + up-samplings of the plane",
       .run = blur_detail::run_pyramid_quasi},
  };
  return methods;
}

}  // namespace

std::string_view border_name(Border border) {
  switch (border) {
    case Border::replicate: return "replicate";
    case Border::mirror: return "mirror";
    case Border::zero: return "zero";
    case Border::periodic: return "periodic";
  }
  return "unknown";
}

std::ptrdiff_t border_index(std::ptrdiff_t i, std::ptrdiff_t n, Border border) {
  if (i >= 0 && i < n) return i;
  switch (border) {
    case Border::replicate: return i < 0 ? 0 : n - 1;
    case Border::zero: return -1;
    case Border::periodic: return (i % n + n) % n;
    case Border::mirror: {
      const std::ptrdiff_t m = (i % (2 * n) + 2 * n) % (2 * n);
      return m < n ? m : 2 * n - 1 - m;
    }
  }
  return -1;
}

std::span<const BlurMethod> blur_methods() { return registry(); }

const BlurMethod& find_blur_method(std::string_view name) {
  std::string known;
  for (const BlurMethod& method : registry()) {
    if (method.name == name) return method;
    known += (known.empty() ? "" : ", ") + std::string(method.name);
  }
  throw InvalidArgument("method",
                        "unknown blur method '" + std::string(name) + "' (known: " + known + ")");
}

namespace {

bool overlap(ConstPlane a, ConstPlane b) {
  const float* a_end = a.row(a.height() - 1) + a.width();
  const float* b_end = b.row(b.height() - 1) + b.width();
  return a.data() < b_end && b.data() < a_end;
}

void check(const BlurMethod& method, ConstPlane in, ConstPlane out, const BlurOptions& s) {
  const std::string who = "method '" + std::string(method.name) + "'";
  if (in.width() < 1 || in.height() < 1 || !in.data()) throw InvalidArgument("in", "is empty");
  if (out.width() != in.width() || out.height() != in.height())
    throw InvalidArgument(
        "out", "is " + std::to_string(out.width()) + " x " + std::to_string(out.height()) +
                   ", in is " + std::to_string(in.width()) + " x " + std::to_string(in.height()));
  if (overlap(in, out)) throw InvalidArgument("out", "overlaps in");
  if (!std::isfinite(s.sigma) || s.sigma < method.min_sigma || s.sigma > method.max_sigma)
    throw InvalidArgument("sigma", std::to_string(s.sigma) + " is outside [" +
                                       std::to_string(method.min_sigma) + ", " +
                                       std::to_string(method.max_sigma) + "] for " + who);
  if (!method.borders.contains(s.border))
    throw InvalidArgument("border",
                          std::string(border_name(s.border)) + " is not supported by " + who);
  if (s.threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
}

}  // namespace

void blur(Plane out, ConstPlane in, const BlurMethod& method, const BlurOptions& options) {
  check(method, in, out, options);
  method.run(out, in, options);
}

void blur(Image& out, const Image& in, const BlurMethod& method, const BlurOptions& options) {
  if (in.empty()) throw InvalidArgument("in", "is empty");
  if (&in == &out) throw InvalidArgument("out", "is the input image");
  if (out.empty() || out.width() != in.width() || out.height() != in.height() ||
      out.channels() != in.channels())
    out.reset(in.width(), in.height(), in.channels());
  for (int c = 0; c < in.channels(); ++c) blur(out.plane(c), in.plane(c), method, options);
}

}  // namespace tridiff
