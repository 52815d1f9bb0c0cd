// The ADI passes: bands of kTile rows (or columns) are one SIMD batch of diffusion-form
// solves; inside a band only the runs of tiles with a non-zero link are solved.
#include "tridiff/diffusion/adi.hpp"

#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <span>
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

enum class Direction { Rows, Columns };

// One pass (rows or columns) over several planes that share the links: band by band (a band is
// one tile row of image rows, or one tile column of image columns), and inside a band plane by
// plane, so that the band's links and segments are found once and stay in cache for every
// plane. dst[c] may be src[c].
DiffusionReport run_pass(Direction direction, std::span<const Plane> dst,
                         std::span<const ConstPlane> src, const LinkField& beta,
                         const DiffusionOptions& options) {
  const bool rows = direction == Direction::Rows;
  const ConstPlane links = rows ? beta.horizontal() : beta.vertical();
  for (std::size_t c = 0; c < src.size(); ++c) {
    require_same_size(src[c], dst[c], "dst");
    require_same_size(src[c], links, "beta");
  }
  const std::ptrdiff_t width = links.width(), height = links.height(), pitch = links.pitch();
  const std::ptrdiff_t bands = rows ? beta.tiles_y() : beta.tiles_x();
  const std::ptrdiff_t tiles_along = rows ? beta.tiles_x() : beta.tiles_y();
  const std::ptrdiff_t length = rows ? width : height;  // of one system
  const SolveOptions solve_options = one_thread_thomas();
  std::vector<std::ptrdiff_t> solved(bands, 0);

  for_each_band(bands, detail::resolve_threads(options.threads),
                [&](std::ptrdiff_t band, std::vector<Segment>& segments) {
    const std::ptrdiff_t first = band * kTile;  // first row (rows) or column (columns)
    const std::ptrdiff_t count = std::min(kTile, (rows ? height : width) - first);
    find_segments(tiles_along, length, options.skip_inactive, [&](std::ptrdiff_t t) {
      return rows ? beta.horizontal_active(t, band) : beta.vertical_active(band, t);
    }, segments);
    // (along, across) -> (x, y): rows run along x, columns along y.
    auto pixel_x = [&](std::ptrdiff_t along, std::ptrdiff_t across) { return rows ? along : across; };
    auto pixel_y = [&](std::ptrdiff_t along, std::ptrdiff_t across) { return rows ? across : along; };
    for (std::size_t c = 0; c < src.size(); ++c) {
      const Plane out = dst[c];
      const ConstPlane in = src[c];
      // Copies pixels [from, to) along every system of the band (the parts not solved).
      auto copy_span = [&](std::ptrdiff_t from, std::ptrdiff_t to) {
        if (out.data() == in.data() || to <= from) return;
        if (rows)
          for (std::ptrdiff_t y = first; y < first + count; ++y)
            copy_finite(out.row(y) + from, in.row(y) + from, to - from, from, y);
        else
          for (std::ptrdiff_t y = from; y < to; ++y)
            copy_finite(out.row(y) + first, in.row(y) + first, count, first, y);
      };
      std::ptrdiff_t copied_to = 0;
      for (const Segment& s : segments) {
        copy_span(copied_to, s.begin);
        const std::ptrdiff_t n = s.end - s.begin;
        const std::ptrdiff_t origin = rows ? first * pitch + s.begin : s.begin * pitch + first;
        const BatchLayout layout =
            rows ? BatchLayout::rows(n, count, pitch) : BatchLayout::columns(n, count, pitch);
        try {
          solve_diffusion(links.data() + origin, in.data() + origin, out.data() + origin, layout,
                          solve_options);
        } catch (const InvalidArgument& e) {
          const std::ptrdiff_t along = s.begin + std::max<std::ptrdiff_t>(e.row(), 0);
          rethrow_at_pixel(e, pixel_x(along, first + e.system()), pixel_y(along, first + e.system()));
        } catch (const NumericalError& e) {
          const std::ptrdiff_t along = s.begin + e.row();
          rethrow_at_pixel(e, pixel_x(along, first + e.system()), pixel_y(along, first + e.system()));
        }
        solved[band] += n * count;
        copied_to = s.end;
      }
      copy_span(copied_to, length);
    }
  });
  const auto planes = std::ptrdiff_t(src.size());
  DiffusionReport report{width * height * planes, 0};
  for (std::ptrdiff_t s : solved) report.pixels_solved += s;  // already per plane
  return report;
}

}  // namespace

DiffusionReport diffuse_rows(Plane dst, ConstPlane src, const LinkField& beta,
                             const DiffusionOptions& options) {
  return run_pass(Direction::Rows, {&dst, 1}, {&src, 1}, beta, options);
}

DiffusionReport diffuse_columns(Plane dst, ConstPlane src, const LinkField& beta,
                                const DiffusionOptions& options) {
  return run_pass(Direction::Columns, {&dst, 1}, {&src, 1}, beta, options);
}

DiffusionReport diffuse_adi(Image& dst, const Image& src, const LinkField& beta,
                            const DiffusionOptions& options) {
  if (&dst != &src && (dst.width() != src.width() || dst.height() != src.height() ||
                       dst.channels() != src.channels()))
    dst.reset(src.width(), src.height(), src.channels());
  std::vector<Plane> out;
  std::vector<ConstPlane> in, in_place;
  for (int c = 0; c < src.channels(); ++c) {
    out.push_back(dst.plane(c));
    in.push_back(src.plane(c));
    in_place.push_back(dst.plane(c));
  }
  DiffusionReport report = run_pass(Direction::Rows, out, in, beta, options);
  if (options.progress) options.progress(0.5);
  report += run_pass(Direction::Columns, out, in_place, beta, options);
  if (options.progress) options.progress(1.0);
  return report;
}

}  // namespace tridiff
