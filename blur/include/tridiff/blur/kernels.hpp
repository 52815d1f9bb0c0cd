// Convolution with explicit kernels: the sampled Gaussian, the triangle ("pyramid") kernel of
// seed 000 §5.3.2 and the bilinear 2x2 box of seed 000 §3.3.1, applied separably (seed 001
// §3.3), as a full 2D sum (seed 001 §3.2) or through the FFT (seed 001 §3.4).
//
// Conventions shared by every function here:
// - A 1D kernel has odd length 2r + 1; weight j applies at offset j - r. A 2D kernel is
//   (2rx + 1) x (2ry + 1), row-major, weight (i, j) at offset (i - rx, j - ry).
// - The kernel is laid over the image as it is stored (correlation, no flip; the same as
//   seed 001 eq. 3.3 for the symmetric kernels it uses):
//       out(x, y) = sum_{i,j} k(i, j) in(x + i - rx, y + j - ry)
//   and for a separable kernel k(i, j) = kx[i] ky[j].
// - Pixels outside the plane come from `border` (border_index of blur.hpp), however far out:
//   a kernel may be wider than the image.
// - threads: 0 means all cores. Bad input throws InvalidArgument naming the argument.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

// The largest total weight the truncated Gaussian kernels drop (both tails together, relative
// to the untruncated sampled Gaussian). Dropping mass e and renormalising moves any output on
// an image in [0, 1] by at most about e per pass, below the float rounding of the sums.
inline constexpr double kGaussianTailMass = 1e-7;

// Half-width of gaussian_kernel(sigma): the smallest r >= 1 whose dropped tail mass is at most
// kGaussianTailMass (about 5.3 sigma for sigma >= 1), never more than reference_radius(sigma)
// (ceil(6 sigma)), whose kernel is the reference itself. InvalidArgument unless sigma is finite
// and > 0.
std::ptrdiff_t gaussian_radius(double sigma);
// The same for another bound on the dropped tail mass (in (0, 1)).
std::ptrdiff_t gaussian_radius(double sigma, double tail_mass);

// The sampled Gaussian exp(-k^2 / (2 sigma^2)), k in [-r, r], normalised to sum 1 in double and
// then rounded to float. r = gaussian_radius(sigma) unless given.
std::vector<float> gaussian_kernel(double sigma);
std::vector<float> gaussian_kernel(double sigma, std::ptrdiff_t radius);

// The triangle ("pyramid") kernel of odd size n (seed 000 §5.3.2): the middle tap weighs
// m = (n + 1) / 2, each step away from it one less (the end taps weigh 1), normalised by m^2.
// Its variance is (m^2 - 1) / 6.
std::vector<float> triangle_kernel(std::ptrdiff_t size);

// The bilinear 2x2 box (seed 000 §3.3.1, eq. 5.1 there) in one dimension: a bilinear lookup at
// the pixel's lower-right corner averages pixels x and x + 1. As an odd kernel: {0, 1/2, 1/2}.
std::vector<float> bilinear_box_kernel();

// A 2D kernel: width x height weights, both odd, row-major.
struct Kernel2D {
  std::ptrdiff_t width = 0, height = 0;
  std::vector<float> weights;

  float operator()(std::ptrdiff_t i, std::ptrdiff_t j) const { return weights[j * width + i]; }
};

// k(i, j) = kx[i] ky[j], each product formed in double and rounded once.
Kernel2D outer_product(std::span<const float> kx, std::span<const float> ky);
// The 2D sampled Gaussian: the outer product of gaussian_kernel(sigma) with itself.
Kernel2D gaussian_kernel_2d(double sigma);
// The bilinear 2x2 box (1/4 [1 1; 1 1] at offsets 0 and +1) as a 3 x 3 kernel.
Kernel2D bilinear_box_kernel_2d();

// out = in convolved with kx along rows and ky along columns (a row pass into a small ring of
// rows per thread, then the column pass; no full-size temporary). Symmetric kernels take half
// the multiplications. O(pixels (|kx| + |ky|)). Every output row is computed the same way
// whatever the thread count: the result does not depend on `threads`.
void convolve_separable(Plane out, ConstPlane in, std::span<const float> kx,
                        std::span<const float> ky, Border border, int threads = 0);

// out = in convolved with a 2D kernel, summed tap by tap. O(pixels |kernel|).
void convolve_2d(Plane out, ConstPlane in, const Kernel2D& kernel, Border border, int threads = 0);

// The same two convolutions through the FFT (blur/src/fft_convolve.cpp): single-precision
// FFTW, the plane padded by the kernel radius with the border rule (replicate, mirror, zero) or
// not padded at all (periodic), to sizes 2^a 3^b 5^c 7^d. The cost does not depend on the
// kernel size, only on the padded size: O(N log N).
void fft_convolve_separable(Plane out, ConstPlane in, std::span<const float> kx,
                            std::span<const float> ky, Border border, int threads = 0);
void fft_convolve(Plane out, ConstPlane in, const Kernel2D& kernel, Border border, int threads = 0);

namespace blur_detail {
// The argument checks the functions above share: in non-empty, out the same size and not
// overlapping in, threads >= 0.
void check_convolution_planes(ConstPlane out, ConstPlane in, int threads);
// `kernel` (named `name` in the error) is non-empty, of odd length and finite.
void check_kernel(std::span<const float> kernel, const char* name);
void check_kernel(const Kernel2D& kernel, const char* name);
}  // namespace blur_detail

}  // namespace tridiff
