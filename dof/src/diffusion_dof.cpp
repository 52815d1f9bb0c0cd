// Depth of field by diffusion: one pass over the whole frame, or (with layers) the near field
// blurred on its own and composited over a background whose hidden parts are filled in.
#include "diffusion_dof.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "tridiff/solvers/solve.hpp"
#include "stage_clock.hpp"

namespace tridiff::dof_detail {
namespace {

// Adds the time `work` takes to the report as a stage called `name`.
template <class Work>
auto timed(DofReport& report, const char* name, Work&& work) {
  struct Record {
    DofReport& report;
    const char* name;
    StageClock::time_point start;
    ~Record() { report.stages.push_back({name, seconds_since(start)}); }
  } record{report, name, StageClock::now()};
  return work();
}

// Normalised diffusion ("push-pull" by heat): diffuses value*weight and weight, then returns
// the ratio where weight is zero and the value itself elsewhere. Fills holes (weight 0) with
// a smooth average of the surrounding known values. planes: value channels then the weight.
void fill_holes(Image& premultiplied, const Image& original, float fill_beta, int threads) {
  const int values = premultiplied.channels() - 1;
  DiffusionOptions options;
  options.threads = threads;
  Image diffused;
  const ConstPlane any_plane = premultiplied.plane(0);  // the conductance is uniform
  diffuse_adi(diffused, premultiplied, any_plane, [fill_beta](float) { return fill_beta; },
              options);
  const ConstPlane known = premultiplied.plane(values), spread = diffused.plane(values);
  for (int c = 0; c < values; ++c) {
    Plane out = premultiplied.plane(c);
    const ConstPlane sum = diffused.plane(c), fallback = original.plane(c);
    for (std::ptrdiff_t y = 0; y < out.height(); ++y)
      for (std::ptrdiff_t x = 0; x < out.width(); ++x) {
        if (known(x, y) > 0.5f) {
          out(x, y) = fallback(x, y);
        } else {
          // Far inside a hole the weight can underflow: keep the original value there.
          const float w = spread(x, y);
          out(x, y) = w > 1e-30f ? sum(x, y) / w : fallback(x, y);
        }
      }
  }
}

bool has_near_blur(ConstPlane coc, float in_focus_px) {
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x)
      if (coc(x, y) <= -in_focus_px) return true;
  return false;
}

float max_abs(ConstPlane plane) {
  float largest = 0;
  for (std::ptrdiff_t y = 0; y < plane.height(); ++y)
    for (std::ptrdiff_t x = 0; x < plane.width(); ++x)
      largest = std::max(largest, std::abs(plane(x, y)));
  return largest;
}

void layered_dof(Image& out, const Image& color, ConstPlane coc, const DofSettings& settings,
                 DofReport& report, const Diffuser& diffuse, const DiffusionOptions& options) {
  const std::ptrdiff_t width = color.width(), height = color.height();
  const int channels = color.channels();
  const float fill_beta = adi_beta_for_coc(max_abs(coc));
  DiffusionReport diffusion;  // of the two blurs (the fills are always solved in full)
  auto is_near = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
    return coc(x, y) <= -settings.in_focus_coc_px;
  };

  // Background: the near field cut out and its hole filled from around it, CoC included.
  Image background(width, height, channels + 2), original(width, height, channels + 2);
  timed(report, "background fill", [&] {
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        const float keep = is_near(x, y) ? 0.f : 1.f;
        for (int c = 0; c < channels; ++c) original(x, y, c) = color(x, y, c);
        original(x, y, channels) = std::abs(coc(x, y));
        for (int c = 0; c <= channels; ++c) background(x, y, c) = keep * original(x, y, c);
        background(x, y, channels + 1) = keep;
      }
    fill_holes(background, original, fill_beta, settings.threads);
  });
  Image background_blur(width, height, channels);
  timed(report, "background blur", [&] {
    Image colour_only(width, height, channels);
    for (int c = 0; c < channels; ++c) copy_plane(background.plane(c), colour_only.plane(c));
    diffusion += diffuse(background_blur, colour_only, background.plane(channels),
                         settings.in_focus_coc_px, options);
  });

  // Near field: premultiplied colour and coverage, spreading out with its own CoC.
  Image near_layer(width, height, channels + 1);
  timed(report, "near blur", [&] {
    Image near_coc(width, height, 2), near_coc_original(width, height, 2);
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        const float inside = is_near(x, y) ? 1.f : 0.f;
        near_coc(x, y, 0) = inside * std::abs(coc(x, y));
        near_coc(x, y, 1) = inside;
        near_coc_original(x, y, 0) = std::abs(coc(x, y));
        for (int c = 0; c < channels; ++c) near_layer(x, y, c) = inside * color(x, y, c);
        near_layer(x, y, channels) = inside;
      }
    fill_holes(near_coc, near_coc_original, fill_beta, settings.threads);
    diffusion +=
        diffuse(near_layer, near_layer, near_coc.plane(0), settings.in_focus_coc_px, options);
  });

  timed(report, "composite", [&] {
    out.reset(width, height, channels);
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        const float coverage = std::clamp(near_layer(x, y, channels), 0.f, 1.f);
        for (int c = 0; c < channels; ++c)
          out(x, y, c) = near_layer(x, y, c) + (1.f - coverage) * background_blur(x, y, c);
      }
  });
  report.layered = true;
  report.skipped_fraction = diffusion.skipped_fraction();
}

}  // namespace

LinkField coc_links(ConstPlane coc, float in_focus_px, int threads) {
  return links_from_pixels(coc, CocConductance{in_focus_px}, threads);
}

void diffusion_dof(Image& out, const Image& color, ConstPlane coc, const DofSettings& settings,
                   DofReport& report, const Diffuser& diffuse) {
  DiffusionOptions options;
  options.threads = settings.threads;
  options.skip_inactive = settings.skip_in_focus;
  options.progress = settings.progress;
  if (settings.layers && has_near_blur(coc, settings.in_focus_coc_px)) {
    validate_dof_input(color, coc);
    return layered_dof(out, color, coc, settings, report, diffuse, options);
  }
  // The colour is checked by the diffuser where it passes (see Diffuser), and so is the CoC:
  // a CoC that is not finite has no finite conductance, which the diffuser refuses before it
  // writes anything. Its error names the diffuser's argument ("value"); it is named here as
  // the CoC's, as every method names it.
  validate_coc_size(color, coc);
  const DiffusionReport diffusion = timed(report, "diffusion", [&] {
    try {
      return diffuse(out, color, coc, settings.in_focus_coc_px, options);
    } catch (const InvalidArgument& error) {
      if (error.argument() != "value") throw;
      validate_coc(color, coc);  // names a CoC pixel that is not finite
      // A finite CoC whose conductance is not (|CoC| above about 1e19 px).
      throw InvalidArgument("coc", error.system(), error.row(), error.message());
    }
  });
  report.skipped_fraction = diffusion.skipped_fraction();
}

}  // namespace tridiff::dof_detail
