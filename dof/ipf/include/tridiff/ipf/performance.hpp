// The performance model of the Inverse Post Filter (seed 004 §4): clocks per frame from the
// frame plan, memory traffic, and the frame time at a clock rate and memory bandwidth — with the
// number of pixels the unit finishes per clock stated, not assumed.
#pragma once

#include <cstddef>

#include "tridiff/ipf/model.hpp"

namespace tridiff::ipf {

struct PerformanceInput {
  std::ptrdiff_t width = 1600, height = 1200;
  int mask = 17;
  int parts = 1;
  std::ptrdiff_t register_size = 0;  // 0: sized for the frame, §4
  double cycles_per_pixel = 5;       // program clocks per pipe step (§5: fig. 11 in five)
  double pixels_per_clock = 1;       // pipe steps finished per clock: units (or pipes) working
                                     // side by side; one IPF unit is 1
  double clock_hz = 310e6;
  double bandwidth_bytes_per_s = 20e9;
  int read_bytes_per_pixel = 8;   // §4: 32-bit colour + 32-bit z (DOF); colour only: 4
  int write_bytes_per_pixel = 4;  // 32-bit colour
};
// Throws InvalidArgument naming the field at fault (e.g. "clock_hz", "pixels_per_clock").
void validate(const PerformanceInput& input);

struct Performance {
  FramePlan plan;
  std::ptrdiff_t pixels = 0;
  std::ptrdiff_t clocks_per_frame = 0;      // pipe steps, every part with its halo and fill
  std::ptrdiff_t overhead_steps = 0;        // clocks_per_frame - pixels
  std::ptrdiff_t split_overhead = 0;        // clocks_per_frame - the same frame in one part
  std::ptrdiff_t fixed_register_waste = 0;  // steps a register fixed at register_size would
                                            // waste on the shorter lines (§3.1.2's 1600 vs 320)
  std::ptrdiff_t pixel_reads = 0, pixel_writes = 0;
  double bytes = 0;                  // read + written
  double memory_seconds = 0;         // bytes / bandwidth
  double compute_seconds = 0;        // clocks * cycles_per_pixel / (pixels_per_clock * clock)
  double ideal_compute_seconds = 0;  // the same for the pixels alone (no halo, no fill)
  double frame_seconds = 0;          // the slower of the two (they overlap)
  bool memory_bound = false;
  // Pixels per clock the program's clocks need to finish the pixels in `seconds`.
  double pixels_per_clock_for(double seconds) const;
  double cycles_per_pixel = 0, clock_hz = 0;
};

Performance estimate(const PerformanceInput& input);

// §4 as printed: splitting into `parts` costs 2 (mask - 1) (parts - 1) * width stages
// (1600 x 1200, mask 17, four parts: 153 600), each part's register being width / parts +
// mask - 1 long (416).
std::ptrdiff_t paper_split_overhead(std::ptrdiff_t width, int mask, int parts);
std::ptrdiff_t paper_part_register(std::ptrdiff_t width, int mask, int parts);

}  // namespace tridiff::ipf
