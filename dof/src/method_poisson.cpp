// The `poisson` method: the Poisson-disc gather depth of field of seed 000 §3.3.3 / §5.3.3
// (after Scheuermann 2004 and Tatarchuk): every out-of-focus pixel averages a fixed pattern of
// taps scaled to its own circle of confusion, reading a blend of the full-resolution image and
// pre-blurred copies so that a large disc is not undersampled.
//
// The taps. One pattern for every pixel, built once in code: the centre plus 12 quadruples
// (p, -p, and p turned by ±90°) chosen by best-candidate dart throwing (Mitchell 1991) with a
// fixed seed in the unit disc, so that every prefix of q quadruples is itself an even Poisson
// disc of 1 + 4q taps with zero mean and an isotropic second moment (x and y equal, no
// covariance). A pixel of radius R = |c| / 2 uses q = clamp(ceil(R² / 2), 3, 12) quadruples
// (13 taps for R <= 2 ... 49 from R = 5 on): small discs need few taps.
//
// The scale. The tap offsets are R' p_i where R' makes the gather's variance per axis equal to
// that of the `scatter` reference's anti-aliased disc of radius R (var(R) below, ~R²/4):
// m2 R'² + V = var(R), m2 the pattern's second moment, V the variance the sampled image adds
// (1/6 for bilinear reads of the full-resolution image, more for a blurred one).
//
// The blend (seed 000 §5.3.3's "full scale and down sampled image", generalised). The taps of a
// disc lie R' sqrt(pi / n) apart; sampling an image sharper than about half that spacing
// aliases (the seed's remedy: a downsampled image). So V = max(1/6, pi R'² / (4 n)), and the
// taps read (1 - t) L_l + t L_{l+1} from a chain of levels: L_0 the input, L_l (l >= 1) the
// input blurred by three box passes of sigma ~ 2^(l-1) (blur/box.hpp) and stored every
// max(1, 2^(l-2)) pixels (1.3 frames of memory in all), read bilinearly. Levels have variance
// V_l (their box passes plus their bilinear reads), and t interpolates the variance: the blend
// adds exactly V. Deviation: the seed has one downsampled image of 1/16 the size, so its blur
// is small and bounded; the chain keeps any CoC sampled at the same cost per pixel. Levels stop
// at sigma = min(256, 2 max(W, H)) (memory); beyond R ~ 2000 px the taps would alias.
//
// The tap weights (seed 000 §5.3.3: "scale the taps' contribution depending on if they have
// CoC values larger or smaller than the middle tap"), made precise as the scatter's own rule:
// a neighbour contributes to a pixel only where its own disc reaches it. A tap standing for the
// distance rho = R |p_i| in the pixel's disc reads the CoC of the nearest pixel, radius r_n:
//     w_i = 0                                  if that pixel is sharp (a point covers itself only)
//     w_i = clamp(r_n + 1 - rho, 0, 1) * min(1, (R / r_n)²)    otherwise,
// a one-pixel ramp beyond the neighbour's rim (so that for a uniform CoC every weight is 1) times
// the area normalisation of a scatter splat for neighbours larger than the pixel (a wider splat
// spreads its energy thinner). The centre has weight 1; out = sum w_i s_i / sum w_i. A sharp
// neighbour therefore does not bleed into a blurred pixel, and a sharp pixel gathers nothing
// (R = 0: its output is its input, bit for bit), so a blurred neighbour cannot bleed into it.
// Deviation (beyond the seed): the weights alone leave the colour leak of §6.5 (fig. 6.2) —
// a tap's bilinear read and the blurred levels mix in the sharp pixels beside it. So every
// level is a mask-normalised read, blur(colour m) / blur(m) with m = 1 on out-of-focus pixels
// and 1/1024 on sharp ones (level 0: the bilinear reads of colour m and of m, the division
// folded into the tap weights). A bright sharp line next to a blur leaks 1e-4 of itself
// (the test measures it; plain bilinear reads leaked 1.5 %).
//
// The frame border is a mirror, as in `scatter`: a tap outside the frame reads the image
// reflected about the outer edge of the border pixels (-1 is 0, W is W - 1); the blurred levels
// are blurs of the mirror-extended image (padded before the box passes).
//
// Known artifacts (seed 000 §6.5). (1) The foreground: the gather by the pixel's own CoC cannot
// blur a near object over a sharp background — the sharp background pixels keep their values, so
// an out-of-focus near object keeps a sharp silhouette (fig. 6.3); blurs_foreground is false and
// DofOptions::layers is ignored. (2) Colour leaking (fig. 6.2): the blurred levels already mix a
// sharp object's colour into its surroundings, so a blurred pixel next to a bright sharp object
// gets a faint halo whatever the weights (bilinear reads leak up to one pixel too). (3) Depth
// order between two out-of-focus regions is approximated by the coverage weights, not
// composited: a far pixel next to a blurred near object takes some of its colour, a near edge
// does not become transparent. (4) 13 to 49 taps give a slightly blotchy disc on textured
// regions where the blend is mostly full resolution.
//
// What holds exactly: all-sharp input returns the input bit for bit; a constant image stays
// constant up to float rounding (weights sum to 1, levels are normalised blurs); the output of a
// pixel is a convex combination of input values (within the input's range); the result does
// not depend on the thread count (one pixel, one fixed sequence of operations).
//
// Skipping: a pixel's gather radius is its own, so a tile without an out-of-focus pixel of its
// own returns its input; such tiles are copied (the TileMap's unreached tiles by
// copy_unreached_tiles, reached ones with no own disc here). This changes no bit.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "tridiff/blur/box.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"
#include "tridiff/threads.hpp"
#include "frame.hpp"
#include "tiled_gather.hpp"

namespace tridiff {
namespace {

constexpr int kQuads = 12;  // the pattern's quadruples: 48 taps + the centre
constexpr int kMaxTaps = 1 + 4 * kQuads;
constexpr int kMinQuads = 3;
constexpr float kMaxRadius = 1 << 20;         // px; a larger CoC is clamped (float positions)
constexpr double kMaxLevelSigma = 256;        // px; the padded blur of one plane stays < 1 GB
constexpr float kBilinearVariance = 1.f / 6;  // mean f (1 - f) of a bilinear read
constexpr float kSharpMask = 1.f / 1024;      // a sharp pixel's share in the blurred levels

// The tap pattern in the unit disc, and the per-axis second moment of each prefix.
struct TapPattern {
  std::array<float, kMaxTaps> x{}, y{}, radius{};
  std::array<float, kQuads + 1> m2{};           // m2[q]: of the first 1 + 4q taps
  std::array<float, kQuads + 1> alias_ratio{};  // a / (m2 + a), a = pi / (4 (1 + 4q))
};

TapPattern make_pattern() {
  TapPattern pattern;
  // A fixed generator and an explicit float conversion: the same pattern on every platform
  // (std::uniform_real_distribution is not specified bit for bit).
  std::uint32_t state = 0x2545F491u;
  auto uniform = [&state] {
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return double(state >> 8) * (1.0 / 16777216.0);
  };
  int count = 1;  // the centre, at (0, 0)
  for (int q = 0; q < kQuads; ++q) {
    double best_x = 0, best_y = 0, best_gap = -1;
    for (int candidate = 0; candidate < 64 * (q + 1); ++candidate) {
      const double r = std::sqrt(uniform()), angle = 2 * std::numbers::pi * uniform();
      const double cx = r * std::cos(angle), cy = r * std::sin(angle);
      // Distance to the taps so far and to the candidate's own quadruple.
      double gap = std::min(std::hypot(2 * cx, 2 * cy), std::sqrt(2.0) * r);
      for (int i = 0; i < count; ++i)
        gap = std::min(gap, std::hypot(cx - pattern.x[i], cy - pattern.y[i]));
      if (gap > best_gap) {
        best_gap = gap;
        best_x = cx;
        best_y = cy;
      }
    }
    const double quad[4][2] = {
        {best_x, best_y}, {-best_x, -best_y}, {-best_y, best_x}, {best_y, -best_x}};
    for (const auto& p : quad) {
      pattern.x[count] = float(p[0]);
      pattern.y[count] = float(p[1]);
      pattern.radius[count] = float(std::hypot(p[0], p[1]));
      ++count;
    }
  }
  for (int q = 0; q <= kQuads; ++q) {
    const int n = 1 + 4 * q;
    double sum = 0;
    for (int i = 0; i < n; ++i)
      sum += 0.5 * (double(pattern.x[i]) * pattern.x[i] + double(pattern.y[i]) * pattern.y[i]);
    pattern.m2[q] = float(sum / n);
    const double a = std::numbers::pi / (4.0 * n);
    pattern.alias_ratio[q] = float(a / (sum / n + a));
  }
  return pattern;
}

const TapPattern& tap_pattern() {
  static const TapPattern pattern = make_pattern();
  return pattern;
}

// The per-axis variance of the scatter reference's disc of radius r (method_scatter.cpp:
// coverage min(1, r + 1/2 - |d|) on the pixel grid, normalised), tabulated every 1/16 px up to
// 32 px; beyond, r²/4 plus the table's last excess over r²/4 (the rim's share, constant).
class ScatterDiscVariance {
 public:
  static constexpr int kPerPixel = 16, kTableRadius = 32;

  ScatterDiscVariance() {
    for (int i = 0; i < kSize; ++i) table_[i] = direct(double(i) / kPerPixel);
    excess_ = table_[kSize - 1] - 0.25f * kTableRadius * kTableRadius;
  }
  float operator()(float r) const {
    const float u = r * kPerPixel;
    if (u >= float(kSize - 1)) return 0.25f * r * r + excess_;
    const int i = int(u);
    const float f = u - float(i);
    return table_[i] + f * (table_[i + 1] - table_[i]);
  }

 private:
  static constexpr int kSize = kTableRadius * kPerPixel + 1;

  static float direct(double r) {
    const double outer = r + 0.5;
    const std::ptrdiff_t reach = std::ptrdiff_t(std::ceil(outer)) - 1;
    double sum = 0, moment = 0;
    for (std::ptrdiff_t dy = -reach; dy <= reach; ++dy)
      for (std::ptrdiff_t dx = -reach; dx <= reach; ++dx) {
        const double w = std::min(1.0, outer - std::sqrt(double(dx * dx + dy * dy)));
        if (w <= 0) continue;
        sum += w;
        moment += w * 0.5 * double(dx * dx + dy * dy);
      }
    return float(moment / sum);
  }

  std::array<float, kSize> table_{};
  float excess_ = 0;
};

const ScatterDiscVariance& scatter_disc_variance() {
  static const ScatterDiscVariance variance;
  return variance;
}

// The mirror fold of a continuous coordinate into [-1/2, n - 1/2]: the frame reflected about the
// outer edges of its border pixels.
inline float fold_position(float x, std::ptrdiff_t n) {
  const float hi = float(n) - 0.5f;
  if (x >= -0.5f && x <= hi) return x;
  const float period = 2.f * float(n);
  float m = std::fmod(x + 0.5f, period);
  if (m < 0) m += period;
  if (m > float(n)) m = period - m;
  return std::clamp(m - 0.5f, -0.5f, hi);
}

// The mirror fold of an integer coordinate into [0, n).
inline std::ptrdiff_t fold_index(std::ptrdiff_t x, std::ptrdiff_t n) {
  if (x >= 0 && x < n) return x;
  const std::ptrdiff_t period = 2 * n;
  std::ptrdiff_t m = x % period;
  if (m < 0) m += period;
  return m < n ? m : period - 1 - m;
}

// One level of the chain: sample (i, j) holds the (blurred) mirror-extended image at input
// position ((i - 1) h, (j - 1) h), so that every folded position has a bilinear neighbourhood.
struct Level {
  Image samples;
  Image mask;          // level 0 only: samples hold colour x mask; reads divide by it
  float spacing = 1;   // h, input pixels between samples
  float variance = 0;  // per axis, of the blur and the bilinear read together
};

Level build_level(const Image& color, ConstPlane coc, FocusTest focus, double sigma, int threads) {
  const std::ptrdiff_t width = color.width(), height = color.height();
  Level level;
  std::vector<BoxPass> passes;
  double blur_variance = 0;
  std::ptrdiff_t support = 0;
  std::ptrdiff_t spacing = 1;
  if (sigma > 0) {
    passes = plain_box_passes(sigma, kDefaultBoxPasses);
    for (const BoxPass& pass : passes) {
      blur_variance += box_variance(2 * pass.radius + 1);
      support += pass.radius;
    }
    // Samples sigma / 2 apart: a bilinear read of a Gaussian-like blur that wide errs ~1 %.
    spacing = std::max<std::ptrdiff_t>(1, std::ptrdiff_t(std::sqrt(blur_variance) / 2));
  }
  level.spacing = float(spacing);
  level.variance = float(blur_variance) + kBilinearVariance * float(spacing * spacing);
  const std::ptrdiff_t cols = (2 * width - 1) / (2 * spacing) + 3,
                       rows = (2 * height - 1) / (2 * spacing) + 3;
  level.samples.reset(cols, rows, color.channels());
  auto mask_of = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
    return !focus.is_sharp(coc(fold_index(x, width), fold_index(y, height))) ? 1.f : kSharpMask;
  };
  if (passes.empty()) {
    // The input premultiplied by the mask, and the mask: a bilinear read divided by the
    // mask's read takes (almost) nothing from a sharp pixel beside the tap.
    level.mask.reset(cols, rows, 1);
    const Plane mask = level.mask.plane(0);
    for (std::ptrdiff_t j = 0; j < rows; ++j)
      for (std::ptrdiff_t i = 0; i < cols; ++i) mask(i, j) = mask_of(i - 1, j - 1);
    for (int c = 0; c < color.channels(); ++c) {
      const ConstPlane in = color.plane(c);
      const Plane to = level.samples.plane(c);
#pragma omp parallel for num_threads(threads) schedule(static)
      for (std::ptrdiff_t j = 0; j < rows; ++j)
        for (std::ptrdiff_t i = 0; i < cols; ++i)
          to(i, j) = mask(i, j) * in(fold_index(i - 1, width), fold_index(j - 1, height));
    }
    return level;
  }
  // A normalised blur of the mirror-padded planes: blur(colour mask) / blur(mask), the mask
  // kSharpMask on sharp pixels and 1 elsewhere, so that the blurred levels carry (almost) no
  // colour of sharp pixels into their surroundings — the colour leaking of seed 000 §6.5
  // (fig. 6.2) that tap weights alone cannot stop. The padded planes' own (replicate) border
  // lies beyond what is read.
  const std::ptrdiff_t pad = support + spacing + 2;
  const std::ptrdiff_t padded_width = width + 2 * pad, padded_height = height + 2 * pad;
  Image mask(padded_width, padded_height, 1), padded(padded_width, padded_height, 1);
  const Plane mask_plane = mask.plane(0), work = padded.plane(0);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t y = 0; y < padded_height; ++y)
    for (std::ptrdiff_t x = 0; x < padded_width; ++x) mask_plane(x, y) = mask_of(x - pad, y - pad);
  Image blurred_mask = mask;
  box_passes(blurred_mask.plane(0), blurred_mask.plane(0), passes, threads);
  const ConstPlane norm = blurred_mask.plane(0);
  for (int c = 0; c < color.channels(); ++c) {
    const ConstPlane in = color.plane(c);
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t y = 0; y < padded_height; ++y) {
      const float* from = in.row(fold_index(y - pad, height));
      const float* weights = mask_plane.row(y);
      float* row = work.row(y);
      for (std::ptrdiff_t x = 0; x < padded_width; ++x)
        row[x] = weights[x] * from[fold_index(x - pad, width)];
    }
    box_passes(work, work, passes, threads);
    const Plane to = level.samples.plane(c);
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t j = 0; j < rows; ++j)
      for (std::ptrdiff_t i = 0; i < cols; ++i) {
        const std::ptrdiff_t px = pad + (i - 1) * spacing, py = pad + (j - 1) * spacing;
        to(i, j) = work(px, py) / norm(px, py);
      }
  }
  return level;
}

// How one pixel of radius R gathers: its taps, their scale, and the blend of two levels.
struct PixelPlan {
  int taps = 1;
  float scale = 0;  // R'
  int level = 0;    // reads (1 - blend) level + blend (level + 1)
  float blend = 0;
};

int quads_for(float radius) {
  return std::clamp(int(std::ceil(0.5f * radius * radius)), kMinQuads, kQuads);
}

PixelPlan plan_pixel(float radius, const std::vector<Level>& levels) {
  const TapPattern& pattern = tap_pattern();
  PixelPlan plan;
  const int q = quads_for(radius);
  plan.taps = 1 + 4 * q;
  const float target = scatter_disc_variance()(radius);
  const float m2 = pattern.m2[q], alias = std::numbers::pi_v<float> / (4.f * float(plan.taps));
  // m2 R'² + max(1/6, alias R'²) = target: the smaller root of the two linear pieces.
  const float scale2 =
      std::max(0.f, std::min((target - kBilinearVariance) / m2, target / (m2 + alias)));
  plan.scale = std::sqrt(scale2);
  const float wanted = std::max(kBilinearVariance, alias * scale2);
  const int top = int(levels.size()) - 1;
  while (plan.level < top && levels[plan.level + 1].variance <= wanted) ++plan.level;
  if (plan.level < top) {
    const float lo = levels[plan.level].variance, hi = levels[plan.level + 1].variance;
    plan.blend = std::clamp((wanted - lo) / (hi - lo), 0.f, 1.f);
  }
  return plan;
}

// The bilinear read of tap position (x, y), already folded, on one level: the offset of the
// top-left sample and the four weights.
struct Bilinear {
  std::ptrdiff_t offset;
  float w00, w10, w01, w11;
};

inline Bilinear bilinear(const Level& level, float x, float y) {
  const float inv = 1.f / level.spacing;
  const float u = x * inv, v = y * inv;
  const float u0 = std::floor(u), v0 = std::floor(v);
  const float fu = u - u0, fv = v - v0;
  const std::ptrdiff_t i = std::ptrdiff_t(u0) + 1, j = std::ptrdiff_t(v0) + 1;
  return {j * level.samples.pitch() + i, (1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv,
          fu * fv};
}

inline void scale(Bilinear& b, float factor) {
  b.w00 *= factor;
  b.w10 *= factor;
  b.w01 *= factor;
  b.w11 *= factor;
}

inline float read(const float* plane, std::ptrdiff_t pitch, const Bilinear& b) {
  const float* p = plane + b.offset;
  return b.w00 * p[0] + b.w10 * p[1] + b.w01 * p[pitch] + b.w11 * p[pitch + 1];
}

// The gather of one pixel (x, y) of signed CoC c into out (every channel). A sharp pixel keeps
// its value. This is the whole per-pixel mathematics; the driver below only traverses.
void gather_pixel(Image& out, const Image& color, ConstPlane coc, std::ptrdiff_t x,
                  std::ptrdiff_t y, FocusTest focus, const std::vector<Level>& levels) {
  const std::ptrdiff_t width = color.width(), height = color.height();
  const float c = coc(x, y);
  const int channels = color.channels();
  if (focus.is_sharp(c)) {
    for (int ch = 0; ch < channels; ++ch) out(x, y, ch) = color(x, y, ch);
    return;
  }
  const float radius = std::min(0.5f * std::fabs(c), kMaxRadius);
  const PixelPlan plan = plan_pixel(radius, levels);
  const TapPattern& pattern = tap_pattern();
  const Level& lo = levels[std::size_t(plan.level)];
  const Level& hi = levels[std::size_t(std::min<int>(plan.level + 1, int(levels.size()) - 1))];
  const bool two = plan.blend > 0;

  std::array<Bilinear, kMaxTaps> read_lo, read_hi;
  float weight_sum = 0;
  for (int i = 0; i < plan.taps; ++i) {
    const float px = fold_position(float(x) + plan.scale * pattern.x[i], width);
    const float py = fold_position(float(y) + plan.scale * pattern.y[i], height);
    const std::ptrdiff_t nx = std::min(std::ptrdiff_t(std::floor(px + 0.5f)), width - 1);
    const std::ptrdiff_t ny = std::min(std::ptrdiff_t(std::floor(py + 0.5f)), height - 1);
    const float neighbour = std::fabs(coc(nx, ny));
    float w = 0;
    if (i == 0) {
      w = 1;  // the pixel itself
    } else if (!focus.is_sharp(neighbour)) {
      const float r = std::min(0.5f * neighbour, kMaxRadius);
      const float area = r > radius ? (radius / r) * (radius / r) : 1.f;
      w = std::clamp(r + 1 - radius * pattern.radius[i], 0.f, 1.f) * area;
    }
    weight_sum += w;
    // The tap's weight and its share of the blend folded into the bilinear weights.
    read_lo[i] = bilinear(lo, px, py);
    float share = w * (1 - plan.blend);
    if (!lo.mask.empty()) share /= read(lo.mask.plane(0).data(), lo.mask.pitch(), read_lo[i]);
    scale(read_lo[i], share);
    if (two) {
      read_hi[i] = bilinear(hi, px, py);
      scale(read_hi[i], w * plan.blend);
    }
  }
  const float inv_sum = 1.f / weight_sum;
  for (int ch = 0; ch < channels; ++ch) {
    const float* plane_lo = lo.samples.plane(ch).data();
    const std::ptrdiff_t pitch_lo = lo.samples.pitch();
    float sum = 0;
    for (int i = 0; i < plan.taps; ++i) sum += read(plane_lo, pitch_lo, read_lo[i]);
    if (two) {
      const float* plane_hi = hi.samples.plane(ch).data();
      const std::ptrdiff_t pitch_hi = hi.samples.pitch();
      for (int i = 0; i < plan.taps; ++i) sum += read(plane_hi, pitch_hi, read_hi[i]);
    }
    out(x, y, ch) = sum * inv_sum;
  }
}

// The levels the frame's largest disc needs: V <= max(1/6, var(R) a / (m2 + a)) for every
// pixel (plan_pixel), so the chain stops at the first level of at least that variance. None
// when no pixel is out of focus.
std::vector<Level> build_levels(const DofFrame& frame) {
  std::vector<Level> levels;
  const float max_radius = std::min(frame.max_radius(), kMaxRadius);
  if (!(max_radius > 0)) return levels;
  const Image& color = frame.color();
  const ConstPlane coc = frame.coc();
  const FocusTest focus = frame.focus();
  const int team = frame.threads();
  const TapPattern& pattern = tap_pattern();
  const float ratio =
      *std::max_element(pattern.alias_ratio.begin() + kMinQuads, pattern.alias_ratio.end());
  const float needed = std::max(kBilinearVariance, scatter_disc_variance()(max_radius) * ratio);
  const double cap =
      std::min(kMaxLevelSigma, 2.0 * double(std::max(color.width(), color.height())));
  levels.push_back(build_level(color, coc, focus, 0, team));
  for (double sigma = 1; levels.back().variance < needed && sigma <= cap; sigma *= 2)
    levels.push_back(build_level(color, coc, focus, sigma, team));
  return levels;
}

std::string describe_levels(const std::vector<Level>& levels) {
  std::string sigmas;
  for (std::size_t l = 1; l < levels.size(); ++l)
    sigmas += (l > 1 ? ", " : "") + std::to_string(std::sqrt(levels[l].variance)).substr(0, 5);
  return std::to_string(levels.size()) + " levels (read sigma 0.41" +
         (sigmas.empty() ? "" : ", " + sigmas) +
         " px), 13-49 taps; the near field is not blurred over its background";
}

}  // namespace

namespace dof_detail {

void run_poisson(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  const Image& color = frame.color();
  Stages stages(report);
  const TiledGather gather(frame.tiles(), settings.skip_in_focus, frame.threads());
  out.reset(frame.width(), frame.height(), frame.channels());
  stages.end("tiles");

  const std::vector<Level> levels = build_levels(frame);
  stages.end("levels");

  // A pixel's gather radius is its own: a tile without a disc of its own is a copy.
  const std::ptrdiff_t copied = gather.for_each_tile([&](const Rect& area,
                                                         const TileInfo& tile) -> std::ptrdiff_t {
    if (levels.empty() || (gather.skip() && tile.max_radius == 0)) {
      for (int ch = 0; ch < color.channels(); ++ch)
        for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
          std::copy_n(color.plane(ch).row(y) + area.x, area.width, out.plane(ch).row(y) + area.x);
      return gather.skip() ? area.area() : 0;
    }
    for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
      for (std::ptrdiff_t x = area.x; x < area.x + area.width; ++x)
        gather_pixel(out, color, frame.coc(), x, y, frame.focus(), levels);
    return 0;
  });
  gather.copy_the_rest(out, color);
  stages.end("gather");

  report.skipped_fraction = double(copied) / double(frame.width() * frame.height());
  report.layered = false;
  report.notes = describe_levels(levels);
  if (settings.progress) settings.progress(1.0);
}

}  // namespace dof_detail
}  // namespace tridiff
