// The performance model of seed 004 §4, counted from the same frame plan the clocked model runs.
#include "tridiff/ipf/performance.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace tridiff::ipf {
namespace {

void require_positive(double value, const char* name) {
  if (!(value > 0) || !std::isfinite(value))
    throw InvalidArgument(name, "must be finite and > 0, got " + std::to_string(value));
}

// Pixels a part fetches per line: its columns and the halo columns that lie inside the frame.
std::ptrdiff_t reads_per_line(const FramePlan& plan, const Part& part) {
  const std::ptrdiff_t h = plan.mask / 2;
  const std::ptrdiff_t first = std::max<std::ptrdiff_t>(part.first - h, 0);
  const std::ptrdiff_t end = std::min(part.first + part.count + h, plan.scan_width);
  return end - first;
}

std::ptrdiff_t frame_clocks(const FramePlan& plan) {
  std::ptrdiff_t clocks = 0;
  for (const Part& part : plan.parts) clocks += plan.part_clocks(part);
  return clocks;
}

}  // namespace

void validate(const PerformanceInput& input) {
  require_positive(input.cycles_per_pixel, "cycles_per_pixel");
  require_positive(input.pixels_per_clock, "pixels_per_clock");
  require_positive(input.clock_hz, "clock_hz");
  require_positive(input.bandwidth_bytes_per_s, "bandwidth_bytes_per_s");
  if (input.read_bytes_per_pixel < 0 || input.write_bytes_per_pixel < 0)
    throw InvalidArgument("read_bytes_per_pixel", "must be >= 0");
}

double Performance::pixels_per_clock_for(double seconds) const {
  return double(pixels) * cycles_per_pixel / (clock_hz * seconds);
}

Performance estimate(const PerformanceInput& input) {
  validate(input);
  Performance p;
  p.plan = plan_frame(input.width, input.height, input.mask, input.parts, input.register_size);
  p.pixels = input.width * input.height;
  p.clocks_per_frame = frame_clocks(p.plan);
  p.overhead_steps = p.clocks_per_frame - p.pixels;
  p.split_overhead =
      p.clocks_per_frame -
      frame_clocks(plan_frame(
          input.width, input.height, input.mask, 1,
          std::max(p.plan.register_size, register_size(input.width, input.height, input.mask))));
  for (const Part& part : p.plan.parts) {
    const std::ptrdiff_t lines = p.plan.scan_lines + p.plan.mask - 1;
    p.fixed_register_waste += (p.plan.register_size - p.plan.line_length(part)) * lines;
    p.pixel_reads += reads_per_line(p.plan, part) * p.plan.scan_lines;
  }
  p.pixel_writes = p.pixels;
  p.bytes = double(p.pixel_reads) * input.read_bytes_per_pixel +
            double(p.pixel_writes) * input.write_bytes_per_pixel;
  p.memory_seconds = p.bytes / input.bandwidth_bytes_per_s;
  const double clock_rate = input.pixels_per_clock * input.clock_hz;
  p.compute_seconds = double(p.clocks_per_frame) * input.cycles_per_pixel / clock_rate;
  p.ideal_compute_seconds = double(p.pixels) * input.cycles_per_pixel / clock_rate;
  p.memory_bound = p.memory_seconds >= p.compute_seconds;
  p.frame_seconds = std::max(p.memory_seconds, p.compute_seconds);
  p.cycles_per_pixel = input.cycles_per_pixel;
  p.clock_hz = input.clock_hz;
  return p;
}

std::ptrdiff_t paper_split_overhead(std::ptrdiff_t width, int mask, int parts) {
  return 2 * std::ptrdiff_t(mask - 1) * (parts - 1) * width;
}

std::ptrdiff_t paper_part_register(std::ptrdiff_t width, int mask, int parts) {
  return (width + parts - 1) / parts + mask - 1;
}

}  // namespace tridiff::ipf
