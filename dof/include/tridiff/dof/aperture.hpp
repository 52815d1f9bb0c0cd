// The shape of a lens's aperture: what a defocused point of light becomes (its bokeh). A
// circle by default; a polygon of straight blades, rotated and rounded towards the circle, as
// the iris of a real lens stopped down.
#pragma once

namespace tridiff {

class Image;

struct ApertureShape {
  int blades = 0;          // 0: a circle; >= 3: a polygon of that many straight blades
  float rotation_deg = 0;  // the polygon's rotation, degrees counter-clockwise
  float roundness = 0;     // 0: straight blades; 1: a circle (the rim blends between the two)
  bool is_circle() const { return blades == 0 || roundness >= 1; }
};

// Throws InvalidArgument naming the option ("aperture_blades", "aperture_roundness",
// "aperture_rotation") for blades 1, 2 or < 0, roundness outside [0, 1], a rotation that is not
// finite.
void validate(const ApertureShape& shape);

// A custom aperture (DofOptions::aperture_image, its first channel is read): InvalidArgument
// naming "aperture_image" for an empty image, a value that is negative or not finite, or an
// image that is zero everywhere (no light would pass).
void validate_aperture_image(const Image& kernel);

// The aperture's rim at polar angle `theta` (radians, anticlockwise from +u), as a fraction of
// the circumscribed unit circle: 1 for a circle; for N blades a regular polygon inscribed in it
// with corner 0 straight up (+v) turned anticlockwise by rotation_deg, cos(pi/N) / cos(phi) with
// phi the angle from the nearest blade's middle; blended linearly with 1 by roundness.
float aperture_rim(const ApertureShape& shape, float theta);

// Whether (u, v), in units of the circumscribed circle's radius, lies inside the aperture.
bool inside(const ApertureShape& shape, float u, float v);

}  // namespace tridiff
