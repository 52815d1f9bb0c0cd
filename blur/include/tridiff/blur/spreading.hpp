// Polynomial spreading (Kosloff; seed 001 §3.6.2, eq. 3.17): the tent kernel, whose second
// derivative is three impulses (1, -2, 1) r pixels apart, is spread at every pixel and then
// integrated twice, so the work per pixel does not depend on the kernel's width. The 2D kernel
// is the tensor product tent(x) tent(y) of eq. 3.17, applied as a column pass and a row pass.
//
// The seed's tents have integer half-widths only (sigma in steps of ~0.4). Here the kernel is
// a blend of the two integer tents around a fractional half-width,
//   K(k) = (1 - blend) T_r(k) + blend T_{r+1}(k),   T_r(k) = max(r - |k|, 0) / r^2,
// still piecewise linear (its second derivative is five impulses), so any sigma is reachable.
#pragma once

#include <cstddef>

#include "tridiff/blur/blur.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct SpreadingKernel {
  std::ptrdiff_t radius = 1;  // r >= 1: T_r is zero from |k| = r on (T_1 is the identity)
  double blend = 0;           // in [0, 1]: the weight of T_{r+1}
};

// The variance of T_r is (r^2 - 1) / 6 (sum of k^2 (r - |k|) / r^2); a blend's variance is the
// blend of the two. Throws InvalidArgument("kernel") for radius < 1 or blend outside [0, 1].
double spreading_variance(const SpreadingKernel& kernel);

// The tent's own standard deviation, as a fraction of the target Gaussian's, that the sigma
// mapping uses. A tent is best fitted (least mean absolute difference over images, seed 001
// §4.1.2) by a Gaussian 3.5-4.5 % wider than its own sigma: seed 001 Table A.4 (r = 10: own
// sqrt(99 / 6) = 4.06, fitted 4.25) and our effective_sigma on quality_test_set (4.22) agree.
// Scaling by 0.96 makes the effective sigma the target one, and also gives the smallest max
// error on the test patterns; 0.935 would minimise the l1 (operator norm) distance instead,
// by ~5 % (0.133 vs 0.140), at a 2.5 % smaller effective sigma.
inline constexpr double kTentSigmaScale = 0.96;

// The kernel used for a target Gaussian sigma: the blend whose variance is
// (kTentSigmaScale sigma)^2. InvalidArgument("sigma") unless sigma is finite and > 0.
SpreadingKernel spreading_kernel_for_sigma(double sigma);

// out = in convolved with K(x) K(y). Borders: replicate (pixels beyond the edge repeat the edge
// pixel, added in closed form from the kernel's tail sums) or zero; others throw
// InvalidArgument("border"). O(pixels) whatever the radius; threads 0 means all cores.
void polynomial_spread(Plane out, ConstPlane in, const SpreadingKernel& kernel, Border border,
                       int threads = 0);

}  // namespace tridiff
