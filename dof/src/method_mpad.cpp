// The `mpad` method: multi-pass anisotropic diffusion (seed 000 §5.3.4, eq. 5.4, appendix B),
// explicit steps with a conductance per link. It targets the same blur as `adi` (the same
// links diffused for unit time); the step count grows with the largest CoC squared, as the
// stability bound of the explicit step demands (diffuse_explicit sub-steps).
#include "diffusion_dof.hpp"
#include "tridiff/diffusion/explicit.hpp"

namespace tridiff::dof_detail {

void run_mpad(Image& out, const Image& color, ConstPlane coc, const DofSettings& settings,
              DofReport& report) {
  int steps = 0;
  diffusion_dof(out, color, coc, settings, report,
                [&steps](Image& dst, const Image& src, ConstPlane coc, float in_focus_px,
                         const DiffusionOptions& options) {
                  const LinkField beta = coc_links(coc, in_focus_px, options.threads);
                  int taken = 0;
                  DiffusionReport r = diffuse_explicit(dst, src, beta, options, &taken);
                  steps = std::max(steps, taken);
                  return r;
                });
  report.explicit_steps = steps;
}

}  // namespace tridiff::dof_detail
