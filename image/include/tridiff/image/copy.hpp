// The whole-image copy on OpenMP threads: the least any filter of an image must cost (it reads
// and writes every pixel once), which the benchmarks measure every method against.
#pragma once

#include "tridiff/image/image.hpp"

namespace tridiff {

// dst = src, every channel, rows shared among `threads` (0: all cores). dst must have src's
// width, height and channel count (InvalidArgument("dst") otherwise).
void copy_image(Image& dst, const Image& src, int threads = 0);

}  // namespace tridiff
