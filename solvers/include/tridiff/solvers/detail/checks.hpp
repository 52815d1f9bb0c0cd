// Checks done once per system, outside the hot loops: are the coefficients finite, is the
// matrix diagonally dominant (the condition under which the pivot-free methods are stable),
// and, after a kernel reported a breakdown, what exactly went wrong.
#pragma once

#include <algorithm>
#include <climits>
#include <cmath>
#include <complex>
#include <cstddef>
#include <string>
#include <type_traits>

#include "tridiff/solvers/detail/scalar.hpp"
#include "tridiff/solvers/error.hpp"

namespace tridiff::detail {

// The coefficient arrays of one system, with the names the public API gives them.
template <class T>
struct SystemView {
  Strided<const T> a, b, c, d;
  std::ptrdiff_t n;
  bool periodic;  // a[0] and c[n-1] are the corner entries
};

// Calls body(a, b, c) with raw pointers when the diagonals are contiguous, so that its loop
// vectorises with plain loads, and with the strided views otherwise.
template <class T, class Body>
void with_unit_stride_if_possible(const SystemView<T>& s, Body&& body) {
  if (s.a.stride == 1 && s.b.stride == 1 && s.c.stride == 1)
    body(s.a.data, s.b.data, s.c.data);
  else
    body(s.a, s.b, s.c);
}

// Throws InvalidArgument naming the first non-finite coefficient of rows [begin, end).
template <class T>
void require_finite_matrix(const SystemView<T>& s, std::ptrdiff_t system, std::ptrdiff_t begin = 0,
                           std::ptrdiff_t end = -1) {
  using R = real_t<T>;
  if (end < 0) end = s.n;
  // A vectorised pass over the rows whose three entries are all read: value * 0 is NaN
  // exactly when the value is infinite or NaN.
  const std::ptrdiff_t first = std::max<std::ptrdiff_t>(begin, 1);
  const std::ptrdiff_t last = std::min<std::ptrdiff_t>(end, s.n - 1);
  R probe = 0;
  with_unit_stride_if_possible(s, [&](auto a, auto b, auto c) {
#pragma omp simd reduction(+ : probe)
    for (std::ptrdiff_t i = first; i < last; ++i)
      probe += (magnitude(a[i]) + magnitude(b[i]) + magnitude(c[i])) * 0;
  });
  const bool scan_all = !(probe == 0) || first >= last;
  for (std::ptrdiff_t i = begin; i < end; ++i) {
    if (!scan_all && i == first) i = last;  // interior rows already known finite
    if (i >= end) break;
    const bool reads_a = i > 0 || s.periodic, reads_c = i + 1 < s.n || s.periodic;
    if (reads_a && !is_finite(s.a[i])) throw InvalidArgument("sub", system, i, "is not finite");
    if (!is_finite(s.b[i])) throw InvalidArgument("diag", system, i, "is not finite");
    if (reads_c && !is_finite(s.c[i])) throw InvalidArgument("super", system, i, "is not finite");
  }
}

template <class T>
void require_finite_rhs(const SystemView<T>& s, std::ptrdiff_t system) {
  for (std::ptrdiff_t i = 0; i < s.n; ++i)
    if (!is_finite(s.d[i])) throw InvalidArgument("rhs", system, i, "is not finite");
}

// Diagonal dominance of rows [begin, end): the first row that is not dominant, and whether
// every column of the range is. A matrix is safe for the pivot-free methods if it is dominant
// by rows or by columns (weakly, with a few ulps of slack for rounding in the caller's own
// arithmetic). The vectorised tests (dominance's first pass, the checks fused into
// thomas_lanes, thomas_rows and reduce_part_group) compare without that slack: what they
// accept, this exact scan accepts too, and what they refuse goes to it.
struct Dominance {
  std::ptrdiff_t first_row_failure = -1;
  bool by_columns = true;

  bool holds() const { return first_row_failure < 0 || by_columns; }
  void merge(const Dominance& later) {
    if (first_row_failure < 0) first_row_failure = later.first_row_failure;
    by_columns = by_columns && later.by_columns;
  }
};

// The exact scan: names the first row that is not dominant.
template <class T>
Dominance dominance_by_row(const SystemView<T>& s, std::ptrdiff_t begin, std::ptrdiff_t end) {
  using R = real_t<T>;
  const R slack = 1 - 4 * epsilon<T>;
  const std::ptrdiff_t n = s.n;
  auto entry_a = [&](std::ptrdiff_t i) { return (i > 0 || s.periodic) ? modulus(s.a[i]) : R(0); };
  auto entry_c = [&](std::ptrdiff_t i) {
    return (i + 1 < n || s.periodic) ? modulus(s.c[i]) : R(0);
  };
  Dominance result;
  for (std::ptrdiff_t i = begin; i < end; ++i) {
    const R diagonal = modulus(s.b[i]);
    if (result.first_row_failure < 0 && diagonal < slack * (entry_a(i) + entry_c(i)))
      result.first_row_failure = i;
    // Column i holds c[i-1] above the diagonal and a[i+1] below it (wrapping when periodic).
    const std::ptrdiff_t above = i > 0 ? i - 1 : n - 1, below = i + 1 < n ? i + 1 : 0;
    R off = 0;
    if (i > 0 || s.periodic) off += entry_c(above);
    if (i + 1 < n || s.periodic) off += entry_a(below);
    if (diagonal < slack * off) result.by_columns = false;
    if (!result.holds()) break;
  }
  return result;
}

// Dominance of rows [begin, end). The interior rows are first counted in a branch-free loop
// that the compiler vectorises; only a range with a failure is scanned again row by row.
template <class T>
Dominance dominance(const SystemView<T>& s, std::ptrdiff_t begin, std::ptrdiff_t end) {
  using R = real_t<T>;
  const std::ptrdiff_t first = std::max<std::ptrdiff_t>(begin, 1);
  const std::ptrdiff_t last = std::min<std::ptrdiff_t>(end, s.n - 1);
  if (first >= last) return dominance_by_row(s, begin, end);
  std::ptrdiff_t row_failures = 0, column_failures = 0;
  with_unit_stride_if_possible(s, [&](auto a, auto b, auto c) {
#pragma omp simd reduction(+ : row_failures, column_failures)
    for (std::ptrdiff_t i = first; i < last; ++i) {
      const R diagonal = modulus(b[i]);
      row_failures += diagonal < modulus(a[i]) + modulus(c[i]);
      column_failures += diagonal < modulus(c[i - 1]) + modulus(a[i + 1]);
    }
  });
  const bool edges = begin < first || last < end;
  if (row_failures == 0 && column_failures == 0 && !edges) return {};
  if (row_failures > 0 && column_failures > 0) return dominance_by_row(s, begin, end);
  Dominance result = edges ? dominance_by_row(s, begin, std::min(end, first)) : Dominance{};
  if (row_failures > 0 || column_failures > 0) result.merge(dominance_by_row(s, first, last));
  if (last < end) result.merge(dominance_by_row(s, std::max(begin, last), end));
  return result;
}

// -1 if the matrix is dominant by rows or by columns; otherwise the first row that is not.
template <class T>
std::ptrdiff_t first_non_dominant_row(const SystemView<T>& s) {
  const Dominance d = dominance(s, 0, s.n);
  return d.holds() ? -1 : d.first_row_failure;
}

// More precision and range than T, for the backward-error check.
template <class T>
struct wider {
  using type = long double;
};
template <>
struct wider<float> {
  using type = double;
};
template <class R>
struct wider<std::complex<R>> {
  using type = std::complex<typename wider<R>::type>;
};

struct BackwardError {
  long double value;   // ||d - A x|| / (||A|| ||x|| + ||d||), infinity norms (Rigal and Gaches)
  std::ptrdiff_t row;  // the row of the largest residual
};

// backward_error computed in the scalar type W.
template <class W, class T>
BackwardError backward_error_in(const SystemView<T>& s, Strided<const T> x) {
  using WR = real_t<W>;
  const std::ptrdiff_t n = s.n;
  WR worst = 0, norm_a = 0, norm_x = 0, norm_d = 0;
  std::ptrdiff_t worst_row = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::ptrdiff_t before = i > 0 ? i - 1 : n - 1, after = i + 1 < n ? i + 1 : 0;
    W product = W(s.b[i]) * W(x[i]);
    WR row_norm = magnitude(W(s.b[i]));
    if (i > 0 || s.periodic) {
      product += W(s.a[i]) * W(x[before]);
      row_norm += magnitude(W(s.a[i]));
    }
    if (i + 1 < n || s.periodic) {
      product += W(s.c[i]) * W(x[after]);
      row_norm += magnitude(W(s.c[i]));
    }
    const WR residual = magnitude(W(s.d[i]) - product);
    if (residual > worst) {
      worst = residual;
      worst_row = i;
    }
    norm_a = std::max(norm_a, row_norm);
    norm_x = std::max(norm_x, magnitude(W(x[i])));
    norm_d = std::max(norm_d, magnitude(W(s.d[i])));
  }
  const WR denominator = norm_a * norm_x + norm_d;
  return {static_cast<long double>(denominator > 0 ? worst / denominator : worst), worst_row};
}

// The normwise backward error of x as a solution of s: the smallest relative perturbation of
// A and d that x solves exactly. One pass over the system. Float systems are measured in
// double. Double ones in double too (x87 long double made the check cost as much as the
// hybrid's solve): rounding moves the measured value by at most ~4u, against bounds of 32u
// and more; only where a product overflowed (entries near max()) is it measured again in
// long double.
template <class T>
BackwardError backward_error(const SystemView<T>& s, Strided<const T> x) {
  if constexpr (std::is_same_v<real_t<T>, float>) {
    return backward_error_in<typename wider<T>::type>(s, x);
  } else {
    const BackwardError fast = backward_error_in<T>(s, x);
    if (std::isfinite(fast.value)) return fast;
    return backward_error_in<typename wider<T>::type>(s, x);
  }
}

// The exponent e of the largest entry of d (2^e <= max |d_i| < 2^(e+1), real and imaginary
// parts apart), or INT_MIN if d is zero.
template <class T>
int largest_exponent(Strided<const T> d, std::ptrdiff_t n) {
  real_t<T> largest = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    if constexpr (is_complex_v<T>)
      largest = std::max({largest, std::abs(d[i].real()), std::abs(d[i].imag())});
    else
      largest = std::max(largest, std::abs(d[i]));
  }
  return largest > 0 ? std::ilogb(largest) : INT_MIN;
}

// Runs kernel(rhs, result) -> the row of a breakdown or -1. If it succeeded with a non-finite
// result although rhs is finite and large, an intermediate sum overflowed, not x (the forward
// sweep's d[i] - a[i] x[i-1] with rhs near max(), where x itself is representable): it runs
// again on rhs scaled down by a power of two (exactly, into `scaled`, n scalars) and scales
// the result back, which is inf only where x itself overflows.
template <class T, class Kernel>
std::ptrdiff_t solve_rescaling_on_overflow(std::ptrdiff_t n, Strided<const T> d, T* result,
                                           T* scaled, Kernel&& kernel) {
  using R = real_t<T>;
  const std::ptrdiff_t bad = kernel(d, result);
  if (bad >= 0 || std::all_of(result, result + n, [](const T& v) { return is_finite(v); }))
    return bad;
  const int exponent = largest_exponent(d, n);
  if (exponent <= 0) return bad;  // rhs is not large: scaling it cannot help
  // Two normal factors: 2^-exponent alone is subnormal for the largest exponents.
  const R down_half = std::ldexp(R(1), -(exponent / 2));
  const R down_rest = std::ldexp(R(1), exponent / 2 - exponent);
  for (std::ptrdiff_t i = 0; i < n; ++i) scaled[i] = d[i] * down_half * down_rest;
  const std::ptrdiff_t again = kernel(Strided<const T>{scaled, 1}, result);
  for (std::ptrdiff_t i = 0; i < n; ++i) result[i] *= std::ldexp(R(1), exponent);
  return again;
}

// Throws NumericalError naming the first non-finite entry of a solution from finite inputs.
template <class T>
void require_finite_solution(const T* result, std::ptrdiff_t n, std::ptrdiff_t system,
                             const char* method) {
  for (std::ptrdiff_t i = 0; i < n; ++i)
    if (!is_finite(result[i]))
      throw NumericalError(system, i,
                           std::string("the solution overflowed in ") + method +
                               " (first at this row): the matrix is singular or badly scaled");
}

// Called after a kernel reported a breakdown at `row` (or -1 for a non-finite result):
// throws the most specific error, blaming the caller's input first.
template <class T>
[[noreturn]] void report_breakdown(const SystemView<T>& s, std::ptrdiff_t system,
                                   std::ptrdiff_t row, const char* method) {
  require_finite_matrix(s, system);
  require_finite_rhs(s, system);
  if (row >= 0)
    throw NumericalError(system, row,
                         std::string("zero or vanishing pivot in ") + method +
                             ": the matrix is singular to working precision");
  throw NumericalError(system, -1,
                       std::string("the solution overflowed in ") + method +
                           ": the matrix is singular or badly scaled");
}

}  // namespace tridiff::detail
