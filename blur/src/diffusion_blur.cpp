// Diffusion blurs: the diffusion module's operators, driven to a target sigma.
#include "tridiff/blur/diffusion_blur.hpp"

#include <cmath>
#include <string>

#include "tridiff/blur/blur.hpp"
#include "tridiff/diffusion/adi.hpp"
#include "tridiff/diffusion/explicit.hpp"

namespace tridiff {

namespace {

Image single_plane(ConstPlane plane) {
  Image image(plane.width(), plane.height(), 1);
  copy_plane(image.plane(0), plane);
  return image;
}

void require_sigma(double sigma) {
  if (!std::isfinite(sigma) || !(sigma > 0))
    throw InvalidArgument("sigma", "must be finite and > 0, got " + std::to_string(sigma));
}

DiffusionOptions with_threads(int threads) {
  DiffusionOptions options;
  options.threads = threads;
  return options;
}

}  // namespace

int explicit_diffusion_steps(double sigma) {
  require_sigma(sigma);
  return static_cast<int>(std::ceil(2 * sigma * sigma));
}

void explicit_diffusion_blur(Plane out, ConstPlane in, double sigma, int threads) {
  const int steps = explicit_diffusion_steps(sigma);
  const float c = static_cast<float>(sigma * sigma / (2.0 * steps));
  Image image = single_plane(in);
  diffuse_isotropic(image, image, c, steps, with_threads(threads));
  copy_plane(out, image.plane(0));
}

void implicit_diffusion_blur(Plane out, ConstPlane in, double sigma, int steps, int threads) {
  require_sigma(sigma);
  if (steps < 1) throw InvalidArgument("steps", "must be >= 1");
  LinkField beta(in.width(), in.height());
  const float b = static_cast<float>(sigma * sigma / (2.0 * steps));
  for (Plane links : {beta.horizontal(), beta.vertical()})
    for (std::ptrdiff_t y = 0; y < links.height(); ++y) std::fill_n(links.row(y), links.width(), b);
  beta.finish(threads);
  Image image = single_plane(in);
  for (int s = 0; s < steps; ++s) diffuse_adi(image, image, beta, with_threads(threads));
  copy_plane(out, image.plane(0));
}

namespace blur_detail {

// Steps of the registered implicit method: the kernel of K implicit steps has excess kurtosis
// that falls like 1/K; 4 steps keep it within the stated error (see the tests).
constexpr int kImplicitSteps = 4;

void run_diffusion_explicit(Plane out, ConstPlane in, const BlurOptions& options) {
  explicit_diffusion_blur(out, in, options.sigma, resolve_threads(options.threads));
}

void run_diffusion_implicit(Plane out, ConstPlane in, const BlurOptions& options) {
  implicit_diffusion_blur(out, in, options.sigma, kImplicitSteps, resolve_threads(options.threads));
}

}  // namespace blur_detail
}  // namespace tridiff
