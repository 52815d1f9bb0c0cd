// The configurable shift-register pipe of seed 004 (§3.1.2, fig. 5, §4) and how a frame is cut
// into the lines that run through it.
#include <algorithm>
#include <bit>
#include <string>

#include "tridiff/ipf/model.hpp"

namespace tridiff::ipf {

PipeLayout::PipeLayout(std::ptrdiff_t size) : size_(size) {
  if (size < 1) throw InvalidArgument("register_size", "must be >= 1");
  // Stages 1, 2, ..., 2^(m-1) sum to 2^m - 1; the last makes up the rest (§4's lastloopsize).
  const std::ptrdiff_t top = std::ptrdiff_t{1} << (std::bit_width(std::size_t(size)) - 1);
  for (std::ptrdiff_t length = 1; length < top; length *= 2) stages_.push_back(length);
  stages_.push_back(size - top + 1);
}

std::vector<bool> PipeLayout::connect(std::ptrdiff_t length) const {
  if (length < 0 || length > size_)
    throw InvalidArgument("length",
                          std::to_string(length) + " is not in [0, " + std::to_string(size_) + "]");
  std::vector<bool> on(stages_.size(), false);
  const std::size_t last = stages_.size() - 1;
  // The power-of-two stages alone reach 2^m - 1 = the last stage's start; beyond it, the last
  // stage plus the binary rest (length - last <= 2^m - 1 since size < 2^(m+1)).
  std::ptrdiff_t rest = length;
  const std::ptrdiff_t binary_max = size_ - stages_[last];
  if (rest > binary_max) {
    on[last] = true;
    rest -= stages_[last];
  }
  for (std::size_t i = 0; i < last; ++i) on[i] = (rest >> i) & 1;
  return on;
}

std::ptrdiff_t register_size(std::ptrdiff_t max_width, std::ptrdiff_t max_height, int mask) {
  return std::min(max_width, max_height) + mask - 1;
}

std::ptrdiff_t FramePlan::max_line_length() const {
  std::ptrdiff_t longest = 0;
  for (const Part& part : parts) longest = std::max(longest, line_length(part));
  return longest;
}

std::ptrdiff_t FramePlan::part_clocks(const Part& part) const {
  // A pixel's accumulators leave the mask (n-1) lines and (n-1) pixels after it entered it.
  return (scan_lines + mask - 1) * line_length(part) + mask - 1;
}

namespace {

std::vector<Part> vertical_parts(std::ptrdiff_t width, int parts) {
  std::vector<Part> out;
  for (int p = 0; p < parts; ++p) {
    const std::ptrdiff_t first = width * p / parts, end = width * (p + 1) / parts;
    out.push_back({first, end - first});
  }
  return out;
}

}  // namespace

FramePlan plan_frame(std::ptrdiff_t width, std::ptrdiff_t height, int mask, int parts,
                     std::ptrdiff_t size) {
  if (mask < 3 || mask % 2 == 0 || mask > kMaxMask)
    throw InvalidArgument("mask", "must be odd and in [3, " + std::to_string(kMaxMask) + "], got " +
                                      std::to_string(mask));
  if (parts < 1) throw InvalidArgument("parts", "must be >= 1, got " + std::to_string(parts));
  if (width < 1 || height < 1) throw InvalidArgument("size", "frame is empty");
  if (size == 0) size = register_size(width, height, mask);
  if (size < mask) throw InvalidArgument("register_size", "must be >= the mask");
  for (bool columns : {false, true}) {
    FramePlan plan;
    plan.columns = columns;
    plan.scan_width = columns ? height : width;
    plan.scan_lines = columns ? width : height;
    plan.mask = mask;
    plan.register_size = size;
    if (parts > plan.scan_width) continue;
    plan.parts = vertical_parts(plan.scan_width, parts);
    if (plan.max_line_length() <= size) return plan;
  }
  throw InvalidArgument("parts", std::to_string(parts) + " part(s) of a " + std::to_string(width) +
                                     " x " + std::to_string(height) + " frame do not fit a " +
                                     std::to_string(size) + "-stage register with mask " +
                                     std::to_string(mask));
}

}  // namespace tridiff::ipf
