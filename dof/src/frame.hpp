// The frame a depth-of-field method works on, checked and analysed once (issue 22): the
// registry builds it before any method runs (registry.cpp), and `auto` hands the one it chose
// with to the method it chose. Private to dof/src.
#pragma once

#include <memory>

#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"

namespace tridiff {

class DofFrame {
 public:
  // Checks that `coc` has the colour's size and that every value of both is finite
  // (InvalidArgument naming "coc" or "color", the pixel and the channel). Both are borrowed.
  DofFrame(const Image& color, ConstPlane coc, const DofOptions& settings);
  // The same analysis over `color`, a copy of frame.color() (same size and values).
  DofFrame(const DofFrame& frame, const Image& color);

  const Image& color() const { return *color_; }
  ConstPlane coc() const { return coc_; }
  std::ptrdiff_t width() const { return color_->width(); }
  std::ptrdiff_t height() const { return color_->height(); }
  int channels() const { return color_->channels(); }
  // DofOptions::threads resolved: at least 1.
  int threads() const { return threads_; }

  // Sharp or out of focus for the gather and scatter methods and the tiles below:
  // sharp_below_px(DofOptions::in_focus_coc_px).
  FocusTest focus() const { return focus_; }
  float sharp_below() const { return focus_.sharp_below; }
  // The largest |c| of the frame, sharp pixels included.
  float max_abs_coc() const { return max_abs_coc_; }

  // The classification in TileMap::kDefaultTile squares without a margin, made on first use
  // (the diffusion methods need none); whole-frame summaries below come from it. A method
  // whose filters reach beyond the discs makes its own TileMap with a margin, from focus().
  const TileMap& tiles() const;
  bool has_near() const { return tiles().has_near(); }
  bool has_far() const { return tiles().has_far(); }
  float max_radius() const { return tiles().max_radius(); }

 private:
  const Image* color_;
  ConstPlane coc_;
  int threads_;
  FocusTest focus_;
  float max_abs_coc_ = 0;
  mutable std::shared_ptr<const TileMap> tiles_;  // shared with a frame made over a copy
};

namespace dof_detail {

// Runs `method` on a frame already checked: what DofMethod::run does after checking, and what
// `auto` does with the method it chose. A method that cannot work in place is given a copy of
// the colour when out is the colour.
void run_on_frame(const DofMethod& method, Image& out, const DofFrame& frame,
                  const DofOptions& settings, DofReport& report);

}  // namespace dof_detail
}  // namespace tridiff
