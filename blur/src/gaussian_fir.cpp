// Method "gaussian-fir": the sampled Gaussian cut where its two tails together weigh at most
// kTailMass (r about 3.7 sigma), for small sigma, where a recursive filter's fixed cost is
// larger than a short kernel's.
//
// Why it is faster than "separable" (which keeps a tail of 1e-7, r about 5.3 sigma): the
// image goes through in strips of 16 rows. The column pass sums 16 + 2r input rows into the
// strip's 16 rows; the strip is then transposed so that each of its 16 rows is one SIMD lane,
// and the row pass runs along it exactly like the column pass. Both passes slide a window of
// 2r + 1 vectors held in registers (r is a compile-time constant), so each input vector is
// loaded once and each output costs r + 1 multiply-adds and r additions, with no unaligned
// loads. The strip (16 rows) stays in L2 between the passes; the image is read once and
// written once.
//
// Error: cutting mass e and renormalising moves an output on an image in [0, 1] by at most e
// per pass, so at most 2 kTailMass = 4e-4 against the exact sampled Gaussian, plus float
// rounding; the registry states 5e-4.
#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "row_blocks.hpp"
#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/kernels.hpp"

namespace tridiff::blur_detail {

namespace {

constexpr double kTailMass = 2e-4;
constexpr int kLanes = kVectorLanes;  // rows of a strip: one lane each in the row pass
constexpr int kMaxRadius = 12;        // sigma <= 3 needs r <= 11: a window of 23 registers

// out(j) = sum_t k[t] in(j + t), t in [0, 2R], for j in [0, n): in(i) and out(j) point at 16
// floats. The kernel is symmetric (k[t] = k[2R - t]), so the two ends of the window are added
// before the multiply.
template <int R, class In, class Out>
[[gnu::always_inline]] inline void slide(const float* k, std::ptrdiff_t n, In in, Out out) {
  FloatVector window[2 * R + 1];
  for (int t = 0; t < 2 * R; ++t) window[t] = load(in(t));
  for (std::ptrdiff_t j = 0; j < n; ++j) {
    window[2 * R] = load(in(j + 2 * R));
    FloatVector sum = k[R] * window[R];
    for (int t = 0; t < R; ++t) sum += k[t] * (window[t] + window[2 * R - t]);
    store(out(j), sum);
    for (int t = 0; t < 2 * R; ++t) window[t] = window[t + 1];
  }
}

// Output rows [y0, y0 + kLanes) of the plane (fewer at its bottom), replicate borders.
template <int R>
void filter_strip(ConstPlane in, Plane out, const float* k, std::ptrdiff_t y0) {
  const std::ptrdiff_t w = in.width(), h = in.height();
  const std::ptrdiff_t blocks = (w + kLanes - 1) / kLanes;
  // lanes[(R + x) * 16 + l]: column x of strip row l, with R copies of the first and of the
  // last column on either side (replicate), and room for the reads of a last partial block.
  float* lanes = scratch(kFreeScratchSlot, std::size_t((blocks * kLanes + 2 * R) * kLanes));
  float* staging = scratch(kFreeScratchSlot + 1, std::size_t((kLanes + 2 * R) * kLanes));
  alignas(64) float block[kLanes * kLanes];

  // Column pass over rows y0 - R ... y0 + 15 + R (clamped), 16 columns at a time, each block
  // of 16 x 16 results transposed into lanes while it is in L1.
  const float* rows[kLanes + 2 * R];
  for (int i = 0; i < kLanes + 2 * R; ++i)
    rows[i] = in.row(std::clamp<std::ptrdiff_t>(y0 - R + i, 0, h - 1));
  for (std::ptrdiff_t x = 0; x < w; x += kLanes) {
    const std::ptrdiff_t n = std::min<std::ptrdiff_t>(kLanes, w - x);
    if (n == kLanes) {
      slide<R>(
          k, kLanes, [&](int i) { return rows[i] + x; },
          [&](std::ptrdiff_t j) { return block + j * kLanes; });
    } else {  // the last columns through a staging block: nothing past the row is read
      std::fill_n(staging, (kLanes + 2 * R) * kLanes, 0.f);
      for (int i = 0; i < kLanes + 2 * R; ++i)
        std::copy(rows[i] + x, rows[i] + w, staging + i * kLanes);
      slide<R>(
          k, kLanes, [&](int i) { return staging + i * kLanes; },
          [&](std::ptrdiff_t j) { return block + j * kLanes; });
    }
    detail::transpose_into_lanes<float, kLanes>(block, kLanes, n, lanes + (R + x) * kLanes);
  }
  for (int e = 0; e < R; ++e) {
    std::copy_n(lanes + R * kLanes, kLanes, lanes + e * kLanes);
    std::copy_n(lanes + (R + w - 1) * kLanes, kLanes, lanes + (R + w + e) * kLanes);
  }

  // Row pass along the lanes, 16 outputs at a time transposed back into the strip's rows.
  float* out_rows[kLanes];
  const std::ptrdiff_t count = std::min<std::ptrdiff_t>(kLanes, h - y0);
  for (int l = 0; l < kLanes; ++l) out_rows[l] = l < count ? out.row(y0 + l) : staging;
  for (std::ptrdiff_t x = 0; x < w; x += kLanes) {
    slide<R>(
        k, kLanes, [&](std::ptrdiff_t i) { return lanes + (x + i) * kLanes; },
        [&](std::ptrdiff_t j) { return block + j * kLanes; });
    detail::scatter_from_lanes<float, kLanes>(block, std::min<std::ptrdiff_t>(kLanes, w - x),
                                              out_rows, x, true);
  }
  detail::finish_streaming_stores();
}

template <int R>
void filter_plane(ConstPlane in, Plane out, const float* k, int threads) {
  const std::ptrdiff_t strips = (in.height() + kLanes - 1) / kLanes;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t s = 0; s < strips; ++s) filter_strip<R>(in, out, k, s * kLanes);
}

using PlaneFilter = void (*)(ConstPlane, Plane, const float*, int);

template <std::size_t... I>
constexpr std::array<PlaneFilter, sizeof...(I)> filters(std::index_sequence<I...>) {
  return {&filter_plane<int(I) + 1>...};
}

}  // namespace

void run_gaussian_fir(Plane out, ConstPlane in, const BlurOptions& options) {
  const std::ptrdiff_t r = gaussian_radius(options.sigma, kTailMass);
  if (r > kMaxRadius)  // the registry's sigma range keeps r within the compiled windows
    throw InvalidArgument(
        "sigma", "needs a radius of " + std::to_string(r) + " > " + std::to_string(kMaxRadius));
  const std::vector<float> k = gaussian_kernel(options.sigma, r);
  static constexpr auto kFilters = filters(std::make_index_sequence<kMaxRadius>());
  kFilters[r - 1](in, out, k.data(), resolve_threads(options.threads));
}

}  // namespace tridiff::blur_detail
