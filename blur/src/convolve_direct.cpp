// Method "direct" (seed 001 §3.2): the exact Gaussian as one 2D convolution with the 2D
// sampled Gaussian (the outer product of gaussian_kernel(sigma) with itself), every tap summed
// (convolve_2d in kernels.cpp). O(pixels r^2), r ~ 5.3 sigma: a reference point for what
// separation (method "separable") and the FFT save, not a method to use.
#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/kernels.hpp"

namespace tridiff::blur_detail {

void run_convolve_direct(Plane out, ConstPlane in, const BlurOptions& options) {
  convolve_2d(out, in, gaussian_kernel_2d(options.sigma), options.border,
              resolve_threads(options.threads));
}

}  // namespace tridiff::blur_detail
