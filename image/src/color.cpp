// The sRGB curves applied to whole images: the colour planes of an Image, row by row, on
// OpenMP threads.
#include "tridiff/image/color.hpp"

#include <algorithm>

#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

// Applies `curve` to every pixel of the first min(3, channels) planes; the fourth plane is alpha
// (a coverage fraction, not light) and the padding stays zero because only `width` columns are
// touched.
template <class Curve>
void apply_to_colour_planes(Image& image, int threads, Curve curve) {
  const int team = resolve_threads(threads);
  if (image.empty()) return;
  const std::ptrdiff_t width = image.width(), height = image.height(), pitch = image.pitch();
  const std::ptrdiff_t rows = std::min(3, image.channels()) * height;
  float* const data = image.data();
  // One flat loop over the rows of all colour planes: enough iterations to balance threads
  // even for a short, wide image.
#pragma omp parallel for num_threads(team) schedule(static) if (team > 1)
  for (std::ptrdiff_t r = 0; r < rows; ++r) {
    float* row = data + (r / height) * image.plane_stride() + (r % height) * pitch;
    for (std::ptrdiff_t x = 0; x < width; ++x) row[x] = curve(row[x]);
  }
}

}  // namespace

void srgb_to_linear(Image& image, int threads) {
  apply_to_colour_planes(image, threads, [](float v) { return srgb_to_linear(v); });
}

void linear_to_srgb(Image& image, int threads) {
  apply_to_colour_planes(image, threads, [](float v) { return linear_to_srgb(v); });
}

}  // namespace tridiff
