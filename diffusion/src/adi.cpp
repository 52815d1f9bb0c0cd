// The ADI passes: bands of kTile rows (or columns) are one SIMD batch of diffusion-form
// solves; inside a band only the runs of tiles with a non-zero link are solved.
#include "tridiff/diffusion/adi.hpp"

#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "tridiff/solvers/solve.hpp"

namespace tridiff {
namespace {

constexpr std::ptrdiff_t kTile = LinkField::kTile;

// A run of pixels [begin, end) along a band that forms one independent system.
struct Segment {
  std::ptrdiff_t begin, end;
};

// The runs of active tiles of one band, as pixel ranges. A run of tiles [t0, t1] covers the
// links t0*kTile ... (t1+1)*kTile - 1, so its system spans pixels t0*kTile ... (t1+1)*kTile; the
// links on either side are zero (they lie in inactive tiles or outside the image), so the
// systems are exactly decoupled from the pixels around them.
template <class IsActive>
void find_segments(std::ptrdiff_t tiles, std::ptrdiff_t extent, bool skip, IsActive is_active,
                   std::vector<Segment>& segments) {
  segments.clear();
  if (!skip) {
    segments.push_back({0, extent});
    return;
  }
  for (std::ptrdiff_t t = 0; t < tiles;) {
    if (!is_active(t)) {
      ++t;
      continue;
    }
    const std::ptrdiff_t first = t;
    while (t < tiles && is_active(t)) ++t;
    segments.push_back({first * kTile, std::min(extent, t * kTile + 1)});
  }
}

// Rethrows a solver error with the pixel it concerns, in image coordinates.
[[noreturn]] void rethrow_at_pixel(const std::exception& error, std::ptrdiff_t x, std::ptrdiff_t y) {
  std::string reason = error.what();
  const auto colon = reason.rfind(": ");
  if (colon != std::string::npos) reason = reason.substr(colon + 2);
  throw InvalidArgument("src", -1, -1,
                        "pixel (" + std::to_string(x) + ", " + std::to_string(y) + "): " + reason);
}

// Runs body(band) for every band in parallel; the first error (by band) is rethrown after.
template <class Body>
void for_each_band(std::ptrdiff_t bands, int threads, Body&& body) {
  std::exception_ptr error;
  std::ptrdiff_t error_band = std::numeric_limits<std::ptrdiff_t>::max();
  std::mutex guard;
#pragma omp parallel num_threads(threads) if (threads > 1 && bands > 1)
  {
    std::vector<Segment> segments;  // reused across the bands of this thread
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t band = 0; band < bands; ++band) {
      try {
        body(band, segments);
      } catch (...) {
        std::lock_guard<std::mutex> lock(guard);
        if (band < error_band) {
          error_band = band;
          error = std::current_exception();
        }
      }
    }
  }
  if (error) std::rethrow_exception(error);
}

void require_same_size(ConstPlane a, ConstPlane b, const char* what) {
  if (a.width() != b.width() || a.height() != b.height())
    throw InvalidArgument(what, -1, -1,
                          "is " + std::to_string(b.width()) + " x " + std::to_string(b.height()) +
                              ", the source is " + std::to_string(a.width()) + " x " +
                              std::to_string(a.height()));
}

// dst[0, n) = src[0, n); throws naming the pixel if a value is not finite (the solver checks
// the pixels it solves; this is the check of the ones it skips).
void copy_finite(float* dst, const float* src, std::ptrdiff_t n, std::ptrdiff_t x0,
                 std::ptrdiff_t y) {
  float probe = 0;  // sum of 0 * value: zero unless a value is NaN or infinite
#pragma omp simd reduction(+ : probe)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    dst[i] = src[i];
    probe += 0.f * src[i];
  }
  if (probe == 0) return;
  for (std::ptrdiff_t i = 0; i < n; ++i)
    if (!std::isfinite(src[i]))
      throw InvalidArgument("src", -1, -1,
                            "pixel (" + std::to_string(x0 + i) + ", " + std::to_string(y) +
                                "): is not finite");
}

SolveOptions one_thread_thomas() {
  SolveOptions options;
  options.method = Method::Thomas;  // the diffusion form is always dominant: no pivoting
  options.threads = 1;              // the bands are already spread over the threads
  return options;
}

}  // namespace

DiffusionReport diffuse_rows(Plane dst, ConstPlane src, const LinkField& beta,
                             const DiffusionOptions& options) {
  require_same_size(src, dst, "dst");
  require_same_size(src, beta.horizontal(), "beta");
  const std::ptrdiff_t width = src.width(), height = src.height();
  const ConstPlane links = beta.horizontal();
  const SolveOptions solve_options = one_thread_thomas();
  const bool copy = dst.data() != src.data();
  std::vector<std::ptrdiff_t> solved(beta.tiles_y(), 0);

  for_each_band(beta.tiles_y(), detail::resolve_threads(options.threads),
                [&](std::ptrdiff_t ty, std::vector<Segment>& segments) {
    const std::ptrdiff_t y0 = ty * kTile, rows = std::min(kTile, height - y0);
    find_segments(beta.tiles_x(), width, options.skip_inactive,
                  [&](std::ptrdiff_t tx) { return beta.horizontal_active(tx, ty); }, segments);
    std::ptrdiff_t copied_to = 0;
    for (const Segment& s : segments) {
      if (copy)
        for (std::ptrdiff_t y = y0; y < y0 + rows; ++y)
          copy_finite(dst.row(y) + copied_to, src.row(y) + copied_to, s.begin - copied_to,
                      copied_to, y);
      const std::ptrdiff_t origin = y0 * src.pitch() + s.begin;
      try {
        solve_diffusion(links.data() + origin, src.data() + origin, dst.data() + origin,
                        BatchLayout::rows(s.end - s.begin, rows, src.pitch()), solve_options);
      } catch (const InvalidArgument& e) {
        rethrow_at_pixel(e, s.begin + std::max<std::ptrdiff_t>(e.row(), 0), y0 + e.system());
      } catch (const NumericalError& e) {
        rethrow_at_pixel(e, s.begin + e.row(), y0 + e.system());
      }
      solved[ty] += (s.end - s.begin) * rows;
      copied_to = s.end;
    }
    if (copy)
      for (std::ptrdiff_t y = y0; y < y0 + rows; ++y)
        copy_finite(dst.row(y) + copied_to, src.row(y) + copied_to, width - copied_to,
                    copied_to, y);
  });
  DiffusionReport report{width * height, 0};
  for (std::ptrdiff_t s : solved) report.pixels_solved += s;
  return report;
}

DiffusionReport diffuse_columns(Plane dst, ConstPlane src, const LinkField& beta,
                                const DiffusionOptions& options) {
  require_same_size(src, dst, "dst");
  require_same_size(src, beta.vertical(), "beta");
  const std::ptrdiff_t width = src.width(), height = src.height();
  const ConstPlane links = beta.vertical();
  const SolveOptions solve_options = one_thread_thomas();
  const bool copy = dst.data() != src.data();
  std::vector<std::ptrdiff_t> solved(beta.tiles_x(), 0);

  for_each_band(beta.tiles_x(), detail::resolve_threads(options.threads),
                [&](std::ptrdiff_t tx, std::vector<Segment>& segments) {
    const std::ptrdiff_t x0 = tx * kTile, columns = std::min(kTile, width - x0);
    find_segments(beta.tiles_y(), height, options.skip_inactive,
                  [&](std::ptrdiff_t ty) { return beta.vertical_active(tx, ty); }, segments);
    std::ptrdiff_t copied_to = 0;
    auto copy_rows = [&](std::ptrdiff_t from, std::ptrdiff_t to) {
      if (copy)
        for (std::ptrdiff_t y = from; y < to; ++y)
          copy_finite(dst.row(y) + x0, src.row(y) + x0, columns, x0, y);
    };
    for (const Segment& s : segments) {
      copy_rows(copied_to, s.begin);
      const std::ptrdiff_t origin = s.begin * src.pitch() + x0;
      try {
        solve_diffusion(links.data() + origin, src.data() + origin, dst.data() + origin,
                        BatchLayout::columns(s.end - s.begin, columns, src.pitch()),
                        solve_options);
      } catch (const InvalidArgument& e) {
        rethrow_at_pixel(e, x0 + e.system(), s.begin + std::max<std::ptrdiff_t>(e.row(), 0));
      } catch (const NumericalError& e) {
        rethrow_at_pixel(e, x0 + e.system(), s.begin + e.row());
      }
      solved[tx] += (s.end - s.begin) * columns;
      copied_to = s.end;
    }
    copy_rows(copied_to, height);
  });
  DiffusionReport report{width * height, 0};
  for (std::ptrdiff_t s : solved) report.pixels_solved += s;
  return report;
}

DiffusionReport diffuse_adi(Image& dst, const Image& src, const LinkField& beta,
                            const DiffusionOptions& options) {
  if (&dst != &src && (dst.width() != src.width() || dst.height() != src.height() ||
                       dst.channels() != src.channels()))
    dst.reset(src.width(), src.height(), src.channels());
  DiffusionReport report;
  const int channels = src.channels();
  for (int c = 0; c < channels; ++c) {
    report += diffuse_rows(dst.plane(c), src.plane(c), beta, options);
    if (options.progress) options.progress((2 * c + 1) / (2.0 * channels));
    report += diffuse_columns(dst.plane(c), dst.plane(c), beta, options);
    if (options.progress) options.progress((2 * c + 2) / (2.0 * channels));
  }
  return report;
}

}  // namespace tridiff
