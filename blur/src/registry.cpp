// The registry of blur methods (one line per method) and the argument checks every method
// shares.
#include <cmath>
#include <string>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/solvers/solve.hpp"

namespace tridiff {
namespace blur_detail {
// One declaration per method file (blur/src/<method>.cpp).
void run_iir_deriche(ConstPlane, Plane, const BlurSettings&);
void run_gaussian_fir(ConstPlane, Plane, const BlurSettings&);
void run_iir_decimated(ConstPlane, Plane, const BlurSettings&);
void run_diffusion_explicit(ConstPlane, Plane, const BlurSettings&);
void run_diffusion_implicit(ConstPlane, Plane, const BlurSettings&);
void run_convolve_direct(ConstPlane, Plane, const BlurSettings&);
void run_convolve_separable(ConstPlane, Plane, const BlurSettings&);
void run_fft_convolve(ConstPlane, Plane, const BlurSettings&);
void run_kosloff(ConstPlane, Plane, const BlurSettings&);
void run_reshuffle(ConstPlane, Plane, const BlurSettings&);
void run_box(ConstPlane, Plane, const BlurSettings&);
void run_box_extended(ConstPlane, Plane, const BlurSettings&);
void run_box_sat(ConstPlane, Plane, const BlurSettings&);
void run_pyramid_box2(ConstPlane, Plane, const BlurSettings&);
void run_pyramid_box4(ConstPlane, Plane, const BlurSettings&);
void run_pyramid_quasi(ConstPlane, Plane, const BlurSettings&);
}  // namespace blur_detail

namespace {

constexpr BorderSet kReplicateZero{Border::replicate, Border::zero};
constexpr BorderSet kAllBorders{Border::replicate, Border::mirror, Border::zero,
                                 Border::periodic};

const std::vector<BlurMethod>& registry() {
  static const std::vector<BlurMethod> methods{
      // name, summary, exact, max_error, min_sigma, max_sigma, borders, cost, run
      {"direct", "2D convolution with the 2D sampled Gaussian, every tap summed (seed 001 §3.2)",
       true, 2e-6, 0.25, 16.0, kAllBorders,
       "O(pixels sigma^2): (2r + 1)^2 taps, r ~ 5.3 sigma; quadratic, hence max sigma 16",
       blur_detail::run_convolve_direct},
      {"separable",
       "sampled Gaussian as a row pass then a column pass (seed 001 §3.3); fastest for small "
       "sigma",
       true, 2e-6, 0.25, 128.0, kAllBorders, "O(pixels sigma): 2 (2r + 1) taps, r ~ 5.3 sigma",
       blur_detail::run_convolve_separable},
      {"fft",
       "sampled Gaussian through single-precision FFTs of the border-padded plane (seed 001 "
       "§3.4)",
       true, 2e-6, 0.25, 128.0, kAllBorders,
       "O(N log N), N the plane padded by up to 2r (r ~ 5.3 sigma): almost flat in sigma",
       blur_detail::run_fft_convolve},
      {"gaussian-fir",
       "the sampled Gaussian cut at a tail of 2e-4 (r ~ 3.7 sigma), columns then rows in "
       "strips of 16 rows, the rows transposed into lanes; for small sigma",
       false, 5e-4, 0.5, 3.0, BorderSet{Border::replicate},
       "O(pixels sigma): 2 (r + 1) multiply-adds and 2 r additions per pixel",
       blur_detail::run_gaussian_fir},
      {"iir-deriche",
       "recursive Gaussian, Deriche's 4th-order causal + anticausal filters (Deriche 1993)",
       false, 5e-4, 1.0, 1024.0, kReplicateZero, "O(pixels), independent of sigma",
       blur_detail::run_iir_deriche},
      {"iir-decimated",
       "the recursive Gaussian on the plane decimated by f = 2^k <= sigma / 2 (binomial [1 4 6 "
       "4 1] per level, at most 16), brought back with a cubic B-spline; for sigma >= 4",
       false, 5e-4, 4.0, 1024.0, BorderSet{Border::replicate},
       "O(pixels), independent of sigma: the recursion on pixels / f^2, a decimation and an "
       "up-sampling of the plane",
       blur_detail::run_iir_decimated},
      {"diffusion-explicit",
       "heat diffusion, ceil(2 sigma^2) forward-Euler steps of c <= 1/4 (seed 001 §3.9)", false,
       0.26, 0.5, 16.0, BorderSet{Border::mirror}, "O(pixels sigma^2)",
       blur_detail::run_diffusion_explicit},
      {"diffusion-implicit",
       "heat diffusion, 4 ADI steps of tridiagonal solves along rows and columns", false, 0.12,
       1.0, 1024.0, BorderSet{Border::mirror}, "O(pixels), independent of sigma",
       blur_detail::run_diffusion_implicit},
      {"kosloff",
       "polynomial spreading: the tent of eq. 3.17 (fractional half-width), spread and "
       "integrated twice in double, exact replicate borders (Kosloff; seed 001 §3.6.2)",
       false, 0.09, 0.5, 1024.0, kReplicateZero,
       "O(pixels), independent of sigma: 5 taps + 2 running sums per pixel and pass",
       blur_detail::run_kosloff},
      {"reshuffle",
       "the sampled Gaussian through unique weights and linkage sets, single-output "
       "algorithm, rows then columns (Porikli 2008; seed 001 §3.7)",
       true, 2e-6, 0.25, 64.0, kAllBorders,
       "O(pixels sigma): per pass 2r + 1 additions and r + 1 multiplications, r = ceil(6 sigma)",
       blur_detail::run_reshuffle},
      {"box",
       "3 box passes, odd widths by the ideal-widths rule (Wells; Kovesi), running sums along "
       "columns and rows (seed 001 §3.8)",
       false, 0.1, 2.0, 1024.0, BorderSet{Border::replicate},
       "O(pixels), independent of sigma: 3 running sums per pixel and direction",
       blur_detail::run_box},
      {"box-extended",
       "3 extended boxes: width 2r + 1 plus fractional end weights, variance exactly sigma^2 "
       "(Gwosdek et al. 2011)",
       false, 0.055, 1.0, 1024.0, BorderSet{Border::replicate},
       "O(pixels), independent of sigma: 3 running sums per pixel and direction",
       blur_detail::run_box_extended},
      {"box-sat",
       "the 3 boxes of 'box', each a 2D box mean from a double summed-area table (seed 001 "
       "§2.1, §3.8)",
       false, 0.1, 2.0, 128.0, BorderSet{Border::replicate},
       "O(pixels), independent of sigma: a table build and 4 lookups per pixel and pass, on the "
       "image padded by the boxes' reach (~3 sigma each side; hence max sigma 128)",
       blur_detail::run_box_sat},
      {"pyramid-box2",
       "pyramid: 2x2 box down-sampling, biquadratic B-spline up-sampling, a 3-tap smoothing "
       "at the coarsest level between levels; exact replicate borders (seed 001 §3.5)",
       false, 0.2, 1.05, 64.0, BorderSet{Border::replicate},
       "O(pixels), independent of sigma: ~1.3 down + up-samplings of the plane",
       blur_detail::run_pyramid_box2},
      {"pyramid-box4",
       "pyramid: 4x4 box down-sampling, biquadratic B-spline up-sampling, a 3-tap smoothing "
       "at the coarsest level between levels; exact replicate borders (seed 001 §3.5)",
       false, 0.15, 1.51, 64.0, BorderSet{Border::replicate},
       "O(pixels), independent of sigma: ~1.3 down + up-samplings of the plane",
       blur_detail::run_pyramid_box4},
      {"pyramid-quasi",
       "pyramid: Kraus's quasi-convolution down-sampling (eq. 3.15), biquadratic B-spline "
       "up-sampling, a 3-tap smoothing at the coarsest level between levels; exact "
       "replicate borders (seed 001 §3.5)",
       false, 0.1, 1.42, 64.0, BorderSet{Border::replicate},
       "O(pixels), independent of sigma: ~1.3 down + up-samplings of the plane",
       blur_detail::run_pyramid_quasi},
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
  throw InvalidArgument("method", -1, -1,
                        "unknown blur method '" + std::string(name) + "' (known: " + known + ")");
}

namespace blur_detail {
int threads_of(const BlurSettings& settings) { return detail::resolve_threads(settings.threads); }
}  // namespace blur_detail

namespace {

bool overlap(ConstPlane a, ConstPlane b) {
  const float* a_end = a.row(a.height() - 1) + a.width();
  const float* b_end = b.row(b.height() - 1) + b.width();
  return a.data() < b_end && b.data() < a_end;
}

void check(const BlurMethod& method, ConstPlane in, ConstPlane out, const BlurSettings& s) {
  const std::string who = "method '" + std::string(method.name) + "'";
  if (in.width() < 1 || in.height() < 1 || !in.data())
    throw InvalidArgument("in", -1, -1, "is empty");
  if (out.width() != in.width() || out.height() != in.height())
    throw InvalidArgument("out", -1, -1,
                          "is " + std::to_string(out.width()) + " x " +
                              std::to_string(out.height()) + ", in is " +
                              std::to_string(in.width()) + " x " + std::to_string(in.height()));
  if (overlap(in, out)) throw InvalidArgument("out", -1, -1, "overlaps in");
  if (!std::isfinite(s.sigma) || s.sigma < method.min_sigma || s.sigma > method.max_sigma)
    throw InvalidArgument("sigma", -1, -1,
                          std::to_string(s.sigma) + " is outside [" +
                              std::to_string(method.min_sigma) + ", " +
                              std::to_string(method.max_sigma) + "] for " + who);
  if (!method.borders.contains(s.border))
    throw InvalidArgument("border", -1, -1,
                          std::string(border_name(s.border)) + " is not supported by " + who);
  if (s.threads < 0) throw InvalidArgument("threads", -1, -1, "must be >= 0 (0: all cores)");
}

}  // namespace

void blur(const BlurMethod& method, ConstPlane in, Plane out, const BlurSettings& settings) {
  check(method, in, out, settings);
  method.run(in, out, settings);
}

void blur(const BlurMethod& method, const Image& in, Image& out, const BlurSettings& settings) {
  if (in.empty()) throw InvalidArgument("in", -1, -1, "is empty");
  if (&in == &out) throw InvalidArgument("out", -1, -1, "is the input image");
  if (out.empty() || out.width() != in.width() || out.height() != in.height() ||
      out.channels() != in.channels())
    out.reset(in.width(), in.height(), in.channels());
  for (int c = 0; c < in.channels(); ++c) blur(method, in.plane(c), out.plane(c), settings);
}

}  // namespace tridiff
