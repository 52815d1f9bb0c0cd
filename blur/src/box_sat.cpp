// Repeated box filtering through summed-area tables (seed 001 §3.8, the third variant of
// §3.8.2): each pass builds the table of the current image and takes every pixel's square box
// mean from four lookups (eq. 2.3), so a pass costs the same whatever the box width. The widths
// are those of the "box" method (box_widths), so both give the same blur up to rounding; this
// one moves far more bytes (a double table a pass) and is here for what the seed measured.
//
// The replicate border of the combined kernel (as in box_passes): the image is padded by the
// passes' total reach with its edge pixels, the passes run over the padded image (each one's
// own clamping at the padded edge only spoils pixels within the padding), and the middle is
// cropped out.
#include <algorithm>

#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/box.hpp"
#include "tridiff/blur/sat.hpp"

namespace tridiff::blur_detail {

namespace {

Image replicate_padded(ConstPlane in, std::ptrdiff_t margin) {
  const std::ptrdiff_t w = in.width(), h = in.height();
  Image padded(w + 2 * margin, h + 2 * margin, 1);
  for (std::ptrdiff_t y = 0; y < padded.height(); ++y) {
    const float* src = in.row(std::clamp<std::ptrdiff_t>(y - margin, 0, h - 1));
    float* dst = padded.plane(0).row(y);
    std::fill_n(dst, margin, src[0]);
    std::copy_n(src, w, dst + margin);
    std::fill_n(dst + margin + w, margin, src[w - 1]);
  }
  return padded;
}

}  // namespace

void run_box_sat(Plane out, ConstPlane in, const BlurOptions& options) {
  const int threads = resolve_threads(options.threads);
  const std::vector<std::ptrdiff_t> widths = box_widths(options.sigma, kDefaultBoxPasses);
  std::ptrdiff_t margin = 0;
  for (std::ptrdiff_t width : widths) margin += (width - 1) / 2;
  Image padded = replicate_padded(in, margin);
  const Plane plane = padded.plane(0);
  for (std::ptrdiff_t width : widths) {
    // The table holds all the pass needs, so the pass may write over its own input.
    const SummedAreaTable table(plane, threads);
    const std::ptrdiff_t radius = (width - 1) / 2;
    sat_box_filter(plane, table, radius, radius, threads);
  }
  copy_plane(out, plane.sub({margin, margin, in.width(), in.height()}));
}

}  // namespace tridiff::blur_detail
