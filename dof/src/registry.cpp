// The registry of depth-of-field methods (one entry per method), and the checked frame that
// every method is run on (frame.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "tridiff/dof/method.hpp"
#include "tridiff/threads.hpp"
#include "frame.hpp"

namespace tridiff {
namespace dof_detail {
void run_adi(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_mpad(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_ipf(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_scatter(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_auto(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_poisson(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_pyramid_layers(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_sat(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_sat_layers(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_gems(Image&, const DofFrame&, const DofOptions&, DofReport&);
void run_bokeh(Image&, const DofFrame&, const DofOptions&, DofReport&);
}  // namespace dof_detail

namespace {

const DofMethod& registered_with(DofKernel kernel);
void refuse_unhonoured(const DofMethod& method, const DofOptions& settings);

// Every method runs through this. It refuses a CoC plane inside out (out is reallocated, or
// written, while the CoC is still read), checks and analyses the frame once (DofFrame), and
// runs the method on it (run_on_frame).
template <DofKernel Kernel>
DofReport checked(Image& out, const Image& color, ConstPlane coc, const DofOptions& settings) {
  if (!out.empty() && coc.data()) {
    const float* begin = out.data();
    const float* end = begin + out.plane_stride() * out.channels();
    if (coc.data() >= begin && coc.data() < end)
      throw InvalidArgument("coc", "lies in the output image (give a separate plane)");
  }
  refuse_unhonoured(registered_with(Kernel), settings);
  const DofFrame frame(color, coc, settings);
  DofReport report;
  // `auto` copies nothing itself: the method it chooses decides (run_on_frame).
  if (Kernel == dof_detail::run_auto)
    Kernel(out, frame, settings, report);
  else
    dof_detail::run_on_frame(registered_with(Kernel), out, frame, settings, report);
  return report;
}

// A registry entry: the method's description, run through `checked`.
template <DofKernel Kernel>
constexpr DofMethod method(DofMethod description) {
  description.run = checked<Kernel>;
  description.kernel = Kernel;
  return description;
}

constexpr std::array kMethods{
    method<dof_detail::run_adi>(
        {.name = "adi",
         .summary = "implicit heat diffusion, one ADI step of tridiagonal solves (seed 000 §3.5)",
         .blurs_foreground = false,
         .unbounded_blur = true,
         .cost = "O(pixels), independent of the CoC",
         .keeps_sharp = true,
         .in_place = true,
         .honours_layers = true}),
    method<dof_detail::run_mpad>(
        {.name = "mpad",
         .summary = "multi-pass anisotropic diffusion, explicit steps (seed 000 §5.3.4)",
         .blurs_foreground = false,
         .unbounded_blur = false,
         .cost = "O(pixels x max CoC^2 / 8) steps",
         .keeps_sharp = true,
         .in_place = false,
         .honours_layers = true}),
    method<dof_detail::run_ipf>(
        {.name = "ipf",
         .summary = "Inverse Post Filter scatter, depth test, 8-bit registers (seed 004 §5)",
         .blurs_foreground = true,
         .unbounded_blur = false,
         .cost = "O(pixels x min(max |CoC|, 16)^2)",
         .keeps_sharp = false,
         .in_place = false}),
    method<dof_detail::run_scatter>(
        {.name = "scatter",
         .summary = "the slow reference: area-normalised anti-aliased CoC discs, depth layers",
         .blurs_foreground = true,
         .unbounded_blur = false,
         .cost = "O(pixels x CoC^2)",
         .keeps_sharp = true,
         .in_place = false,
         .shapes_bokeh = true,
         .boosts_highlights = true}),
    method<dof_detail::run_poisson>(
        {.name = "poisson",
         .summary = "Poisson-disc gather by the own CoC, blurred levels (seed 000 §5.3.3)",
         .blurs_foreground = false,
         .unbounded_blur = true,
         .cost = "O(pixels x 13..49 taps) + O(pixels) levels",
         .keeps_sharp = true,
         .in_place = false}),
    method<dof_detail::run_pyramid_layers>(
        {.name = "pyramid-layers",
         .summary = "CoC depth layers, quasi-convolution pyramids, over (seed 001 4.5)",
         .blurs_foreground = true,
         .unbounded_blur = true,
         .cost = "O(pixels x layers), layers ~ 2 log2(max |CoC|)",
         .keeps_sharp = false,
         .in_place = false}),
    method<dof_detail::run_sat>(
        {.name = "sat",
         .summary = "three boxes from a half-resolution summed-area table (seed 003)",
         .blurs_foreground = false,
         .unbounded_blur = true,
         .cost = "O(pixels), independent of the CoC",
         .keeps_sharp = true,
         .in_place = false}),
    method<dof_detail::run_sat_layers>(
        {.name = "sat-layers",
         .summary = "near over far summed-area tables normalised by coverage (seed 003)",
         .blurs_foreground = true,
         .unbounded_blur = true,
         .cost = "O(pixels), independent of the CoC",
         .keeps_sharp = false,
         .in_place = false}),
    method<dof_detail::run_gems>(
        {.name = "gems",
         .summary = "GPU Gems 3 ch. 28: blend of 3 blur levels, spread near CoC (seed 002)",
         .blurs_foreground = true,
         .unbounded_blur = false,
         .cost = "O(pixels x (1 + min(max |CoC|, 512) / 12))",
         .keeps_sharp = false,
         .in_place = false}),
    method<dof_detail::run_bokeh>(
        {.name = "bokeh",
         .summary = "adi's diffusion (1.25x its conductance) for the body, out-of-focus highlights "
                    "as shaped sprites (issue 26)",
         .blurs_foreground = false,
         .unbounded_blur = false,
         .cost = "O(pixels) + O(highlights x CoC^2)",
         .keeps_sharp = true,
         .in_place = false,
         .honours_layers = true,
         .shapes_bokeh = true,
         .boosts_highlights = true}),
    method<dof_detail::run_auto>(
        {.name = "auto",
         .summary = "the cheapest method whose measured error meets --psnr-budget (auto.hpp)",
         .blurs_foreground = false,
         .unbounded_blur = false,
         .cost = "the chosen method's",
         .keeps_sharp = false,
         .in_place = false,
         // It chooses among the methods that honour what is asked (choose_dof_method).
         .honours_layers = true,
         .shapes_bokeh = true,
         .boosts_highlights = true}),
};

}  // namespace

std::span<const DofMethod> dof_methods() { return kMethods; }

void validate_lens_character(const DofOptions& settings) {
  validate(settings.aperture);
  if (settings.aperture_image) validate_aperture_image(*settings.aperture_image);
  if (!(settings.highlight_threshold > 0))
    throw InvalidArgument("highlight_threshold", "must be > 0 (infinity: no highlights), got " +
                                                     std::to_string(settings.highlight_threshold));
  if (!(settings.highlight_gain >= 0) || !std::isfinite(settings.highlight_gain))
    throw InvalidArgument("highlight_gain", "must be finite and >= 0, got " +
                                                std::to_string(settings.highlight_gain));
}

bool honours_options(const DofMethod& method, const DofOptions& options) {
  const bool shaped = options.aperture_image || !options.aperture.is_circle();
  const bool highlights = std::isfinite(options.highlight_threshold) || options.highlight_gain != 1;
  return (!options.layers || method.honours_layers) && (!shaped || method.shapes_bokeh) &&
         (!highlights || method.boosts_highlights);
}

const DofMethod& find_dof_method(std::string_view name) {
  std::string known;
  for (const DofMethod& method : kMethods) {
    if (method.name == name) return method;
    known += (known.empty() ? "" : ", ") + std::string(method.name);
  }
  throw InvalidArgument("method",
                        "unknown method '" + std::string(name) + "' (known: " + known + ")");
}

namespace {

[[noreturn]] void bad_pixel(const char* what, std::ptrdiff_t x, std::ptrdiff_t y, int c) {
  throw InvalidArgument(what, "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")" +
                                  (c >= 0 ? ", channel " + std::to_string(c) : std::string()) +
                                  " is not finite");
}

// A fast pass (probe = sum of 0 * v is zero unless some v is NaN or infinite), then, only if
// it failed, a slow pass that names the first bad pixel.
void require_finite(ConstPlane plane, const char* what, int channel, int threads) {
  const int team = resolve_threads(threads);
  bool bad = false;
#pragma omp parallel for num_threads(team) schedule(static) reduction(|| : bad)
  for (std::ptrdiff_t y = 0; y < plane.height(); ++y) {
    const float* row = plane.row(y);
    float probe = 0;
#pragma omp simd reduction(+ : probe)
    for (std::ptrdiff_t x = 0; x < plane.width(); ++x) probe += 0.f * row[x];
    bad = bad || probe != 0;
  }
  if (!bad) return;
  for (std::ptrdiff_t y = 0; y < plane.height(); ++y)
    for (std::ptrdiff_t x = 0; x < plane.width(); ++x)
      if (!std::isfinite(plane(x, y))) bad_pixel(what, x, y, channel);
}

const DofMethod& registered_with(DofKernel kernel) {
  for (const DofMethod& method : kMethods)
    if (method.kernel == kernel) return method;
  throw std::logic_error("a DOF method kernel that is not registered");
}

// The registered names of the methods for which `honours` holds, comma-separated.
template <class Honours>
std::string methods_that(Honours honours) {
  std::string names;
  for (const DofMethod& method : kMethods)
    if (honours(method)) names += (names.empty() ? "" : ", ") + std::string(method.name);
  return names.empty() ? "none" : names;
}

// An option the method would ignore is refused, naming it and the methods that honour it.
void refuse_unhonoured(const DofMethod& method, const DofOptions& settings) {
  const auto refuse = [&](const char* option, const char* what, auto honours) {
    throw InvalidArgument(option, "method '" + std::string(method.name) + "' has no " + what +
                                      " (methods that do: " + methods_that(honours) + ")");
  };
  if (settings.layers && !method.honours_layers)
    refuse("layers", "near-field layer", [](const DofMethod& m) { return m.honours_layers; });
  validate_lens_character(settings);
  const auto shapes = [](const DofMethod& m) { return m.shapes_bokeh; };
  if (settings.aperture_image && !method.shapes_bokeh)
    refuse("aperture_image", "aperture shapes", shapes);
  if (!settings.aperture.is_circle() && !method.shapes_bokeh)
    refuse("aperture_blades", "aperture shapes", shapes);
  const auto boosts = [](const DofMethod& m) { return m.boosts_highlights; };
  if (std::isfinite(settings.highlight_threshold) && !method.boosts_highlights)
    refuse("highlight_threshold", "highlight treatment", boosts);
  if (settings.highlight_gain != 1 && !method.boosts_highlights)
    refuse("highlight_gain", "highlight treatment", boosts);
}

// The largest |v| of a plane that require_finite has passed.
float max_abs(ConstPlane plane, int threads) {
  float largest = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(max : largest)
  for (std::ptrdiff_t y = 0; y < plane.height(); ++y) {
    const float* row = plane.row(y);
    for (std::ptrdiff_t x = 0; x < plane.width(); ++x)
      largest = std::max(largest, std::abs(row[x]));
  }
  return largest;
}

}  // namespace

DofFrame::DofFrame(const Image& color, ConstPlane coc, const DofOptions& settings)
    : color_(&color), coc_(coc), threads_(1), focus_{sharp_below_px(settings.in_focus_coc_px)} {
  threads_ = resolve_threads(settings.threads);
  validate_dof_input(color, coc, threads_);
  max_abs_coc_ = max_abs(coc, threads_);
}

DofFrame::DofFrame(const DofFrame& frame, const Image& color) : DofFrame(frame) { color_ = &color; }

const TileMap& DofFrame::tiles() const {
  if (!tiles_)
    tiles_ = std::make_shared<const TileMap>(coc_, focus_.sharp_below, TileMap::kDefaultTile, 0,
                                             threads_);
  return *tiles_;
}

namespace dof_detail {

void run_on_frame(const DofMethod& method, Image& out, const DofFrame& frame,
                  const DofOptions& settings, DofReport& report) {
  if (method.in_place || &out != &frame.color()) return method.kernel(out, frame, settings, report);
  const Image input = frame.color();
  method.kernel(out, DofFrame(frame, input), settings, report);
}

}  // namespace dof_detail

void validate_dof_input(const Image& color, ConstPlane coc, int threads) {
  validate_coc(color, coc, threads);
  for (int c = 0; c < color.channels(); ++c) require_finite(color.plane(c), "color", c, threads);
}

void validate_coc(const Image& color, ConstPlane coc, int threads) {
  validate_coc_size(color, coc);
  require_finite(coc, "coc", -1, threads);
}

void validate_coc_size(const Image& color, ConstPlane coc) {
  if (coc.width() != color.width() || coc.height() != color.height())
    throw InvalidArgument("coc", "is " + std::to_string(coc.width()) + " x " +
                                     std::to_string(coc.height()) + ", the colour image is " +
                                     std::to_string(color.width()) + " x " +
                                     std::to_string(color.height()));
}

}  // namespace tridiff
