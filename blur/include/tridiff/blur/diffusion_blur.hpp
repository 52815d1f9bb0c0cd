// Heat diffusion as a Gaussian blur (seed 001 §3.9). Diffusing for time t spreads every axis by
// variance 2t, so both discretisations below have exactly variance sigma^2 per axis; their
// kernels approach the Gaussian as the step count grows. Borders are insulated (Border::mirror).
#pragma once

#include "tridiff/image/image.hpp"

namespace tridiff {

// Forward-Euler steps: N = ceil(2 sigma^2) steps of conductance c = sigma^2 / (2 N) <= 1/4
// (the stability bound), through diffuse_isotropic. Cost O(pixels sigma^2).
int explicit_diffusion_steps(double sigma);
void explicit_diffusion_blur(Plane out, ConstPlane in, double sigma, int threads = 0);

// `steps` ADI steps (one tridiagonal solve per row and per column each) of conductance
// beta = sigma^2 / (2 steps), through diffuse_adi. Stable for every sigma; cost O(pixels steps).
void implicit_diffusion_blur(Plane out, ConstPlane in, double sigma, int steps, int threads = 0);

}  // namespace tridiff
