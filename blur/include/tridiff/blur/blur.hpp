// Blur methods on image planes, each registered once: the exact Gaussian convolutions and the
// approximations of seeds 000, 001 and 003 (pyramids, polynomial spreading, reshuffling,
// repeated boxes, summed-area tables, diffusion) and a recursive (IIR) Gaussian. Every method
// takes a target Gaussian sigma; approximations state how far from that Gaussian they are.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>

#include "tridiff/image/image.hpp"
#include "tridiff/threads.hpp"

namespace tridiff {

// What lies beyond the image edge. replicate: the edge pixel repeats (clamp); mirror: the image
// is reflected about its edge, the edge pixel repeated (d c b a | a b c d: the insulated border
// of diffusion); zero: black; periodic: the image repeats (what a plain FFT does).
enum class Border { replicate, mirror, zero, periodic };

std::string_view border_name(Border border);

// A set of borders, for what a method supports.
struct BorderSet {
  unsigned bits = 0;
  constexpr BorderSet() = default;
  constexpr BorderSet(std::initializer_list<Border> borders) {
    for (Border b : borders) bits |= 1u << static_cast<unsigned>(b);
  }
  constexpr bool contains(Border b) const { return bits >> static_cast<unsigned>(b) & 1u; }
};

// Where pixel i of a line of n pixels (i may lie outside [0, n)) reads from, or -1 for a zero
// border. Any i, however far outside: a kernel may be wider than the image.
std::ptrdiff_t border_index(std::ptrdiff_t i, std::ptrdiff_t n, Border border);

struct BlurOptions {
  double sigma = 1;  // the target Gaussian's standard deviation, in pixels
  Border border = Border::replicate;
  int threads = 0;  // 0: all cores
};

// out = blur of `in`. The views have the same size and do not overlap.
using BlurRun = void (*)(Plane out, ConstPlane in, const BlurOptions& options);

struct BlurMethod {
  std::string_view name;
  std::string_view summary;     // what it is, and the seed section it comes from
  bool exact;                   // a Gaussian up to float rounding (max error <= 1e-5)
  double max_error;             // the stated bound: max |out - exact Gaussian of sigma| on
                                // images in [0, 1], for sigma in [min_sigma, max_sigma]
  double min_sigma, max_sigma;  // the sigmas the method accepts
  BorderSet borders;            // the borders it supports
  std::string_view cost;        // how the work grows with the image and sigma
  BlurRun run;
};

// Every registered method, in a fixed order.
std::span<const BlurMethod> blur_methods();
// The method called `name`; InvalidArgument listing the known names otherwise.
const BlurMethod& find_blur_method(std::string_view name);

// Checks the arguments (sizes, overlap, sigma in the method's range and finite, the border,
// threads >= 0: InvalidArgument naming the one at fault) and runs the method.
void blur(Plane out, ConstPlane in, const BlurMethod& method, const BlurOptions& options);
// Every channel of `in`; out is reallocated to in's size when it differs.
void blur(Image& out, const Image& in, const BlurMethod& method, const BlurOptions& options);

}  // namespace tridiff
