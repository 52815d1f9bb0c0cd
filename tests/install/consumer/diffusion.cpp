// tridiff::diffusion, installed: one ADI step (a batch of tridiagonal solves per direction)
// conserves the sum of the image, moves every value towards its neighbours' and creates no
// new extremum. Exits 0 only if every check holds.
#include <tridiff/diffusion/adi.hpp>
#include <tridiff/diffusion/links.hpp>
#include <tridiff/image/image.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

int main() {
  constexpr std::ptrdiff_t width = 40, height = 24;
  tridiff::Image src(width, height, 1), dst(width, height, 1);
  double sum_before = 0;
  float lowest = 1, highest = 0;
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      src(x, y, 0) = float((7 * x + 3 * y) % 11) / 10.f;
      sum_before += src(x, y, 0);
      lowest = std::min(lowest, src(x, y, 0));
      highest = std::max(highest, src(x, y, 0));
    }
  tridiff::LinkField beta(width, height);
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      beta.horizontal()(x, y) = 2.f;
      beta.vertical()(x, y) = 2.f;
    }
  beta.finish();

  tridiff::DiffusionOptions options;
  options.threads = 2;
  tridiff::diffuse_adi(dst, src, beta, options);

  double sum_after = 0, changed = 0;
  bool in_range = true;
  for (std::ptrdiff_t y = 0; y < height; ++y)
    for (std::ptrdiff_t x = 0; x < width; ++x) {
      sum_after += dst(x, y, 0);
      changed = std::max(changed, double(std::abs(dst(x, y, 0) - src(x, y, 0))));
      in_range = in_range && dst(x, y, 0) >= lowest - 1e-6f && dst(x, y, 0) <= highest + 1e-6f;
    }
  int failures = 0;
  // Float solves of 40 and 24 unknowns: a relative error of a few hundred float epsilons at most.
  if (!(std::abs(sum_after - sum_before) <= 1e-4 * sum_before)) {
    std::printf("sum %.9g before, %.9g after\n", sum_before, sum_after);
    ++failures;
  }
  if (!(changed > 0.1)) {
    std::printf("the step changed no value by more than %g\n", changed);
    ++failures;
  }
  if (!in_range) {
    std::printf("a value left [%g, %g]\n", lowest, highest);
    ++failures;
  }
  std::printf("%s\n", failures == 0 ? "tridiff::diffusion consumer: ok"
                                    : "tridiff::diffusion consumer: FAILED");
  return failures == 0 ? 0 : 1;
}
