// Measures how far one ADI step (and MPAD, its explicit counterpart) spreads a point of light
// for a uniform circle of confusion D, next to the disc of diameter D that a real lens makes:
// per-axis standard deviation, and the radii holding 50% and 90% of the energy. Prints a
// Markdown table (the README's "CoC to conductance" section comes from it).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "tridiff/diffusion/adi.hpp"
#include "tridiff/diffusion/explicit.hpp"

namespace {

using namespace tridiff;

struct Spread {
  double sigma, r50, r90;
};

// Spread of an impulse response centred at (c, c).
Spread measure(const Image& response, std::ptrdiff_t c) {
  std::vector<std::pair<double, double>> by_radius;  // (radius, energy)
  double total = 0, second = 0;
  for (std::ptrdiff_t y = 0; y < response.height(); ++y)
    for (std::ptrdiff_t x = 0; x < response.width(); ++x) {
      const double w = response(x, y, 0), dx = double(x - c), dy = double(y - c);
      total += w;
      second += w * dx * dx;
      by_radius.push_back({std::sqrt(dx * dx + dy * dy), w});
    }
  std::sort(by_radius.begin(), by_radius.end());
  double sum = 0, r50 = 0, r90 = 0;
  for (auto [r, w] : by_radius) {
    sum += w;
    if (r50 == 0 && sum >= 0.5 * total) r50 = r;
    if (r90 == 0 && sum >= 0.9 * total) r90 = r;
  }
  return {std::sqrt(second / total), r50, r90};
}

Image impulse(std::ptrdiff_t size) {
  Image image(size, size, 1);
  image(size / 2, size / 2, 0) = 1.f;
  return image;
}

LinkField uniform(std::ptrdiff_t size, float beta) {
  LinkField links(size, size);
  for (Plane p : {links.horizontal(), links.vertical()})
    for (std::ptrdiff_t y = 0; y < size; ++y)
      for (std::ptrdiff_t x = 0; x < size; ++x) p(x, y) = beta;
  links.finish();
  return links;
}

}  // namespace

int main() {
  std::printf(
      "| CoC D (px) | beta = D^2/32 | sigma ADI | sigma MPAD | sigma disc = D/4 |"
      " r50 ADI | r50 MPAD | r50 disc | r90 ADI | r90 MPAD | r90 disc |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (float d : {2.f, 4.f, 8.f, 16.f, 32.f, 64.f}) {
    const std::ptrdiff_t size = std::ptrdiff_t(8 * d) + 65, c = size / 2;
    const float beta = adi_beta_for_coc(d);
    const LinkField links = uniform(size, beta);
    Image adi, mpad;
    diffuse_adi(adi, impulse(size), links);
    diffuse_explicit(mpad, impulse(size), links);
    const Spread a = measure(adi, c), m = measure(mpad, c);
    // A disc of radius R: energy within r is (r / R)^2.
    const double radius = d / 2;
    std::printf("| %g | %g | %.3f | %.3f | %.3f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", d,
                beta, a.sigma, m.sigma, d / 4.0, a.r50, m.r50, radius * std::sqrt(0.5), a.r90,
                m.r90, radius * std::sqrt(0.9));
  }
  return 0;
}
