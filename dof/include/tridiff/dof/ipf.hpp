// The Inverse Post Filter of seed 004: the pipe data of one pixel with the bit widths of its
// fig. 10, and the per-position maths of its two programs (fig. 9 mask filter, fig. 11 depth of
// field). Shared by the software `ipf` DOF method and the hardware model (dof/ipf/), so that the
// two quantise, test and accumulate alike and can be compared bit for bit.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff::ipf {

// Colour channels a pipe stage carries (fig. 10: 24-bit OriginalColor, three of 8 bits; a
// fourth lane lets RGBA images through).
constexpr int kMaxLanes = 4;

// The widest execution mask: fig. 10's Radius register has 8 bits, so no pixel reaches beyond
// 255 pixels and a mask wider than 2 x 255 + 1 only adds units nothing can reach (and the
// model's work grows with the mask's square). validate() refuses a wider one.
constexpr int kMaxMask = 511;

// Fig. 11's second condition as printed reads `positionCoCRadius < curDistance`: a background
// centre then reaches every nearer pixel *outside* that pixel's CoC, so a sharp foreground pixel
// (radius 0) averages in every farther pixel of the mask and is washed out. The text beside it
// ("the background object affects the foreground object with CoCs of rendered point") and the
// artifact it removes (the 100%-0% side of a blurred border) need the opposite comparison:
// a background centre within the foreground pixel's own CoC. `corrected` is that reading and
// the default; `as_printed` keeps the figure's literal text for comparison.
enum class DofRule { corrected, as_printed };

struct DofProgram {
  int mask = 17;                // n of the n x n execution mask (odd, in [3, kMaxMask]);
                                // radius <= (n-1)/2
  float in_focus_coc_px = 1.f;  // |CoC| diameter below this gets radius 0 (never dithered up)
  DofRule rule = DofRule::corrected;
  // Fig. 10: AreaWeight 8 bit, ColorWeight (the weight accumulator) 8 bit, Color 48 bit = three
  // of 8 + 8. With equal widths a pixel whose received weights sum past one radius-0 weight
  // saturates (dithered radii and depth edges do this often); a wider ColorWeight is headroom
  // (Color widens with it: 8 + color_weight_bits per channel).
  int area_weight_bits = 8;
  int color_weight_bits = 8;
};

// Throws InvalidArgument naming the field ("mask", "in_focus_coc_px", "area_weight_bits",
// "color_weight_bits").
void validate(const DofProgram& program);

// One pipe stage's input data (fig. 10 "calculate"/"copy" rows) plus a presence bit that fig. 10
// has no row for: the model needs it for the padding beyond the frame border, which must
// scatter nothing (any Z or radius would let fig. 11 reach real pixels).
struct PipeData {
  float z = 0;                    // Z-Value, 32 bit, copied
  std::uint16_t area_weight = 0;  // AreaWeight, area_weight_bits (8)
  std::uint8_t radius = 0;        // Radius, 8 bit, dithered CoC radius in pixels
  bool present = false;
  std::array<std::uint8_t, kMaxLanes> color{};  // OriginalColor, 8 bit per channel
};

// The cleared stage data (fig. 10 "clear" rows): Color (16 bit per channel with 8-bit weights)
// and ColorWeight. Signed so the mask filter's negative weights fit the same registers.
struct Accumulators {
  std::array<std::int32_t, kMaxLanes> color{};
  std::int32_t weight = 0;
};

// Linear light in [0, 1] to 8 bits (round to nearest; values above 1, highlights, clip: the
// 24-bit colour of fig. 10 has no headroom) and back.
inline std::uint8_t quantize_color(float value) {
  if (!(value > 0.f)) return 0;
  if (value >= 1.f) return 255;
  // In double the product is exact (24 + 8 bits), so this rounds the true value half up.
  return static_cast<std::uint8_t>(static_cast<double>(value) * 255.0 + 0.5);
}
inline float color_value(std::int32_t code) { return static_cast<float>(code) / 255.f; }

// The ordered-dither threshold at (x, y): a 4 x 4 Bayer matrix, (k + 1/2) / 16. Seed 004 §5
// dithers the radius against the aliased CoC steps; an ordered pattern is what an input unit
// can compute from the pixel address alone, with no state.
inline float dither_threshold(std::ptrdiff_t x, std::ptrdiff_t y) {
  static constexpr std::array<int, 16> kBayer{0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5};
  return (static_cast<float>(kBayer[(y & 3) * 4 + (x & 3)]) + 0.5f) / 16.f;
}

// Integer offsets (dx, dy) with dx^2 + dy^2 <= r^2: the pixels a centre of radius r reaches,
// which is the "area of the circle" whose reciprocal fig. 10's AreaWeight holds.
std::int32_t disc_pixels(int radius);

// The largest value a weight_bits-wide unsigned register holds.
constexpr std::int32_t register_max(int bits) { return (std::int32_t{1} << bits) - 1; }

// The input processing unit of the DOF program: CoC diameter -> dithered, clamped radius ->
// area weight floor(max / disc_pixels) (never 0, so every pixel keeps its own contribution), and
// the quantised colour. The floor keeps a uniform region's weight sum at or below the register.
class DofQuantizer {
 public:
  explicit DofQuantizer(const DofProgram& program);

  const DofProgram& program() const { return program_; }
  int max_radius() const { return max_radius_; }
  std::uint8_t radius(float coc_px, std::ptrdiff_t x, std::ptrdiff_t y) const;
  std::uint16_t area_weight(int radius) const { return weights_[radius]; }
  // lanes: `channels` colour values of pixel (x, y).
  PipeData pipe_data(const float* lanes, int channels, float z, float coc_px, std::ptrdiff_t x,
                     std::ptrdiff_t y) const;

 private:
  DofProgram program_;
  int max_radius_;
  std::vector<std::uint16_t> weights_;  // by radius
};

// Fig. 11 for one (centre, position) pair at squared distance `distance2`: the weight the
// position adds (0: none). curDistance <= radius is compared as squares, exactly.
inline std::int32_t dof_weight(const PipeData& centre, const PipeData& position,
                               std::int32_t distance2, DofRule rule) {
  if (centre.z <= position.z)
    return distance2 <= std::int32_t{centre.radius} * centre.radius ? centre.area_weight : 0;
  const std::int32_t position_r2 = std::int32_t{position.radius} * position.radius;
  const bool reaches =
      rule == DofRule::corrected ? distance2 <= position_r2 : position_r2 < distance2;
  return reaches ? position.area_weight : 0;
}

// tmpColor += centerColor * weight; tmpWeight += weight, saturating at the register widths
// (ColorWeight color_weight_bits, Color 8 + color_weight_bits per channel). A saturating add of
// non-negative terms ends at min(sum, limit) whatever the order, so scatter and gather agree
// exactly. Returns true when a register saturated.
inline bool dof_accumulate(Accumulators& acc, const PipeData& centre, std::int32_t weight,
                           int channels, int color_weight_bits) {
  const std::int32_t weight_limit = register_max(color_weight_bits);
  const std::int32_t color_limit = register_max(8 + color_weight_bits);
  bool saturated = false;
  for (int c = 0; c < channels; ++c) {
    const std::int32_t sum = acc.color[c] + weight * centre.color[c];
    saturated |= sum > color_limit;
    acc.color[c] = sum > color_limit ? color_limit : sum;
  }
  const std::int32_t sum = acc.weight + weight;
  saturated |= sum > weight_limit;
  acc.weight = sum > weight_limit ? weight_limit : sum;
  return saturated;
}

// The output processing unit: colour = tmpColor / tmpWeight, rounded half up, clipped to 8 bits.
inline std::int32_t dof_output(std::int32_t color, std::int32_t weight) {
  if (weight <= 0) return 0;
  const std::int32_t code = (2 * color + weight) / (2 * weight);
  return code > 255 ? 255 : code;
}

// ---------------------------------------------------------------------------------------------
// The mask filter (fig. 9): tmpColor += centerColor * positionWeight; tmpWeight +=
// positionWeight, positionWeight from each unit's constant memory.

struct MaskKernel {
  int size = 3;              // odd, in [3, kMaxMask]
  std::vector<int> weights;  // size x size, row-major: weights[(dy + h) * size + dx + h] is
                             // the weight of the position (dx, dy) away from the centre
  int at(int dx, int dy) const { return weights[(dy + size / 2) * size + dx + size / 2]; }
};

// Fig. 8's edge detector (4 at the centre, -1 at the four neighbours) in a size x size mask
// (zeros elsewhere: the constant memory of the other units).
MaskKernel laplacian_kernel(int size = 3);

// The registers of fig. 10 hold the filter without overflow: 16-bit signed Color and 8-bit
// signed ColorWeight need sum |w| <= 127 (then |tmpColor| <= 127 * 255 < 2^15). Throws
// InvalidArgument ("mask", "weights") otherwise.
void validate(const MaskKernel& kernel);

// The output unit: where the kernel's weights sum to non-zero (a blur) the result is normalised
// by tmpWeight, which also renormalises the clipped border; a zero-sum kernel (an edge detector,
// fig. 8) passes tmpColor through. Division rounds half away from zero.
inline std::int32_t mask_output(std::int32_t color, std::int32_t weight, bool normalise) {
  if (!normalise || weight == 0) return color;
  const std::int32_t magnitude =
      (2 * (color < 0 ? -color : color) + (weight < 0 ? -weight : weight)) /
      (2 * (weight < 0 ? -weight : weight));
  return (color < 0) != (weight < 0) ? -magnitude : magnitude;
}
inline bool kernel_normalises(const MaskKernel& kernel) {
  int sum = 0;
  for (int w : kernel.weights) sum += w;
  return sum != 0;
}

}  // namespace tridiff::ipf

namespace tridiff {

struct IpfDofStats {
  std::ptrdiff_t saturated_pixels = 0;  // pixels where a register of fig. 10 saturated
  double skipped_fraction = 0;          // of the pixels: in tiles whose neighbourhood is sharp
};

// The plain software IPF depth of field (seed 004 §5, fig. 11): every pixel scatters to the
// pixels within its dithered, quantised CoC radius subject to the depth test, with its area
// weight; accumulated and normalised in the registers of fig. 10. Written as the equivalent
// gather over the mask window, parallel over tiles; tiles whose whole neighbourhood has radius 0
// (and, for the printed rule, one depth) are copied, which changes nothing.
// out: 8-bit codes / 255, `color`'s channel count (at most 4). z: depth order (smaller = nearer).
IpfDofStats ipf_dof(Image& out, const Image& color, ConstPlane z, ConstPlane coc,
                    const ipf::DofProgram& program, int threads = 0, bool skip_in_focus = true);

}  // namespace tridiff
