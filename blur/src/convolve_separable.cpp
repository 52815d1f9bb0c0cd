// Method "separable" (seed 001 §3.3): the exact Gaussian as two 1D passes with the sampled,
// normalised kernel of gaussian_radius(sigma) (tail mass dropped <= 1e-7): a row pass into a
// small per-thread ring of rows, then the column pass (convolve_separable in kernels.cpp).
// O(pixels r), r ~ 5.3 sigma; the fastest exact method for small sigma.
#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/kernels.hpp"

namespace tridiff::blur_detail {

void run_convolve_separable(Plane out, ConstPlane in, const BlurOptions& options) {
  const std::vector<float> kernel = gaussian_kernel(options.sigma);
  convolve_separable(out, in, kernel, kernel, options.border, resolve_threads(options.threads));
}

}  // namespace tridiff::blur_detail
