// The `mpad` method: multi-pass anisotropic diffusion (seed 000 §5.3.4, eq. 5.4, appendix B),
// explicit steps with a conductance per link. It targets the same blur as `adi` (the same
// links diffused for unit time); the step count grows with the largest CoC squared, as the
// stability bound of the explicit step demands (diffuse_explicit sub-steps).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "diffusion_dof.hpp"
#include "tridiff/diffusion/explicit.hpp"

namespace tridiff::dof_detail {
namespace {

// The explicit scheme takes a sub-step per kExplicitStabilityBound of the largest link
// (diffuse_explicit); the links come from the CoC, so a CoC that needs more steps than allowed
// is refused as the CoC's, before any work.
void require_steppable(const LinkField& beta, const DiffusionOptions& options) {
  const double steps = std::max(1.0, std::ceil(double(beta.max_link()) / kExplicitStabilityBound));
  if (steps <= options.max_explicit_steps) return;
  std::ostringstream message;
  message << "the largest conductance " << beta.max_link() << " needs " << steps
          << " explicit steps, more than the " << options.max_explicit_steps
          << " allowed (DiffusionOptions::max_explicit_steps); an implicit (ADI) step blurs "
             "this far in one";
  throw InvalidArgument("coc", message.str());
}

}  // namespace

void run_mpad(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  int steps = 0;
  diffusion_dof(out, frame, settings, report,
                [&steps](Image& dst, const Image& src, ConstPlane coc,
                         const CocConductance& conductance, const DiffusionOptions& options) {
                  const LinkField beta = coc_links(coc, conductance, options.threads);
                  require_steppable(beta, options);
                  int taken = 0;
                  DiffusionReport r = diffuse_explicit(dst, src, beta, options, &taken);
                  steps = std::max(steps, taken);
                  return r;
                });
  report.explicit_steps = steps;
}

}  // namespace tridiff::dof_detail
