// The depth split of the near layer (near_layer.hpp).
#include "tridiff/dof/near_layer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

constexpr int kBins = 64;
using Histogram = std::array<double, kBins>;

// The smallest and the largest |CoC| of the near field (+inf and 0 when there is none).
std::pair<float, float> near_range(ConstPlane coc, FocusTest focus, int threads) {
  float smallest = INFINITY, largest = 0;
// clang-format off
#pragma omp parallel for num_threads(threads) schedule(static) \
    reduction(min : smallest) reduction(max : largest)
  // clang-format on
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y) {
    const float* row = coc.row(y);
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x)
      if (focus.is_near(row[x])) {
        smallest = std::min(smallest, -row[x]);
        largest = std::max(largest, -row[x]);
      }
  }
  return {smallest, largest};
}

// Near pixels by log2 |CoC| in kBins bins over [log2 low, log2 high].
Histogram near_histogram(ConstPlane coc, FocusTest focus, float low, float high, int threads) {
  const double origin = std::log2(double(low)), scale = kBins / (std::log2(double(high)) - origin);
  double counts[kBins] = {};
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : counts[:kBins])
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y) {
    const float* row = coc.row(y);
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x)
      if (focus.is_near(row[x])) {
        const int bin = int((std::log2(double(-row[x])) - origin) * scale);
        counts[std::clamp(bin, 0, kBins - 1)] += 1;
      }
  }
  Histogram histogram;
  std::copy(counts, counts + kBins, histogram.begin());
  return histogram;
}

// Otsu's threshold: the bin edge t (1 .. kBins - 1) that maximises w0 w1 (mu0 - mu1)^2 of the
// classes below and above it.
int otsu_edge(const Histogram& h) {
  double total = 0, moment = 0;
  for (int b = 0; b < kBins; ++b) {
    total += h[b];
    moment += b * h[b];
  }
  double below = 0, below_moment = 0, best = -1;
  int edge = 1;
  for (int t = 1; t < kBins; ++t) {
    below += h[t - 1];
    below_moment += (t - 1) * h[t - 1];
    const double above = total - below;
    if (below == 0 || above == 0) continue;
    const double gap = below_moment / below - (moment - below_moment) / above;
    const double between = below * above * gap * gap;
    if (between > best) {
      best = between;
      edge = t;
    }
  }
  return edge;
}

}  // namespace

NearLayer near_layer(ConstPlane coc, float in_focus_coc_px, int threads) {
  const int team = resolve_threads(threads);
  NearLayer layer{FocusTest{in_focus_coc_px}, 0};  // the diffusion methods' threshold
  const auto [low, high] = near_range(coc, layer.focus, team);
  layer.empty = !(low <= high);  // no near pixel leaves low at +inf
  layer.split_px = std::max(layer.focus.sharp_below, 0.f);
  if (!(high >= 2 * low)) return layer;  // no near field, or one depth: all of it
  const int edge = otsu_edge(near_histogram(coc, layer.focus, low, high, team));
  layer.split_px = float(std::exp2(
      std::log2(double(low)) + edge * (std::log2(double(high)) - std::log2(double(low))) / kBins));
  return layer;
}

}  // namespace tridiff
