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

// The conductance of a pixel of CoC diameter |coc_px|: adi_beta_for_coc, or zero (the pixel
// insulates itself) when it is sharp by FocusTest{in_focus_px}. Links take the smaller of their
// two ends.
struct CocConductance {
  float in_focus_px;
  float operator()(float coc_px) const {
    return FocusTest{in_focus_px}.is_sharp(coc_px) ? 0.f : adi_beta_for_coc(std::abs(coc_px));
  }
};

// A diffusion operator: dst = diffuse(src) with the conductances CocConductance{in_focus_px}
// of the CoC plane `coc` (dst may be src). The frame is checked before (DofFrame), and so is
// every pixel's conductance (diffusion_dof): what the operator refuses beyond that it must name
// as the CoC's ("coc"), as a user who gave the CoC understands it.
using Diffuser = std::function<DiffusionReport(Image& dst, const Image& src, ConstPlane coc,
                                               float in_focus_px, const DiffusionOptions&)>;

// The links of CocConductance{in_focus_px} as a LinkField (for the explicit methods).
LinkField coc_links(ConstPlane coc, float in_focus_px, int threads);

void diffusion_dof(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report,
                   const Diffuser& diffuse);

}  // namespace tridiff::dof_detail
