// Running one system of the stability suite: tridiff with one method, and LAPACK ?gtsv as the
// yardstick, both measured in long double against refined_reference (reference_solve of
// reference.hpp, refined). Shared by tests/solvers_stability_test.cpp and
// bench/stability_table.cpp; link with LAPACK::LAPACK.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "lapack.hpp"
#include "reference.hpp"

namespace tridiff::test {

// Solves A y = r in long double by Gaussian elimination with partial pivoting, the algorithm of
// LAPACK ?gtsv (no growth beyond a factor 2 per step for tridiagonal matrices). Used only for the
// refinement corrections of refined_reference, where an O(n) solve keeps the suite fast; a zero
// pivot leaves the correction at zero.
template <class T>
WideVector<T> wide_pivoting_solve(const System<T>& s, WideVector<T> r) {
  const std::ptrdiff_t n = s.n();
  std::vector<long double> lower(n, 0), diag(n), upper(n, 0), upper2(n, 0);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    diag[i] = s.b[i];
    if (i + 1 < n) {
      lower[i] = s.a[i + 1];
      upper[i] = s.c[i];
    }
  }
  for (std::ptrdiff_t i = 0; i + 1 < n; ++i) {
    if (std::abs(diag[i]) >= std::abs(lower[i])) {
      if (diag[i] == 0) return WideVector<T>::Zero(n);
      const long double factor = lower[i] / diag[i];
      diag[i + 1] -= factor * upper[i];
      r[i + 1] -= factor * r[i];
    } else {  // interchange rows i and i + 1
      const long double factor = diag[i] / lower[i];
      diag[i] = lower[i];
      const long double old_diag = diag[i + 1];
      diag[i + 1] = upper[i] - factor * old_diag;
      if (i + 2 < n) {
        upper2[i] = upper[i + 1];
        upper[i + 1] = -factor * upper2[i];
      }
      upper[i] = old_diag;
      std::swap(r[i], r[i + 1]);
      r[i + 1] -= factor * r[i];
    }
  }
  if (diag[n - 1] == 0) return WideVector<T>::Zero(n);
  for (std::ptrdiff_t i = n - 1; i >= 0; --i) {
    long double sum = r[i];
    if (i + 1 < n) sum -= upper[i] * r[i + 1];
    if (i + 2 < n) sum -= upper2[i] * r[i + 2];
    r[i] = sum / diag[i];
  }
  return r;
}

// The reference solution of the stability suite: reference_solve (reference.hpp), then two
// steps of iterative refinement with residuals and corrections in long double.
// reference_solve (Eigen's sparse LU, partial pivoting after a column ordering) is normwise
// backward stable but not invariant under row scaling: on the rows_scaled classes at n = 65537
// its own error was ~1e-12, above the true error of Thomas in double, which the table then
// misreported. Refinement in the same precision makes the backward error componentwise small
// (Higham, Accuracy and Stability, Thm 12.3), leaving an error of about cond(A, x) u_ld, with
// u_ld ~ 5e-20: far below every error measured here.
template <class T>
WideVector<T> refined_reference(const System<T>& s) {
  static_assert(!is_complex_v<T>, "the stability suite is real");
  const std::ptrdiff_t n = s.n();
  WideVector<T> x = reference_solve(s), residual(n);
  for (int step = 0; step < 2; ++step) {
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      long double ax = static_cast<long double>(s.b[i]) * x[i];
      if (i > 0) ax += static_cast<long double>(s.a[i]) * x[i - 1];
      if (i + 1 < n) ax += static_cast<long double>(s.c[i]) * x[i + 1];
      residual[i] = static_cast<long double>(s.d[i]) - ax;
    }
    x += wide_pivoting_solve(s, residual);
  }
  return x;
}

enum class Outcome {
  Solved,      // returned a finite x
  Refused,     // NumericalError: not diagonally dominant, unsafe for a pivot-free method
  Singular,    // NumericalError: zero or vanishing pivot (LAPACK: info > 0)
  Overflow,    // NumericalError: the solution overflowed
  Inaccurate,  // NumericalError: the answer failed the backward-error check (cancellation)
  Error,       // any other exception
  NonFinite,   // returned normally with a non-finite x: a bug, the API promises never to
};

inline const char* to_string(Outcome outcome) {
  switch (outcome) {
    case Outcome::Solved: return "solved";
    case Outcome::Refused: return "refused";
    case Outcome::Singular: return "singular";
    case Outcome::Overflow: return "overflow";
    case Outcome::Inaccurate: return "inaccurate";
    case Outcome::Error: return "error";
    case Outcome::NonFinite: return "nonfinite";
  }
  return "unknown";
}

// NumericalError has no kind field; its messages (solve.hpp check_system, checks.hpp
// report_breakdown) are the only way to tell a refusal from a breakdown.
inline Outcome classify(const NumericalError& error) {
  const std::string what = error.what();
  if (what.find("not diagonally dominant") != std::string::npos) return Outcome::Refused;
  if (what.find("pivot") != std::string::npos) return Outcome::Singular;
  if (what.find("overflow") != std::string::npos) return Outcome::Overflow;
  if (what.find("backward error") != std::string::npos) return Outcome::Inaccurate;
  return Outcome::Error;
}

struct Measurement {
  Outcome outcome = Outcome::Error;
  long double forward = std::numeric_limits<long double>::quiet_NaN();   // forward_error
  long double backward = std::numeric_limits<long double>::quiet_NaN();  // backward_error
  std::string message;         // the exception's message, if any
  int info = 0;                // LAPACK only
  int parts = 1;               // tridiff only: SolveReport::parts (> 1: partitioned Thomas ran)
  std::ptrdiff_t pivoted = 0;  // tridiff only: SolveReport::pivoted_systems
};

template <class T>
bool all_finite(const std::vector<T>& x) {
  for (const T& v : x)
    if (!std::isfinite(v)) return false;
  return true;
}

template <class T>
Measurement measure_solution(const System<T>& s, const std::vector<T>& x,
                             const WideVector<T>& reference) {
  Measurement m;
  if (!all_finite(x)) {
    m.outcome = Outcome::NonFinite;
    return m;
  }
  m.outcome = Outcome::Solved;
  m.forward = forward_error(x, reference);
  m.backward = backward_error(s, x);
  return m;
}

// Solves s with `method` on `threads` threads. One system is solved on one thread, except by
// Thomas (and Auto on a dominant matrix) when n >= detail::kPartitionedMinRows: then the
// partitioned method splits it into one part per thread.
template <class T>
Measurement measure_tridiff(const System<T>& s, Method method, const WideVector<T>& reference,
                            int threads = 1) {
  std::vector<T> x(s.n());
  SolveReport report;
  try {
    SolveOptions options;
    options.method = method;
    options.threads = threads;
    report = solve(s.a.data(), s.b.data(), s.c.data(), s.d.data(), x.data(),
                   BatchLayout::single(s.n()), options);
  } catch (const NumericalError& error) {
    Measurement m;
    m.outcome = classify(error);
    m.message = error.what();
    return m;
  } catch (const std::exception& error) {
    Measurement m;
    m.message = error.what();
    return m;
  }
  Measurement m = measure_solution(s, x, reference);
  m.parts = report.parts;
  m.pivoted = report.pivoted_systems;
  return m;
}

// LAPACK ?gtsv on copies of s (it overwrites its arguments); outcome Singular if info > 0.
template <class T>
Measurement measure_lapack(const System<T>& s, const WideVector<T>& reference) {
  static_assert(std::is_same_v<T, float> || std::is_same_v<T, double>);
  const int n = static_cast<int>(s.n()), one = 1;
  std::vector<T> dl(s.a.begin() + 1, s.a.end()), du(s.c.begin(), s.c.end() - 1);  // n - 1 each
  std::vector<T> d(s.b), x(s.d);
  if (n == 1) {  // no off-diagonals, but LAPACK still wants valid pointers
    dl.assign(1, T(0));
    du.assign(1, T(0));
  }
  int info = 0;
  if constexpr (std::is_same_v<T, float>)
    sgtsv_(&n, &one, dl.data(), d.data(), du.data(), x.data(), &n, &info);
  else
    dgtsv_(&n, &one, dl.data(), d.data(), du.data(), x.data(), &n, &info);
  Measurement m;
  if (info != 0) {
    m.outcome = info > 0 ? Outcome::Singular : Outcome::Error;
    m.info = info;
    m.message = "?gtsv info = " + std::to_string(info);
    return m;
  }
  return measure_solution(s, x, reference);
}

// LAPACK's estimate of kappa_1(A) = ||A||_1 ||A^{-1}||_1 (dgttrf + dgtcon in double, on s
// converted to double); infinity if dgttrf finds A exactly singular. For interpreting forward
// errors only: forward_error <~ kappa * backward_error.
template <class T>
long double condition_estimate(const System<T>& s) {
  const int n = static_cast<int>(s.n());
  std::vector<double> dl(std::max(n - 1, 1), 0.0), d(n), du(std::max(n - 1, 1), 0.0),
      du2(std::max(n - 2, 1), 0.0), work(2 * n);
  std::vector<int> ipiv(n), iwork(n);
  // kappa does not change when A is scaled, but ||A^{-1}|| of a matrix with entries ~1e-307
  // overflows double: scale A by a power of two (exactly) so that its largest entry is ~1.
  long double largest = 0;
  for (int i = 0; i < n; ++i)
    largest = std::max({largest, std::abs(static_cast<long double>(s.a[i])),
                        std::abs(static_cast<long double>(s.b[i])),
                        std::abs(static_cast<long double>(s.c[i]))});
  if (largest == 0) return std::numeric_limits<long double>::infinity();
  const int shift = -std::ilogb(largest);
  auto scaled = [&](T v) {
    return static_cast<double>(std::ldexp(static_cast<long double>(v), shift));
  };
  double norm = 0;  // the 1-norm: the largest column sum
  for (int j = 0; j < n; ++j) {
    d[j] = scaled(s.b[j]);
    double column = std::abs(d[j]);
    if (j + 1 < n) {
      dl[j] = scaled(s.a[j + 1]);
      du[j] = scaled(s.c[j]);
      column += std::abs(dl[j]);
    }
    if (j > 0) column += std::abs(scaled(s.c[j - 1]));
    norm = std::max(norm, column);
  }
  int info = 0;
  dgttrf_(&n, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), &info);
  if (info != 0) return std::numeric_limits<long double>::infinity();
  double rcond = 0;
  dgtcon_("1", &n, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), &norm, &rcond,
          work.data(), iwork.data(), &info, 1);
  return rcond > 0 ? 1.0L / rcond : std::numeric_limits<long double>::infinity();
}

// The floor under LAPACK's error when comparing with it: eps of T (= 2u). Rounding the exact
// solution to T already leaves a forward error of up to u and a normwise backward error of up
// to u (|A| u |x| over ||A|| ||x||), so an error below eps says nothing about a method, and a
// LAPACK error that happens to be 0 or ~u (lucky rounding, n = 1) must not make "within 10x"
// demand better than working precision.
template <class T>
long double lapack_floor() {
  return std::numeric_limits<T>::epsilon();
}

// ours / max(lapack, floor): how many times LAPACK's error (floored) tridiff's is.
template <class T>
long double ratio_to_lapack(long double ours, long double lapack) {
  return ours / std::max(lapack, lapack_floor<T>());
}

}  // namespace tridiff::test
