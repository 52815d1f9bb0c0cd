// The registry of depth-of-field methods: one line per method.
#include <array>
#include <cmath>
#include <string>

#include "tridiff/dof/method.hpp"

namespace tridiff {
namespace dof_detail {
void run_adi(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_mpad(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_ipf(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_scatter(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_auto(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_poisson(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_pyramid_layers(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_sat(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_sat_layers(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
void run_gems(Image&, const Image&, ConstPlane, const DofSettings&, DofReport&);
}  // namespace dof_detail

namespace {

// Every method runs through this. It refuses a CoC plane inside out (out is reallocated, or
// written, while the CoC is still read), and gives a method that cannot work in place a copy
// of the colour when out is the colour (it would reallocate out before reading it). `auto`
// passes out == color on to the method it runs, whose own wrapper decides.
template <DofRun Run, bool kInPlace>
void checked(Image& out, const Image& color, ConstPlane coc, const DofSettings& settings,
             DofReport& report) {
  if (!out.empty() && coc.data()) {
    const float* begin = out.data();
    const float* end = begin + out.plane_stride() * out.channels();
    if (coc.data() >= begin && coc.data() < end)
      throw InvalidArgument("coc", -1, -1, "lies in the output image (give a separate plane)");
  }
  if (kInPlace || &out != &color) return Run(out, color, coc, settings, report);
  const Image input = color;
  Run(out, input, coc, settings, report);
}

constexpr std::array kMethods{
    DofMethod{"adi", "implicit heat diffusion, one ADI step of tridiagonal solves (seed 000 §3.5)",
              false, true, "O(pixels), independent of the CoC",
              checked<dof_detail::run_adi, true>, true, true},
    DofMethod{"mpad", "multi-pass anisotropic diffusion, explicit steps (seed 000 §5.3.4)",
              false, false, "O(pixels x max CoC^2 / 8) steps",
              checked<dof_detail::run_mpad, false>, true, false},
    DofMethod{"ipf", "Inverse Post Filter scatter, depth test, 8-bit registers (seed 004 §5)",
              true, false, "O(pixels x min(max |CoC|, 16)^2)",
              checked<dof_detail::run_ipf, false>, false, false},
    DofMethod{"scatter", "the slow reference: area-normalised anti-aliased CoC discs, depth layers",
              true, false, "O(pixels x CoC^2)", checked<dof_detail::run_scatter, false>, true,
              false},
    DofMethod{"poisson", "Poisson-disc gather by the own CoC, blurred levels (seed 000 §5.3.3)",
              false, true, "O(pixels x 13..49 taps) + O(pixels) levels",
              checked<dof_detail::run_poisson, false>, true, false},
    DofMethod{"pyramid-layers", "CoC depth layers, quasi-convolution pyramids, over (seed 001 4.5)",
              true, true, "O(pixels x layers), layers ~ 2 log2(max |CoC|)",
              checked<dof_detail::run_pyramid_layers, false>, false, false},
    DofMethod{"sat", "three boxes from a half-resolution summed-area table (seed 003)", false, true,
              "O(pixels), independent of the CoC", checked<dof_detail::run_sat, false>, true,
              false},
    DofMethod{"sat-layers", "near over far summed-area tables normalised by coverage (seed 003)",
              true, true, "O(pixels), independent of the CoC",
              checked<dof_detail::run_sat_layers, false>, false, false},
    DofMethod{"gems", "GPU Gems 3 ch. 28: blend of 3 blur levels, spread near CoC (seed 002)",
              true, false, "O(pixels x (1 + min(max |CoC|, 512) / 12))",
              checked<dof_detail::run_gems, false>, false, false},
    DofMethod{"auto", "the cheapest method whose measured error meets --psnr-budget (auto.hpp)",
              false, false, "the chosen method's", checked<dof_detail::run_auto, true>, false,
              false},
};

}  // namespace

std::span<const DofMethod> dof_methods() { return kMethods; }

const DofMethod& find_dof_method(std::string_view name) {
  std::string known;
  for (const DofMethod& method : kMethods) {
    if (method.name == name) return method;
    known += (known.empty() ? "" : ", ") + std::string(method.name);
  }
  throw InvalidArgument("method", -1, -1,
                        "unknown method '" + std::string(name) + "' (known: " + known + ")");
}

namespace {

[[noreturn]] void bad_pixel(const char* what, std::ptrdiff_t x, std::ptrdiff_t y, int c) {
  throw InvalidArgument(what, -1, -1,
                        "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")" +
                            (c >= 0 ? ", channel " + std::to_string(c) : std::string()) +
                            " is not finite");
}

// A fast pass (probe = sum of 0 * v is zero unless some v is NaN or infinite), then, only if
// it failed, a slow pass that names the first bad pixel.
void require_finite(ConstPlane plane, const char* what, int channel) {
  bool bad = false;
#pragma omp parallel for schedule(static) reduction(|| : bad)
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

}  // namespace

void validate_dof_input(const Image& color, ConstPlane coc) {
  validate_coc(color, coc);
  for (int c = 0; c < color.channels(); ++c) require_finite(color.plane(c), "color", c);
}

void validate_coc(const Image& color, ConstPlane coc) {
  validate_coc_size(color, coc);
  require_finite(coc, "coc", -1);
}

void validate_coc_size(const Image& color, ConstPlane coc) {
  if (coc.width() != color.width() || coc.height() != color.height())
    throw InvalidArgument("coc", -1, -1,
                          "is " + std::to_string(coc.width()) + " x " +
                              std::to_string(coc.height()) + ", the colour image is " +
                              std::to_string(color.width()) + " x " +
                              std::to_string(color.height()));
}

}  // namespace tridiff
