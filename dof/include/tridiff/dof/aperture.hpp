// The shape of a lens's aperture: a circle, or a polygon of N blades whose corners can be rounded
// towards the circle. Shared by what renders through a lens (truth.hpp) and the bokeh kernels.
#pragma once

namespace tridiff {

// blades 0: a circle. blades >= 3: a regular polygon inscribed in the unit circle (its corners on
// it), one corner straight up (+v) turned anticlockwise by rotation_deg; roundness blends the
// polygon's boundary radius linearly into the circle's (0: the polygon, 1: the circle).
struct ApertureShape {
  int blades = 0;
  float rotation_deg = 0;
  float roundness = 0;
};

// InvalidArgument("aperture-blades" | "aperture-roundness" | "aperture-rotation", message) for
// blades < 0 or 1-2, roundness outside [0, 1], a rotation that is not finite.
void validate(const ApertureShape& shape);

// Whether (u, v), in the coordinates of the unit disc (u right, v up), lies in the aperture.
bool inside(const ApertureShape& shape, float u, float v);

}  // namespace tridiff
