// Which pixels the diffusion methods blur as their own near layer (DofOptions::layers; Kass,
// Lefohn & Owens 2006), following the scene's depth rather than a fixed CoC.
//
// The near layer is blurred on its own and composited over the rest, so its blur spreads over
// what lies behind it; inside a layer the smaller conductance of two neighbours rules, which
// keeps a strongly blurred object's silhouette sharp over a less blurred one beside it. Were
// every pixel in front of the focus (CoC <= -1 px) in the near layer, a subject just in front
// of the focus (CoC -1 ... -5 px) would share it with a blurred object nearer still, and that
// object's edge would stay razor sharp over the subject (issue 26). So the near field is split
// where its depths part: by Otsu's threshold (the split that maximises the variance between
// the two classes) on log2 |CoC| of the near field's pixels, which is a split in depth (the CoC
// is affine in 1 / depth). What lies in front of the split is the near layer; the near pixels
// behind it stay with the background and blur there with their own, smaller, CoC. A near field
// whose |CoC| spans less than an octave is one depth: all of it is the near layer.
#pragma once

#include "tridiff/dof/tiles.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct NearLayer {
  FocusTest focus;     // near: c <= -focus.sharp_below
  float split_px = 0;  // the near layer: c <= -split_px (split_px >= focus.sharp_below)
  bool empty = true;   // no pixel is near: there is nothing to blur as a layer
  bool contains(float coc_px) const { return focus.is_near(coc_px) && -coc_px >= split_px; }
};

// The near layer of a CoC map (finite values) at the in-focus threshold `in_focus_coc_px` (as
// DofOptions::in_focus_coc_px: FocusTest{in_focus_coc_px}). threads: 0 = all cores.
NearLayer near_layer(ConstPlane coc, float in_focus_coc_px, int threads = 0);

}  // namespace tridiff
