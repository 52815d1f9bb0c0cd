// The boundary of an aperture shape (aperture.hpp) as a radius per direction: what inside() tests
// and what the aperture sampler (truth.cpp) integrates. Library-internal.
#pragma once

#include "tridiff/dof/aperture.hpp"

namespace tridiff {

// The boundary's distance from the centre in the direction `angle` (radians, anticlockwise from
// +u), in units of the circle's radius. A polygon's is 1 at a corner, cos(pi / N) mid-edge.
float aperture_radius(const ApertureShape& shape, float angle);

// The same for a polygon (blades >= 3) at `phi` in [0, 2 pi / N) past a corner: every sector
// between two corners is the same.
float aperture_radius_in_sector(const ApertureShape& shape, float phi);

}  // namespace tridiff
