// The `ipf` method: seed 004's Inverse Post Filter depth of field as plain software — the scatter
// of fig. 11 written as the equivalent gather, in the fixed-point registers of fig. 10. The
// hardware model (dof/ipf/) must produce the same bits.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "tridiff/dof/ipf.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/threads.hpp"
#include "stage_clock.hpp"
#include "frame.hpp"

namespace tridiff {
namespace ipf {

namespace {

// The mask's size: odd, in [3, kMaxMask].
void require_mask(int size) {
  if (size < 3 || size % 2 == 0 || size > kMaxMask)
    throw InvalidArgument("mask", "must be odd and in [3, " + std::to_string(kMaxMask) +
                                      "] (fig. 10's 8-bit Radius reaches 255 pixels), got " +
                                      std::to_string(size));
}

}  // namespace

void validate(const DofProgram& program) {
  require_mask(program.mask);
  if (!(program.in_focus_coc_px >= 0.f) || !std::isfinite(program.in_focus_coc_px))
    throw InvalidArgument("in_focus_coc_px", "must be finite and >= 0");
  if (program.area_weight_bits < 1 || program.area_weight_bits > 16)
    throw InvalidArgument("area_weight_bits",
                          "must be in [1, 16], got " + std::to_string(program.area_weight_bits));
  // At least as wide as one weight; at most 20 so that Color (8 more) stays in 32 bits.
  if (program.color_weight_bits < program.area_weight_bits || program.color_weight_bits > 20)
    throw InvalidArgument("color_weight_bits", "must be in [area_weight_bits, 20], got " +
                                                   std::to_string(program.color_weight_bits));
}

std::int32_t disc_pixels(int radius) {
  std::int32_t count = 0;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) count += dx * dx + dy * dy <= radius * radius;
  return count;
}

DofQuantizer::DofQuantizer(const DofProgram& program) : program_(program) {
  validate(program);
  // The mask reaches (n-1)/2 pixels; the 8-bit Radius register 255.
  max_radius_ = std::min(program.mask / 2, 255);
  const std::int32_t full = register_max(program.area_weight_bits);
  for (int r = 0; r <= max_radius_; ++r)
    weights_.push_back(static_cast<std::uint16_t>(std::max(full / disc_pixels(r), 1)));
}

std::uint8_t DofQuantizer::radius(float coc_px, std::ptrdiff_t x, std::ptrdiff_t y) const {
  const float diameter = std::fabs(coc_px);
  if (diameter < program_.in_focus_coc_px) return 0;
  const float dithered = std::floor(0.5f * diameter + dither_threshold(x, y));
  return static_cast<std::uint8_t>(std::min(dithered, static_cast<float>(max_radius_)));
}

PipeData DofQuantizer::pipe_data(const float* lanes, int channels, float z, float coc_px,
                                 std::ptrdiff_t x, std::ptrdiff_t y) const {
  PipeData data;
  data.z = z;
  data.radius = radius(coc_px, x, y);
  data.area_weight = weights_[data.radius];
  data.present = true;
  for (int c = 0; c < channels; ++c) data.color[c] = quantize_color(lanes[c]);
  return data;
}

MaskKernel laplacian_kernel(int size) {
  require_mask(size);
  MaskKernel kernel{size, std::vector<int>(std::size_t(size) * size, 0)};
  const int h = size / 2;
  kernel.weights[h * size + h] = 4;
  for (auto [dx, dy] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}})
    kernel.weights[(h + dy) * size + h + dx] = -1;
  return kernel;
}

void validate(const MaskKernel& kernel) {
  require_mask(kernel.size);
  if (kernel.weights.size() != std::size_t(kernel.size) * kernel.size)
    throw InvalidArgument("weights", "must hold mask x mask values");
  int magnitude = 0;
  for (int w : kernel.weights) magnitude += std::abs(w);
  if (magnitude > 127)
    throw InvalidArgument("weights",
                          "sum of |weight| is " + std::to_string(magnitude) +
                              "; the 8-bit ColorWeight and 16-bit Color registers of seed 004 "
                              "fig. 10 hold at most 127");
}

}  // namespace ipf

namespace {

constexpr std::ptrdiff_t kTile = 32;

std::vector<ipf::PipeData> input_processing(const Image& color, ConstPlane z, ConstPlane coc,
                                            const ipf::DofQuantizer& quantizer, int team) {
  const std::ptrdiff_t width = color.width(), height = color.height();
  const int channels = color.channels();
  std::vector<ipf::PipeData> pipe(std::size_t(width * height));
#pragma omp parallel for num_threads(team) schedule(static)
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      float lanes[ipf::kMaxLanes] = {};
      for (int c = 0; c < channels; ++c) lanes[c] = color(x, y, c);
      pipe[y * width + x] = quantizer.pipe_data(lanes, channels, z(x, y), coc(x, y), x, y);
    }
  return pipe;
}

// How far the gather around the pixels of `tile` must look: the largest radius within the mask's
// reach of it (no fig. 11 condition fires beyond max(centre radius, position radius)), or the
// whole mask for the printed rule, whose second condition fires *beyond* the position's radius.
// -1: the neighbourhood is sharp (and, for the printed rule, of one depth) — the tile is its
// own quantised colour.
int gather_reach(const std::vector<ipf::PipeData>& pipe, std::ptrdiff_t width,
                 std::ptrdiff_t height, const Rect& tile, const ipf::DofProgram& program) {
  const int h = program.mask / 2;
  const std::ptrdiff_t x0 = std::max<std::ptrdiff_t>(tile.x - h, 0),
                       x1 = std::min(tile.x + tile.width + h, width);
  const std::ptrdiff_t y0 = std::max<std::ptrdiff_t>(tile.y - h, 0),
                       y1 = std::min(tile.y + tile.height + h, height);
  int largest = 0;
  float z_lo = pipe[y0 * width + x0].z, z_hi = z_lo;
  for (std::ptrdiff_t y = y0; y < y1; ++y)
    for (std::ptrdiff_t x = x0; x < x1; ++x) {
      const ipf::PipeData& p = pipe[y * width + x];
      largest = std::max<int>(largest, p.radius);
      z_lo = std::min(z_lo, p.z);
      z_hi = std::max(z_hi, p.z);
    }
  if (program.rule == ipf::DofRule::as_printed) return largest == 0 && z_lo == z_hi ? -1 : h;
  return largest == 0 ? -1 : largest;
}

// The fig. 11 gather at one pixel: every centre within `reach` offers its contribution; returns
// whether a register saturated.
bool gather_pixel(const std::vector<ipf::PipeData>& pipe, std::ptrdiff_t width,
                  std::ptrdiff_t height, std::ptrdiff_t x, std::ptrdiff_t y, int reach,
                  const ipf::DofProgram& program, int channels, ipf::Accumulators& acc) {
  const ipf::PipeData& position = pipe[y * width + x];
  bool saturated = false;
  for (int dy = -reach; dy <= reach; ++dy) {
    const std::ptrdiff_t cy = y - dy;
    if (cy < 0 || cy >= height) continue;
    for (int dx = -reach; dx <= reach; ++dx) {
      const std::ptrdiff_t cx = x - dx;
      if (cx < 0 || cx >= width) continue;
      const ipf::PipeData& centre = pipe[cy * width + cx];
      const std::int32_t weight =
          ipf::dof_weight(centre, position, dx * dx + dy * dy, program.rule);
      if (weight)
        saturated |= ipf::dof_accumulate(acc, centre, weight, channels, program.color_weight_bits);
    }
  }
  return saturated;
}

}  // namespace

IpfDofStats ipf_dof(Image& out, const Image& color, ConstPlane z, ConstPlane coc,
                    const ipf::DofProgram& program, int threads, bool skip_in_focus) {
  const ipf::DofQuantizer quantizer(program);
  if (color.channels() > ipf::kMaxLanes)
    throw InvalidArgument("color", "has " + std::to_string(color.channels()) +
                                       " channels; the IPF pipe carries at most 4");
  require_size(color, z.width(), z.height(), "color (against z)");
  require_size(color, coc.width(), coc.height(), "color (against coc)");
  const std::ptrdiff_t width = color.width(), height = color.height();
  const int channels = color.channels();
  const int team = resolve_threads(threads);
  const std::vector<ipf::PipeData> pipe = input_processing(color, z, coc, quantizer, team);

  out.reset(width, height, channels);
  const std::ptrdiff_t tiles_x = (width + kTile - 1) / kTile,
                       tiles_y = (height + kTile - 1) / kTile;
  std::ptrdiff_t saturated = 0, skipped = 0;
#pragma omp parallel for num_threads(team) schedule(dynamic) reduction(+ : saturated, skipped)
  for (std::ptrdiff_t t = 0; t < tiles_x * tiles_y; ++t) {
    const Rect tile{t % tiles_x * kTile, t / tiles_x * kTile, 0, 0};
    const Rect area{tile.x, tile.y, std::min(kTile, width - tile.x),
                    std::min(kTile, height - tile.y)};
    const int reach =
        skip_in_focus ? gather_reach(pipe, width, height, area, program) : program.mask / 2;
    if (reach < 0) skipped += area.area();
    for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
      for (std::ptrdiff_t x = area.x; x < area.x + area.width; ++x) {
        ipf::Accumulators acc;
        if (reach < 0) {
          // Only the pixel's own contribution: tmpColor / tmpWeight = its colour code.
          for (int c = 0; c < channels; ++c)
            out(x, y, c) = ipf::color_value(pipe[y * width + x].color[c]);
          continue;
        }
        saturated += gather_pixel(pipe, width, height, x, y, reach, program, channels, acc);
        for (int c = 0; c < channels; ++c)
          out(x, y, c) = ipf::color_value(ipf::dof_output(acc.color[c], acc.weight));
      }
  }
  return {saturated, double(skipped) / double(width * height)};
}

namespace dof_detail {

// The registry's interface carries no depth map; the signed CoC rises monotonically with
// distance (thin lens and artist curve alike), so it orders pixels as fig. 11's Z-Value does.
void run_ipf(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  ipf::DofProgram program;
  program.in_focus_coc_px = settings.in_focus_coc_px;
  const auto start = StageClock::now();
  const IpfDofStats stats =
      ipf_dof(out, color, coc, coc, program, settings.threads, settings.skip_in_focus);
  report.stages.push_back({"ipf", seconds_since(start)});
  report.skipped_fraction = stats.skipped_fraction;
  report.notes = "mask " + std::to_string(program.mask) + ", " +
                 std::to_string(stats.saturated_pixels) +
                 " pixels saturated the 8-bit ColorWeight register";
  if (settings.progress) settings.progress(1.0);
}

}  // namespace dof_detail
}  // namespace tridiff
