// Internal to the blur library: the row pass shared by the lane-parallel methods (IIR Deriche,
// repeated box, Kosloff). They filter columns with one SIMD lane per column; rows are brought
// into the same layout W at a time by a transpose, filtered there and transposed back.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "tridiff/image/image.hpp"
#include "tridiff/solvers/detail/transpose.hpp"

namespace tridiff::blur_detail {

// One AVX-512 vector of floats (GCC/Clang vector extension: lowered to narrower vectors where
// AVX-512 is missing), and unaligned loads and stores of it.
inline constexpr int kVectorLanes = 16;
using FloatVector = float __attribute__((vector_size(kVectorLanes * sizeof(float))));
inline FloatVector load(const float* p) {
  FloatVector v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline void store(float* p, FloatVector v) { __builtin_memcpy(p, &v, sizeof v); }

// Scratch slots: for_each_row_block uses the first two itself, so the kernels it runs use
// slots from kFreeScratchSlot on; code outside it (the column passes) may use any slot.
inline constexpr int kRowBlockLanesSlot = 0;
inline constexpr int kRowBlockStagingSlot = 1;
inline constexpr int kFreeScratchSlot = 2;
inline constexpr int kScratchSlots = 8;

// Per-thread scratch that lives from call to call (OpenMP keeps its threads): a fresh 512 KiB
// buffer costs 128 page faults per call and thread, milliseconds on a virtual machine, more
// than filtering a block. Slot `which` (< kScratchSlots) of the calling thread, at least
// `floats` long; the pointer stays valid until the same slot is asked for more.
inline float* scratch(int which, std::size_t floats) {
  thread_local std::vector<float> buffers[kScratchSlots];
  std::vector<float>& buffer = buffers[which];
  if (buffer.size() < floats) buffer.resize(floats);
  return buffer.data();
}

// Rows [y0, y0 + W) of `plane` (fewer at its bottom), in place: the block is transposed into
// lane order (element x of row l at lanes[x * W + l]), `kernel(lanes, width)` overwrites it with
// its result, and it is transposed back. A partial block is staged through a zeroed W-row buffer
// (its unused lanes hold zeros). Uses the calling thread's scratch slots 0 and 1.
template <int W, class Kernel>
void filter_row_block(Plane plane, std::ptrdiff_t y0, Kernel& kernel) {
  const std::ptrdiff_t w = plane.width(), rows = std::min<std::ptrdiff_t>(W, plane.height() - y0);
  float* lanes = scratch(kRowBlockLanesSlot, static_cast<std::size_t>(w) * W);
  float* first = plane.row(y0);
  std::ptrdiff_t pitch = plane.pitch();
  if (rows < W) {  // stage the last rows in a full block
    first = scratch(kRowBlockStagingSlot, static_cast<std::size_t>(w) * W);
    std::fill_n(first, w * W, 0.f);
    for (std::ptrdiff_t r = 0; r < rows; ++r) std::copy_n(plane.row(y0 + r), w, first + r * w);
    pitch = w;
  }
  detail::transpose_into_lanes<float, W>(first, pitch, w, lanes);
  kernel(lanes, w);
  detail::transpose_from_lanes<float, W>(lanes, w, first, pitch);
  if (rows < W)
    for (std::ptrdiff_t r = 0; r < rows; ++r) std::copy_n(first + r * w, w, plane.row(y0 + r));
}

// Rows of `plane`, in place, W at a time (filter_row_block), the blocks split statically over
// `threads` threads.
//
// The kernel gets no per-thread state from here: one that needs buffers of its own takes them
// from scratch(kFreeScratchSlot + i, n) (or a thread_local), which costs a size check per
// block and keeps them from call to call. That is simpler than threading a state factory
// through this template, and cheaper than a fresh allocation per parallel region.
template <int W, class Kernel>
void for_each_row_block(Plane plane, int threads, Kernel kernel) {
  const std::ptrdiff_t blocks = (plane.height() + W - 1) / W;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t b = 0; b < blocks; ++b) filter_row_block<W>(plane, b * W, kernel);
}

}  // namespace tridiff::blur_detail
