// Implicit heat diffusion by alternating directions (ADI; seed 000 §3.5, eq. 3.8-3.10; Kass,
// Lefohn & Owens 2006): a horizontal pass of tridiagonal solves along every row, then a
// vertical pass along every column, each one backward-Euler step of unit time.
#pragma once

#include <cstddef>
#include <functional>

#include "tridiff/diffusion/links.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff {

struct DiffusionOptions {
  int threads = 0;            // 0: all cores
  bool skip_inactive = true;  // false solves every row and column in full (the reference path)
  std::function<void(double)> progress;  // called with the fraction done (0..1); may be empty
  // diffuse_explicit refuses a field that needs more sub-steps than this (a blur that large is
  // the implicit method's work; 2^14 steps cover a CoC of 360 px by adi_beta_for_coc).
  int max_explicit_steps = 1 << 14;
};

// What a diffusion call did: pixel visits per pass, summed over passes and channels.
struct DiffusionReport {
  std::ptrdiff_t pixels = 0;         // pixels the passes cover
  std::ptrdiff_t pixels_solved = 0;  // of those, the ones inside a solved segment
  double skipped_fraction() const {
    return pixels ? 1.0 - double(pixels_solved) / double(pixels) : 0.0;
  }
  DiffusionReport& operator+=(const DiffusionReport& other) {
    pixels += other.pixels;
    pixels_solved += other.pixels_solved;
    return *this;
  }
};

// One ADI step: per row, (1 + beta_{x-1} + beta_x) y_x - beta_{x-1} y_{x-1} - beta_x y_{x+1}
// = src_x with beta = beta.horizontal(); then the same along columns with beta.vertical().
// Stable for any beta >= 0 (every solve is diagonally dominant); y is a convex combination of
// src (no new extrema), and the sum over every row and then every column is conserved.
//
// Work is skipped where a scene has nothing to diffuse: a row band (or column band) of one
// tile is solved only over the runs of tiles with a non-zero link; the rest is copied. The
// result is the same as a full solve (the skipped systems are the identity).
// dst may be src. src must be finite: InvalidArgument naming the pixel otherwise (when dst is
// src, values in skipped parts are left as they are, unchecked).
DiffusionReport diffuse_adi(Image& dst, const Image& src, const LinkField& beta,
                            const DiffusionOptions& options = {});

// The two passes on their own (the layered DOF mixes them with other work). dst may be src.
DiffusionReport diffuse_rows(Plane dst, ConstPlane src, const LinkField& beta,
                             const DiffusionOptions& options = {});
DiffusionReport diffuse_columns(Plane dst, ConstPlane src, const LinkField& beta,
                                const DiffusionOptions& options = {});

// One ADI step with the conductances given per pixel: the link between neighbours a and b
// conducts min(to_link(value(a)), to_link(value(b))), the links links_from_pixels builds, but
// computed as the solves read them, with no LinkField written, checked and read back (a third
// of the work of a DOF step). Every to_link(value) must be finite and >= 0: InvalidArgument
// naming the pixel ("value") otherwise. value has the size of src.
template <class ToLink>
DiffusionReport diffuse_adi(Image& dst, const Image& src, ConstPlane value, ToLink to_link,
                            const DiffusionOptions& options = {});

// One isotropic step: the ADI step above with half of each conductance, then the same
// backward-Euler solve along the two diagonals (x - y and x + y constant) with a quarter. A
// diagonal link spans sqrt(2) pixels, so the four passes spread a uniform region by the same
// variance 2 beta along each axis as the ADI step, but where one ADI step's impulse response is
// the product of two exponentials, a diamond (|x| + |y| constant), the four passes' is round:
// its extent along the diagonals and along the axes agree within 1 % (tests/diffusion_test.cpp),
// against a ratio of 0.71 for the ADI step. About twice the ADI step's work. A diagonal link
// conducts the smallest conductance of the 2 x 2 pixels it crosses (detail/diagonal_impl.hpp).
// The same stability, extrema and conservation as the ADI step; dst may be src.
template <class ToLink>
DiffusionReport diffuse_isotropic(Image& dst, const Image& src, ConstPlane value, ToLink to_link,
                                  const DiffusionOptions& options = {});

// The conductance beta that makes one ADI step spread a region of uniform circle of confusion
// like the disc itself: a disc of diameter D has variance D^2/16 along each axis, one implicit
// pass of conductance beta has variance 2 beta, so beta = D^2 / 32.
inline float adi_beta_for_coc(float coc_diameter_px) {
  return coc_diameter_px * coc_diameter_px * (1.f / 32.f);
}

}  // namespace tridiff

#include "tridiff/diffusion/detail/adi_impl.hpp"
