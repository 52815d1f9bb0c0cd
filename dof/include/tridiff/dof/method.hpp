// Depth-of-field methods and their registry: every method is registered once (name, what it
// handles, its cost) so that the command line, the tests and the benchmarks enumerate the same
// list. Adding a method is one new file (its DofKernel), one entry in registry.cpp's kMethods
// (with the kernel's declaration beside the others) and one line in dof/CMakeLists.txt; the
// registry checks and analyses the frame for it.
#pragma once

#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tridiff/dof/aperture.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct DofOptions {
  int threads = 0;                // 0: all cores
  bool skip_in_focus = true;      // false: every pixel takes the full path (the reference)
  bool layers = false;            // blur the near field as its own layer (Kass et al. 2006)
  float in_focus_coc_px = 1.f;    // |CoC| below this (a sub-pixel blur) counts as sharp
  double error_budget_psnr = 30;  // `auto`: the least PSNR (dB) to accept (auto.hpp: against
                                  // the thin-lens truth, or scatter where a scene has none)
  // Lens character, for the methods that shape their bokeh (DofMethod::shapes_bokeh; the others
  // refuse a shape other than the circle, or a kernel image, rather than ignore it).
  ApertureShape aperture;
  // A custom aperture (one channel, any size; overrides `aperture`): a point of light takes
  // this picture, scaled to its CoC diameter. Empty: the shape above.
  std::shared_ptr<const Image> aperture_image;
  // Highlights, in linear light, for the methods that treat them (DofMethod::boosts_highlights):
  // a pixel whose largest channel exceeds the threshold is a highlight; its excess over the
  // threshold is multiplied by the gain. The default threshold (infinity) treats none.
  float highlight_threshold = std::numeric_limits<float>::infinity();
  float highlight_gain = 1.f;
  std::function<void(double)> progress;  // fraction done, 0..1; may be empty
};

struct DofStage {
  std::string name;
  double seconds = 0;
};

struct DofReport {
  std::vector<DofStage> stages;
  double skipped_fraction = 0;  // of the per-pixel work of the diffusion passes
  int explicit_steps = 0;       // explicit methods: forward-Euler steps taken
  bool layered = false;         // whether the near field was blurred as its own layer
  std::string chosen_method;    // `auto`: the method it ran
  std::string notes;
};

// out = `color` (linear light, any channel count) with depth of field for the signed CoC
// diameters `coc` (pixels; negative in front of the focus). out is reallocated as needed. out
// may be color itself (see DofMethod::in_place); coc must not lie in out (InvalidArgument).
using DofRun = DofReport (*)(Image& out, const Image& color, ConstPlane coc,
                             const DofOptions& options);

// What a method implements: the same, on a frame that the registry has checked and analysed
// once (dof/src/frame.hpp, library-internal). `run` builds the frame and calls this.
class DofFrame;
using DofKernel = void (*)(Image& out, const DofFrame& frame, const DofOptions&, DofReport&);

struct DofMethod {
  std::string_view name;
  std::string_view summary;
  bool blurs_foreground = false;  // the near field's blur spreads over what lies behind it
                                  // (for the diffusion methods: with layers)
  bool unbounded_blur = false;    // any CoC at the same cost per pixel
  std::string_view cost;          // how the work grows
  DofRun run = nullptr;
  // A sharp pixel that the reference leaves unchanged (no nearer blur covers it) keeps its input
  // value bit for bit: the method never blurs what is in focus (tests/dof_quality_test.cpp).
  bool keeps_sharp = false;
  // Whether the method works where the image lies when out is color: the pixels it skips
  // (tiles in focus) then cost nothing at all. The others are given a copy of the colour.
  bool in_place = false;
  // Which of DofOptions' optional treatments the method honours; the registry refuses the
  // others (InvalidArgument naming the option) rather than ignore them silently.
  bool honours_layers = false;     // DofOptions::layers
  bool shapes_bokeh = false;       // DofOptions::aperture and aperture_image
  bool boosts_highlights = false;  // DofOptions::highlight_threshold and highlight_gain
  DofKernel kernel = nullptr;
};

// out = `color` with depth of field by `method`: method.run, the one way to call any method.
inline DofReport depth_of_field(Image& out, const Image& color, ConstPlane coc,
                                const DofMethod& method, const DofOptions& options = {}) {
  return method.run(out, color, coc, options);
}

// Checks DofOptions' lens character before any work: the aperture (validate), the kernel image
// (validate_aperture_image), highlight_threshold > 0 and highlight_gain finite and >= 0;
// InvalidArgument naming the field. Every method's `run` checks it too.
void validate_lens_character(const DofOptions& options);

// Whether `method` honours every optional treatment that `options` asks for (layers, an
// aperture shape, highlights); `run` refuses the options it would ignore.
bool honours_options(const DofMethod& method, const DofOptions& options);

// Every registered method, in a fixed order.
std::span<const DofMethod> dof_methods();
// The method called `name`; InvalidArgument listing the known names otherwise.
const DofMethod& find_dof_method(std::string_view name);

// Checks colour and CoC before a method runs: same size, every value finite (InvalidArgument
// naming the pixel and channel otherwise). Every registered method's `run` does this once,
// before the method; validate_coc checks the sizes and the CoC only, validate_coc_size the
// sizes alone.
// `threads`: 0 = all cores.
void validate_dof_input(const Image& color, ConstPlane coc, int threads = 0);
void validate_coc(const Image& color, ConstPlane coc, int threads = 0);
void validate_coc_size(const Image& color, ConstPlane coc);

}  // namespace tridiff
