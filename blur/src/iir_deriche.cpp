// Recursive Gaussian (Deriche 1993, 4th order): the Gaussian's right half is approximated by
//   g(t) = (1.680 cos(0.6318 t) + 3.735 sin(0.6318 t)) exp(-1.783 t)
//        - (0.6803 cos(1.997 t) + 0.2598 sin(1.997 t)) exp(-1.723 t),   t = x / sigma,
// i.e. g(n) = Re sum_k c_k z_k^n with two complex poles z_k. The filter is the sum of a causal part
// (n >= 0) and an anticausal part (n < 0), each a pair of real second-order sections (one per
// conjugate pole pair): the parallel form keeps float rounding small where the poles crowd towards
// 1 at large sigma. O(1) work per pixel whatever sigma.
//
// Layout: both passes run the same sweep, one SIMD lane per signal: the columns in place (they are
// in lane order already), the rows 16 at a time transposed (row_blocks.hpp); see run_iir_deriche
// for how the two passes share the trips through memory. Replicate borders start each recursion
// in its steady state for the edge value, so the result equals the IIR applied to the extended
// signal.
//
// Cost: 32 vector multiply-adds per 16 pixels (two sections, both directions, both axes). On the
// shared 2-core machine a core retires about 2.1e9 512-bit multiply-adds a second (measured), so
// 4096^2 RGB cannot take less than 24 ms on two cores; it takes about 40.
#include <algorithm>
#include <complex>
#include <vector>

#include <omp.h>

#include "row_blocks.hpp"
#include "tridiff/blur/blur.hpp"

namespace tridiff::blur_detail {

namespace {

constexpr int kLanes = kVectorLanes;

// One real second-order section: y(n) = b0 x(n) + b1 x(n-1) - a1 y(n-1) - a2 y(n-2) for the causal
// part, y(n) = b1 x(n+1) + b2 x(n+2) - a1 y(n+1) - a2 y(n+2) for the anticausal one.
struct Section {
  float b0, b1, a1, a2;  // causal numerator, shared denominator
  float c1, c2;          // anticausal numerator
  double causal_gain() const { return (double(b0) + b1) / (1.0 + a1 + a2); }
  double anticausal_gain() const { return (double(c1) + c2) / (1.0 + a1 + a2); }
};

struct Coefficients {
  Section s[2];
};

Coefficients deriche_coefficients(double sigma) {
  using C = std::complex<double>;
  const C c[2] = {{1.680, -3.735}, {-0.6803, 0.2598}};
  const C z[2] = {std::exp(C(-1.783, 0.6318) / sigma), std::exp(C(-1.723, 1.997) / sigma)};
  Coefficients k;
  double gain = 0;
  for (int i = 0; i < 2; ++i) {
    Section& s = k.s[i];
    // The denominator is rounded to float first; the numerators follow from it, and the whole
    // filter is then scaled to a DC gain of exactly 1 for the coefficients actually used.
    s.a1 = static_cast<float>(-2 * z[i].real());
    s.a2 = static_cast<float>(std::norm(z[i]));
    s.b0 = static_cast<float>(c[i].real());
    s.b1 = static_cast<float>(-(c[i] * std::conj(z[i])).real());
    s.c1 = static_cast<float>((c[i] * z[i]).real());
    s.c2 = static_cast<float>(-std::norm(z[i]) * c[i].real());
    gain += s.causal_gain() + s.anticausal_gain();
  }
  for (Section& s : k.s) {
    s.b0 = static_cast<float>(s.b0 / gain);
    s.b1 = static_cast<float>(s.b1 / gain);
    s.c1 = static_cast<float>(s.c1 / gain);
    s.c2 = static_cast<float>(s.c2 / gain);
  }
  return k;
}

// kLanes signals in one vector: the recursion state stays in registers, one lane per signal.
using Lanes = FloatVector;

// The recursion state of kLanes signals between two stretches of a sweep: the last two inputs
// (x(i-1), x(i-2) going forward, x(i+1), x(i+2) going back) and the last two outputs of each
// section. Kept in memory as kStateFloats floats, so that a sweep can stop and resume.
struct State {
  Lanes x1, x2, yp1, yp2, yq1, yq2;
};
constexpr std::ptrdiff_t kStateFloats = sizeof(State) / sizeof(float);

// The state of a sweep that starts on the edge value `edge` (replicate: the recursion's steady
// state for a constant signal) or on zeros.
State steady_state(Lanes edge, double gain_p, double gain_q) {
  return {edge,
          edge,
          edge * static_cast<float>(gain_p),
          edge * static_cast<float>(gain_p),
          edge * static_cast<float>(gain_q),
          edge * static_cast<float>(gain_q)};
}

// Advances kVectors x kLanes signals by `n` steps along i, forward (causal, i = 0, 1, ...) or
// back (anticausal, i = 0, -1, ...): element i of signal (j, l) is in[i * in_stride + j * kLanes
// + l], and likewise for out. The causal sweep stores its part in out; the anticausal one adds
// its part to the causal part (in `causal`, laid out like out) and stores the sum in out, which
// may be in or causal: each input is read before its output is stored over it. `state`
// (kVectors x kStateFloats floats) is loaded at the start and saved at the end. Within a step
// the vectors are independent, so their recursions overlap (kVectors is fixed at compile time:
// the state stays in registers); each one's dependency chain is one multiply-add per section
// (the terms that do not depend on y(i-1) are summed first).
template <bool kCausal, int kVectors>
void sweep(const float* in, std::ptrdiff_t in_stride, const float* causal, float* out,
           std::ptrdiff_t out_stride, std::ptrdiff_t n, const Coefficients& coefficients,
           float* state) {
  // Coefficients as locals: stores to out could alias them, so the compiler would reload them
  // at every step.
  const Section p = coefficients.s[0], q = coefficients.s[1];
  State s[kVectors];
  __builtin_memcpy(s, state, sizeof s);
  const std::ptrdiff_t step_in = kCausal ? in_stride : -in_stride;
  const std::ptrdiff_t step_out = kCausal ? out_stride : -out_stride;
  for (std::ptrdiff_t i = 0; i < n; ++i, in += step_in, causal += step_out, out += step_out)
#pragma GCC unroll 8
    for (int j = 0; j < kVectors; ++j) {
      State& t = s[j];
      const Lanes x = load(in + j * kLanes);
      Lanes yp, yq;
      if constexpr (kCausal) {
        yp = (p.b0 * x + p.b1 * t.x1 - p.a2 * t.yp2) - p.a1 * t.yp1;
        yq = (q.b0 * x + q.b1 * t.x1 - q.a2 * t.yq2) - q.a1 * t.yq1;
      } else {
        yp = (p.c1 * t.x1 + p.c2 * t.x2 - p.a2 * t.yp2) - p.a1 * t.yp1;
        yq = (q.c1 * t.x1 + q.c2 * t.x2 - q.a2 * t.yq2) - q.a1 * t.yq1;
      }
      t.x2 = t.x1, t.x1 = x;
      t.yp2 = t.yp1, t.yp1 = yp;
      t.yq2 = t.yq1, t.yq1 = yq;
      store(out + j * kLanes, kCausal ? yp + yq : load(causal + j * kLanes) + yp + yq);
    }
  __builtin_memcpy(state, s, sizeof s);
}

// The state before the first step of a sweep over `vectors` x kLanes signals whose first sample
// (in the sweep's order) is at edge[0, vectors x kLanes).
template <bool kCausal>
void start_state(const float* edge, std::ptrdiff_t vectors, const Coefficients& k, bool replicate,
                 float* state) {
  for (std::ptrdiff_t j = 0; j < vectors; ++j) {
    const Lanes x = replicate ? load(edge + j * kLanes) : Lanes{};
    const State s = kCausal ? steady_state(x, k.s[0].causal_gain(), k.s[1].causal_gain())
                            : steady_state(x, k.s[0].anticausal_gain(), k.s[1].anticausal_gain());
    __builtin_memcpy(state + j * kStateFloats, &s, sizeof s);
  }
}

// The columns pass streams along the rows: the causal sweep goes down the image kBandRows rows at
// a time and stores its part in out, then the anticausal one comes back up, reading in and the
// causal part, and stores the sum. Each thread owns a range of whole vectors of columns, whose
// recursion state waits in per-thread scratch from one band to the next. Every access is a run
// along a row, which the prefetchers follow (filtering a block of columns down the image, a few
// cache lines a row apart, runs at the latency of memory instead). The rows pass is fused into
// the way back up: a band just finished by the anticausal sweep is still in cache, and is
// filtered along its rows there, kBandBlocks blocks of kRowBlock rows per thread. The image is
// read twice and written
// twice in all, where separate passes would read it three times and write it three times.
constexpr int kColumnVectors = 2;  // two independent recursions hide each other's latency
constexpr int kRowVectors = 1;     // the rows pass: 16 rows in lane order, 256 KiB at width 4096
constexpr std::ptrdiff_t kRowBlock = kRowVectors * kLanes;
// Rows per stretch of a column sweep: its state is loaded and saved once per stretch, and the
// stretch reads 2 x kStreamRows rows side by side (measured best of 2, 4, 8).
constexpr std::ptrdiff_t kStreamRows = 8;
// Row blocks per thread in a band of the way back up: each band ends in a barrier, and four
// blocks (a 2 MiB band at width 4096 on two threads, served from L3) measured 7 % faster than
// one, and fewer barriers lose less when a core is shared with another process.
constexpr std::ptrdiff_t kBandBlocks = 4;
constexpr int kColumnStateSlot = kFreeScratchSlot + 1;

// Whole vectors of columns that one thread filters: [x0, x0 + 16 vectors) of in and out.
struct ColumnRange {
  ConstPlane in;
  Plane out;
  std::ptrdiff_t x0 = 0, vectors = 0;
  float* state = nullptr;  // vectors x kStateFloats
};

// One band of a column sweep: rows [y, y + rows) going down (causal) or [y - rows + 1, y] going
// up (anticausal).
template <bool kCausal>
void column_band(const ColumnRange& c, std::ptrdiff_t y, std::ptrdiff_t rows,
                 const Coefficients& k) {
  const std::ptrdiff_t in_pitch = c.in.pitch(), out_pitch = c.out.pitch();
  for (std::ptrdiff_t done = 0; done < rows; done += kStreamRows) {
    const std::ptrdiff_t n = std::min(kStreamRows, rows - done);
    const std::ptrdiff_t row = kCausal ? y + done : y - done;
    const float* src = c.in.row(row) + c.x0;
    float* dst = c.out.row(row) + c.x0;
    std::ptrdiff_t j = 0;
    for (; j + kColumnVectors <= c.vectors; j += kColumnVectors)
      sweep<kCausal, kColumnVectors>(src + j * kLanes, in_pitch, dst + j * kLanes, dst + j * kLanes,
                                     out_pitch, n, k, c.state + j * kStateFloats);
    for (; j < c.vectors; ++j)
      sweep<kCausal, 1>(src + j * kLanes, in_pitch, dst + j * kLanes, dst + j * kLanes, out_pitch,
                        n, k, c.state + j * kStateFloats);
  }
}

// Both sweeps along the rows of a block in lane order (w signals of kRowBlock lanes), in place.
void filter_row_lanes(float* lanes, std::ptrdiff_t w, const Coefficients& k, bool replicate) {
  float* causal = scratch(kFreeScratchSlot, w * kRowBlock);
  float state[kRowVectors * kStateFloats];
  start_state<true>(lanes, kRowVectors, k, replicate, state);
  sweep<true, kRowVectors>(lanes, kRowBlock, causal, causal, kRowBlock, w, k, state);
  const std::ptrdiff_t last = (w - 1) * kRowBlock;
  start_state<false>(lanes + last, kRowVectors, k, replicate, state);
  sweep<false, kRowVectors>(lanes + last, kRowBlock, causal + last, lanes + last, kRowBlock, w, k,
                            state);
}

}  // namespace

void run_iir_deriche(Plane out, ConstPlane in, const BlurOptions& options) {
  const Coefficients k = deriche_coefficients(options.sigma);
  const bool replicate = options.border == Border::replicate;
  const std::ptrdiff_t w = in.width(), h = in.height();
  const std::ptrdiff_t vectors = w / kLanes, rest = w - vectors * kLanes;
  // The last w mod 16 columns go through a strip one vector wide (its unused lanes zero),
  // filtered by the last thread.
  std::vector<float> strip_in, strip_out;
  if (rest > 0) {
    strip_in.assign(h * kLanes, 0.f);
    strip_out.resize(h * kLanes);
    for (std::ptrdiff_t y = 0; y < h; ++y)
      std::copy_n(in.row(y) + vectors * kLanes, rest, strip_in.data() + y * kLanes);
  }
  auto rows_pass = [&](float* lanes, std::ptrdiff_t width) {
    filter_row_lanes(lanes, width, k, replicate);
  };
#pragma omp parallel num_threads(resolve_threads(options.threads))
  {
    const int team = omp_get_num_threads(), t = omp_get_thread_num();
    const std::ptrdiff_t v0 = vectors * t / team, v1 = vectors * (t + 1) / team;
    const bool owns_strip = rest > 0 && t == team - 1;
    float strip_state[kStateFloats];
    ColumnRange ranges[2];
    int count = 0;
    if (v1 > v0)
      ranges[count++] = {in, out, v0 * kLanes, v1 - v0,
                         scratch(kColumnStateSlot, (v1 - v0) * kStateFloats)};
    if (owns_strip)
      ranges[count++] = {ConstPlane(strip_in.data(), kLanes, h, kLanes),
                         Plane(strip_out.data(), kLanes, h, kLanes), 0, 1, strip_state};
    const std::ptrdiff_t band_rows = kRowBlock * kBandBlocks * team;
    const std::ptrdiff_t bands = (h + band_rows - 1) / band_rows;

    for (int r = 0; r < count; ++r)
      start_state<true>(ranges[r].in.row(0) + ranges[r].x0, ranges[r].vectors, k, replicate,
                        ranges[r].state);
    for (std::ptrdiff_t y = 0; y < h; y += band_rows)
      for (int r = 0; r < count; ++r)
        column_band<true>(ranges[r], y, std::min(band_rows, h - y), k);

    for (int r = 0; r < count; ++r)
      start_state<false>(ranges[r].in.row(h - 1) + ranges[r].x0, ranges[r].vectors, k, replicate,
                         ranges[r].state);
    for (std::ptrdiff_t b = bands - 1; b >= 0; --b) {
      const std::ptrdiff_t y0 = b * band_rows, y1 = std::min(h, y0 + band_rows);
      for (int r = 0; r < count; ++r) column_band<false>(ranges[r], y1 - 1, y1 - y0, k);
      if (owns_strip)
        for (std::ptrdiff_t y = y0; y < y1; ++y)
          std::copy_n(strip_out.data() + y * kLanes, rest, out.row(y) + vectors * kLanes);
          // Every column of the band is final: the rows pass may read the other threads' columns.
#pragma omp barrier
      for (std::ptrdiff_t y = y0 + t * kRowBlock; y < y1; y += team * kRowBlock)
        filter_row_block<kRowBlock>(out, y, rows_pass);
    }
  }
}

}  // namespace tridiff::blur_detail
