// Conductances on the links between neighbouring pixels, the coefficients of every diffusion
// operator in tridiff, with a record of which tiles have any conductance at all so that the
// operators skip the parts of the image that have nothing to diffuse.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff {

// horizontal(x, y) is the conductance between pixels (x, y) and (x + 1, y); vertical(x, y)
// between (x, y) and (x, y + 1). The last column of horizontal and the last row of vertical
// stay zero: the image border is insulated (seed 000 eq. 3.10, beta_0 = beta_n = 0).
class LinkField {
 public:
  // Tiles are kTile x kTile pixels: one tile row of image rows (or tile column of image
  // columns) is exactly one SIMD batch of the float solvers (kLanes<float> systems).
  static constexpr std::ptrdiff_t kTile = 64;

  LinkField() = default;
  LinkField(std::ptrdiff_t width, std::ptrdiff_t height);

  std::ptrdiff_t width() const { return links_.width(); }
  std::ptrdiff_t height() const { return links_.height(); }
  Plane horizontal() { return links_.plane(0); }
  Plane vertical() { return links_.plane(1); }
  ConstPlane horizontal() const { return links_.plane(0); }
  ConstPlane vertical() const { return links_.plane(1); }

  // Recomputes which tiles hold a non-zero link; call after writing the planes. Also checks
  // every link is finite and >= 0 (InvalidArgument naming the link otherwise) and zeroes the
  // border links. OpenMP over tiles with `threads` (0: all cores).
  void finish(int threads = 0);

  // What finish() does, for a builder that checked its links and found the largest of each
  // tile (tile (tx, ty) at ty * tiles_x() + tx) while writing them.
  void set_activity(const std::vector<float>& horizontal_max,
                    const std::vector<float>& vertical_max);

  std::ptrdiff_t tiles_x() const { return tiles_x_; }
  std::ptrdiff_t tiles_y() const { return tiles_y_; }
  // Whether tile (tx, ty) holds a non-zero horizontal / vertical link.
  bool horizontal_active(std::ptrdiff_t tx, std::ptrdiff_t ty) const {
    return horizontal_active_[ty * tiles_x_ + tx] != 0;
  }
  bool vertical_active(std::ptrdiff_t tx, std::ptrdiff_t ty) const {
    return vertical_active_[ty * tiles_x_ + tx] != 0;
  }
  // Largest link value (after finish()).
  float max_link() const { return max_link_; }

 private:
  [[noreturn]] void throw_first_invalid_link() const;

  Image links_;  // plane 0: horizontal, plane 1: vertical
  std::ptrdiff_t tiles_x_ = 0, tiles_y_ = 0;
  std::vector<std::uint8_t> horizontal_active_, vertical_active_;
  float max_link_ = 0;
};

// Builds links from a per-pixel quantity: link(a, b) = min(to_link(value(a)), to_link(value(b))),
// a link limited by its less conductive end, so a pixel whose value maps to zero insulates
// itself on all four sides. `to_link` maps a value to a conductance (>= 0, finite).
template <class ToLink>
LinkField links_from_pixels(ConstPlane value, ToLink to_link, int threads = 0);

}  // namespace tridiff

#include "tridiff/diffusion/detail/links_impl.hpp"
