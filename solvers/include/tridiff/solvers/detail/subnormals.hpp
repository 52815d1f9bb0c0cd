// Subnormal floats read and written as zero in one thread, for as long as a guard lives.
//
// A solve that spreads values into a region of zeros (a layer's coverage, a hole's weight)
// decays them geometrically, and far enough out they fall below the smallest normal float
// (about 1e-38). Every operation on such a number then takes a microcode assist of about a
// hundred cycles on x86: the near-field blur of the layered depth of field, 1920 x 1080, four
// planes, took 28-31 ms against 8.9 for the same solve on ordinary values. Flushing them to
// zero changes values below 1e-38 only, and only towards zero: every bound and invariant the
// solves keep (maximum principle, mass to rounding) still holds.
#pragma once

#if defined(__SSE__) || defined(_M_X64)
#include <xmmintrin.h>
#endif

namespace tridiff::detail {

class SubnormalsAsZero {
 public:
#if defined(__SSE__) || defined(_M_X64)
  // MXCSR bit 15: flush results to zero (FTZ); bit 6: read inputs as zero (DAZ).
  static constexpr unsigned kFlushBits = 0x8040u;
  SubnormalsAsZero() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFlushBits); }
  ~SubnormalsAsZero() { _mm_setcsr(saved_); }

 private:
  unsigned saved_;
#else
  SubnormalsAsZero() = default;
#endif

 public:
  SubnormalsAsZero(const SubnormalsAsZero&) = delete;
  SubnormalsAsZero& operator=(const SubnormalsAsZero&) = delete;
};

// The opposite, for the solvers: gradual underflow in one thread for as long as the guard
// lives, whatever the caller chose (-ffast-math sets FTZ and DAZ at program start). A general
// solver cannot flush: with beta = 1e38 in float the first pivot's inverse, 1/(1 + beta), is
// the subnormal 1e-38, and flushed to zero it makes x = 0 without any sign of failure. Where
// the caller's state already keeps subnormals, nothing is written.
class SubnormalsKept {
 public:
#if defined(__SSE__) || defined(_M_X64)
  SubnormalsKept() : saved_(_mm_getcsr()) {
    if (saved_ & SubnormalsAsZero::kFlushBits) _mm_setcsr(saved_ & ~SubnormalsAsZero::kFlushBits);
  }
  ~SubnormalsKept() {
    if (saved_ & SubnormalsAsZero::kFlushBits) _mm_setcsr(saved_);
  }

 private:
  unsigned saved_;
#else
  SubnormalsKept() = default;
#endif

 public:
  SubnormalsKept(const SubnormalsKept&) = delete;
  SubnormalsKept& operator=(const SubnormalsKept&) = delete;
};

}  // namespace tridiff::detail
