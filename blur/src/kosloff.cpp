// Polynomial spreading (Kosloff; seed 001 §3.6.2, eq. 3.17), method "kosloff".
//
// Along one line of n pixels x[0..n), the blended tent K has a sparse second derivative: five
// impulses ("taps") at offsets o_j with weights w_j (T_r: 1, -2, 1 at 1 - r, 1, 1 + r, over r^2;
// T_{r+1}: at -r, 1, 2 + r, over (r + 1)^2; the +1 makes two inclusive prefix sums land the
// tent's peak on the source pixel). Spreading builds D(q) = sum_j w_j x[q - o_j]; integrating
// twice, S1(q) = sum_{q' <= q} D(q'), S2(q) = sum_{q' <= q} S1(q'), gives S2 = K * x.
//
// Borders, done properly (the seed skipped pixels within r of the edge):
//  * D also has entries left of the line (q < 0) that every output depends on. Only two
//    numbers matter, the integrators' state at q = -1: S1(-1) = sum_{q<0} D(q) and
//    S2(-1) = sum_{q<0} -q D(q). They are found from prefix sums of x and p x at the (at most
//    five) points -o_j, so no work is spent on positions outside the line: O(n) per line even
//    when r >> n. Entries right of the line (q >= n) never reach an output and are dropped.
//  * Replicate: the pixels beyond the edge all equal the edge pixel, so their contribution to
//    output q is x[0] times the kernel's tail mass beyond q (C(q) = sum_{k > q} K(k), closed
//    form), and x[n-1] times C(n - 1 - q) on the right. The result equals convolution with the
//    clamped signal exactly (up to rounding), however wide the kernel. Zero: no tail terms.
//
// Precision: S1 and S2 run over the whole line and never restart, so a rounding error made in
// S1 stays in it and S2 integrates it: the error grows like n^1.5 eps. Simulated in float on
// a 4096-pixel line of values in [0, 1] it reaches 3e-4 (r = 2) and 8e-5 (r = 19), a hundred
// times the rounding of a direct convolution; in double the same is ~1e-12. Hence D, S1 and
// S2 are doubles and only the output is rounded to float. (Centering the values around their
// mean would only shrink the constant, not the n^1.5 growth; doubles cost ~nothing here.)
//
// 2D: the tensor product of eq. 3.17 equals a column pass followed by a row pass, which is
// what is done: columns in strips of kLanes (rows of the strip are contiguous, so the inner
// loops run over lanes), then rows in place, kLanes at a time transposed into the same lanes.
// Each line is computed alone in a fixed order, so the result does not depend on threads.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "tridiff/blur/spreading.hpp"
#include "row_blocks.hpp"

namespace tridiff {

namespace {

constexpr int kLanes = 16;  // one AVX-512 vector of floats

struct Tap {
  std::ptrdiff_t offset;
  double weight;
};

void check_kernel(const SpreadingKernel& kernel) {
  if (kernel.radius < 1)
    throw InvalidArgument("kernel", "radius must be >= 1, got " + std::to_string(kernel.radius));
  if (!(kernel.blend >= 0 && kernel.blend <= 1))
    throw InvalidArgument("kernel", "blend must be in [0, 1], got " + std::to_string(kernel.blend));
}

// The second derivative of K as five taps (see the file comment for the +1).
std::array<Tap, 5> taps_of(const SpreadingKernel& kernel) {
  const double r = static_cast<double>(kernel.radius);
  const double a = (1 - kernel.blend) / (r * r), b = kernel.blend / ((r + 1) * (r + 1));
  const std::ptrdiff_t n = kernel.radius;
  return {{{-n, b}, {1 - n, a}, {1, -2 * (a + b)}, {1 + n, a}, {2 + n, b}}};
}

// sum_{k > i} T_r(k) for i >= 0: the tent's mass strictly beyond i.
double tent_tail(std::ptrdiff_t r, std::ptrdiff_t i) {
  if (i >= r) return 0;
  const double m = static_cast<double>(r - i);
  return (m - 1) * m / (2.0 * static_cast<double>(r) * static_cast<double>(r));
}

// C(i) = sum_{k > i} K(k) for i in [0, n): the weight of the replicated pixels beyond the edge
// seen from i pixels inside it.
std::vector<double> tail_masses(const SpreadingKernel& kernel, std::ptrdiff_t n) {
  std::vector<double> tail(n);
  for (std::ptrdiff_t i = 0; i < n; ++i)
    tail[i] = (1 - kernel.blend) * tent_tail(kernel.radius, i) +
              kernel.blend * tent_tail(kernel.radius + 1, i);
  return tail;
}

// Filters `lanes` interleaved lines of n samples: sample i of lane l is at in[i * in_stride +
// l] (likewise out). `d` is scratch of n * lanes doubles. All input is read before any output
// is written, so out may be in.
class LineSpreader {
 public:
  LineSpreader(const SpreadingKernel& kernel, std::ptrdiff_t n, bool replicate)
      : taps_(taps_of(kernel)), tail_(tail_masses(kernel, n)), n_(n), replicate_(replicate) {}

  void run(const float* in, std::ptrdiff_t in_stride, float* out, std::ptrdiff_t out_stride,
           std::ptrdiff_t lanes, std::vector<double>& d) const {
    d.assign(n_ * lanes, 0.0);
    double s1[kLanes], s2[kLanes], left[kLanes], right[kLanes];
    initial_state(in, in_stride, lanes, s1, s2);
    spread(in, in_stride, lanes, d.data());
    for (std::ptrdiff_t l = 0; l < lanes; ++l) {
      left[l] = replicate_ ? in[l] : 0.0;
      right[l] = replicate_ ? in[(n_ - 1) * in_stride + l] : 0.0;
    }
    for (std::ptrdiff_t q = 0; q < n_; ++q) {
      const double* dq = d.data() + q * lanes;
      float* y = out + q * out_stride;
      const double tl = tail_[q], tr = tail_[n_ - 1 - q];
      for (std::ptrdiff_t l = 0; l < lanes; ++l) {
        s1[l] += dq[l];
        s2[l] += s1[l];
        y[l] = static_cast<float>(s2[l] + tl * left[l] + tr * right[l]);
      }
    }
  }

 private:
  // D(q) += w_j x[q - o_j] for every q in [0, n) whose source lies on the line.
  void spread(const float* in, std::ptrdiff_t stride, std::ptrdiff_t lanes, double* d) const {
    for (const Tap& tap : taps_) {
      const std::ptrdiff_t first = std::max<std::ptrdiff_t>(0, tap.offset);
      const std::ptrdiff_t last = std::min(n_, n_ + tap.offset);
      const double weight = tap.weight;  // a local: stores to d could alias tap.weight
      for (std::ptrdiff_t q = first; q < last; ++q) {
        const float* x = in + (q - tap.offset) * stride;
        double* dq = d + q * lanes;
        for (std::ptrdiff_t l = 0; l < lanes; ++l) dq[l] += weight * x[l];
      }
    }
  }

  // S1(-1) and S2(-1) from the taps that reach left of the line: a tap at o < 0 puts
  // w x[p] at q = p + o < 0 for p < -o, adding w x[p] to S1(-1) and w x[p] (-(p + o)) to
  // S2(-1). With P0(m) = sum_{p<m} x[p] and P1(m) = sum_{p<m} p x[p] (m clamped to n) that is
  // w P0(m) and w (-o P0(m) - P1(m)).
  void initial_state(const float* in, std::ptrdiff_t stride, std::ptrdiff_t lanes, double* s1,
                     double* s2) const {
    double p0[kLanes] = {}, p1[kLanes] = {};
    std::fill_n(s1, lanes, 0.0);
    std::fill_n(s2, lanes, 0.0);
    std::ptrdiff_t p = 0;
    // Offsets in taps_ ascend, so -o descends: settle the taps from the last negative one
    // (smallest prefix) to the first (longest prefix) while p sweeps upwards.
    for (std::ptrdiff_t j = static_cast<std::ptrdiff_t>(taps_.size()) - 1; j >= 0; --j) {
      const Tap& tap = taps_[j];
      if (tap.offset >= 0) continue;
      const std::ptrdiff_t m = std::min(n_, -tap.offset);
      for (; p < m; ++p) {
        const float* x = in + p * stride;
        for (std::ptrdiff_t l = 0; l < lanes; ++l) {
          p0[l] += x[l];
          p1[l] += static_cast<double>(p) * x[l];
        }
      }
      const double minus_o = static_cast<double>(-tap.offset);
      for (std::ptrdiff_t l = 0; l < lanes; ++l) {
        s1[l] += tap.weight * p0[l];
        s2[l] += tap.weight * (minus_o * p0[l] - p1[l]);
      }
    }
  }

  std::array<Tap, 5> taps_;
  std::vector<double> tail_;
  std::ptrdiff_t n_;
  bool replicate_;
};

void spread_columns(ConstPlane in, Plane out, const SpreadingKernel& kernel, bool replicate,
                    int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height();
  const LineSpreader spreader(kernel, h, replicate);
  const std::ptrdiff_t strips = (w + kLanes - 1) / kLanes;
#pragma omp parallel num_threads(threads)
  {
    std::vector<double> d;
#pragma omp for schedule(static)
    for (std::ptrdiff_t s = 0; s < strips; ++s) {
      const std::ptrdiff_t x0 = s * kLanes, lanes = std::min<std::ptrdiff_t>(kLanes, w - x0);
      spreader.run(in.row(0) + x0, in.pitch(), out.row(0) + x0, out.pitch(), lanes, d);
    }
  }
}

// Rows, in place: kLanes rows at a time in lane order (row_blocks.hpp), so the row pass runs
// with the same SIMD lanes as the column pass.
void spread_rows(Plane plane, const SpreadingKernel& kernel, bool replicate, int threads) {
  const LineSpreader spreader(kernel, plane.width(), replicate);
  blur_detail::for_each_row_block<kLanes>(plane, threads, [&](float* lanes, std::ptrdiff_t) {
    thread_local std::vector<double> d;  // kept from call to call, as row_blocks.hpp's scratch
    spreader.run(lanes, kLanes, lanes, kLanes, kLanes, d);
  });
}

}  // namespace

double spreading_variance(const SpreadingKernel& kernel) {
  check_kernel(kernel);
  const double r = static_cast<double>(kernel.radius);
  return ((1 - kernel.blend) * (r * r - 1) + kernel.blend * ((r + 1) * (r + 1) - 1)) / 6;
}

SpreadingKernel spreading_kernel_for_sigma(double sigma) {
  if (!std::isfinite(sigma) || !(sigma > 0))
    throw InvalidArgument("sigma", "must be finite and > 0, got " + std::to_string(sigma));
  // (r^2 - 1) / 6 + blend ((r + 1)^2 - r^2) / 6 = s^2  =>  r = floor(sqrt(6 s^2 + 1)).
  const double s = kTentSigmaScale * sigma;
  const double v = 6 * s * s + 1;
  const double r = std::max(1.0, std::floor(std::sqrt(v)));
  const double blend = std::clamp((v - r * r) / (2 * r + 1), 0.0, 1.0);
  return {static_cast<std::ptrdiff_t>(r), blend};
}

void polynomial_spread(Plane out, ConstPlane in, const SpreadingKernel& kernel, Border border,
                       int threads) {
  check_kernel(kernel);
  if (in.width() < 1 || in.height() < 1 || !in.data()) throw InvalidArgument("in", "is empty");
  if (out.width() != in.width() || out.height() != in.height())
    throw InvalidArgument("out", "size differs from in");
  if (border != Border::replicate && border != Border::zero)
    throw InvalidArgument("border",
                          std::string(border_name(border)) +
                              " is not supported by polynomial spreading (replicate, zero)");
  if (threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
  const bool replicate = border == Border::replicate;
  const int team = resolve_threads(threads);
  spread_columns(in, out, kernel, replicate, team);
  spread_rows(out, kernel, replicate, team);
}

namespace blur_detail {
void run_kosloff(Plane out, ConstPlane in, const BlurOptions& options) {
  polynomial_spread(out, in, spreading_kernel_for_sigma(options.sigma), options.border,
                    options.threads);
}
}  // namespace blur_detail

}  // namespace tridiff
