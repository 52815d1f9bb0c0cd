// Method "iir-decimated": the recursive Gaussian of iir_deriche.cpp run on the plane decimated by
// f = 2^k (the largest power of two <= sigma / 2, at most 16), then brought back to full size with
// a cubic B-spline. A Gaussian of sigma >= 2 f leaves little above the coarse grid's Nyquist
// frequency, so the detour costs little accuracy, and the recursion, which dominates the cost,
// runs on f^2 times fewer pixels: at 4096^2 RGB on two threads, 24 ms at sigma 8 and 17 ms at
// sigma 64 against 41 ms for iir-deriche.
//
// Variances add (full-resolution pixels^2, per axis):
//   - each decimation level filters with the binomial [1 4 6 4 1] / 16 (variance 1 in its own
//     input's pixels) and keeps every second sample: (f^2 - 1) / 3 over k levels;
//   - the coarse Gaussian, sigma_c on the coarse grid: f^2 sigma_c^2;
//   - the cubic B-spline up-sampling, variance 1/3 of a coarse pixel^2 at every phase: f^2 / 3;
// so sigma_c^2 = (sigma^2 - (2 f^2 - 1) / 3) / f^2, at least 1.8^2 coarse pixels^2.
//
// Error: the binomial has a zero of order 4 at the coarse grid's Nyquist frequency, so what folds
// over at a decimation and survives the Gaussian is of order 0.14 (f / sigma)^4 of a component
// just below that frequency (about 1e-4 for stripes of period 2.2 px and amplitude 0.5 at sigma 4);
// the shapes of the small kernels are lost in the large Gaussian. Measured on the test set for
// sigma 4 to 64: max error 3.0e-4 (iir-deriche alone: 2.4e-4), operator-norm error 0.74e-3 to
// 1.6e-3, the most where sigma / f = 2 exactly.
//
// Borders: only replicate. Every coarse grid keeps kMargin samples beyond each end, far enough
// that they are the filtered constant continuation of the edge, so the coarse filter's replicate
// start sees the same signal the full-resolution one would.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "row_blocks.hpp"
#include "tridiff/blur/blur.hpp"

namespace tridiff::blur_detail {

void run_iir_deriche(Plane, ConstPlane, const BlurOptions&);  // iir_deriche.cpp

namespace {

constexpr int kLanes = kVectorLanes;
using Vec = FloatVector;
using Index = int __attribute__((vector_size(kLanes * sizeof(int))));  // permutations of a Vec

// v[mask[l]] in lane l, and the same over the 2 kLanes lanes of a then b: GCC's
// __builtin_shuffle. Clang (the fuzzing build) has no form taking a mask known only at run
// time, so it gets the same permutation lane by lane.
inline Vec permute(Vec v, Index mask) {
#if defined(__clang__)
  Vec result;
  for (int l = 0; l < kLanes; ++l) result[l] = v[mask[l] & (kLanes - 1)];
  return result;
#else
  return __builtin_shuffle(v, mask);
#endif
}

inline Vec permute(Vec a, Vec b, Index mask) {
#if defined(__clang__)
  Vec result;
  for (int l = 0; l < kLanes; ++l) {
    const int i = mask[l] & (2 * kLanes - 1);
    result[l] = i < kLanes ? a[i] : b[i - kLanes];
  }
  return result;
#else
  return __builtin_shuffle(a, b, mask);
#endif
}

constexpr std::ptrdiff_t kMargin = 2;  // coarse samples kept beyond each end of a level
constexpr int kMaxLevels = 4;          // f <= 16
// Scratch slots of the calling thread for the coarse planes (run_iir_deriche, called in between,
// uses the lower slots of every thread).
constexpr int kLevelSlot[2] = {4, 5};
constexpr int kBlurredSlot = 6;
static_assert(kBlurredSlot < kScratchSlots);

std::ptrdiff_t round_up(std::ptrdiff_t n, std::ptrdiff_t to) { return (n + to - 1) / to * to; }

// Samples of one decimation level for an input of n: sample i sits at input position
// 2 (i - kMargin); the last two lie at least 2 beyond the input's end, past the filter's reach.
std::ptrdiff_t coarse_length(std::ptrdiff_t n) { return kMargin + (n + 4) / 2 + 1; }

// A coarse plane in the calling thread's scratch slot, rows padded to whole vectors (the passes
// below store whole vectors; nothing reads the padding).
Plane coarse_plane(int slot, std::ptrdiff_t width, std::ptrdiff_t height) {
  const std::ptrdiff_t pitch = round_up(width, kLanes);
  return {scratch(slot, static_cast<std::size_t>(pitch * height)), width, height, pitch};
}

// One level: out(i, j) = sum_{a,b} k[a] k[b] in(2 (i - kMargin) + a - 2, 2 (j - kMargin) + b - 2),
// k = [1 4 6 4 1] / 16, `in` extended by replicating its edges.
void decimate(ConstPlane in, Plane out, int threads) {
  const std::ptrdiff_t w = in.width(), h = in.height(), m = out.width();
  // Padded row: input column x at x + kPad; even[i], odd[i] are positions 2 i - kPad and
  // 2 i + 1 - kPad.
  constexpr std::ptrdiff_t kPad = 2 * kMargin + 2;
  const std::ptrdiff_t pairs = round_up(m + 2, kLanes);  // even/odd samples needed, whole vectors
  const std::ptrdiff_t padded_length = 2 * pairs + kLanes;
  const Index evens = {0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30};
  const Index odds = evens + 1;
#pragma omp parallel num_threads(threads)
  {
    float* padded = scratch(1, padded_length);
    float* even = scratch(2, pairs + kLanes);
    float* odd = scratch(3, pairs + kLanes);
#pragma omp for schedule(static)
    for (std::ptrdiff_t j = 0; j < out.height(); ++j) {
      const float* r[5];
      for (int b = 0; b < 5; ++b)
        r[b] = in.row(std::clamp<std::ptrdiff_t>(2 * (j - kMargin) + b - 2, 0, h - 1));
      float* row = padded + kPad;
#pragma omp simd
      for (std::ptrdiff_t x = 0; x < w; ++x)
        row[x] = (r[0][x] + r[4][x]) * (1.f / 16) + (r[1][x] + r[3][x]) * (4.f / 16) +
                 r[2][x] * (6.f / 16);
      std::fill(padded, row, row[0]);
      std::fill(row + w, padded + padded_length, row[w - 1]);
      for (std::ptrdiff_t i = 0; i < pairs; i += kLanes) {
        const Vec a = load(padded + 2 * i), b = load(padded + 2 * i + kLanes);
        store(even + i, permute(a, b, evens));
        store(odd + i, permute(a, b, odds));
      }
      // Sample i reads positions 2 i - kPad + {0 .. 4}: even[i], odd[i], even[i + 1],
      // odd[i + 1], even[i + 2].
      float* dst = out.row(j);
      for (std::ptrdiff_t i = 0; i < m; i += kLanes)
        store(dst + i, (load(even + i) + load(even + i + 2)) * (1.f / 16) +
                           (load(odd + i) + load(odd + i + 1)) * (4.f / 16) +
                           load(even + i + 1) * (6.f / 16));
    }
  }
}

// The cubic B-spline's weights for samples n - 1 .. n + 2 at fraction u of the way from n to n + 1.
void bspline_weights(double u, float* w) {
  w[0] = static_cast<float>((1 - u) * (1 - u) * (1 - u) / 6);
  w[1] = static_cast<float>((3 * u * u * u - 6 * u * u + 4) / 6);
  w[2] = static_cast<float>((-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6);
  w[3] = static_cast<float>(u * u * u / 6);
}

// Up-sampling by f along one axis: full position x is coarse coordinate (x + offset) / f.
struct Upsampling {
  std::ptrdiff_t f, offset;
  std::ptrdiff_t sample(std::ptrdiff_t x) const { return (x + offset) / f; }
  double fraction(std::ptrdiff_t x) const { return double((x + offset) % f) / double(f); }
};

// out(x, y) = sum_{s,t} B(x / f - s) B(y / f - t) coarse(s, t) in the coarse coordinates of
// `up`, coarse samples beyond its ends replicated. Columns first (4 coarse rows per output row),
// then along the row 16 outputs at a time: they need at most 11 consecutive samples, so one load
// and a permutation per tap gather them; the pattern repeats every 16 outputs (f divides 16).
void upsample(ConstPlane coarse, Plane out, const Upsampling& up, int threads) {
  const std::ptrdiff_t m = coarse.width(), w = out.width();
  Index gather[4];
  Vec weight[4];
  for (int l = 0; l < kLanes; ++l) {
    float wl[4];
    bspline_weights(up.fraction(l), wl);
    for (int t = 0; t < 4; ++t) {
      gather[t][l] = static_cast<int>(up.sample(l) - up.sample(0) + t);
      weight[t][l] = wl[t];
    }
  }
  const std::ptrdiff_t blocks = round_up(w, kLanes);
  // Output block x0 reads samples from first(x0) = sample(x0) - 1 on.
  const std::ptrdiff_t last_read = up.sample(blocks - kLanes) - 1 + kLanes;
  const std::ptrdiff_t line_length = std::max(m, last_read + 1);
#pragma omp parallel num_threads(threads)
  {
    float* line = scratch(1, line_length);
    float* block = scratch(2, kLanes);
#pragma omp for schedule(static)
    for (std::ptrdiff_t y = 0; y < out.height(); ++y) {
      float wy[4];
      bspline_weights(up.fraction(y), wy);
      const float* r[4];
      for (int t = 0; t < 4; ++t)
        r[t] = coarse.row(std::clamp<std::ptrdiff_t>(up.sample(y) - 1 + t, 0, coarse.height() - 1));
#pragma omp simd
      for (std::ptrdiff_t s = 0; s < m; ++s)
        line[s] = wy[0] * r[0][s] + wy[1] * r[1][s] + wy[2] * r[2][s] + wy[3] * r[3][s];
      std::fill(line + m, line + line_length, line[m - 1]);
      float* dst = out.row(y);
      for (std::ptrdiff_t x0 = 0; x0 < w; x0 += kLanes) {
        const Vec samples = load(line + up.sample(x0) - 1);
        Vec sum = weight[0] * permute(samples, gather[0]);
        for (int t = 1; t < 4; ++t) sum += weight[t] * permute(samples, gather[t]);
        if (x0 + kLanes <= w) {
          store(dst + x0, sum);
        } else {
          store(block, sum);
          std::copy_n(block, w - x0, dst + x0);
        }
      }
    }
  }
}

}  // namespace

void run_iir_decimated(Plane out, ConstPlane in, const BlurOptions& options) {
  const double sigma = options.sigma;
  int levels = 1;
  while (levels < kMaxLevels && (std::ptrdiff_t{2} << (levels + 1)) <= sigma) ++levels;
  const std::ptrdiff_t f = std::ptrdiff_t{1} << levels;
  const int threads = resolve_threads(options.threads);

  // Decimate level by level, alternating between two scratch planes; `offset` tracks where
  // coarse sample 0 sits: full position f_k i - offset_k.
  ConstPlane level = in;
  std::ptrdiff_t offset = 0, spacing = 1;
  for (int k = 0; k < levels; ++k) {
    const Plane next = coarse_plane(kLevelSlot[k % 2], coarse_length(level.width()),
                                    coarse_length(level.height()));
    decimate(level, next, threads);
    offset += 2 * kMargin * spacing;
    spacing *= 2;
    level = next;
  }
  const Plane blurred = coarse_plane(kBlurredSlot, level.width(), level.height());
  const double variance = (sigma * sigma - (2.0 * double(f * f) - 1) / 3) / double(f * f);
  run_iir_deriche(blurred, level, {std::sqrt(variance), Border::replicate, threads});
  upsample(blurred, out, {f, offset}, threads);
}

}  // namespace tridiff::blur_detail
