// Diffusion operators (tridiff::diffusion): the ADI step of seed 000 §3.5 (eq. 3.8-3.10) against
// dense LU solves in long double, its invariants (mass per row and column, maximum principle,
// insulated pixels untouched, skipping and threads change nothing), the variance a step adds
// (2 beta per pass, so adi_beta_for_coc spreads like the disc), the explicit steps of seed 001
// §3.9 (eq. 3.21) and seed 000 eq. 5.4 (variance 2cN, stability bound, sub-stepping), the
// convergence of both schemes to the exact exp(-L) of the heat equation, the links (min rule,
// tiles, validation) and the pixel named when the input is not finite.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "tridiff/diffusion/adi.hpp"
#include "tridiff/diffusion/explicit.hpp"
#include "tridiff/diffusion/links.hpp"
#include "test_util.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

constexpr double kEps = std::numeric_limits<float>::epsilon();  // 2^-23
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr std::ptrdiff_t kTile = LinkField::kTile;

struct Size {
  std::ptrdiff_t width, height;
};

// Degenerate shapes, shapes below, at and across the 64-pixel tiles (one tile row is one SIMD
// batch of 64 float lanes) and odd sizes whose last tile and last batch are partial.
constexpr Size kSizes[] = {{1, 1},   {1, 37},   {37, 1},   {2, 3},    {7, 5},
                           {63, 65}, {65, 130}, {129, 67}, {200, 150}};

std::string name(Size size) {
  return std::to_string(size.width) + " x " + std::to_string(size.height);
}

std::string pixel(std::ptrdiff_t x, std::ptrdiff_t y) {
  return "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")";
}

// Uniform random values in [0, 1), the same for every run.
Image random_image(Size size, int channels, std::uint64_t seed) {
  Image image(size.width, size.height, channels);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<float> uniform(0.f, 1.f);
  for (int c = 0; c < channels; ++c)
    for (std::ptrdiff_t y = 0; y < size.height; ++y)
      for (std::ptrdiff_t x = 0; x < size.width; ++x) image(x, y, c) = uniform(random);
  return image;
}

// Links uniform in [0, max_beta), a fraction `zeros` of them exactly zero.
LinkField random_links(Size size, float max_beta, double zeros, std::uint64_t seed) {
  LinkField links(size.width, size.height);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<float> uniform(0.f, 1.f);
  for (Plane p : {links.horizontal(), links.vertical()})
    for (std::ptrdiff_t y = 0; y < size.height; ++y)
      for (std::ptrdiff_t x = 0; x < size.width; ++x)
        p(x, y) = uniform(random) < zeros ? 0.f : max_beta * uniform(random);
  links.finish();
  return links;
}

// Every link equal to `beta` (finish() then insulates the border).
LinkField uniform_links(Size size, float beta) {
  LinkField links(size.width, size.height);
  for (Plane p : {links.horizontal(), links.vertical()})
    for (std::ptrdiff_t y = 0; y < size.height; ++y)
      std::fill(p.row(y), p.row(y) + size.width, beta);
  links.finish();
  return links;
}

// Links scaled by `scale` (rounded to float), as the per-step conductances of a finer scheme.
LinkField scaled_links(const LinkField& links, float scale) {
  LinkField scaled(links.width(), links.height());
  for (int d = 0; d < 2; ++d) {
    ConstPlane from = d == 0 ? links.horizontal() : links.vertical();
    Plane to = d == 0 ? scaled.horizontal() : scaled.vertical();
    for (std::ptrdiff_t y = 0; y < from.height(); ++y)
      for (std::ptrdiff_t x = 0; x < from.width(); ++x) to(x, y) = from(x, y) * scale;
  }
  scaled.finish();
  return scaled;
}

double max_abs(const Image& image) {
  double m = 0;
  for (int c = 0; c < image.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < image.height(); ++y)
      for (std::ptrdiff_t x = 0; x < image.width(); ++x)
        m = std::max(m, std::abs(double(image(x, y, c))));
  return m;
}

// The first pixel (in channel, row, column order) whose bits differ, or "" if none.
std::string first_bit_difference(const Image& a, const Image& b) {
  if (a.width() != b.width() || a.height() != b.height() || a.channels() != b.channels())
    return "sizes differ";
  for (int c = 0; c < a.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < a.height(); ++y)
      for (std::ptrdiff_t x = 0; x < a.width(); ++x)
        if (std::bit_cast<std::uint32_t>(a(x, y, c)) != std::bit_cast<std::uint32_t>(b(x, y, c)))
          return pixel(x, y) + " channel " + std::to_string(c) + ": " + std::to_string(a(x, y, c)) +
                 " vs " + std::to_string(b(x, y, c));
  return "";
}

// ---------------------------------------------------------------------------------------------
// Independent references in long double (as in reference.hpp; Eigen's vectorised double GEMM
// also trips a false -Wmaybe-uninitialized of GCC 12 with AVX-512)

using WideMatrix = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
using WideVector = Eigen::Matrix<long double, Eigen::Dynamic, 1>;

// y = (I + L) \ x for one line, L the weighted Laplacian of links beta[i] between i and i + 1
// (beta[n - 1] is not a link): the matrix of seed 000 eq. 3.10 with gamma = 1, built densely
// and solved by LU with partial pivoting.
WideVector dense_line_solve(const std::vector<long double>& beta, const WideVector& x) {
  const Eigen::Index n = x.size();
  WideMatrix m = WideMatrix::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const long double left = i > 0 ? beta[i - 1] : 0.0L, right = i + 1 < n ? beta[i] : 0.0L;
    m(i, i) = 1 + left + right;
    if (i > 0) m(i, i - 1) = -left;
    if (i + 1 < n) m(i, i + 1) = -right;
  }
  return m.partialPivLu().solve(x);
}

// One ADI step of one plane: every row solved densely, then every column of that result.
// Returns the values in row-major order (index y * width + x).
std::vector<double> reference_adi(ConstPlane src, const LinkField& beta) {
  const std::ptrdiff_t w = src.width(), h = src.height();
  std::vector<double> out(w * h);
  for (std::ptrdiff_t y = 0; y < h; ++y) {
    WideVector line(w);
    std::vector<long double> links(w);
    for (std::ptrdiff_t x = 0; x < w; ++x) {
      line(x) = src(x, y);
      links[x] = beta.horizontal()(x, y);
    }
    const WideVector solved = dense_line_solve(links, line);
    for (std::ptrdiff_t x = 0; x < w; ++x) out[y * w + x] = double(solved(x));
  }
  for (std::ptrdiff_t x = 0; x < w; ++x) {
    WideVector line(h);
    std::vector<long double> links(h);
    for (std::ptrdiff_t y = 0; y < h; ++y) {
      line(y) = out[y * w + x];
      links[y] = beta.vertical()(x, y);
    }
    const WideVector solved = dense_line_solve(links, line);
    for (std::ptrdiff_t y = 0; y < h; ++y) out[y * w + x] = double(solved(y));
  }
  return out;
}

// The 2-D weighted Laplacian (positive semi-definite) of a link field, pixel (x, y) at index
// y * width + x: the heat equation dI/dt = div(beta grad I) of seed 000 eq. 3.8 is dI/dt = -L I.
WideMatrix laplacian(const LinkField& beta) {
  const std::ptrdiff_t w = beta.width(), h = beta.height();
  WideMatrix l = WideMatrix::Zero(w * h, w * h);
  auto link = [&](std::ptrdiff_t a, std::ptrdiff_t b, long double k) {
    l(a, a) += k;
    l(b, b) += k;
    l(a, b) -= k;
    l(b, a) -= k;
  };
  for (std::ptrdiff_t y = 0; y < h; ++y)
    for (std::ptrdiff_t x = 0; x < w; ++x) {
      if (x + 1 < w) link(y * w + x, y * w + x + 1, beta.horizontal()(x, y));
      if (y + 1 < h) link(y * w + x, (y + 1) * w + x, beta.vertical()(x, y));
    }
  return l;
}

WideVector to_vector(ConstPlane p) {
  WideVector v(p.width() * p.height());
  for (std::ptrdiff_t y = 0; y < p.height(); ++y)
    for (std::ptrdiff_t x = 0; x < p.width(); ++x) v(y * p.width() + x) = p(x, y);
  return v;
}

double max_difference(ConstPlane p, const WideVector& v) {
  return double((to_vector(p) - v).cwiseAbs().maxCoeff());
}

// Mass, centroid and per-axis variance of a non-negative plane.
struct Moments {
  double mass = 0, mean_x = 0, mean_y = 0, var_x = 0, var_y = 0;
};
Moments moments(ConstPlane p) {
  Moments m;
  for (std::ptrdiff_t y = 0; y < p.height(); ++y)
    for (std::ptrdiff_t x = 0; x < p.width(); ++x) {
      m.mass += p(x, y);
      m.mean_x += double(x) * p(x, y);
      m.mean_y += double(y) * p(x, y);
    }
  m.mean_x /= m.mass;
  m.mean_y /= m.mass;
  for (std::ptrdiff_t y = 0; y < p.height(); ++y)
    for (std::ptrdiff_t x = 0; x < p.width(); ++x) {
      m.var_x += (x - m.mean_x) * (x - m.mean_x) * p(x, y);
      m.var_y += (y - m.mean_y) * (y - m.mean_y) * p(x, y);
    }
  m.var_x /= m.mass;
  m.var_y /= m.mass;
  return m;
}

Image impulse(Size size, std::ptrdiff_t cx, std::ptrdiff_t cy) {
  Image image(size.width, size.height, 1);
  image(cx, cy, 0) = 1.f;
  return image;
}

DiffusionOptions with_skip(bool skip, int threads = 0) {
  DiffusionOptions options;
  options.skip_inactive = skip;
  options.threads = threads;
  return options;
}

// ---------------------------------------------------------------------------------------------
// 1. Mass: the diffusion matrices of eq. 3.10 are symmetric with row sums 1, so their columns
// sum to 1 and every row (rows pass) or column (columns pass) keeps its sum. Each output has a
// rounding error of a few eps * max|x| (see AdiMatchesDenseSolve), so a line of n pixels keeps
// its sum to within about n * eps * max|x|; the tolerance allows 4 eps per pixel.

TEST(Diffusion, AdiRowsConserveMassPerRow) {
  for (const Size size : kSizes)
    for (const float max_beta : {1.f, 30.f, 1e6f, 1e9f}) {
      SCOPED_TRACE(name(size) + ", beta < " + std::to_string(max_beta));
      const Image src = random_image(size, 1, 11);
      const LinkField beta = random_links(size, max_beta, 0.3, 12);
      Image dst(size.width, size.height, 1);
      diffuse_rows(dst.plane(0), src.plane(0), beta);
      for (std::ptrdiff_t y = 0; y < size.height; ++y) {
        double before = 0, after = 0, largest = 0;
        for (std::ptrdiff_t x = 0; x < size.width; ++x) {
          before += src(x, y, 0);
          after += dst(x, y, 0);
          largest = std::max(largest, double(src(x, y, 0)));
        }
        ASSERT_NEAR(after, before, 4 * double(size.width) * kEps * largest) << "row " << y;
      }
    }
}

TEST(Diffusion, AdiColumnsConserveMassPerColumn) {
  for (const Size size : kSizes)
    for (const float max_beta : {1.f, 30.f, 1e6f, 1e9f}) {
      SCOPED_TRACE(name(size) + ", beta < " + std::to_string(max_beta));
      const Image src = random_image(size, 1, 21);
      const LinkField beta = random_links(size, max_beta, 0.3, 22);
      Image dst(size.width, size.height, 1);
      diffuse_columns(dst.plane(0), src.plane(0), beta);
      for (std::ptrdiff_t x = 0; x < size.width; ++x) {
        double before = 0, after = 0, largest = 0;
        for (std::ptrdiff_t y = 0; y < size.height; ++y) {
          before += src(x, y, 0);
          after += dst(x, y, 0);
          largest = std::max(largest, double(src(x, y, 0)));
        }
        ASSERT_NEAR(after, before, 4 * double(size.height) * kEps * largest) << "column " << x;
      }
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Maximum principle: (I + L)^-1 is non-negative with row sums 1, so every output is a convex
// combination of its line of the input. The subtraction-free elimination keeps that exactly in
// float (no tolerance), for beta = 1e6 and even for beta = 1e9, where the 1 of the diagonal
// 1 + beta_{i-1} + beta_i is far below one ulp of the float sum.

TEST(Diffusion, AdiObeysMaximumPrinciple) {
  for (const Size size : kSizes)
    for (const float max_beta : {2.f, 1e6f, 1e9f}) {
      for (const bool uniform : {false, true}) {
        SCOPED_TRACE(name(size) + ", beta " + (uniform ? "= " : "< ") + std::to_string(max_beta));
        const Image src = random_image(size, 1, 31);
        const LinkField beta =
            uniform ? uniform_links(size, max_beta) : random_links(size, max_beta, 0.3, 32);
        Image rows(size.width, size.height, 1);
        diffuse_rows(rows.plane(0), src.plane(0), beta);
        for (std::ptrdiff_t y = 0; y < size.height; ++y) {
          const float* in = src.plane(0).row(y);
          const float* out = rows.plane(0).row(y);
          const auto [low, high] = std::minmax_element(in, in + size.width);
          for (std::ptrdiff_t x = 0; x < size.width; ++x) {
            ASSERT_GE(out[x], *low) << "rows pass, " << pixel(x, y);
            ASSERT_LE(out[x], *high) << "rows pass, " << pixel(x, y);
          }
        }
        Image dst;
        diffuse_adi(dst, src, beta);
        float low = 1, high = 0;
        for (std::ptrdiff_t y = 0; y < size.height; ++y)
          for (std::ptrdiff_t x = 0; x < size.width; ++x) {
            low = std::min(low, src(x, y, 0));
            high = std::max(high, src(x, y, 0));
          }
        for (std::ptrdiff_t y = 0; y < size.height; ++y)
          for (std::ptrdiff_t x = 0; x < size.width; ++x) {
            ASSERT_GE(dst(x, y, 0), low) << "full step, " << pixel(x, y);
            ASSERT_LE(dst(x, y, 0), high) << "full step, " << pixel(x, y);
          }
      }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. A pixel with no conductance on any of its four links is its own 1 x 1 system in both
// passes: its value must come back with the same bits (in-focus pixels stay exactly sharp).

TEST(Diffusion, AdiLeavesInsulatedPixelsUnchangedBitForBit) {
  for (const Size size : kSizes)
    for (const bool skip : {true, false}) {
      SCOPED_TRACE(name(size) + (skip ? ", skipping" : ", full solve"));
      const Image src = random_image(size, 2, 41);
      LinkField beta = random_links(size, 3.f, 0.6, 42);
      // Also a fully insulated rectangle that crosses a tile border, when the image has one.
      if (size.width > 70 && size.height > 70) {
        for (std::ptrdiff_t y = 50; y < 80; ++y)
          for (std::ptrdiff_t x = 40; x < 70; ++x)
            beta.horizontal()(x, y) = beta.vertical()(x, y) = 0;
        beta.finish();
      }
      Image dst;
      diffuse_adi(dst, src, beta, with_skip(skip));
      ConstPlane h = beta.horizontal(), v = beta.vertical();
      std::ptrdiff_t insulated = 0;
      for (std::ptrdiff_t y = 0; y < size.height; ++y)
        for (std::ptrdiff_t x = 0; x < size.width; ++x) {
          const bool isolated = h(x, y) == 0 && v(x, y) == 0 && (x == 0 || h(x - 1, y) == 0) &&
                                (y == 0 || v(x, y - 1) == 0);
          if (!isolated) continue;
          ++insulated;
          for (int c = 0; c < 2; ++c)
            ASSERT_EQ(std::bit_cast<std::uint32_t>(dst(x, y, c)),
                      std::bit_cast<std::uint32_t>(src(x, y, c)))
                << pixel(x, y) << " channel " << c << ": " << src(x, y, c) << " became "
                << dst(x, y, c);
        }
      EXPECT_GT(insulated, 0);
    }
}

TEST(Diffusion, ExplicitLeavesInsulatedPixelsUnchangedBitForBit) {
  for (const Size size : kSizes)
    for (const bool skip : {true, false}) {
      SCOPED_TRACE(name(size) + (skip ? ", skipping" : ", full steps"));
      const Image src = random_image(size, 1, 43);
      const LinkField kappa = random_links(size, 0.25f, 0.6, 44);
      Image dst;
      diffuse_explicit_steps(dst, src, kappa, 7, with_skip(skip));
      ConstPlane h = kappa.horizontal(), v = kappa.vertical();
      for (std::ptrdiff_t y = 0; y < size.height; ++y)
        for (std::ptrdiff_t x = 0; x < size.width; ++x)
          if (h(x, y) == 0 && v(x, y) == 0 && (x == 0 || h(x - 1, y) == 0) &&
              (y == 0 || v(x, y - 1) == 0)) {
            ASSERT_EQ(std::bit_cast<std::uint32_t>(dst(x, y, 0)),
                      std::bit_cast<std::uint32_t>(src(x, y, 0)))
                << pixel(x, y);
          }
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Against the dense reference. Per pass the matrix M = I + L is an M-matrix with
// ||M^-1||_inf = 1, and the subtraction-free elimination has a componentwise backward error of
// a few eps, so each pass adds a forward error of a few eps * max|x| (the row pass error is not
// amplified by the column pass, ||M^-1|| = 1). Measured worst: 2.3 eps * max|x| for the whole
// step; allowed: 4 eps per pass, 8 eps * max|x| in all.
//
// The sizes cover every path of the float solver: full 64-system bands (rows transposed block
// by block, columns in place), partial bands of 16..63 systems (gathered into lanes), and
// fewer than 16 systems (one at a time).
constexpr Size kDenseSizes[] = {{1, 1}, {1, 37},  {37, 1},  {2, 3},
                                {7, 5}, {63, 65}, {130, 9}, {9, 130}};
// Smaller ones, for the tests that repeat the reference per channel.
constexpr Size kSmallDenseSizes[] = {{1, 1}, {1, 37}, {37, 1}, {2, 3}, {7, 5}, {70, 20}, {20, 70}};

// reference_adi of every channel.
std::vector<std::vector<double>> reference_image(const Image& src, const LinkField& beta) {
  std::vector<std::vector<double>> expected;
  for (int c = 0; c < src.channels(); ++c) expected.push_back(reference_adi(src.plane(c), beta));
  return expected;
}

void expect_matches(const Image& result, const std::vector<std::vector<double>>& expected,
                    double largest_input) {
  const double tolerance = 8 * kEps * largest_input;
  double worst = 0;
  ASSERT_EQ(std::size_t(result.channels()), expected.size());
  for (int c = 0; c < result.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < result.height(); ++y)
      for (std::ptrdiff_t x = 0; x < result.width(); ++x) {
        const double want = expected[c][y * result.width() + x];
        const double error = std::abs(result(x, y, c) - want);
        worst = std::max(worst, error);
        ASSERT_LE(error, tolerance) << pixel(x, y) << " channel " << c << ": got "
                                    << result(x, y, c) << ", expected " << want;
      }
  ::testing::Test::RecordProperty("worst_error_in_eps_" + std::to_string(result.width()) + "x" +
                                      std::to_string(result.height()),
                                  std::to_string(worst / kEps / std::max(1e-300, largest_input)));
}

TEST(Diffusion, AdiMatchesDenseSolve) {
  for (const Size size : kDenseSizes)
    for (const float max_beta : {0.5f, 8.f, 200.f}) {
      SCOPED_TRACE(name(size) + ", beta < " + std::to_string(max_beta));
      const LinkField beta = random_links(size, max_beta, 0.25, 51);
      const Image src = random_image(size, 1, 52);
      Image dst;
      diffuse_adi(dst, src, beta);
      expect_matches(dst, reference_image(src, beta), max_abs(src));
    }
}

TEST(Diffusion, AdiMatchesDenseSolveForEveryChannel) {
  for (const Size size : kSmallDenseSizes) {
    SCOPED_TRACE(name(size));
    const LinkField beta = random_links(size, 4.f, 0.25, 53);
    const Image src = random_image(size, 3, 54);
    Image dst(3, 3, 1);  // the wrong size: diffuse_adi resizes it
    diffuse_adi(dst, src, beta);
    expect_matches(dst, reference_image(src, beta), max_abs(src));
  }
}

TEST(Diffusion, AdiMatchesDenseSolveInPlace) {
  for (const Size size : kSmallDenseSizes) {
    const LinkField beta = random_links(size, 4.f, 0.25, 55);
    const Image src = random_image(size, 3, 56);
    const std::vector<std::vector<double>> expected = reference_image(src, beta);
    for (const bool skip : {true, false}) {
      SCOPED_TRACE(name(size) + (skip ? ", skipping" : ", full solve"));
      Image image = src;
      diffuse_adi(image, image, beta, with_skip(skip));
      expect_matches(image, expected, max_abs(src));
      // In place gives the very same bits as out of place.
      Image separate;
      diffuse_adi(separate, src, beta, with_skip(skip));
      EXPECT_EQ(first_bit_difference(image, separate), "");
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 5. Skipping. A link of zero makes the elimination restart exactly (g = 1 + 0 * e = 1 and the
// carried value is multiplied by 0), so the systems of the active segments are bit for bit the
// pieces of the full systems, and the copied pixels are what the full solve computes for a
// 1 x 1 system (x / 1). Expect identical bits.

// Zeroes every link of the tiles for which inactive(tx, ty) holds.
void clear_tiles(LinkField& links,
                 const std::function<bool(std::ptrdiff_t, std::ptrdiff_t)>& inactive,
                 bool horizontal, bool vertical) {
  for (std::ptrdiff_t y = 0; y < links.height(); ++y)
    for (std::ptrdiff_t x = 0; x < links.width(); ++x)
      if (inactive(x / kTile, y / kTile)) {
        if (horizontal) links.horizontal()(x, y) = 0;
        if (vertical) links.vertical()(x, y) = 0;
      }
  links.finish();
}

TEST(Diffusion, AdiSkippingMatchesFullSolve) {
  for (const Size size : kSizes)
    for (int pattern = 0; pattern < 3; ++pattern) {
      SCOPED_TRACE(name(size) + ", pattern " + std::to_string(pattern));
      const Image src = random_image(size, 3, 61);
      LinkField beta = random_links(size, 5.f, 0.2, 62 + pattern);
      if (pattern == 1)  // a checkerboard of active tiles
        clear_tiles(
            beta, [](auto tx, auto ty) { return (tx + ty) % 2 == 1; }, true, true);
      if (pattern == 2)  // different tiles per direction
        clear_tiles(
            beta, [](auto tx, auto) { return tx % 3 == 1; }, true, false);
      Image skipped, full, in_place = src;
      const DiffusionReport skipped_report = diffuse_adi(skipped, src, beta, with_skip(true));
      const DiffusionReport full_report = diffuse_adi(full, src, beta, with_skip(false));
      diffuse_adi(in_place, in_place, beta, with_skip(true));
      EXPECT_EQ(first_bit_difference(skipped, full), "");
      EXPECT_EQ(first_bit_difference(in_place, full), "");
      const std::ptrdiff_t pixels = 2 * 3 * size.width * size.height;  // 2 passes, 3 channels
      EXPECT_EQ(full_report.pixels, pixels);
      EXPECT_EQ(full_report.pixels_solved, pixels);
      EXPECT_EQ(skipped_report.pixels, pixels);
      EXPECT_LE(skipped_report.pixels_solved, pixels);
    }
}

// The exact work of the segment rule of find_segments: a run of active tiles [t0, t1] of a
// band is solved over pixels [64 t0, min(extent, 64 (t1 + 1) + 1)), i.e. the run plus the first
// pixel after it, which its last link reaches.
TEST(Diffusion, AdiSkippingSolvesOnlyTheActiveSegments) {
  const Size size{200, 150};  // 4 x 3 tiles, the last column of tiles 8 wide, last row 22 high
  const Image src = random_image(size, 3, 63);
  {
    SCOPED_TRACE("one active 64 x 64 block, tile (1, 1)");
    LinkField beta = random_links(size, 2.f, 0.0, 64);
    clear_tiles(
        beta, [](auto tx, auto ty) { return tx != 1 || ty != 1; }, true, true);
    Image skipped, full;
    const DiffusionReport report = diffuse_adi(skipped, src, beta, with_skip(true));
    diffuse_adi(full, src, beta, with_skip(false));
    EXPECT_EQ(first_bit_difference(skipped, full), "");
    // Rows pass: band 1 solves pixels [64, 129) of its 64 rows; columns pass: band 1 solves
    // rows [64, 129) of its 64 columns. Three channels.
    EXPECT_EQ(report.pixels, 2 * 3 * 200 * 150);
    EXPECT_EQ(report.pixels_solved, 3 * (65 * 64 + 65 * 64));
    EXPECT_NEAR(report.skipped_fraction(), 1.0 - 24960.0 / 180000.0, 1e-15);
  }
  {
    SCOPED_TRACE("runs that merge, end at the border and cover partial tiles");
    LinkField beta = random_links(size, 2.f, 0.0, 65);
    // Horizontal links: band 0, tiles 0, 1 and 3 (a run of two, and the partial last tile).
    clear_tiles(
        beta, [](auto tx, auto ty) { return ty != 0 || tx == 2; }, true, false);
    // Vertical links: tiles (2, 0), (2, 1), (0, 2) and (3, 1).
    auto vertical_active = [](std::ptrdiff_t tx, std::ptrdiff_t ty) {
      return (tx == 2 && ty <= 1) || (tx == 0 && ty == 2) || (tx == 3 && ty == 1);
    };
    clear_tiles(
        beta, [&](auto tx, auto ty) { return !vertical_active(tx, ty); }, false, true);
    Image skipped, full;
    const DiffusionReport report = diffuse_adi(skipped, src, beta, with_skip(true));
    diffuse_adi(full, src, beta, with_skip(false));
    EXPECT_EQ(first_bit_difference(skipped, full), "");
    const std::ptrdiff_t rows_pass = (129 + (200 - 192)) * 64;  // [0, 129) and [192, 200)
    const std::ptrdiff_t columns_pass = 129 * 64                // band 2: rows [0, 129)
                                        + 22 * 64               // band 0: rows [128, 150)
                                        + 65 * 8;  // band 3 (8 columns): rows [64, 129)
    EXPECT_EQ(report.pixels_solved, 3 * (rows_pass + columns_pass));
  }
  {
    SCOPED_TRACE("no link at all");
    const LinkField beta(size.width, size.height);
    Image skipped;
    const DiffusionReport report = diffuse_adi(skipped, src, beta, with_skip(true));
    EXPECT_EQ(report.pixels_solved, 0);
    EXPECT_EQ(report.skipped_fraction(), 1.0);
    EXPECT_EQ(first_bit_difference(skipped, src), "");
  }
}

TEST(Diffusion, ExplicitSkippingMatchesFullSteps) {
  for (const Size size : kSizes) {
    SCOPED_TRACE(name(size));
    const Image src = random_image(size, 2, 66);
    LinkField kappa = random_links(size, 0.25f, 0.2, 67);
    clear_tiles(
        kappa, [](auto tx, auto ty) { return (tx + 2 * ty) % 3 != 0; }, true, true);
    Image skipped, full;
    diffuse_explicit_steps(skipped, src, kappa, 9, with_skip(true));
    diffuse_explicit_steps(full, src, kappa, 9, with_skip(false));
    EXPECT_EQ(first_bit_difference(skipped, full), "");
  }
}

// ---------------------------------------------------------------------------------------------
// 6. One implicit pass with uniform beta has the kernel whose Fourier transform is
// 1 / (1 + 2 beta (1 - cos w)) = 1 - beta w^2 + ..., so it adds a variance of exactly 2 beta
// along its axis on an unbounded line; the kernel decays like r^|k| with
// r = (1 + 2 beta - sqrt(1 + 4 beta)) / (2 beta) (0.84 for D = 32), so 256 pixels of margin
// leave nothing at the insulated border. The ADI step of an impulse is the product of the two
// 1-D kernels, and with beta = adi_beta_for_coc(D) = D^2 / 32 its variance per axis is
// D^2 / 16, that of a uniform disc of diameter D. Measured relative error: 4 eps (5e-7).

TEST(Diffusion, AdiBetaMapsCocToDiscVariance) {
  const Size size{513, 513};
  const Image src = impulse(size, 256, 256);
  for (const float d : {4.f, 8.f, 16.f, 32.f}) {
    SCOPED_TRACE("D = " + std::to_string(d));
    const float beta = adi_beta_for_coc(d);
    EXPECT_EQ(beta, d * d / 32);
    Image dst;
    diffuse_adi(dst, src, uniform_links(size, beta));
    const Moments m = moments(dst.plane(0));
    const double disc = double(d) * d / 16;
    // Each pass leaves a relative error of a few eps on every kernel value (AdiMatchesDenseSolve:
    // under 4 eps * max|x| for the whole step), and mass, mean and variance are weighted sums
    // of those values, so they carry a relative error of the same few eps. Allowed: 64 eps
    // (measured: at most 6 eps on the mass, 4 eps on the variance, for D = 32).
    const double tolerance = 64 * kEps;
    EXPECT_NEAR(m.mass, 1.0, tolerance);
    EXPECT_NEAR(m.mean_x, 256.0, tolerance * d);
    EXPECT_NEAR(m.mean_y, 256.0, tolerance * d);
    EXPECT_NEAR(m.var_x / disc, 1.0, tolerance);
    EXPECT_NEAR(m.var_y / disc, 1.0, tolerance);
    ::testing::Test::RecordProperty("variance_ratio_minus_1_in_eps_D" + std::to_string(int(d)),
                                    std::to_string((m.var_x / disc - 1) / kEps) + " " +
                                        std::to_string((m.var_y / disc - 1) / kEps) +
                                        ", mass - 1: " + std::to_string((m.mass - 1) / kEps));
  }
}

// ---------------------------------------------------------------------------------------------
// 7. One explicit isotropic step (seed 001 eq. 3.21) is the kernel 1 - 4c at the centre and c
// on each neighbour: its variance per axis is exactly 2c, and N steps add up to 2cN. With the
// support N pixels wide and the border further away, the float result differs only by
// rounding: each step rounds each value with a relative error of a few eps, so the variance
// is off by at most N * few eps relative; the tolerance is 8 N eps.

TEST(Diffusion, ExplicitIsotropicVarianceIs2cN) {
  const Size size{161, 161};
  const Image src = impulse(size, 80, 80);
  for (const float c : {0.1f, 0.25f})
    for (const int n : {1, 7, 60}) {
      SCOPED_TRACE("c = " + std::to_string(c) + ", N = " + std::to_string(n));
      Image dst;
      diffuse_isotropic(dst, src, c, n);
      const Moments m = moments(dst.plane(0));
      const double expected = 2.0 * double(c) * n;
      const double tolerance = 8 * n * kEps;
      EXPECT_NEAR(m.mass, 1.0, tolerance);
      EXPECT_NEAR(m.var_x / expected, 1.0, tolerance);
      EXPECT_NEAR(m.var_y / expected, 1.0, tolerance);
      ::testing::Test::RecordProperty(
          "variance_ratio_minus_1_in_eps_c" + std::to_string(c) + "_N" + std::to_string(n),
          std::to_string((m.var_x / expected - 1) / kEps) + " " +
              std::to_string((m.var_y / expected - 1) / kEps) +
              ", mass - 1: " + std::to_string((m.mass - 1) / kEps));
    }
}

TEST(Diffusion, IsotropicIterationsForSigmaIsCeilSigmaSquaredOver2c) {
  for (const float c : {0.05f, 0.1f, 0.2f, 0.25f})
    for (const float sigma : {0.f, 0.3f, 0.5f, 1.f, 1.7f, 2.f, 3.f, 5.5f, 10.f, 25.f}) {
      const double exact = double(sigma) * double(sigma) / (2.0 * double(c));
      EXPECT_EQ(isotropic_iterations_for_sigma(sigma, c), int(std::ceil(exact)))
          << "sigma " << sigma << ", c " << c << ": sigma^2 / 2c = " << exact;
    }
  EXPECT_EQ(isotropic_iterations_for_sigma(4.f), 32);  // the default c = 0.25: 16 / 0.5
  // Far from integers the iteration count reaches the target variance and stays within one
  // step of it.
  for (const float sigma : {1.3f, 4.1f, 9.9f}) {
    const int n = isotropic_iterations_for_sigma(sigma, 0.25f);
    EXPECT_GE(0.5 * n, double(sigma) * sigma);
    EXPECT_LT(0.5 * (n - 1), double(sigma) * sigma);
  }
  for (const float bad : {-1.f, kNaN, std::numeric_limits<float>::infinity()})
    EXPECT_THROW(isotropic_iterations_for_sigma(bad), InvalidArgument) << bad;
  for (const float bad_c : {0.f, -0.1f, 0.3f, kNaN})
    EXPECT_THROW(isotropic_iterations_for_sigma(1.f, bad_c), InvalidArgument) << bad_c;
}

// Seed 000 eq. 5.5 sets N = sigma^2 / (2 sqrt 2) iterations of its 0.25-step (eq. 5.4) for a
// Gaussian "of width sigma". The variance those steps reach is 2 * 0.25 * N = sigma^2 / (4 sqrt 2),
// a standard deviation of sigma / sqrt(4 sqrt 2) = sigma / 2.378: eq. 5.5's sigma is a kernel
// width of about 2.4 standard deviations, not a standard deviation. Measured on the impulse
// response of diffuse_isotropic.
TEST(Diffusion, Seed000Eq55SigmaIsAbout2Point38StandardDeviations) {
  const double sqrt2 = std::sqrt(2.0);
  const double factor = std::sqrt(4 * sqrt2);
  EXPECT_NEAR(factor, 2.3784142300054421, 1e-15);
  const Size size{129, 129};
  const Image src = impulse(size, 64, 64);
  for (const int n : {8, 20, 50}) {
    // The width for which eq. 5.5 prescribes exactly n iterations.
    const double width = std::sqrt(2 * sqrt2 * n);
    Image dst;
    diffuse_isotropic(dst, src, 0.25f, n);
    const Moments m = moments(dst.plane(0));
    const double reached = std::sqrt(m.var_x);
    EXPECT_NEAR(width / reached, factor, 8 * n * kEps * factor) << "N = " << n;
    EXPECT_NEAR(width / std::sqrt(m.var_y), factor, 8 * n * kEps * factor) << "N = " << n;
    ::testing::Test::RecordProperty("eq55_width_over_sigma_N" + std::to_string(n),
                                    std::to_string(width / reached));
    // tridiff's own count for that width is 4 sqrt 2 (about 5.66) times eq. 5.5's.
    const int ours = isotropic_iterations_for_sigma(float(width), 0.25f);
    EXPECT_NEAR(double(ours) / n, 4 * sqrt2, 1.0 / n) << "N = " << n;
  }
}

// ---------------------------------------------------------------------------------------------
// 8. Stability: forward Euler needs the four links of a pixel to sum to at most 1; tridiff
// asks for each link <= 0.25 and refuses anything else rather than blowing up silently.

TEST(Diffusion, ExplicitRejectsUnstableConductance) {
  const Size size{70, 66};
  const Image src = random_image(size, 1, 81);
  Image dst;
  LinkField kappa = uniform_links(size, 0.25f);  // the bound itself is allowed
  EXPECT_NO_THROW(diffuse_explicit_steps(dst, src, kappa, 3));
  kappa.vertical()(65, 64) = std::nextafter(0.25f, 1.f);
  kappa.finish();
  const Thrown thrown = invalid_argument_of([&] { diffuse_explicit_steps(dst, src, kappa, 1); });
  EXPECT_EQ(thrown.argument, "kappa");
  EXPECT_TRUE(contains(thrown.message, "0.25"));
  EXPECT_THROW(diffuse_explicit_steps(dst, src, uniform_links(size, 0.1f), -1), InvalidArgument);
  for (const float c : {0.3f, std::nextafter(0.25f, 1.f), 0.f, -0.1f, kNaN,
                        std::numeric_limits<float>::infinity()}) {
    const Thrown isotropic = invalid_argument_of([&] { diffuse_isotropic(dst, src, c, 4); });
    EXPECT_EQ(isotropic.argument, "c") << c;
  }
  EXPECT_NO_THROW(diffuse_isotropic(dst, src, 0.25f, 4));
}

// diffuse_explicit sub-steps instead: steps = ceil(max beta / 0.25) of beta / steps. The result
// stays within [min, max] of the input and keeps its sum. Rounding bound for the sum: each of
// the 5 operations of a step rounds a value of size <= max|x| (the values stay in [0, 1]), so
// the sum drifts by at most 5 eps * max|x| * pixels * steps (measured: under 50 eps in all,
// over 400 steps). The range is asserted exactly: float rounding could in principle push a
// convex combination one ulp out, but it does not happen here (and none is seen).
TEST(Diffusion, DiffuseExplicitSubstepsLargeBetaWithoutBlowingUp) {
  for (const Size size : {Size{65, 130}, Size{7, 5}, Size{1, 37}})
    for (const float max_beta : {0.2f, 1.f, 13.3f, 100.f}) {
      SCOPED_TRACE(name(size) + ", beta < " + std::to_string(max_beta));
      const Image src = random_image(size, 1, 82);
      const LinkField beta = random_links(size, max_beta, 0.3, 83);
      Image dst;
      int steps = 0;
      const DiffusionReport report = diffuse_explicit(dst, src, beta, {}, &steps);
      EXPECT_EQ(steps, std::max(1, int(std::ceil(double(beta.max_link()) / 0.25))));
      EXPECT_EQ(report.pixels, size.width * size.height * steps);
      double before = 0, after = 0, low = 1, high = 0, out_low = 1, out_high = 0;
      for (std::ptrdiff_t y = 0; y < size.height; ++y)
        for (std::ptrdiff_t x = 0; x < size.width; ++x) {
          before += src(x, y, 0);
          after += dst(x, y, 0);
          low = std::min(low, double(src(x, y, 0)));
          high = std::max(high, double(src(x, y, 0)));
          out_low = std::min(out_low, double(dst(x, y, 0)));
          out_high = std::max(out_high, double(dst(x, y, 0)));
        }
      EXPECT_GE(out_low, low);
      EXPECT_LE(out_high, high);
      EXPECT_NEAR(after, before, 5 * kEps * double(size.width * size.height) * steps * high);
      ::testing::Test::RecordProperty("explicit_mass_drift_" + std::to_string(size.width) + "x" +
                                          std::to_string(size.height) + "_beta" +
                                          std::to_string(max_beta),
                                      std::to_string((after - before) / kEps) + " eps over " +
                                          std::to_string(steps) + " steps");
    }
}

// A value spreading into zeros decays geometrically (about 0.915 a pixel at beta 128) and
// would fall below the smallest normal float some 1000 pixels out, where every operation on it
// takes a slow microcode assist. The solves flush such values to zero: no output is subnormal,
// the mass lost is below 1e-36, and the caller's floating-point modes are as they were, on one
// thread (the solve runs in the calling thread) and on two.
TEST(Diffusion, SubnormalsFlushedToZeroAndCallersStateKept) {
  const Size size{3000, 1};
  for (const int threads : {1, 2}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    Image src(size.width, size.height, 1);
    src(0, 0, 0) = 1.f;
    const LinkField beta = uniform_links(size, 128.f);
    Image dst;
    DiffusionOptions options;
    options.threads = threads;
#if defined(__SSE__)
    // The control bits (rounding, flush modes, masks); bits 0-5 are sticky exception flags
    // that any inexact operation sets.
    const auto control = [] { return _mm_getcsr() & ~0x3fu; };
    const unsigned before = control();
#endif
    diffuse_adi(dst, src, beta, options);
#if defined(__SSE__)
    EXPECT_EQ(control(), before);
#endif
    double mass = 0;
    std::ptrdiff_t zeros = 0;
    for (std::ptrdiff_t x = 0; x < size.width; ++x) {
      const float v = dst(x, 0, 0);
      EXPECT_NE(std::fpclassify(v), FP_SUBNORMAL) << "x = " << x << ": " << v;
      mass += v;
      zeros += v == 0.f;
    }
    EXPECT_GT(zeros, 1000);  // the decay did reach the subnormal range
    EXPECT_NEAR(mass, 1.0, 1e-6);

    // The explicit scheme: 512 steps whose front, kappa^k at k pixels, falls below 1e-38.
    Image explicit_dst;
    diffuse_explicit(explicit_dst, src, beta, options);
#if defined(__SSE__)
    EXPECT_EQ(control(), before);
#endif
    double explicit_mass = 0;
    for (std::ptrdiff_t x = 0; x < size.width; ++x) {
      const float v = explicit_dst(x, 0, 0);
      EXPECT_NE(std::fpclassify(v), FP_SUBNORMAL) << "explicit, x = " << x << ": " << v;
      explicit_mass += v;
    }
    EXPECT_NEAR(explicit_mass, 1.0, 1e-5);
  }
}

// The sub-step count has a ceiling (DiffusionOptions::max_explicit_steps): a field that needs
// more is refused naming beta, not run for hours, and a huge conductance (whose step count
// does not fit an int) is refused rather than overflowing into a count of 1 or less.
TEST(Diffusion, DiffuseExplicitRefusesMoreStepsThanAllowed) {
  const Size size{9, 7};
  const Image src = random_image(size, 1, 84);
  Image dst;
  DiffusionOptions options;
  options.max_explicit_steps = 3;
  int steps = 0;
  diffuse_explicit(dst, src, uniform_links(size, 0.75f), options, &steps);  // exactly 3 steps
  EXPECT_EQ(steps, 3);
  const Thrown four = invalid_argument_of(
      [&] { diffuse_explicit(dst, src, uniform_links(size, 0.76f), options, &steps); });
  EXPECT_EQ(four.argument, "beta");
  EXPECT_TRUE(contains(four.message, "4 explicit steps")) << four.message;
  EXPECT_TRUE(contains(four.message, "3 allowed")) << four.message;
  for (const float huge : {1e9f, 1e30f, std::numeric_limits<float>::max()}) {
    const Thrown thrown =
        invalid_argument_of([&] { diffuse_explicit(dst, src, uniform_links(size, huge)); });
    EXPECT_EQ(thrown.argument, "beta") << huge;
  }
}

// ---------------------------------------------------------------------------------------------
// 9. Both schemes integrate dI/dt = -L I (seed 000 eq. 3.8 with gamma = 1) over unit time, whose
// exact solution is exp(-L) I, computed here by Eigen's matrix exponential in long double. N
// forward-Euler steps of L / N and K backward-Euler (ADI) steps of L / K are both first order:
// (I - L/N)^N = exp(-L - L^2 / 2N + ...) and (I + L/K)^-K = exp(-L + L^2 / 2K + ...), so the
// error falls by 4 per 4x refinement (at least 3 is asserted) and the two approach each
// other. For an image of height 1 the column pass is the identity, so the ADI step is exactly
// the 1-D backward Euler step.

struct Convergence {
  std::vector<double> explicit_error, implicit_error, difference;
};

Convergence converge(const LinkField& beta, const Image& src, const std::vector<int>& refinements) {
  const WideMatrix l = laplacian(beta);
  const WideMatrix propagator = (-l).exp();
  const WideVector exact = propagator * to_vector(src.plane(0));
  Convergence result;
  for (const int n : refinements) {
    const LinkField step = scaled_links(beta, 1.f / float(n));
    Image forward;
    diffuse_explicit_steps(forward, src, step, n);
    Image backward = src;
    for (int k = 0; k < n; ++k) diffuse_adi(backward, backward, step);
    result.explicit_error.push_back(max_difference(forward.plane(0), exact));
    result.implicit_error.push_back(max_difference(backward.plane(0), exact));
    result.difference.push_back(max_difference(forward.plane(0), to_vector(backward.plane(0))));
  }
  return result;
}

void expect_first_order(const std::vector<double>& errors, const char* what) {
  for (std::size_t i = 1; i < errors.size(); ++i)
    EXPECT_GE(errors[i - 1] / errors[i], 3.0)
        << what << ": error " << errors[i - 1] << " -> " << errors[i] << " at refinement " << i;
  std::string list;
  for (const double e : errors) list += std::to_string(e) + " ";
  ::testing::Test::RecordProperty(what, list);
}

TEST(Diffusion, ExplicitConvergesToImplicitAsStepShrinks1D) {
  const Size size{50, 1};
  const LinkField beta = random_links(size, 1.f, 0.2, 91);  // N >= 4 keeps beta / N <= 0.25
  const Image src = random_image(size, 1, 92);
  const Convergence c = converge(beta, src, {4, 16, 64, 256});
  expect_first_order(c.explicit_error, "explicit_error_1d");
  expect_first_order(c.implicit_error, "implicit_error_1d");
  expect_first_order(c.difference, "explicit_minus_implicit_1d");
}

TEST(Diffusion, ExplicitConvergesToImplicitAsStepShrinks2D) {
  const Size size{12, 10};
  const LinkField beta = random_links(size, 1.f, 0.2, 93);
  const Image src = random_image(size, 1, 94);
  const Convergence c = converge(beta, src, {4, 16, 64, 256});
  expect_first_order(c.explicit_error, "explicit_error_2d");
  expect_first_order(c.implicit_error, "implicit_error_2d");
  expect_first_order(c.difference, "explicit_minus_implicit_2d");
}

// ---------------------------------------------------------------------------------------------
// 10. Links.

TEST(Diffusion, LinksUseTheLessConductiveEnd) {
  for (const Size size : kSizes) {
    SCOPED_TRACE(name(size));
    Image value = random_image(size, 1, 101);
    // An in-focus (zero-conductance) block that covers tile (1, 0) exactly, when there is one,
    // with conductive pixels right of it and below it.
    for (std::ptrdiff_t y = 0; y < std::min<std::ptrdiff_t>(size.height, 64); ++y)
      for (std::ptrdiff_t x = 64; x < std::min<std::ptrdiff_t>(size.width, 128); ++x)
        value(x, y, 0) = 0.1f;
    for (std::ptrdiff_t y = 0; y < std::min<std::ptrdiff_t>(size.height, 65); ++y)
      if (size.width > 128) value(128, y, 0) = 0.9f;
    for (std::ptrdiff_t x = 64; x < std::min<std::ptrdiff_t>(size.width, 128); ++x)
      if (size.height > 64) value(x, 64, 0) = 0.9f;
    // Not monotone, so that min(f(a), f(b)) and f(min(a, b)) differ; zero below 0.25.
    auto to_link = [](float v) { return v < 0.25f ? 0.f : 4 * std::abs(v - 0.6f); };
    const LinkField links = links_from_pixels(value.plane(0), to_link);
    ConstPlane h = links.horizontal(), v = links.vertical();
    float largest = 0;
    for (std::ptrdiff_t y = 0; y < size.height; ++y)
      for (std::ptrdiff_t x = 0; x < size.width; ++x) {
        const float here = to_link(value(x, y, 0));
        const float right = x + 1 < size.width ? std::min(here, to_link(value(x + 1, y, 0))) : 0;
        const float down = y + 1 < size.height ? std::min(here, to_link(value(x, y + 1, 0))) : 0;
        ASSERT_EQ(h(x, y), right) << pixel(x, y);
        ASSERT_EQ(v(x, y), down) << pixel(x, y);
        largest = std::max({largest, right, down});
      }
    EXPECT_EQ(links.max_link(), largest);
    ASSERT_EQ(links.tiles_x(), (size.width + 63) / 64);
    ASSERT_EQ(links.tiles_y(), (size.height + 63) / 64);
    for (std::ptrdiff_t ty = 0; ty < links.tiles_y(); ++ty)
      for (std::ptrdiff_t tx = 0; tx < links.tiles_x(); ++tx) {
        bool any_h = false, any_v = false;
        for (std::ptrdiff_t y = ty * 64; y < std::min(size.height, (ty + 1) * 64); ++y)
          for (std::ptrdiff_t x = tx * 64; x < std::min(size.width, (tx + 1) * 64); ++x) {
            any_h = any_h || h(x, y) != 0;
            any_v = any_v || v(x, y) != 0;
          }
        EXPECT_EQ(links.horizontal_active(tx, ty), any_h) << "tile " << tx << ", " << ty;
        EXPECT_EQ(links.vertical_active(tx, ty), any_v) << "tile " << tx << ", " << ty;
      }
    if (size.width >= 129) {  // tile (1, 0) is whole: in focus, so inactive
      EXPECT_FALSE(links.horizontal_active(1, 0));
      EXPECT_FALSE(links.vertical_active(1, 0));
      EXPECT_TRUE(links.horizontal_active(0, 0));
    }
  }
}

TEST(Diffusion, LinksFinishInsulatesTheBorder) {
  const Size size{65, 66};
  LinkField links(size.width, size.height);
  for (Plane p : {links.horizontal(), links.vertical()})
    for (std::ptrdiff_t y = 0; y < size.height; ++y)
      std::fill(p.row(y), p.row(y) + size.width, 2.f);
  // Border links are zeroed by finish(), whatever they held (so not checked).
  links.horizontal()(64, 3) = kNaN;
  links.vertical()(5, 65) = -1.f;
  links.finish();
  for (std::ptrdiff_t y = 0; y < size.height; ++y) EXPECT_EQ(links.horizontal()(64, y), 0.f);
  for (std::ptrdiff_t x = 0; x < size.width; ++x) EXPECT_EQ(links.vertical()(x, 65), 0.f);
  EXPECT_EQ(links.max_link(), 2.f);
  // The last column of tiles holds only the zeroed column 64 of horizontal links.
  EXPECT_FALSE(links.horizontal_active(1, 0));
  EXPECT_TRUE(links.vertical_active(1, 0));
  // Tile row 1 holds image rows 64 and 65: row 64 of vertical links joins them and stays.
  EXPECT_EQ(links.vertical()(0, 64), 2.f);
  EXPECT_TRUE(links.vertical_active(0, 1));
  EXPECT_TRUE(links.horizontal_active(0, 1));
}

TEST(Diffusion, LinksFinishNamesTheBadLink) {
  struct Case {
    bool horizontal;
    std::ptrdiff_t x, y;
    float value;
  };
  const Case cases[] = {{true, 70, 65, kNaN},
                        {false, 3, 140, -1.f},
                        {true, 0, 0, std::numeric_limits<float>::infinity()},
                        {false, 199, 148, -std::numeric_limits<float>::infinity()},
                        {true, 198, 149, -0.5f}};
  for (const Case& c : cases) {
    LinkField links = random_links({200, 150}, 1.f, 0.3, 102);
    (c.horizontal ? links.horizontal() : links.vertical())(c.x, c.y) = c.value;
    const Thrown thrown = invalid_argument_of([&] { links.finish(); });
    EXPECT_EQ(thrown.argument, c.horizontal ? "horizontal link" : "vertical link");
    EXPECT_TRUE(contains(thrown.message, pixel(c.x, c.y)));
  }
}

// finish() runs on the caller's threads: the result does not depend on how many, and a bad
// count is refused.
TEST(LinkFieldErrors, FinishObeysThreads) {
  LinkField one = random_links({130, 70}, 1.f, 0.3, 5);
  LinkField two = one;
  one.finish(1);
  two.finish(2);
  EXPECT_EQ(one.max_link(), two.max_link());
  for (std::ptrdiff_t ty = 0; ty < one.tiles_y(); ++ty)
    for (std::ptrdiff_t tx = 0; tx < one.tiles_x(); ++tx) {
      EXPECT_EQ(one.horizontal_active(tx, ty), two.horizontal_active(tx, ty));
      EXPECT_EQ(one.vertical_active(tx, ty), two.vertical_active(tx, ty));
    }
  EXPECT_EQ(invalid_argument_of([&] { two.finish(-1); }).argument, "threads");
}

// ---------------------------------------------------------------------------------------------
// 11. A non-finite pixel is reported with its image coordinates: by the solver when it lies in
// a solved segment (the error's system and row mapped back to the image), by the copy when it
// lies in a skipped part of an out-of-place pass. In place, skipped parts are documented as
// unchecked, so only pixels inside a solved segment are asserted there.

struct BadPixel {
  Size size;
  std::ptrdiff_t x, y;
  // Which links are non-zero: "all", "horizontal", "vertical", "tile" (only the tile of the
  // bad pixel), "elsewhere" (only tile (0, 0), which does not hold the pixel), "gap" (tile
  // columns 0 and 3 and tile rows 0 and 2: the pixel lies between two segments).
  const char* links;
};

LinkField links_for(const BadPixel& c) {
  LinkField links = random_links(c.size, 2.f, 0.0, 111);
  const std::string which = c.links;
  if (which == "horizontal")
    clear_tiles(
        links, [](auto, auto) { return true; }, false, true);
  if (which == "vertical")
    clear_tiles(
        links, [](auto, auto) { return true; }, true, false);
  if (which == "tile")
    clear_tiles(
        links, [&](auto tx, auto ty) { return tx != c.x / kTile || ty != c.y / kTile; }, true,
        true);
  if (which == "elsewhere")
    clear_tiles(
        links, [](auto tx, auto ty) { return tx != 0 || ty != 0; }, true, true);
  if (which == "gap")
    clear_tiles(
        links, [](auto tx, auto ty) { return tx % 3 != 0 && ty % 2 != 0; }, true, true);
  return links;
}

TEST(Diffusion, AdiNamesNonFinitePixel) {
  const BadPixel cases[] = {
      {{200, 150}, 100, 70, "all"},       // middle of tile (1, 1): the rows pass finds it
      {{200, 150}, 100, 70, "vertical"},  // the same pixel found by the columns pass
      {{200, 150}, 150, 100, "tile"},     // segments that start at pixel 128 and row 64
      {{200, 150}, 150, 100, "horizontal"},
      {{200, 150}, 150, 100, "elsewhere"},  // in a skipped part: a band with no segment
      {{200, 150}, 150, 30, "elsewhere"},   // after the segment of its row band
      {{200, 150}, 30, 100, "elsewhere"},   // after the segment of its column band
      {{200, 150}, 100, 70, "gap"},         // in the skipped part between two segments
      {{200, 150}, 195, 140, "vertical"},   // partial tiles at both ends
      {{200, 150}, 195, 140, "horizontal"},
      {{200, 150}, 64, 64, "tile"},    // the first pixel of a segment
      {{200, 150}, 128, 127, "tile"},  // the pixel after the last link of a segment
      {{65, 130}, 64, 129, "all"},     // the last pixel
      {{65, 130}, 0, 0, "all"},        // the first pixel
      {{1, 37}, 0, 20, "all"},         // one column: only vertical links
      {{37, 1}, 20, 0, "all"},         // one row: only horizontal links
      {{7, 5}, 3, 2, "all"},
      {{1, 1}, 0, 0, "all"},  // no link at all
  };
  for (const BadPixel& c : cases)
    for (const float bad : {kNaN, std::numeric_limits<float>::infinity()})
      for (const bool skip : {true, false}) {
        SCOPED_TRACE(name(c.size) + ", " + pixel(c.x, c.y) + ", links " + c.links +
                     (skip ? ", skipping" : ", full solve") + ", value " + std::to_string(bad));
        const LinkField links = links_for(c);
        Image src = random_image(c.size, 1, 112);
        src(c.x, c.y, 0) = bad;
        Image dst(c.size.width, c.size.height, 1);
        const DiffusionOptions options = with_skip(skip);
        const Thrown thrown = invalid_argument_of([&] { diffuse_adi(dst, src, links, options); });
        EXPECT_EQ(thrown.argument, "src");
        EXPECT_TRUE(contains(thrown.message, pixel(c.x, c.y)));
        // Each pass on its own, out of place.
        const Thrown rows =
            invalid_argument_of([&] { diffuse_rows(dst.plane(0), src.plane(0), links, options); });
        EXPECT_TRUE(contains(rows.message, pixel(c.x, c.y))) << "rows pass";
        const Thrown columns = invalid_argument_of(
            [&] { diffuse_columns(dst.plane(0), src.plane(0), links, options); });
        EXPECT_TRUE(contains(columns.message, pixel(c.x, c.y))) << "columns pass";
        // In place, when a pass solves a segment through the pixel.
        const std::string which = c.links;
        const bool solved =
            !skip || (which != "elsewhere" && which != "gap" && c.size.width * c.size.height > 1);
        if (solved) {
          Image image = src;
          const Thrown in_place =
              invalid_argument_of([&] { diffuse_adi(image, image, links, options); });
          EXPECT_TRUE(contains(in_place.message, pixel(c.x, c.y))) << "in place";
        }
      }
}

// The columns pass keeps its eliminated values in the rows it will overwrite, so in place a
// bad value carries down its column before the search for it. Two bad values in different
// columns and channels of full 32-column lanes: the first by rows is named, and so is a bad
// value in the last row of a column.
TEST(Diffusion, AdiInPlaceColumnsPassNamesFirstBadPixelByRows) {
  const Size size{200, 150};
  LinkField links = random_links(size, 2.f, 0.0, 141);
  clear_tiles(
      links, [](auto, auto) { return true; }, false, true);  // vertical links only
  struct Bad {
    std::ptrdiff_t x, y;
    int channel;
    float value;
  };
  const float inf = std::numeric_limits<float>::infinity();
  const std::pair<Bad, Bad> cases[] = {{{100, 90, 0, kNaN}, {40, 60, 2, inf}},
                                       {{33, 20, 1, -inf}, {34, 21, 1, kNaN}},
                                       {{70, 149, 2, kNaN}, {71, 149, 0, kNaN}}};
  for (const auto& [first, second] : cases) {
    const Bad earlier =
        first.y < second.y || (first.y == second.y && first.x < second.x) ? first : second;
    Image image = random_image(size, 3, 142);
    for (const Bad& b : {first, second}) image(b.x, b.y, b.channel) = b.value;
    const Thrown thrown = invalid_argument_of([&] { diffuse_adi(image, image, links); });
    EXPECT_EQ(thrown.argument, "src");
    EXPECT_TRUE(contains(thrown.message, pixel(earlier.x, earlier.y))) << thrown.message;
  }
}

// Forward Euler would spread a non-finite value over the image: refused up front.
TEST(Diffusion, ExplicitNamesNonFinitePixel) {
  const Size size{130, 70};
  const LinkField kappa = random_links(size, 0.25f, 0.3, 113);
  for (const auto& [x, y, c] :
       {std::tuple{100, 65, 1}, std::tuple{0, 0, 0}, std::tuple{129, 69, 2}})
    for (const bool skip : {true, false}) {
      Image src = random_image(size, 3, 114);
      src(x, y, c) = kNaN;
      Image dst;
      const Thrown thrown =
          invalid_argument_of([&] { diffuse_explicit_steps(dst, src, kappa, 2, with_skip(skip)); });
      EXPECT_EQ(thrown.argument, "src");
      EXPECT_TRUE(contains(thrown.message, pixel(x, y) + ", channel " + std::to_string(c)));
    }
}

// ---------------------------------------------------------------------------------------------
// 12. Threads: every band is solved by one thread with the same kernel, whatever the team.

TEST(Diffusion, ThreadsDoNotChangeTheResult) {
  for (const Size size : {Size{200, 150}, Size{65, 130}, Size{129, 67}}) {
    SCOPED_TRACE(name(size));
    const Image src = random_image(size, 3, 121);
    const LinkField beta = random_links(size, 6.f, 0.3, 122);
    Image one, two;
    diffuse_adi(one, src, beta, with_skip(true, 1));
    diffuse_adi(two, src, beta, with_skip(true, 2));
    EXPECT_EQ(first_bit_difference(one, two), "");
    diffuse_explicit(one, src, beta, with_skip(true, 1));
    diffuse_explicit(two, src, beta, with_skip(true, 2));
    EXPECT_EQ(first_bit_difference(one, two), "");
    const LinkField links_one = links_from_pixels(
        src.plane(0), [](float v) { return 2 * v; }, 1);
    const LinkField links_two = links_from_pixels(
        src.plane(0), [](float v) { return 2 * v; }, 2);
    for (int d = 0; d < 2; ++d)
      for (std::ptrdiff_t y = 0; y < size.height; ++y)
        for (std::ptrdiff_t x = 0; x < size.width; ++x) {
          ConstPlane p1 = d ? links_one.vertical() : links_one.horizontal();
          ConstPlane p2 = d ? links_two.vertical() : links_two.horizontal();
          ASSERT_EQ(std::bit_cast<std::uint32_t>(p1(x, y)), std::bit_cast<std::uint32_t>(p2(x, y)));
        }
  }
}

// ---------------------------------------------------------------------------------------------
// 13. Conductances given per pixel (diffuse_adi(dst, src, value, to_link)): the links are the
// smaller end of each pair, computed as the solves read them. The references are the dense
// solves of the same systems; the links for them come from links_from_pixels.

// A per-pixel value in [0, 3) with whole 64 x 64 tiles and scattered pixels at zero (sharp).
Image sharp_and_blurred(Size size, std::uint64_t seed) {
  Image value = random_image(size, 1, seed);
  std::mt19937_64 random(seed + 1);
  std::uniform_real_distribution<float> uniform(0.f, 1.f);
  for (std::ptrdiff_t y = 0; y < size.height; ++y)
    for (std::ptrdiff_t x = 0; x < size.width; ++x) {
      const bool sharp_tile = (x / kTile + 2 * (y / kTile)) % 3 == 1;
      value(x, y, 0) = sharp_tile || uniform(random) < 0.1f ? 0.f : 3.f * value(x, y, 0);
    }
  return value;
}

// The DOF map: nothing below one pixel, a quadratic above.
float dof_like_link(float v) { return std::abs(v) < 1.f ? 0.f : v * v * 0.75f; }

TEST(Diffusion, AdiFromPixelsMatchesDenseSolve) {
  // Every plane grouping (the solves take up to three planes at once): 1, 2, 3, 3 + 1, 3 + 2.
  for (const Size size : kSmallDenseSizes)
    for (const int channels : {1, 2, 3, 4, 5}) {
      SCOPED_TRACE(name(size) + ", " + std::to_string(channels) + " channels");
      const Image value = sharp_and_blurred(size, 131);
      const Image src = random_image(size, channels, 132);
      const LinkField links = links_from_pixels(value.plane(0), dof_like_link);
      Image dst;
      diffuse_adi(dst, src, value.plane(0), dof_like_link);
      expect_matches(dst, reference_image(src, links), max_abs(src));
    }
}

TEST(Diffusion, AdiFromPixelsSkipsExactlyAndAgreesAcrossThreads) {
  for (const Size size : kSizes) {
    SCOPED_TRACE(name(size));
    const Image value = sharp_and_blurred(size, 133);
    const Image src = random_image(size, 3, 134);
    Image skipped, full, two_threads, in_place = src;
    const DiffusionReport report =
        diffuse_adi(skipped, src, value.plane(0), dof_like_link, with_skip(true, 1));
    diffuse_adi(full, src, value.plane(0), dof_like_link, with_skip(false, 1));
    diffuse_adi(two_threads, src, value.plane(0), dof_like_link, with_skip(true, 2));
    diffuse_adi(in_place, in_place, value.plane(0), dof_like_link, with_skip(true, 2));
    EXPECT_EQ(first_bit_difference(skipped, full), "");
    EXPECT_EQ(first_bit_difference(two_threads, full), "");
    EXPECT_EQ(first_bit_difference(in_place, full), "");
    // The same bits as the LinkField path, which has its own tests against dense solves.
    Image from_links;
    diffuse_adi(from_links, src, links_from_pixels(value.plane(0), dof_like_link),
                with_skip(false));
    EXPECT_EQ(first_bit_difference(from_links, full), "");
    if (size.width >= 3 * kTile && size.height >= 2 * kTile) {
      EXPECT_GT(report.skipped_fraction(), 0.05);  // the sharp tiles
    }
  }
}

TEST(Diffusion, AdiFromPixelsSolvesNothingInASharpFrame) {
  const Size size{200, 150};
  const Image src = random_image(size, 3, 135);
  const Image value(size.width, size.height, 1);  // every pixel 0: insulated
  Image dst;
  const DiffusionReport report = diffuse_adi(dst, src, value.plane(0), dof_like_link);
  EXPECT_EQ(report.pixels_solved, 0);
  EXPECT_EQ(first_bit_difference(dst, src), "");
}

// A bad conductance anywhere is named, also where a link's other end would hide it (a NaN at
// the last pixel of a row only enters the link min(k(x - 1), NaN), whose value is k(x - 1)).
TEST(Diffusion, AdiFromPixelsNamesBadConductanceAndBadPixel) {
  const Size size{130, 70};
  struct Case {
    std::ptrdiff_t x, y;
    float value;
  };
  const float nan = kNaN, inf = std::numeric_limits<float>::infinity();
  for (const Case c : {Case{129, 69, nan}, Case{0, 0, inf}, Case{64, 30, -2.f}, Case{129, 3, nan},
                       Case{5, 69, nan}})
    for (const bool skip : {true, false}) {
      SCOPED_TRACE(pixel(c.x, c.y) + " value " + std::to_string(c.value) +
                   (skip ? ", skipping" : ", full solve"));
      Image value = sharp_and_blurred(size, 136);
      value(c.x, c.y, 0) = c.value;
      const Image src = random_image(size, 3, 137);
      Image dst;
      const auto negative_is_bad = [](float v) { return v < 0 ? v : dof_like_link(v); };
      const Thrown thrown = invalid_argument_of(
          [&] { diffuse_adi(dst, src, value.plane(0), negative_is_bad, with_skip(skip)); });
      EXPECT_EQ(thrown.argument, "value");
      EXPECT_TRUE(contains(thrown.message, pixel(c.x, c.y))) << thrown.message;
    }
  // A non-finite colour value where the frame is blurred, and where it is sharp.
  for (const bool sharp : {false, true}) {
    const Image value = sharp ? Image(size.width, size.height, 1) : sharp_and_blurred(size, 138);
    Image src = random_image(size, 3, 139);
    src(100, 7, 2) = kNaN;
    Image dst;
    const Thrown thrown =
        invalid_argument_of([&] { diffuse_adi(dst, src, value.plane(0), dof_like_link); });
    EXPECT_EQ(thrown.argument, "src");
    EXPECT_TRUE(contains(thrown.message, pixel(100, 7))) << thrown.message;
  }
  const Image wrong_size(size.width + 1, size.height, 1);
  Image dst;
  EXPECT_EQ(invalid_argument_of([&] {
              diffuse_adi(dst, random_image(size, 3, 140), wrong_size.plane(0), dof_like_link);
            }).argument,
            "value");
}

}  // namespace
}  // namespace tridiff::test

namespace tridiff::test {
namespace {

// The impulse response of one step over a uniform conductance beta = adi_beta_for_coc(d), on
// a frame large enough that the border does not matter.
Image impulse_response(float d, bool isotropic) {
  const std::ptrdiff_t n = 8 * std::ptrdiff_t(d) + 1, c = n / 2;
  Image image(n, n, 1), coc(n, n, 1);
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x) {
      image(x, y, 0) = 0.f;
      coc(x, y, 0) = d;
    }
  image(c, c, 0) = 1.f;
  const auto to_link = [](float k) { return adi_beta_for_coc(k); };
  if (isotropic)
    diffuse_isotropic(image, image, coc.plane(0), to_link);
  else
    diffuse_adi(image, image, coc.plane(0), to_link);
  return image;
}

// Where the profile from the centre along (dx, dy) falls to `level` of the peak, in pixels
// (linear interpolation between samples).
double extent(const Image& k, int dx, int dy, double level) {
  const std::ptrdiff_t c = k.width() / 2;
  const double peak = k(c, c, 0), step = std::hypot(dx, dy);
  for (std::ptrdiff_t i = 1; c + i * std::max(dx, dy) < k.width(); ++i) {
    const double here = k(c + i * dx, c + i * dy, 0),
                 before = k(c + (i - 1) * dx, c + (i - 1) * dy, 0);
    if (here < level * peak)
      return step * (double(i - 1) + (before - level * peak) / (before - here));
  }
  return INFINITY;
}

TEST(IsotropicDiffusion, ImpulseIsRoundWhereAdiIsADiamond) {
  for (float d : {12.f, 40.f}) {
    const Image iso = impulse_response(d, true), adi = impulse_response(d, false);
    for (double level : {0.5, 0.2, 0.05}) {
      const double axis = extent(iso, 1, 0, level), diagonal = extent(iso, 1, 1, level);
      EXPECT_NEAR(diagonal / axis, 1.0, 0.03) << "d " << d << " level " << level;
      EXPECT_NEAR(extent(iso, 0, 1, level), axis, 1e-3 * axis);  // symmetric in x and y
      // One ADI step: the diamond, diagonal extent about 1/sqrt(2) of the axis one.
      EXPECT_LT(extent(adi, 1, 1, level) / extent(adi, 1, 0, level), 0.8);
    }
  }
}

// Against the thin-lens disc of diameter d: the same variance d^2 / 16 along each axis (by
// construction of adi_beta_for_coc), the energy conserved, most of it inside the disc and
// almost none beyond twice its radius.
TEST(IsotropicDiffusion, ImpulseSpreadsLikeTheDisc) {
  const float d = 24.f;
  const Image k = impulse_response(d, true);
  const std::ptrdiff_t c = k.width() / 2;
  double sum = 0, xx = 0, yy = 0, inside = 0, beyond = 0;
  for (std::ptrdiff_t y = 0; y < k.height(); ++y)
    for (std::ptrdiff_t x = 0; x < k.width(); ++x) {
      const double v = k(x, y, 0), r = std::hypot(double(x - c), double(y - c));
      sum += v;
      xx += v * double(x - c) * double(x - c);
      yy += v * double(y - c) * double(y - c);
      inside += r <= d / 2 ? v : 0;
      beyond += r > d ? v : 0;
    }
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_NEAR(xx, d * d / 16, 0.01 * d * d / 16);
  EXPECT_NEAR(yy, d * d / 16, 0.01 * d * d / 16);
  EXPECT_GT(inside, 0.75);  // a Gaussian of the same variance: 1 - e^-2 = 0.86
  EXPECT_LT(beyond, 0.02);
}

// A sharp (zero-conductance) diagonal line one pixel wide insulates the two sides: the
// diagonal links do not step over it.
TEST(IsotropicDiffusion, ThinDiagonalLineInsulates) {
  const std::ptrdiff_t n = 64;
  Image image(n, n, 1), coc(n, n, 1);
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x) {
      const bool line = x + y == n - 1;
      image(x, y, 0) = x + y < n - 1 ? 1.f : 0.f;
      coc(x, y, 0) = line ? 0.f : 20.f;
    }
  diffuse_isotropic(image, image, coc.plane(0),
                    [](float k) { return k == 0 ? 0.f : adi_beta_for_coc(k); });
  for (std::ptrdiff_t y = 0; y < n; ++y)
    for (std::ptrdiff_t x = 0; x < n; ++x) {
      if (x + y < n - 1) {
        EXPECT_NEAR(image(x, y, 0), 1.f, 1e-6f) << x << " " << y;
      } else if (x + y > n - 1) {
        EXPECT_FLOAT_EQ(image(x, y, 0), 0.f) << x << " " << y;
      }
    }
}

// Skipping in-focus tiles changes no bit; the sum is conserved on a random frame.
TEST(IsotropicDiffusion, SkipChangesNothingAndMassIsConserved) {
  for (const Size size : kSizes) {
    const std::ptrdiff_t w = size.width, h = size.height;
    const Image color = random_image(size, 3, 4);
    Image coc = random_image(size, 1, 5);  // CoC 0..15 px, a third of it in focus
    const auto to_link = [](float u) { return u < 1.f / 3 ? 0.f : adi_beta_for_coc(15 * u); };
    Image a, b;
    DiffusionOptions full;
    full.skip_inactive = false;
    diffuse_isotropic(a, color, coc.plane(0), to_link);
    diffuse_isotropic(b, color, coc.plane(0), to_link, full);
    for (int c = 0; c < 3; ++c) {
      double in = 0, out = 0;
      for (std::ptrdiff_t y = 0; y < h; ++y)
        for (std::ptrdiff_t x = 0; x < w; ++x) {
          EXPECT_EQ(a(x, y, c), b(x, y, c));
          in += color(x, y, c);
          out += a(x, y, c);
        }
      EXPECT_NEAR(out, in, 1e-5 * in) << name(size);
    }
  }
}

// The reference: each of the four passes solved line by line in double by the Thomas
// algorithm, with the links written out from their definition (adi.hpp, diagonal_impl.hpp).
// A line is the pixels (x0 + i dx, y0 + i dy); link i joins pixels i and i + 1.
void solve_line_reference(
    Image& image, std::ptrdiff_t x0, std::ptrdiff_t y0, int dx, int dy,
    const std::function<double(std::ptrdiff_t, std::ptrdiff_t, int, int)>& link) {
  std::vector<std::pair<std::ptrdiff_t, std::ptrdiff_t>> pixels;
  for (std::ptrdiff_t x = x0, y = y0; x >= 0 && x < image.width() && y >= 0 && y < image.height();
       x += dx, y += dy)
    pixels.push_back({x, y});
  const std::size_t n = pixels.size();
  std::vector<double> beta(n, 0.0);
  for (std::size_t i = 0; i + 1 < n; ++i) beta[i] = link(pixels[i].first, pixels[i].second, dx, dy);
  for (int c = 0; c < image.channels(); ++c) {
    std::vector<double> lower(n), diag(n), upper(n), rhs(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double before = i ? beta[i - 1] : 0.0;
      lower[i] = -before;
      upper[i] = -beta[i];
      diag[i] = 1 + before + beta[i];
      rhs[i] = image(pixels[i].first, pixels[i].second, c);
    }
    for (std::size_t i = 1; i < n; ++i) {
      const double m = lower[i] / diag[i - 1];
      diag[i] -= m * upper[i - 1];
      rhs[i] -= m * rhs[i - 1];
    }
    for (std::size_t i = n; i-- > 0;)
      rhs[i] = (rhs[i] - (i + 1 < n ? upper[i] * rhs[i + 1] : 0.0)) / diag[i];
    for (std::size_t i = 0; i < n; ++i) image(pixels[i].first, pixels[i].second, c) = float(rhs[i]);
  }
}

TEST(IsotropicDiffusion, MatchesLineByLineSolvesInDouble) {
  for (const Size size : {Size{37, 23}, Size{23, 37}, Size{70, 70}, Size{1, 9}, Size{9, 1}}) {
    const std::ptrdiff_t w = size.width, h = size.height;
    const Image color = random_image(size, 3, 8);
    Image coc = random_image(size, 1, 9);
    const auto pixel_link = [&](std::ptrdiff_t x, std::ptrdiff_t y) {
      const float u = coc(x, y, 0);
      return u < 0.2f ? 0.0 : double(adi_beta_for_coc(20 * u));
    };
    Image expected = color;
    const auto axis = [&](std::ptrdiff_t x, std::ptrdiff_t y, int dx, int dy) {
      return 0.5 * std::min(pixel_link(x, y), pixel_link(x + dx, y + dy));
    };
    const auto diagonal = [&](std::ptrdiff_t x, std::ptrdiff_t y, int dx, int dy) {
      return 0.25 * std::min({pixel_link(x, y), pixel_link(x + dx, y + dy), pixel_link(x + dx, y),
                              pixel_link(x, y + dy)});
    };
    for (std::ptrdiff_t y = 0; y < h; ++y) solve_line_reference(expected, 0, y, 1, 0, axis);
    for (std::ptrdiff_t x = 0; x < w; ++x) solve_line_reference(expected, x, 0, 0, 1, axis);
    for (std::ptrdiff_t s = -(h - 1); s < w; ++s)  // x - y = s, down-right
      solve_line_reference(expected, std::max<std::ptrdiff_t>(s, 0),
                           std::max<std::ptrdiff_t>(-s, 0), 1, 1, diagonal);
    for (std::ptrdiff_t s = 0; s < w + h - 1; ++s)  // x + y = s, down-left
      solve_line_reference(expected, std::min(s, w - 1), s - std::min(s, w - 1), -1, 1, diagonal);
    Image out;
    diffuse_isotropic(out, color, coc.plane(0),
                      [](float u) { return u < 0.2f ? 0.f : adi_beta_for_coc(20 * u); });
    for (int c = 0; c < 3; ++c)
      for (std::ptrdiff_t y = 0; y < h; ++y)
        for (std::ptrdiff_t x = 0; x < w; ++x)
          ASSERT_NEAR(out(x, y, c), expected(x, y, c), 2e-5f) << name(size) << " " << pixel(x, y);
  }
}

}  // namespace
}  // namespace tridiff::test
