// The aperture shape of aperture.hpp: its boundary as a radius per direction.
#include "tridiff/dof/aperture.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "aperture_boundary.hpp"
#include "tridiff/solvers/error.hpp"

namespace tridiff {

void validate(const ApertureShape& shape) {
  if (shape.blades < 0 || shape.blades == 1 || shape.blades == 2)
    throw InvalidArgument("aperture-blades",
                          "must be 0 (a circle) or >= 3, got " + std::to_string(shape.blades));
  if (!(shape.roundness >= 0 && shape.roundness <= 1))
    throw InvalidArgument("aperture-roundness",
                          "must lie in [0, 1], got " + std::to_string(shape.roundness));
  if (!std::isfinite(shape.rotation_deg))
    throw InvalidArgument("aperture-rotation",
                          "must be finite, got " + std::to_string(shape.rotation_deg));
}

float aperture_radius(const ApertureShape& shape, float angle) {
  if (shape.blades == 0) return 1.f;
  const float sector = 2 * std::numbers::pi_v<float> / float(shape.blades);
  const float corner =
      std::numbers::pi_v<float> / 2 + shape.rotation_deg * std::numbers::pi_v<float> / 180;
  const float phi = angle - corner - sector * std::floor((angle - corner) / sector);
  return aperture_radius_in_sector(shape, phi);
}

float aperture_radius_in_sector(const ApertureShape& shape, float phi) {
  // The edge between two corners on the unit circle lies at the inradius cos(pi / N).
  const float half = std::numbers::pi_v<float> / float(shape.blades);
  const float polygon = std::cos(half) / std::cos(phi - half);
  return (1 - shape.roundness) * polygon + shape.roundness;
}

bool inside(const ApertureShape& shape, float u, float v) {
  const float r2 = u * u + v * v;
  if (shape.blades == 0) return r2 <= 1;
  const float boundary = aperture_radius(shape, std::atan2(v, u));
  return r2 <= boundary * boundary;
}

}  // namespace tridiff
