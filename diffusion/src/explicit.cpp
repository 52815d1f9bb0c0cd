// Forward-Euler diffusion on planes: one 5-point step per call of step_row, ping-ponging
// between two buffers; tiles with no link in or around them are never touched.
#include "tridiff/diffusion/explicit.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <utility>

#include "tridiff/solvers/detail/subnormals.hpp"
#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

constexpr std::ptrdiff_t kTile = LinkField::kTile;

// One step for pixels [x0, x1) of row y. right/down are the links to (x+1, y) and (x, y+1);
// the left and upper links are the right link of x-1 and the down link of row y-1. Links
// beyond the image are zero (the field stores zeros on its last column and row), so the
// border pixels read their own value in place of a missing neighbour.
void step_row(ConstPlane in, Plane out, ConstPlane right, ConstPlane down, std::ptrdiff_t y,
              std::ptrdiff_t x0, std::ptrdiff_t x1) {
  const std::ptrdiff_t width = in.width(), height = in.height();
  const float* here = in.row(y);
  const float* above = in.row(y > 0 ? y - 1 : y);
  const float* below = in.row(y + 1 < height ? y + 1 : y);
  const float* r = right.row(y);
  const float* d = down.row(y);
  const float* u = y > 0 ? down.row(y - 1) : nullptr;
  float* result = out.row(y);
  for (std::ptrdiff_t x = x0; x < x1; ++x) {
    const float center = here[x];
    const float left_value = x > 0 ? here[x - 1] : center;
    const float right_value = x + 1 < width ? here[x + 1] : center;
    const float left_link = x > 0 ? r[x - 1] : 0.f;
    const float up_link = u ? u[x] : 0.f;
    // seed 000 eq. 5.4 / appendix B: the divergence of the link-weighted gradients.
    result[x] = center + r[x] * (right_value - center) + left_link * (left_value - center) +
                d[x] * (below[x] - center) + up_link * (above[x] - center);
  }
}

// Whether any link touching a pixel of tile (tx, ty) is non-zero: the tile's own links, the
// right links of the column left of it and the down links of the row above it.
bool tile_moves(const LinkField& links, std::ptrdiff_t tx, std::ptrdiff_t ty) {
  return links.horizontal_active(tx, ty) || links.vertical_active(tx, ty) ||
         (tx > 0 && links.horizontal_active(tx - 1, ty)) ||
         (ty > 0 && links.vertical_active(tx, ty - 1));
}

// Forward Euler would spread a NaN over the image: refuse it up front, naming the pixel.
void require_finite(const Image& src) {
  for (int c = 0; c < src.channels(); ++c) {
    const ConstPlane plane = src.plane(c);
    float probe = 0;  // sum of 0 * value: zero unless a value is NaN or infinite
    for (std::ptrdiff_t y = 0; y < plane.height(); ++y) {
      const float* row = plane.row(y);
#pragma omp simd reduction(+ : probe)
      for (std::ptrdiff_t x = 0; x < plane.width(); ++x) probe += 0.f * row[x];
    }
    if (probe == 0) continue;
    for (std::ptrdiff_t y = 0; y < plane.height(); ++y)
      for (std::ptrdiff_t x = 0; x < plane.width(); ++x)
        if (!std::isfinite(plane(x, y)))
          throw InvalidArgument("src", "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                           "), channel " + std::to_string(c) + ": is not finite");
  }
}

void require_stable(const LinkField& kappa) {
  if (kappa.max_link() > kExplicitStabilityBound)
    throw InvalidArgument("kappa",
                          "largest link conductance " + std::to_string(kappa.max_link()) +
                              " exceeds the explicit stability bound 0.25 (seed 001 §3.9); "
                              "use diffuse_explicit, which sub-steps");
}

// `steps` steps of one plane; both buffers start as src so that tiles that never move hold
// the right values in either buffer without being copied.
std::ptrdiff_t run_steps(Plane dst, ConstPlane src, const LinkField& kappa, int steps, bool skip,
                         int threads, const std::function<void(int)>& stepped) {
  const std::ptrdiff_t width = src.width(), height = src.height();
  Image spare(width, height, 1);
  Plane ping = dst, pong = spare.plane(0);
  if (dst.data() != src.data()) copy_plane(dst, src);
  copy_plane(pong, dst);
  const std::ptrdiff_t tiles_x = kappa.tiles_x(), tiles_y = kappa.tiles_y();
  std::ptrdiff_t moving_pixels = 0;
  for (std::ptrdiff_t ty = 0; ty < tiles_y; ++ty)
    for (std::ptrdiff_t tx = 0; tx < tiles_x; ++tx)
      if (!skip || tile_moves(kappa, tx, ty))
        moving_pixels += (std::min(width, (tx + 1) * kTile) - tx * kTile) *
                         (std::min(height, (ty + 1) * kTile) - ty * kTile);
  for (int step = 0; step < steps; ++step) {
#pragma omp parallel num_threads(threads)
    {
      const detail::SubnormalsAsZero flush;  // see subnormals.hpp
#pragma omp for schedule(static)
      for (std::ptrdiff_t y = 0; y < height; ++y) {
        const std::ptrdiff_t ty = y / kTile;
        for (std::ptrdiff_t tx = 0; tx < tiles_x; ++tx) {
          if (skip && !tile_moves(kappa, tx, ty)) continue;
          step_row(ping, pong, kappa.horizontal(), kappa.vertical(), y, tx * kTile,
                   std::min(width, (tx + 1) * kTile));
        }
      }
    }
    std::swap(ping, pong);
    if (stepped) stepped(step + 1);
  }
  if (ping.data() != dst.data()) copy_plane(dst, ping);
  return moving_pixels * steps;
}

// Sub-steps that keep every link within the stability bound, counted in double (an int
// would overflow for a large conductance) and refused above the caller's limit.
int explicit_steps_for(float max_link, int max_steps) {
  const double steps = std::max(1.0, std::ceil(double(max_link) / kExplicitStabilityBound));
  if (steps > max_steps) {
    std::ostringstream message;
    message << "the largest conductance " << max_link << " needs " << steps
            << " explicit steps, more than the " << max_steps
            << " allowed (DiffusionOptions::max_explicit_steps); an implicit (ADI) step blurs "
               "this far in one";
    throw InvalidArgument("beta", message.str());
  }
  return int(steps);
}

}  // namespace

DiffusionReport diffuse_explicit_steps(Image& dst, const Image& src, const LinkField& kappa,
                                       int steps, const DiffusionOptions& options) {
  if (steps < 0) throw InvalidArgument("steps", "must be >= 0");
  require_stable(kappa);
  require_size(src, kappa.width(), kappa.height(), "kappa");
  require_finite(src);
  if (&dst != &src) dst = src;
  const int threads = resolve_threads(options.threads);
  DiffusionReport report;
  const int channels = src.channels();
  for (int c = 0; c < channels; ++c) {
    std::function<void(int)> stepped;
    if (options.progress)
      stepped = [&](int step) { options.progress((c + double(step) / steps) / channels); };
    report.pixels += src.width() * src.height() * std::ptrdiff_t(steps);
    report.pixels_solved += run_steps(dst.plane(c), dst.plane(c), kappa, steps,
                                      options.skip_inactive, threads, stepped);
  }
  return report;
}

DiffusionReport diffuse_explicit(Image& dst, const Image& src, const LinkField& beta,
                                 const DiffusionOptions& options, int* steps_taken) {
  const int steps = explicit_steps_for(beta.max_link(), options.max_explicit_steps);
  if (steps_taken) *steps_taken = steps;
  LinkField kappa(beta.width(), beta.height());
  const float scale = 1.f / float(steps);
  for (int direction = 0; direction < 2; ++direction) {
    ConstPlane from = direction == 0 ? beta.horizontal() : beta.vertical();
    Plane to = direction == 0 ? kappa.horizontal() : kappa.vertical();
    for (std::ptrdiff_t y = 0; y < from.height(); ++y)
      for (std::ptrdiff_t x = 0; x < from.width(); ++x)
        to(x, y) = std::min(kExplicitStabilityBound, from(x, y) * scale);  // rounding guard
  }
  kappa.finish(options.threads);
  return diffuse_explicit_steps(dst, src, kappa, steps, options);
}

void diffuse_isotropic(Image& dst, const Image& src, float c, int iterations,
                       const DiffusionOptions& options) {
  if (!(c > 0 && c <= kExplicitStabilityBound))
    throw InvalidArgument("c", std::to_string(c) +
                                   " is outside (0, 0.25], the range where the "
                                   "explicit step is stable (seed 001 §3.9)");
  LinkField kappa(src.width(), src.height());
  for (Plane p : {kappa.horizontal(), kappa.vertical()})
    for (std::ptrdiff_t y = 0; y < p.height(); ++y) std::fill(p.row(y), p.row(y) + p.width(), c);
  kappa.finish(options.threads);
  diffuse_explicit_steps(dst, src, kappa, iterations, options);
}

int isotropic_iterations_for_sigma(float sigma, float c) {
  if (!(sigma >= 0) || !std::isfinite(sigma))
    throw InvalidArgument("sigma", "must be finite and >= 0");
  if (!(c > 0 && c <= kExplicitStabilityBound)) throw InvalidArgument("c", "must be in (0, 0.25]");
  return int(std::ceil(double(sigma) * sigma / (2.0 * c) - 1e-9));
}

}  // namespace tridiff
