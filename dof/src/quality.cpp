// The DOF error harness (quality.hpp): plain error sums, SSIM from the blur harness, and the
// in-focus and leakage regions from an exact Euclidean distance transform of the sharp pixels.
#include "tridiff/dof/quality.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "tridiff/blur/quality.hpp"

namespace tridiff {
namespace {

void require_same_shape(const Image& image, const Image& reference, const char* name) {
  if (image.width() != reference.width() || image.height() != reference.height() ||
      image.channels() != reference.channels())
    throw InvalidArgument(
        name, "is " + std::to_string(image.width()) + " x " + std::to_string(image.height()) +
                  " x " + std::to_string(image.channels()) + ", the reference is " +
                  std::to_string(reference.width()) + " x " + std::to_string(reference.height()) +
                  " x " + std::to_string(reference.channels()));
}

void require_coc_size(const Image& reference, ConstPlane coc) {
  if (coc.width() != reference.width() || coc.height() != reference.height())
    throw InvalidArgument("coc", "is " + std::to_string(coc.width()) + " x " +
                                     std::to_string(coc.height()) + ", the images are " +
                                     std::to_string(reference.width()) + " x " +
                                     std::to_string(reference.height()));
}

// Stands for "no sharp pixel on this line": larger than any squared distance in a frame, small
// enough that differences of it stay exact enough for the envelope's intersections.
constexpr double kFar = 1e20;

// One line of the squared Euclidean distance transform (Felzenszwalb & Huttenlocher 2012):
// d[q] = min_p (q - p)^2 + f[p], by the lower envelope of the parabolas rooted at each p.
void distance_1d(const std::vector<double>& f, std::vector<double>& d,
                 std::vector<std::ptrdiff_t>& root, std::vector<double>& bound) {
  const auto n = std::ptrdiff_t(f.size());
  root.assign(std::size_t(n), 0);
  bound.assign(std::size_t(n + 1), 0);
  std::ptrdiff_t k = 0;
  bound[0] = -std::numeric_limits<double>::infinity();
  bound[1] = std::numeric_limits<double>::infinity();
  auto meet = [&](std::ptrdiff_t q, std::ptrdiff_t p) {  // where parabolas q and p intersect
    return ((f[std::size_t(q)] + double(q * q)) - (f[std::size_t(p)] + double(p * p))) /
           double(2 * (q - p));
  };
  for (std::ptrdiff_t q = 1; q < n; ++q) {
    double s = meet(q, root[std::size_t(k)]);
    while (s <= bound[std::size_t(k)]) s = meet(q, root[std::size_t(--k)]);  // bound[0] = -inf
    ++k;
    root[std::size_t(k)] = q;
    bound[std::size_t(k)] = s;
    bound[std::size_t(k + 1)] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (std::ptrdiff_t q = 0; q < n; ++q) {
    while (bound[std::size_t(k + 1)] < double(q)) ++k;
    const std::ptrdiff_t p = root[std::size_t(k)];
    d[std::size_t(q)] = double((q - p) * (q - p)) + f[std::size_t(p)];
  }
}

// Squared distance from every pixel centre to the nearest pixel with mask 1 (kFar or more when
// there is none), raster order: columns first, then rows.
std::vector<double> squared_distance(const std::vector<unsigned char>& mask, std::ptrdiff_t width,
                                     std::ptrdiff_t height) {
  std::vector<double> dist(mask.size());
  std::vector<double> f, d;
  std::vector<std::ptrdiff_t> root;
  std::vector<double> bound;
  f.resize(std::size_t(height));
  d.resize(std::size_t(height));
  for (std::ptrdiff_t x = 0; x < width; ++x) {
    for (std::ptrdiff_t y = 0; y < height; ++y)
      f[std::size_t(y)] = mask[std::size_t(y * width + x)] ? 0.0 : kFar;
    distance_1d(f, d, root, bound);
    for (std::ptrdiff_t y = 0; y < height; ++y)
      dist[std::size_t(y * width + x)] = d[std::size_t(y)];
  }
  f.resize(std::size_t(width));
  d.resize(std::size_t(width));
  for (std::ptrdiff_t y = 0; y < height; ++y) {
    std::copy_n(dist.begin() + y * width, width, f.begin());
    distance_1d(f, d, root, bound);
    std::copy_n(d.begin(), width, dist.begin() + y * width);
  }
  return dist;
}

}  // namespace

DofRegions dof_regions(const Image& reference, const Image& input, ConstPlane coc,
                       float in_focus_coc_px) {
  require_same_shape(input, reference, "input");
  require_coc_size(reference, coc);
  const std::ptrdiff_t width = reference.width(), height = reference.height();
  const float sharp_below = std::max(1.f, in_focus_coc_px);
  DofRegions regions;
  std::vector<unsigned char> sharp(std::size_t(width * height), 0);
  regions.in_focus.assign(sharp.size(), 0);
  regions.leakage.assign(sharp.size(), 0);
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      if (!(std::fabs(coc(x, y)) < sharp_below)) continue;
      sharp[std::size_t(y * width + x)] = 1;
      bool unchanged = true;
      for (int c = 0; c < reference.channels(); ++c)
        unchanged = unchanged && std::bit_cast<std::uint32_t>(reference(x, y, c)) ==
                                     std::bit_cast<std::uint32_t>(input(x, y, c));
      regions.in_focus[std::size_t(y * width + x)] = unchanged;
    }
  const std::vector<double> dist2 = squared_distance(sharp, width, height);
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      const double c = coc(x, y);
      const std::size_t i = std::size_t(y * width + x);
      regions.leakage[i] = c >= sharp_below && dist2[i] <= 0.25 * c * c;
    }
  return regions;
}

DofError dof_error(const Image& out, const Image& reference, const Image& input, ConstPlane coc,
                   float in_focus_coc_px) {
  require_same_shape(out, reference, "out");
  const DofRegions regions = dof_regions(reference, input, coc, in_focus_coc_px);
  const std::ptrdiff_t width = reference.width(), height = reference.height();
  const int channels = reference.channels();
  DofError error;
  double sum_sq = 0, in_focus_sq = 0, leak_sq = 0, clipped_mse = 0;
  for (int c = 0; c < channels; ++c) {
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        const std::size_t i = std::size_t(y * width + x);
        const double d = double(out(x, y, c)) - double(reference(x, y, c));
        sum_sq += d * d;
        error.max_abs = std::max(error.max_abs, std::fabs(d));
        if (regions.leakage[i]) leak_sq += d * d;
        if (regions.in_focus[i]) {
          const double e = double(out(x, y, c)) - double(input(x, y, c));
          in_focus_sq += e * e;
          error.in_focus_max = std::max(error.in_focus_max, std::fabs(e));
        }
      }
    // The blur harness's PSNR / SSIM on this channel clipped to [0, 1].
    Image clipped_out(width, height, 1);
    DoublePlane clipped_ref(width, height);
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) {
        clipped_out(x, y, 0) = std::clamp(out(x, y, c), 0.f, 1.f);
        clipped_ref(x, y) = std::clamp(double(reference(x, y, c)), 0.0, 1.0);
      }
    const BlurError channel = blur_error(clipped_out.plane(0), clipped_ref);
    clipped_mse += channel.rmse * channel.rmse / channels;
    error.ssim += channel.ssim / channels;
  }
  for (std::size_t i = 0; i < regions.in_focus.size(); ++i) {
    error.in_focus_pixels += regions.in_focus[i];
    error.leakage_pixels += regions.leakage[i];
  }
  const double samples = double(width * height * channels);
  error.rmse = std::sqrt(sum_sq / samples);
  error.psnr =
      clipped_mse > 0 ? -10 * std::log10(clipped_mse) : std::numeric_limits<double>::infinity();
  if (error.in_focus_pixels > 0)
    error.in_focus_rmse = std::sqrt(in_focus_sq / double(error.in_focus_pixels * channels));
  if (error.leakage_pixels > 0)
    error.leakage = std::sqrt(leak_sq / double(error.leakage_pixels * channels));
  return error;
}

}  // namespace tridiff
