// Recursive Gaussian (Deriche 1993, 4th order): the Gaussian's right half is approximated by
//   g(t) = (1.680 cos(0.6318 t) + 3.735 sin(0.6318 t)) exp(-1.783 t)
//        - (0.6803 cos(1.997 t) + 0.2598 sin(1.997 t)) exp(-1.723 t),   t = x / sigma,
// i.e. g(n) = Re sum_k c_k z_k^n with two complex poles z_k. The filter is the sum of a causal
// part (n >= 0) and an anticausal part (n < 0), each a pair of real second-order sections (one
// per conjugate pole pair): the parallel form keeps float rounding small where the poles crowd
// towards 1 at large sigma. O(1) work per pixel whatever sigma.
//
// Layout: columns are filtered in strips of kLanes columns, the recursion running down the
// rows with one SIMD lane per column; rows are transposed 16 at a time into the same layout,
// filtered in place and transposed back. Replicate borders start each recursion in its steady
// state for the edge value, so the result equals the IIR applied to the extended signal.
#include <algorithm>
#include <complex>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/solvers/detail/transpose.hpp"

namespace tridiff::blur_detail {

namespace {

constexpr int kLanes = 16;  // one AVX-512 vector of floats; a strip of 4096 rows is 256 KiB

// One real second-order section: y(n) = b0 x(n) + b1 x(n-1) - a1 y(n-1) - a2 y(n-2) for the
// causal part, y(n) = b1 x(n+1) + b2 x(n+2) - a1 y(n+1) - a2 y(n+2) for the anticausal one.
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

// kLanes floats as one vector (GCC/Clang vector extension): the recursion state stays in
// registers, one lane per signal.
using Lanes = float __attribute__((vector_size(kLanes * sizeof(float))));

inline Lanes load(const float* p) {
  Lanes v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline void store(float* p, Lanes v) { __builtin_memcpy(p, &v, sizeof v); }

// Columns per panel of the columns pass: rows of 1 KiB stream well through the hardware
// prefetchers (a strip one vector wide, one cache line per row at a stride of a whole row,
// does not, and a power-of-two pitch maps it onto a handful of cache sets), and a panel's
// input and output (2 x 4 MiB at 4096 rows) stay in L3 between the two sweeps.
constexpr int kPanelVectors = 16;

// Filters `vectors` x kLanes signals of length n along i: element i of signal (j, l) is
// in[i * stride + j * kLanes + l], and likewise for out, which must not overlap in. The causal
// sweep writes out; the anticausal sweep adds to it. Within a step the vectors are independent,
// so their recursions overlap; each one's dependency chain is one multiply-add per section
// (the terms that do not depend on y(n-1) are summed first). Up to 4, vectors must equal
// kMaxVectors.
template <int kMaxVectors>
void filter_lanes(const float* in, float* out, std::ptrdiff_t stride, std::ptrdiff_t n,
                  int vectors, const Coefficients& k, bool replicate) {
  // Small counts are fixed at compile time, which keeps the state in registers.
  const int nv = kMaxVectors <= 4 ? kMaxVectors : vectors;
  // Coefficients as local vectors: stores to out could alias k, so the compiler would reload
  // them at every step.
  const Lanes pb0 = k.s[0].b0 + Lanes{}, pb1 = k.s[0].b1 + Lanes{};
  const Lanes pc1 = k.s[0].c1 + Lanes{}, pc2 = k.s[0].c2 + Lanes{};
  const Lanes pa1 = k.s[0].a1 + Lanes{}, pa2 = k.s[0].a2 + Lanes{};
  const Lanes qb0 = k.s[1].b0 + Lanes{}, qb1 = k.s[1].b1 + Lanes{};
  const Lanes qc1 = k.s[1].c1 + Lanes{}, qc2 = k.s[1].c2 + Lanes{};
  const Lanes qa1 = k.s[1].a1 + Lanes{}, qa2 = k.s[1].a2 + Lanes{};
  const float p_causal = static_cast<float>(k.s[0].causal_gain());
  const float q_causal = static_cast<float>(k.s[1].causal_gain());
  const float p_anti = static_cast<float>(k.s[0].anticausal_gain());
  const float q_anti = static_cast<float>(k.s[1].anticausal_gain());
  Lanes x1[kMaxVectors], x2[kMaxVectors], yp1[kMaxVectors], yp2[kMaxVectors],
      yq1[kMaxVectors], yq2[kMaxVectors];
  // Causal sweep (x1 is x(i-1)).
  for (int j = 0; j < nv; ++j) {
    const Lanes x0 = replicate ? load(in + j * kLanes) : Lanes{};
    x1[j] = x0;
    yp1[j] = yp2[j] = x0 * p_causal;
    yq1[j] = yq2[j] = x0 * q_causal;
  }
  for (std::ptrdiff_t i = 0; i < n; ++i)
    for (int j = 0; j < nv; ++j) {
      const Lanes x = load(in + i * stride + j * kLanes);
      const Lanes yp = (pb0 * x + pb1 * x1[j] - pa2 * yp2[j]) - pa1 * yp1[j];
      const Lanes yq = (qb0 * x + qb1 * x1[j] - qa2 * yq2[j]) - qa1 * yq1[j];
      x1[j] = x;
      yp2[j] = yp1[j], yp1[j] = yp;
      yq2[j] = yq1[j], yq1[j] = yq;
      store(out + i * stride + j * kLanes, yp + yq);
    }
  // Anticausal sweep (x1, x2 are x(i+1), x(i+2)), adding to the causal part.
  for (int j = 0; j < nv; ++j) {
    const Lanes xn = replicate ? load(in + (n - 1) * stride + j * kLanes) : Lanes{};
    x1[j] = x2[j] = xn;
    yp1[j] = yp2[j] = xn * p_anti;
    yq1[j] = yq2[j] = xn * q_anti;
  }
  for (std::ptrdiff_t i = n - 1; i >= 0; --i)
    for (int j = 0; j < nv; ++j) {
      const Lanes yp = (pc1 * x1[j] + pc2 * x2[j] - pa2 * yp2[j]) - pa1 * yp1[j];
      const Lanes yq = (qc1 * x1[j] + qc2 * x2[j] - qa2 * yq2[j]) - qa1 * yq1[j];
      x2[j] = x1[j], x1[j] = load(in + i * stride + j * kLanes);
      yp2[j] = yp1[j], yp1[j] = yp;
      yq2[j] = yq1[j], yq1[j] = yq;
      float* y = out + i * stride + j * kLanes;
      store(y, load(y) + yp + yq);
    }
}

// Columns: panels of up to kPanelVectors full vectors of columns; the last columns (fewer
// than kLanes) go through a padded copy.
void filter_columns(ConstPlane in, Plane out, const Coefficients& k, bool replicate,
                    int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height();
  const std::ptrdiff_t full = w / kLanes;  // whole vectors of columns
  const std::ptrdiff_t panels = (full + kPanelVectors - 1) / kPanelVectors;
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(static)
    for (std::ptrdiff_t s = 0; s < panels; ++s) {
      const std::ptrdiff_t first = s * kPanelVectors;
      const int vectors = static_cast<int>(std::min<std::ptrdiff_t>(kPanelVectors, full - first));
      filter_lanes<kPanelVectors>(in.row(0) + first * kLanes, out.row(0) + first * kLanes,
                                  in.pitch(), h, vectors, k, replicate);
    }
#pragma omp single
    if (const std::ptrdiff_t x0 = full * kLanes, lanes = w - x0; lanes > 0) {
      std::vector<float> pad_in(h * kLanes, 0.f), pad_out(h * kLanes);
      for (std::ptrdiff_t y = 0; y < h; ++y)
        std::copy_n(in.row(y) + x0, lanes, pad_in.data() + y * kLanes);
      filter_lanes<1>(pad_in.data(), pad_out.data(), kLanes, h, 1, k, replicate);
      for (std::ptrdiff_t y = 0; y < h; ++y)
        std::copy_n(pad_out.data() + y * kLanes, lanes, out.row(y) + x0);
    }
  }
}

// Rows per block of the rows pass: two vectors of lanes, so that two independent recursions
// hide each other's multiply-add latency; the block's two transposed copies (2 x 32 rows x
// 16 KiB at 4096 columns) stay in L2.
constexpr int kRowVectors = 2;
constexpr std::ptrdiff_t kRowBlock = kRowVectors * kLanes;

// Rows, in place: kRowBlock rows at a time are transposed into lanes, filtered and transposed
// back.
void filter_rows(Plane plane, const Coefficients& k, bool replicate, int threads) {
  const std::ptrdiff_t w = plane.width(), h = plane.height();
  const std::ptrdiff_t blocks = (h + kRowBlock - 1) / kRowBlock;
#pragma omp parallel num_threads(threads)
  {
    std::vector<float> lanes_in(w * kRowBlock), lanes_out(w * kRowBlock), tail;
#pragma omp for schedule(static)
    for (std::ptrdiff_t b = 0; b < blocks; ++b) {
      const std::ptrdiff_t y0 = b * kRowBlock, rows = std::min(kRowBlock, h - y0);
      float* first = plane.row(y0);
      std::ptrdiff_t pitch = plane.pitch();
      if (rows < kRowBlock) {  // stage the last rows in a full block
        tail.assign(kRowBlock * w, 0.f);
        for (std::ptrdiff_t r = 0; r < rows; ++r)
          std::copy_n(plane.row(y0 + r), w, tail.data() + r * w);
        first = tail.data();
        pitch = w;
      }
      detail::transpose_into_lanes<float, kRowBlock>(first, pitch, w, lanes_in.data());
      filter_lanes<kRowVectors>(lanes_in.data(), lanes_out.data(), kRowBlock, w, kRowVectors, k,
                                replicate);
      detail::transpose_from_lanes<float, kRowBlock>(lanes_out.data(), w, first, pitch);
      if (rows < kRowBlock)
        for (std::ptrdiff_t r = 0; r < rows; ++r)
          std::copy_n(tail.data() + r * w, w, plane.row(y0 + r));
    }
  }
}

}  // namespace

void run_iir_deriche(ConstPlane in, Plane out, const BlurSettings& settings) {
  const Coefficients k = deriche_coefficients(settings.sigma);
  const bool replicate = settings.border == Border::replicate;
  const int threads = threads_of(settings);
  filter_columns(in, out, k, replicate, threads);
  filter_rows(out, k, replicate, threads);
}

}  // namespace tridiff::blur_detail
