// LinkField: storage, validation and the per-tile activity record.
#include "tridiff/diffusion/links.hpp"

#include "tridiff/threads.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace tridiff {

LinkField::LinkField(std::ptrdiff_t width, std::ptrdiff_t height)
    : links_(width, height, 2),
      tiles_x_((width + kTile - 1) / kTile),
      tiles_y_((height + kTile - 1) / kTile),
      horizontal_active_(tiles_x_ * tiles_y_, 0),
      vertical_active_(tiles_x_ * tiles_y_, 0) {}

namespace {

void require_valid_link(float link, const char* direction, std::ptrdiff_t x, std::ptrdiff_t y) {
  if (std::isfinite(link) && link >= 0) return;
  throw InvalidArgument(std::string(direction) + " link",
                        "at pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is " +
                            std::to_string(link) + "; conductances must be finite and >= 0");
}

}  // namespace

void LinkField::finish(int threads) {
  const int team = resolve_threads(threads);
  const std::ptrdiff_t w = width(), h = height();
  Plane horizontal_links = horizontal(), vertical_links = vertical();
  for (std::ptrdiff_t y = 0; y < h; ++y) horizontal_links(w - 1, y) = 0;
  std::fill(vertical_links.row(h - 1), vertical_links.row(h - 1) + w, 0.f);

  float largest = 0;
  bool invalid = false;
// clang-format off
#pragma omp parallel for num_threads(team) schedule(static) reduction(max : largest) \
    reduction(|| : invalid)
  // clang-format on
  for (std::ptrdiff_t ty = 0; ty < tiles_y_; ++ty) {
    for (std::ptrdiff_t tx = 0; tx < tiles_x_; ++tx) {
      // probe = sum of 0 * link: zero unless a link is NaN or infinite (inf * 0 is NaN).
      float h_max = 0, v_max = 0, smallest = 0, probe = 0;
      const std::ptrdiff_t x0 = tx * kTile, x_end = std::min(w, x0 + kTile);
      for (std::ptrdiff_t y = ty * kTile; y < std::min(h, (ty + 1) * kTile); ++y) {
        const float* hr = horizontal_links.row(y);
        const float* vr = vertical_links.row(y);
#pragma omp simd reduction(max : h_max, v_max) reduction(min : smallest) reduction(+ : probe)
        for (std::ptrdiff_t x = x0; x < x_end; ++x) {
          h_max = std::max(h_max, hr[x]);
          v_max = std::max(v_max, vr[x]);
          smallest = std::min(smallest, std::min(hr[x], vr[x]));
          probe += 0.f * hr[x] + 0.f * vr[x];
        }
      }
      horizontal_active_[ty * tiles_x_ + tx] = h_max > 0;
      vertical_active_[ty * tiles_x_ + tx] = v_max > 0;
      largest = std::max(largest, std::max(h_max, v_max));
      if (smallest < 0 || probe != 0) invalid = true;
    }
  }
  if (invalid) throw_first_invalid_link();
  max_link_ = largest;
}

void LinkField::set_activity(const std::vector<float>& horizontal_max,
                             const std::vector<float>& vertical_max) {
  float largest = 0;
  for (std::size_t i = 0; i < horizontal_max.size(); ++i) {
    horizontal_active_[i] = horizontal_max[i] > 0;
    vertical_active_[i] = vertical_max[i] > 0;
    largest = std::max(largest, std::max(horizontal_max[i], vertical_max[i]));
  }
  max_link_ = largest;
}

// The slow path of finish(): find the first bad link in reading order and name it (exceptions
// must not leave the parallel loop).
void LinkField::throw_first_invalid_link() const {
  for (std::ptrdiff_t y = 0; y < height(); ++y)
    for (std::ptrdiff_t x = 0; x < width(); ++x) {
      require_valid_link(horizontal()(x, y), "horizontal", x, y);
      require_valid_link(vertical()(x, y), "vertical", x, y);
    }
  throw InvalidArgument("links", "changed while being checked");
}

}  // namespace tridiff
