// The boundary of an aperture shape (aperture.hpp) as a radius per direction: what inside() tests
// and what the aperture sampler (truth.cpp) integrates. Library-internal.
#pragma once

#include "tridiff/dof/aperture.hpp"

namespace tridiff {

// The boundary's distance from the centre (aperture_rim) for a polygon (blades >= 3) at `phi` in
// [0, 2 pi / N) past a corner: every sector between two corners is the same.
float aperture_radius_in_sector(const ApertureShape& shape, float phi);

}  // namespace tridiff
