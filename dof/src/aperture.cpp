// The aperture shapes of aperture.hpp.
#include "tridiff/dof/aperture.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "aperture_boundary.hpp"
#include "tridiff/image/image.hpp"  // InvalidArgument

namespace tridiff {

void validate(const ApertureShape& shape) {
  if (shape.blades < 0 || shape.blades == 1 || shape.blades == 2)
    throw InvalidArgument("aperture_blades", "must be 0 (a circle) or at least 3, got " +
                                                 std::to_string(shape.blades));
  if (!(shape.roundness >= 0 && shape.roundness <= 1))
    throw InvalidArgument("aperture_roundness",
                          "must be in [0, 1], got " + std::to_string(shape.roundness));
  if (!std::isfinite(shape.rotation_deg))
    throw InvalidArgument("aperture_rotation", "must be finite");
}

void validate_aperture_image(const Image& kernel) {
  if (kernel.empty()) throw InvalidArgument("aperture_image", "is empty");
  bool any_light = false;
  const ConstPlane values = kernel.plane(0);
  for (std::ptrdiff_t y = 0; y < values.height(); ++y)
    for (std::ptrdiff_t x = 0; x < values.width(); ++x) {
      const float v = values(x, y);
      if (!std::isfinite(v) || v < 0)
        throw InvalidArgument("aperture_image",
                              "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is " +
                                  std::to_string(v) + "; expected a finite value >= 0");
      any_light = any_light || v > 0;
    }
  if (!any_light) throw InvalidArgument("aperture_image", "is zero everywhere (no light passes)");
}

float aperture_rim(const ApertureShape& shape, float theta) {
  if (shape.is_circle()) return 1.f;
  const float sector = 2 * std::numbers::pi_v<float> / float(shape.blades);
  // Corner 0 straight up (+v), turned anticlockwise by the rotation.
  const float corner =
      std::numbers::pi_v<float> / 2 + shape.rotation_deg * (std::numbers::pi_v<float> / 180);
  const float phi = theta - corner - sector * std::floor((theta - corner) / sector);
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
  if (r2 > 1) return false;
  if (shape.is_circle()) return true;
  const float rim = aperture_rim(shape, std::atan2(v, u));
  return r2 <= rim * rim;
}

}  // namespace tridiff
