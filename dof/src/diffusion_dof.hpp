// Depth of field by heat diffusion, shared by the `adi` and `mpad` methods: conductances from
// the CoC, and the optional near-field layer of Kass, Lefohn & Owens (2006).
#pragma once

#include <functional>

#include "tridiff/diffusion/adi.hpp"
#include "tridiff/diffusion/links.hpp"
#include "tridiff/dof/method.hpp"

namespace tridiff::dof_detail {

// A diffusion operator: dst = diffuse(src) with link conductances beta (dst may be src). It
// must reject non-finite values of src (diffuse_adi does as it solves and copies; explicit
// methods check src first).
using Diffuser = std::function<DiffusionReport(Image& dst, const Image& src,
                                               const LinkField& beta, const DiffusionOptions&)>;

// Links beta = min over the two pixels of adi_beta_for_coc(|CoC|); pixels with |CoC| below
// `in_focus_px` count as sharp (CoC 0) and insulate themselves.
LinkField coc_links(ConstPlane coc, float in_focus_px, int threads);

void diffusion_dof(Image& out, const Image& color, ConstPlane coc, const DofSettings& settings,
                   DofReport& report, const Diffuser& diffuse);

}  // namespace tridiff::dof_detail
