// Explicit heat diffusion: the isotropic Laplacian iteration of seed 001 §3.9 (eq. 3.21) and
// the multi-pass anisotropic diffusion (MPAD) of seed 000 §5.3.4 (eq. 5.4, appendix B), which
// is the same forward-Euler step with a conductance per link.
#pragma once

#include "tridiff/diffusion/adi.hpp"
#include "tridiff/diffusion/links.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

// Forward Euler is stable (and a convex combination: no new extrema) when the conductances
// of the four links of every pixel sum to at most 1; a bound of 1/4 per link (seed 001 §3.9:
// c in (0, 0.25]; seed 000 eq. 5.4 uses 0.25 g with g <= 1) guarantees it.
inline constexpr float kExplicitStabilityBound = 0.25f;

// `steps` forward-Euler steps of I += sum over links kappa (I_neighbour - I), kappa the
// per-step link conductance. Throws InvalidArgument if a link exceeds
// kExplicitStabilityBound — never a silent blow-up — or if src is not finite (naming the
// pixel). dst may be src.
DiffusionReport diffuse_explicit_steps(Image& dst, const Image& src, const LinkField& kappa,
                                       int steps, const DiffusionOptions& options = {});

// Diffuses for unit time with link conductances beta (the same field an ADI step takes) by
// sub-stepping: steps = ceil(max beta / 0.25), kappa = beta / steps. Per axis the variance
// grows by 2 beta, like one ADI step, so with adi_beta_for_coc it targets the same blur.
// Returns the steps taken in `steps_taken` (if not null).
DiffusionReport diffuse_explicit(Image& dst, const Image& src, const LinkField& beta,
                                 const DiffusionOptions& options = {}, int* steps_taken = nullptr);

// Isotropic diffusion, seed 001 eq. 3.21: `iterations` steps with constant conductance c in
// (0, 0.25] (InvalidArgument otherwise), insulated borders. The Gaussian it approximates has
// sigma^2 = 2 c iterations.
void diffuse_isotropic(Image& dst, const Image& src, float c, int iterations,
                       const DiffusionOptions& options = {});

// Iterations for a target sigma at conductance c: ceil(sigma^2 / (2 c)). Seed 000 eq. 5.5 gives
// N = sigma^2 / (2 sqrt 2) at c = 0.25, which is 4 sqrt 2 (about 5.7) times fewer: it holds if
// its sigma is a kernel width of about 2.4 standard deviations (see the tests).
int isotropic_iterations_for_sigma(float sigma, float c = kExplicitStabilityBound);

}  // namespace tridiff
