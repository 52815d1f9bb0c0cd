// A built-in procedural scene (colour and depth), so that depth of field can be shown and
// measured with nothing to download: textured surfaces at several depths, a foreground
// object, and bright highlights.
#pragma once

#include "tridiff/dof/lens.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct Scene {
  Image color;    // linear light, RGB; highlights exceed 1
  Image depth;    // distance along the optical axis, metres, one channel
  ThinLens lens;  // the camera the scene was rendered for (focus on the central sphere)
};

// Renders the scene at width x height (2 x 2 samples per pixel for colour; depth from the
// pixel centre). A pinhole camera with the lens's focal length and sensor width.
Scene procedural_scene(std::ptrdiff_t width, std::ptrdiff_t height, int threads = 0);

}  // namespace tridiff
