// Depth of field by diffusion: one pass over the whole frame, or (with layers) the near field
// blurred on its own and composited over a background whose hidden parts are filled in.
#include "diffusion_dof.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "tridiff/threads.hpp"
#include "frame.hpp"
#include "tridiff/dof/near_layer.hpp"
#include "stage_clock.hpp"

namespace tridiff::dof_detail {
namespace {

// Adds the time `work` takes to the report as a stage called `name`, before the stages `work`
// itself reports (a Diffuser may list its parts), and less their time: the stages add up.
template <class Work>
auto timed(DofReport& report, const char* name, Work&& work) {
  struct Record {
    DofReport& report;
    const char* name;
    std::size_t first_nested;
    StageClock::time_point start;
    ~Record() {
      double seconds = seconds_since(start);
      for (std::size_t i = first_nested; i < report.stages.size(); ++i)
        seconds -= report.stages[i].seconds;
      report.stages.insert(report.stages.begin() + std::ptrdiff_t(first_nested),
                           {name, std::max(seconds, 0.0)});
    }
  } record{report, name, report.stages.size(), StageClock::now()};
  return work();
}

// Diffuses every plane of `image` in place with the conductance `beta` on the links inside
// `reach` (a plane of the image's size, > 0 where the fill may spread) and none elsewhere: the
// solves skip the tiles out of reach.
void diffuse_within(Image& image, float beta, ConstPlane reach, int threads) {
  DiffusionOptions options;
  options.threads = threads;
  diffuse_adi(
      image, image, reach, [beta](float inside) { return inside > 0 ? beta : 0.f; }, options);
}

// 1 in the squares of kReachTile pixels that lie within `radius` pixels (a square's reach) of
// a pixel of the near layer, 0 elsewhere: where the near layer's blur can reach, and so all
// that the fills and the near blur need to solve. Outside it the near layer is empty and the
// background keeps its own values.
constexpr std::ptrdiff_t kReachTile = 32;
Image near_reach(ConstPlane coc, const NearLayer& near, float radius, int threads) {
  const std::ptrdiff_t width = coc.width(), height = coc.height();
  const std::ptrdiff_t tiles_x = (width + kReachTile - 1) / kReachTile;
  const std::ptrdiff_t tiles_y = (height + kReachTile - 1) / kReachTile;
  std::vector<unsigned char> holds(std::size_t(tiles_x * tiles_y), 0);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (std::ptrdiff_t ty = 0; ty < tiles_y; ++ty)
    for (std::ptrdiff_t y = ty * kReachTile; y < std::min(height, (ty + 1) * kReachTile); ++y) {
      const float* k = coc.row(y);
      for (std::ptrdiff_t x = 0; x < width; ++x)
        if (near.contains(k[x])) holds[std::size_t(ty * tiles_x + x / kReachTile)] = 1;
    }
  const auto grow = std::ptrdiff_t(std::ceil(radius / float(kReachTile)));
  Image reach(width, height, 1);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (std::ptrdiff_t ty = 0; ty < tiles_y; ++ty)
    for (std::ptrdiff_t tx = 0; tx < tiles_x; ++tx) {
      bool inside = false;
      for (std::ptrdiff_t sy = std::max<std::ptrdiff_t>(0, ty - grow);
           sy <= std::min(tiles_y - 1, ty + grow) && !inside; ++sy)
        for (std::ptrdiff_t sx = std::max<std::ptrdiff_t>(0, tx - grow);
             sx <= std::min(tiles_x - 1, tx + grow) && !inside; ++sx)
          inside = holds[std::size_t(sy * tiles_x + sx)] != 0;
      for (std::ptrdiff_t y = ty * kReachTile; y < std::min(height, (ty + 1) * kReachTile); ++y)
        std::fill(reach.plane(0).row(y) + tx * kReachTile,
                  reach.plane(0).row(y) + std::min(width, (tx + 1) * kReachTile),
                  inside ? 1.f : 0.f);
    }
  return reach;
}

// Normalised diffusion ("push-pull" by heat) finishes here: `sum` is value * weight and
// `weight` the weight (1 where the value is known, 0 in a hole), both diffused alike. A hole
// takes sum / weight, a smooth average of the known values around it; a known pixel keeps
// `known_value`. Far inside a hole the weight can underflow: the known value stays there too.
inline float filled(bool known, float known_value, float sum, float weight) {
  if (known) return known_value;
  return weight > 1e-30f ? sum / weight : known_value;
}

// Runs row(y) for every row, on `threads` threads.
template <class Row>
void for_each_row(std::ptrdiff_t height, int threads, Row&& row) {
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (std::ptrdiff_t y = 0; y < height; ++y) row(y);
}

// The layers' background: the colour and the CoC's magnitude outside the near field as they
// are, and inside it filled from around it, at half resolution. The 2 x 2 means of the known
// values (premultiplied by known = 0 or 1) and of `known` are diffused with the conductance
// beta / 4 (the same spread in full pixels) inside `reach`, and a near pixel takes the ratio
// of the two (filled()), each interpolated bilinearly (pixel x at x / 2 - 1/4 in the half
// frame: weights 3/4 and 1/4). A quarter of the full resolution's solves, and one pass over
// the frame each way; the fill is a smooth guess at what the near field hides, and against
// the ray-traced truth the result is the same to 4 digits (1080p, both scenes).
void fill_background(Image& background, Plane background_coc, const Image& color, ConstPlane coc,
                     const NearLayer& near, float beta, ConstPlane reach, int threads) {
  const std::ptrdiff_t width = coc.width(), height = coc.height();
  const std::ptrdiff_t half_width = (width + 1) / 2, half_height = (height + 1) / 2;
  const int channels = color.channels();
  // Planes 0 .. channels - 1 the colour, then |CoC|, then the weight.
  Image half(half_width, half_height, channels + 2), half_reach(half_width, half_height, 1);
  for_each_row(half_height, threads, [&](std::ptrdiff_t v) {
    const std::ptrdiff_t rows[2] = {2 * v, std::min(2 * v + 1, height - 1)};
    float* weight = half.plane(channels + 1).row(v);
    float* magnitude = half.plane(channels).row(v);
    float* inside = half_reach.plane(0).row(v);
    for (std::ptrdiff_t u = 0; u < half_width; ++u) {
      const std::ptrdiff_t columns[2] = {2 * u, std::min(2 * u + 1, width - 1)};
      float known[2][2];
      float w = 0, m = 0, r = 0;
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          const float k = coc(columns[i], rows[j]);
          known[j][i] = near.contains(k) ? 0.f : 1.f;
          w += known[j][i];
          m += 0.25f * known[j][i] * std::abs(k);
          r = std::max(r, reach(columns[i], rows[j]));
        }
      weight[u] = 0.25f * w;
      magnitude[u] = m;
      inside[u] = r;
      for (int c = 0; c < channels; ++c) {
        // Each term scaled before the sum: four colours near the float's largest must not
        // add up to inf.
        const ConstPlane p = color.plane(c);
        float sum = 0;
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i) sum += 0.25f * known[j][i] * p(columns[i], rows[j]);
        half(u, v, c) = sum;
      }
    }
  });
  diffuse_within(half, 0.25f * beta, half_reach.plane(0), threads);
  for_each_row(height, threads, [&](std::ptrdiff_t y) {
    const float* k = coc.row(y);
    for (int c = 0; c < channels; ++c)
      std::copy_n(color.plane(c).row(y), width, background.plane(c).row(y));
    float* magnitude = background_coc.row(y);
    for (std::ptrdiff_t x = 0; x < width; ++x) magnitude[x] = std::abs(k[x]);
    const std::ptrdiff_t above = std::max<std::ptrdiff_t>(y % 2 == 0 ? y / 2 - 1 : y / 2, 0);
    const std::ptrdiff_t below = std::min(y % 2 == 0 ? y / 2 : y / 2 + 1, half_height - 1);
    const float fy = y % 2 == 0 ? 0.75f : 0.25f;
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      if (!near.contains(k[x])) continue;
      const std::ptrdiff_t left = std::max<std::ptrdiff_t>(x % 2 == 0 ? x / 2 - 1 : x / 2, 0);
      const std::ptrdiff_t right = std::min(x % 2 == 0 ? x / 2 : x / 2 + 1, half_width - 1);
      const float fx = x % 2 == 0 ? 0.75f : 0.25f;
      const auto at = [&](int c) {
        const float *a = half.plane(c).row(above), *b = half.plane(c).row(below);
        const float top = a[left] + fx * (a[right] - a[left]);
        const float bottom = b[left] + fx * (b[right] - b[left]);
        return top + fy * (bottom - top);
      };
      const float weight = at(channels + 1);
      for (int c = 0; c < channels; ++c) {
        float& value = background(x, y, c);
        value = filled(false, value, at(c), weight);
      }
      magnitude[x] = filled(false, magnitude[x], at(channels), weight);
    }
  });
}

// The layers are filled, blurred and composited in place in four buffers: a fresh full-frame
// image costs its page faults (with the ten buffers of the first version, the layers of the
// built-in scene at 1920 x 1080 on a 2-core VM took 268-584 ms, now typically 56).
void layered_dof(Image& out, const DofFrame& frame, const NearLayer& near,
                 const DofOptions& settings, DofReport& report, const Diffuser& diffuse,
                 const Diffuser& diffuse_near, const CocConductance& conductance,
                 const DiffusionOptions& options) {
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  const std::ptrdiff_t width = color.width(), height = color.height();
  const int channels = color.channels(), threads = settings.threads;
  const float fill_beta = adi_beta_for_coc(frame.max_abs_coc());
  DiffusionReport diffusion;  // of the two blurs (the fills solve what the near layer reaches)
  Image reach;
  timed(report, "near split",
        [&] { reach = near_reach(coc, near, 0.5f * frame.max_abs_coc() + 2, threads); });
  const ConstPlane within = reach.plane(0);
  const auto in_near_field = [&near](float coc_px) { return near.contains(coc_px); };

  // Background: the near field cut out and its hole filled from around it, the colour and
  // the CoC alike (one solve at half resolution: fill_background).
  Image background(width, height, channels),
      background_coc(width, height, 2);  // |CoC|; plane 1 the near blur's weight
  timed(report, "background fill", [&] {
    fill_background(background, background_coc.plane(0), color, coc, near, fill_beta, within,
                    threads);
  });
  timed(report, "background blur", [&] {
    diffusion += diffuse(background, background, background_coc.plane(0), conductance, options);
  });

  // Near field: premultiplied colour and coverage, spreading out with its own CoC, which is
  // filled outside the near field from the near field's edge (in the background CoC's
  // buffer, which is done with).
  Image near_layer(width, height, channels + 1);
  timed(report, "near blur", [&] {
    Image& near_coc = background_coc;
    for_each_row(height, threads, [&](std::ptrdiff_t y) {
      const float* k = coc.row(y);
      float* inside = near_layer.plane(channels).row(y);
      float* sum = near_coc.plane(0).row(y);
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        inside[x] = in_near_field(k[x]) ? 1.f : 0.f;
        sum[x] = inside[x] * std::abs(k[x]);
      }
      std::copy(inside, inside + width, near_coc.plane(1).row(y));
      for (int c = 0; c < channels; ++c) {
        const float* from = color.plane(c).row(y);
        float* to = near_layer.plane(c).row(y);
        for (std::ptrdiff_t x = 0; x < width; ++x) to[x] = inside[x] * from[x];
      }
    });
    diffuse_within(near_coc, fill_beta, within, threads);
    // Out of reach the near layer is empty: no conductance, so the near blur skips it.
    for_each_row(height, threads, [&](std::ptrdiff_t y) {
      const float* k = coc.row(y);
      const float* inside = within.row(y);
      float* value = near_coc.plane(0).row(y);
      const float* weight = near_coc.plane(1).row(y);
      for (std::ptrdiff_t x = 0; x < width; ++x)
        value[x] =
            inside[x] > 0 ? filled(in_near_field(k[x]), std::abs(k[x]), value[x], weight[x]) : 0.f;
    });
    diffusion += diffuse_near(near_layer, near_layer, near_coc.plane(0), conductance, options);
  });

  // Composited into the background's buffer, which then becomes `out` (a fresh buffer for
  // `out` would cost its page faults). `out` may be the colour image itself: it is not read
  // again.
  timed(report, "composite", [&] {
    for_each_row(height, threads, [&](std::ptrdiff_t y) {
      const float* cover = near_layer.plane(channels).row(y);
      for (int c = 0; c < channels; ++c) {
        const float* near = near_layer.plane(c).row(y);
        float* far = background.plane(c).row(y);
        for (std::ptrdiff_t x = 0; x < width; ++x)
          far[x] = near[x] + (1.f - std::clamp(cover[x], 0.f, 1.f)) * far[x];
      }
    });
    out = std::move(background);
  });
  report.layered = true;
  report.notes += "near layer: CoC <= -" + std::to_string(near.split_px) + " px";
  report.skipped_fraction = diffusion.skipped_fraction();
}

}  // namespace

// Every pixel's conductance must be finite: a finite CoC above about 1.8e19 px has none. The
// largest |CoC| decides (the conductance grows with it); the slow path names the first pixel.
void require_finite_conductance(const DofFrame& frame, const CocConductance& conductance) {
  if (std::isfinite(conductance(frame.max_abs_coc()))) return;
  const ConstPlane coc = frame.coc();
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
      const float k = conductance(coc(x, y));
      if (!std::isfinite(k))
        throw InvalidArgument("coc", "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                         "): " + std::to_string(coc(x, y)) +
                                         " maps to conductance " + std::to_string(k) +
                                         "; it must be finite and >= 0");
    }
}

LinkField coc_links(ConstPlane coc, const CocConductance& conductance, int threads) {
  return links_from_pixels(coc, conductance, threads);
}

void diffusion_dof(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report,
                   const Diffuser& diffuse, float spread, const Diffuser* diffuse_near) {
  const CocConductance conductance{settings.in_focus_coc_px, spread};
  require_finite_conductance(frame, conductance);
  DiffusionOptions options;
  options.threads = settings.threads;
  options.skip_inactive = settings.skip_in_focus;
  options.progress = settings.progress;
  if (settings.layers) {
    const NearLayer near =
        near_layer(frame.coc(), settings.in_focus_coc_px, resolve_threads(settings.threads));
    if (!near.empty) {
      layered_dof(out, frame, near, settings, report, diffuse,
                  diffuse_near ? *diffuse_near : diffuse, conductance, options);
      return;
    }
  }
  DiffusionReport diffusion;
  timed(report, "diffusion",
        [&] { diffusion = diffuse(out, frame.color(), frame.coc(), conductance, options); });
  report.skipped_fraction = diffusion.skipped_fraction();
}

}  // namespace tridiff::dof_detail
