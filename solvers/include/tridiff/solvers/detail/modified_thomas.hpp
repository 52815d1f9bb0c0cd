// The modified Thomas elimination of one part of a system (Laszlo, Giles & Appleyard 2016;
// step 1 of PaScaL_TDMA), one row at a time and for any memory layout. Two kernels run it on
// their own rows: the partitioned solve (partitioned_lanes.hpp: parts of one long system, in
// SIMD lanes) and the distributed solve (distributed/detail/slab_lanes.hpp: one rank's slab of
// many systems). The steps below are their shared arithmetic; each kernel keeps only how its
// rows are laid out, where the eliminated rows are kept and how it checks them.
//
// A part holds rows s .. e-1 of the system. After the forward sweep every row i > s reads
//     a'_i x_s + x_i + c'_i x_{i+1} = d'_i,
// row s itself only normalised: a'_s x_{s-1} + x_s + c'_s x_{s+1} = d'_s. The backward sweep
// combines rows e-2 .. s+1 into row s+1 through x_s and x_{e-1} alone, and row s then drops
// x_{s+1} for x_{e-1}. Rows s and e-1 are the part's two rows of the reduced system.
// Stable where Thomas is (a matrix diagonally dominant by rows or by columns): each part is a
// principal submatrix and the reduced system a Schur complement, both dominant again.
#pragma once

namespace tridiff::detail {

// Row s, normalised by its diagonal: (a, c, d) = (sub, super, rhs) / diag.
template <class T>
inline void modified_first_row(T sub, T diag, T super, T rhs, T& a, T& c, T& d) {
  const T inverse = T(1) / diag;
  a = sub * inverse;
  c = super * inverse;
  d = rhs * inverse;
}

// The row before row s+1 in the forward sweep: "x_s = x_s", as (a, c, d) = (-1, 0, 0), so that
// row s+1 takes the general step of modified_forward_row (and comes out only normalised).
template <class T>
inline void modified_forward_start(T& a, T& c, T& d) {
  a = T(-1);
  c = T(0);
  d = T(0);
}

// Forward, row i > s: (a, c, d) holds row i-1 in its forward form and receives row i's, with
// x_{i-1} eliminated from sub x_{i-1} + diag x_i + super x_{i+1} = rhs. Returns the pivot;
// `eliminated` (sub c'_{i-1}) is what a vanishing-pivot test scales the pivot against.
template <class T>
inline T modified_forward_row(T sub, T diag, T super, T rhs, T& a, T& c, T& d, T& eliminated) {
  eliminated = sub * c;
  const T pivot = diag - eliminated;
  const T inverse = T(1) / pivot;
  d = (rhs - sub * d) * inverse;
  a = -sub * a * inverse;
  c = super * inverse;
  return pivot;
}

// The row after row e-2 in the backward sweep: row e-1 as "x_{e-1} = x_{e-1}" in the backward
// form below, (a, c, d) = (0, -1, 0).
template <class T>
inline void modified_backward_start(T& a, T& c, T& d) {
  a = T(0);
  c = T(-1);
  d = T(0);
}

// Backward, rows e-2 .. s+1: (a, c, d) holds row i+1 as a x_s + x_{i+1} + c x_{e-1} = d and
// receives row i in that form, from its forward form (ka, kc, kd).
template <class T>
inline void modified_backward_row(T ka, T kc, T kd, T& a, T& c, T& d) {
  d = kd - kc * d;
  a = ka - kc * a;
  c = -kc * c;
}

// Row s, (a, c, d) normalised, with x_{s+1} taken from row s+1's backward form (next_a,
// next_c, next_d): afterwards a x_{s-1} + x_s + c x_{e-1} = d. Returns the pivot; `coupling`
// (c'_s next_a) is what a vanishing-pivot test scales it against, with 1.
template <class T>
inline T modified_close_first_row(T next_a, T next_c, T next_d, T& a, T& c, T& d, T& coupling) {
  coupling = c * next_a;
  const T pivot = T(1) - coupling;
  const T inverse = T(1) / pivot;
  d = (d - c * next_d) * inverse;
  a = a * inverse;
  c = -c * next_c * inverse;
  return pivot;
}

}  // namespace tridiff::detail
