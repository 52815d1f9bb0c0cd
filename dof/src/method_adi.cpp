// The `adi` method: one ADI step of implicit heat diffusion with conductances from the CoC
// (seed 000 §3.5, §5.3.5; Kass, Lefohn & Owens 2006). Any blur size at the same cost.
#include "diffusion_dof.hpp"
#include "tridiff/diffusion/adi.hpp"

namespace tridiff::dof_detail {

void run_adi(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  diffusion_dof(out, frame, settings, report,
                [](Image& dst, const Image& src, ConstPlane coc, float in_focus_px,
                   const DiffusionOptions& options) {
                  return diffuse_adi(dst, src, coc, CocConductance{in_focus_px}, options);
                });
}

}  // namespace tridiff::dof_detail
