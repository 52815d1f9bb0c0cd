// Depth of field by heat diffusion, shared by the `adi` and `mpad` methods: conductances from
// the CoC, and the optional near-field layer of Kass, Lefohn & Owens (2006).
#pragma once

#include <cmath>
#include <functional>

#include "tridiff/diffusion/adi.hpp"
#include "tridiff/diffusion/links.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"

namespace tridiff::dof_detail {

// The conductance of a pixel of CoC diameter |coc_px|: `spread` times adi_beta_for_coc (the
// beta whose blur has the disc's variance), or zero (the pixel insulates itself) when it is
// sharp by FocusTest{in_focus_px}. Links take the smaller of their two ends.
struct CocConductance {
  float in_focus_px;
  float spread = 1.f;
  float operator()(float coc_px) const {
    return FocusTest{in_focus_px}.is_sharp(coc_px) ? 0.f
                                                   : spread * adi_beta_for_coc(std::abs(coc_px));
  }
};

// A diffusion operator: dst = diffuse(src) with the conductances `conductance` gives the CoC
// plane `coc` (dst may be src). The frame is checked before (DofFrame), and so is
// every pixel's conductance (diffusion_dof): what the operator refuses beyond that it must name
// as the CoC's ("coc"), as a user who gave the CoC understands it. A diffuser may add stages of
// its own to the report diffusion_dof was given; the stage that runs it then counts the rest.
using Diffuser =
    std::function<DiffusionReport(Image& dst, const Image& src, ConstPlane coc,
                                  const CocConductance& conductance, const DiffusionOptions&)>;

// Throws InvalidArgument("coc") naming the first pixel whose conductance is not finite (a
// finite CoC above about 1.8e19 px has none). diffusion_dof checks it first; a method that
// writes to `out` before calling diffusion_dof checks it before that.
void require_finite_conductance(const DofFrame& frame, const CocConductance& conductance);

// The links of `conductance` as a LinkField (for the explicit methods).
LinkField coc_links(ConstPlane coc, const CocConductance& conductance, int threads);

// Depth of field by `diffuse`, with CocConductance{settings.in_focus_coc_px, spread}; with
// layers, the near layer by `diffuse_near` if given (else by `diffuse` too).
void diffusion_dof(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report,
                   const Diffuser& diffuse, float spread = 1.f,
                   const Diffuser* diffuse_near = nullptr);

// The `adi` method's diffusion (method_adi.cpp) with its conductances times `spread`; run_adi
// is spread 1.
void run_adi_spread(Image& out, const DofFrame& frame, const DofOptions& settings,
                    DofReport& report, float spread);
void run_adi(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report);

}  // namespace tridiff::dof_detail
