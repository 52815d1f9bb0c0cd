// The `adi` method: one step of implicit heat diffusion with conductances from the CoC (seed 000
// §3.5, §5.3.5; Kass, Lefohn & Owens 2006), any blur size at the same cost. The step is
// diffuse_isotropic: the ADI step (rows, then columns) with half the conductance and the same
// solves along both diagonals with a quarter. One ADI step alone turns a point of light into a
// diamond with streaks along the rows and columns (its impulse response is a product of two
// exponentials); the four passes make it round for twice the work (issue 26).
#include "diffusion_dof.hpp"
#include "tridiff/diffusion/adi.hpp"

namespace tridiff::dof_detail {

void run_adi_spread(Image& out, const DofFrame& frame, const DofOptions& settings,
                    DofReport& report, float spread) {
  diffusion_dof(
      out, frame, settings, report,
      [](Image& dst, const Image& src, ConstPlane coc, const CocConductance& conductance,
         const DiffusionOptions& options) {
        return diffuse_isotropic(dst, src, coc, conductance, options);
      },
      spread);
}

void run_adi(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  run_adi_spread(out, frame, settings, report, 1.f);
}

}  // namespace tridiff::dof_detail
