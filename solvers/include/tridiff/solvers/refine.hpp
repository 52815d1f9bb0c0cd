// What the factors of factor.hpp say about the answers: a condition estimate per system (as
// LAPACK ?gtcon), iterative refinement with forward and backward error bounds (as ?gtrfs), and
// mixed precision (factor in float, refine double data to a double-precision backward error).
// Per-system work on one SIMD lane of the stored factors: these are O(n) extras on top of a
// solve, priced for the answers they give, not for batch throughput.
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <limits>
#include <vector>

#include "tridiff/solvers/detail/norm_estimate.hpp"
#include "tridiff/solvers/factor.hpp"

namespace tridiff {

namespace detail {

// The scalar a residual is accumulated in: one step wider than the data (detail::wider of
// checks.hpp; ?gtrfs computes it in the working precision, a wider one makes the refined
// answer accurate to the last bits).
// The argument checks refine and solve_mixed share: the layout (one batch dimension, matching
// the factors), the five arrays, and x apart from rhs unless `may_alias` (in place).
template <class F, class T>
void require_refine_arguments(const TridiagonalFactors<F>& factors, const T* sub, const T* diag,
                              const T* super, const T* rhs, const T* x, const BatchLayout& layout,
                              bool may_alias) {
  validate_layout(layout);
  require_one_batch_dimension(layout, "refinement");
  require_matching(factors, layout);
  for (const auto& [p, name] : {std::pair<const T*, const char*>{sub, "sub"},
                                {diag, "diag"},
                                {super, "super"},
                                {rhs, "rhs"},
                                {x, "x"}})
    require_pointer(p, name);
  require_disjoint(rhs, "rhs", x, layout, may_alias);
}

template <class T>
using wider_t = typename wider<T>::type;

// One system's matrix entries seen through op: entry (i, i-1), (i, i), (i, i+1) of op(A).
template <class T>
struct OpRow {
  const SystemView<T>& s;
  Apply apply;
  T conj(const T& v) const { return conjugate_if(v, apply == Apply::Adjoint); }
  T left(std::ptrdiff_t i) const { return conj(apply == Apply::Matrix ? s.a[i] : s.c[i - 1]); }
  T centre(std::ptrdiff_t i) const { return conj(s.b[i]); }
  T right(std::ptrdiff_t i) const { return conj(apply == Apply::Matrix ? s.c[i] : s.a[i + 1]); }
};

// r = b - op(A) x accumulated in Acc and rounded to R, and scale = |op(A)| |x| + |b| (with
// CABS1 magnitudes, as ?gtrfs), for one system.
template <class Acc, class T, class X, class B, class Out>
void residual(const SystemView<T>& s, Apply apply, const X* x, const B* b, Out* r,
              real_t<X>* scale) {
  const OpRow<T> op{s, apply};
  for (std::ptrdiff_t i = 0; i < s.n; ++i) {
    Acc sum = Acc(b[i]);
    real_t<X> size = magnitude(b[i]);
    auto add = [&](const T& entry, const X& value) {
      sum -= Acc(entry) * Acc(value);
      size += real_t<X>(magnitude(entry)) * magnitude(value);
    };
    if (i > 0) add(op.left(i), x[i - 1]);
    add(op.centre(i), x[i]);
    if (i + 1 < s.n) add(op.right(i), x[i + 1]);
    r[i] = Out(sum);
    scale[i] = size;
  }
}

// max_i |r_i| / scale_i, guarded as ?gtrfs does against rows whose scale underflows.
template <class R, class Value>
R componentwise_backward_error(const Value* r, const R* scale, std::ptrdiff_t n) {
  const R safe1 = 4 * std::numeric_limits<R>::min();
  const R safe2 = safe1 / (std::numeric_limits<R>::epsilon() / 2);
  R worst = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const R size = R(magnitude(r[i]));
    if (size == 0) continue;  // an exact row (b = 0 and x = 0 among them) is exact
    worst =
        std::max(worst, scale[i] > safe2 ? size / scale[i] : (size + safe1) / (scale[i] + safe1));
  }
  return worst;
}

// Solves op(A) y = y with lane l of chunk f, y contiguous; the conjugate of A (needed for
// (A^T)^H) by conjugating around a plain solve.
template <class T>
void solve_lane(const ChunkFactors<T>& lane, Apply apply, bool conjugate_matrix, std::ptrdiff_t n,
                T* y) {
  constexpr int W = kLanes<T>;
  if (conjugate_matrix && is_complex_v<T>) {
    for (std::ptrdiff_t i = 0; i < n; ++i) y[i] = conjugate_if(y[i], true);
    solve_factored<T, W, 1>(lane, Apply::Matrix, n, y, 1);
    for (std::ptrdiff_t i = 0; i < n; ++i) y[i] = conjugate_if(y[i], true);
    return;
  }
  solve_factored<T, W, 1>(lane, apply, n, y, 1);
}

// Solves op(A)^H y = y.
template <class T>
void solve_lane_adjoint(const ChunkFactors<T>& lane, Apply apply, std::ptrdiff_t n, T* y) {
  if (apply == Apply::Matrix) return solve_lane(lane, Apply::Adjoint, false, n, y);
  if (apply == Apply::Adjoint) return solve_lane(lane, Apply::Matrix, false, n, y);
  solve_lane(lane, Apply::Matrix, true, n, y);  // (A^T)^H = conj(A)
}

// A bound on ||x - x_true||_inf / ||x||_inf from the residual r (?gtrfs): the estimated
// || |op(A)^{-1}| (|r| + nz eps (|op(A)||x| + |b|)) ||_inf, nz = 4 entries per row plus one.
template <class T>
real_t<T> forward_error_bound(const ChunkFactors<T>& lane, Apply apply, std::ptrdiff_t n,
                              const T* x, const T* r, const real_t<T>* scale) {
  using R = real_t<T>;
  const R eps = std::numeric_limits<R>::epsilon() / 2, safe1 = 4 * std::numeric_limits<R>::min();
  const R safe2 = safe1 / eps;
  std::vector<R> weight(n);
  for (std::ptrdiff_t i = 0; i < n; ++i)
    weight[i] = magnitude(r[i]) + 4 * eps * scale[i] + (scale[i] > safe2 ? R(0) : safe1);
  // ||diag(w) op(A)^{-H}||_1 = || |op(A)^{-1}| w ||_inf for w >= 0.
  const R estimate = estimate_norm1<T>(
      n,
      [&](std::vector<T>& v) {
        solve_lane_adjoint(lane, apply, n, v.data());
        for (std::ptrdiff_t i = 0; i < n; ++i) v[i] *= weight[i];
      },
      [&](std::vector<T>& v) {
        for (std::ptrdiff_t i = 0; i < n; ++i) v[i] *= weight[i];
        solve_lane(lane, apply, false, n, v.data());
      });
  R largest = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) largest = std::max(largest, R(modulus(x[i])));
  return largest > 0 ? estimate / largest : estimate;
}

}  // namespace detail

// Estimates of the reciprocal 1-norm condition number 1 / (||A||_1 ||A^{-1}||_1) of every
// system, as ?gtcon: ||A^{-1}||_1 by Hager and Higham's estimator (a lower bound, in practice
// within a factor of 3), from the factors alone. 0 for a zero matrix.
template <class T>
std::vector<real_t<T>> estimate_rcond(const TridiagonalFactors<T>& factors, int threads = 0) {
  using namespace detail;
  using R = real_t<T>;
  constexpr int W = kLanes<T>;
  const std::ptrdiff_t n = factors.n();
  std::vector<R> rcond(factors.count());
  for_each_chunk<T>(factors.count(), W, resolve_threads(threads),
                    [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<T>&) {
                      const ChunkFactors<T> f = factors.chunk(first / W);
                      for (int l = 0; l < systems; ++l) {
                        const ChunkFactors<T> lane = lane_of<T, W>(f, l);
                        const R norm = factors.norm1(first + l);
                        const R inverse_norm = estimate_norm1<T>(
                            n,
                            [&](std::vector<T>& v) {
                              solve_factored<T, W, 1>(lane, Apply::Matrix, n, v.data(), 1);
                            },
                            [&](std::vector<T>& v) {
                              solve_factored<T, W, 1>(lane, Apply::Adjoint, n, v.data(), 1);
                            });
                        rcond[first + l] =
                            norm > 0 && inverse_norm > 0 ? 1 / inverse_norm / norm : 0;
                      }
                    });
  return rcond;
}

namespace detail {

// 1 / (||A||_1 ||A^{-1}||_1) estimated from lane `lane` of a chunk's factors (?gtcon).
template <class T>
real_t<T> estimate_lane_rcond(const ChunkFactors<T>& lane, std::ptrdiff_t n, real_t<T> norm) {
  constexpr int W = kLanes<T>;
  const real_t<T> inverse_norm = estimate_norm1<T>(
      n, [&](std::vector<T>& v) { solve_factored<T, W, 1>(lane, Apply::Matrix, n, v.data(), 1); },
      [&](std::vector<T>& v) { solve_factored<T, W, 1>(lane, Apply::Adjoint, n, v.data(), 1); });
  return norm > 0 && inverse_norm > 0 ? 1 / inverse_norm / norm : 0;
}

// Systems refined side by side in mixed precision: 16 lanes, one AVX-512 vector of float
// corrections, and five n x 16 slabs of double that stay in the outer caches.
inline constexpr int kMixedLanes = 16;

// Mixed-precision refinement of V systems at once, one lane each: the double data gathered
// into lane-contiguous slabs (a, b, c, d, x), the corrections solved in F with the lanes of a
// factor chunk (stride kLanes<F>), the residuals computed across lanes.
template <class F, class T, int V>
struct MixedLanes {
  using R = real_t<T>;
  std::ptrdiff_t n;
  T *a, *b, *c, *d, *x;
  F* correction;
  T zero_row_[V] = {};  // x_{-1}, x_n and the entries outside the matrix

  MixedLanes(std::ptrdiff_t rows, T* slabs, F* corrections)
      : n(rows),
        a(slabs),
        b(slabs + rows * V),
        c(slabs + 2 * rows * V),
        d(slabs + 3 * rows * V),
        x(slabs + 4 * rows * V),
        correction(corrections) {}

  // Lanes past `count` are identity systems with rhs 0: solved exactly at once.
  void gather(const T* sub, const T* diag, const T* super, const T* rhs, const BatchLayout& layout,
              std::ptrdiff_t first, int count) {
    detail::gather<T, V>(sub, layout, first, count, T(0), a);
    detail::gather<T, V>(diag, layout, first, count, T(1), b);
    detail::gather<T, V>(super, layout, first, count, T(0), c);
    detail::gather<T, V>(rhs, layout, first, count, T(0), d);
  }

  // x = 0, then x += solve(round_F(d - A x)) until each lane's componentwise backward error
  // (?gtrfs's measure, of the x returned) is <= target or stops halving; then the lane is
  // frozen. backward[l] and iterations[l] report each lane.
  void refine(const ChunkFactors<F>& group, R target, int max_iterations, R* backward,
              int* iterations) {
    constexpr int W = kLanes<F>;
    const R safe1 = 4 * std::numeric_limits<R>::min();
    const R safe2 = safe1 / (std::numeric_limits<R>::epsilon() / 2);
    bool active[V];
    R previous[V], error[V];
    for (int l = 0; l < V; ++l) {
      active[l] = true;
      previous[l] = std::numeric_limits<R>::infinity();
      backward[l] = 1;  // of x = 0
      iterations[l] = 0;
    }
    for (std::ptrdiff_t k = 0; k < n * V; ++k) {
      x[k] = T(0);
      correction[k] = F(d[k]);
    }
    for (int step = 0; step < max_iterations; ++step) {
      // Frozen lanes have a zero correction column: their x stays as reported.
      solve_factored<F, W, V>(group, Apply::Matrix, n, correction, V);
      for (std::ptrdiff_t k = 0; k < n * V; ++k) x[k] += T(correction[k]);
      for (int l = 0; l < V; ++l) error[l] = 0;
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        // Rows 0 and n-1 read x_{-1} and x_n as zero times their own x: sub[0] and super[n-1]
        // are not read (they may hold anything).
        const T* xi = x + i * V;
        const T* left = i > 0 ? xi - V : zero_row_;
        const T* right = i + 1 < n ? xi + V : zero_row_;
        const T* ai = i > 0 ? a + i * V : zero_row_;
        const T* ci = i + 1 < n ? c + i * V : zero_row_;
        const T* bi = b + i * V;
        const T* di = d + i * V;
        F* ri = correction + i * V;
#pragma omp simd
        for (int l = 0; l < V; ++l) {
          const T res = di[l] - ai[l] * left[l] - bi[l] * xi[l] - ci[l] * right[l];
          const R scale = magnitude(di[l]) + magnitude(ai[l]) * magnitude(left[l]) +
                          magnitude(bi[l]) * magnitude(xi[l]) +
                          magnitude(ci[l]) * magnitude(right[l]);
          const R size = magnitude(res);
          // ?gtrfs's guard against scales that underflow; an exact row counts 0.
          const bool tiny = !(scale > safe2);
          const R ratio = (size + (tiny ? safe1 : R(0))) / (scale + (tiny ? safe1 : R(0)));
          const R counted = size == 0 ? R(0) : ratio;
          error[l] = error[l] > counted ? error[l] : counted;
          ri[l] = F(res);
        }
      }
      bool any = false;
      for (int l = 0; l < V; ++l) {
        if (!active[l]) continue;
        ++iterations[l];
        backward[l] = error[l];
        // Done, or stalled: each step of a convergent refinement gains a factor of about
        // cond(A) u_F, so a step that does not halve the error will not reach the target.
        active[l] = !(error[l] <= target) && error[l] <= previous[l] / 2;
        previous[l] = error[l];
        any = any || active[l];
        if (!active[l])
          for (std::ptrdiff_t i = 0; i < n; ++i) correction[i * V + l] = F(0);
      }
      if (!any) break;
    }
  }
};

}  // namespace detail

struct RefineOptions {
  Apply apply = Apply::Matrix;
  std::ptrdiff_t nrhs = 1;
  std::ptrdiff_t rhs_stride = 0;  // 0: layout.extent(); as FactoredSolveOptions
  int max_iterations = 5;         // ?gtrfs's ITMAX
  int threads = 0;
};

// Per system and right-hand side, at [s * nrhs + j].
template <class R>
struct RefineReport {
  std::vector<R> forward_error;   // bound on ||x - x_true||_inf / ||x||_inf
  std::vector<R> backward_error;  // smallest e with (A + E) x = b + f, |E| <= e|A|, |f| <= e|b|
  std::vector<int> iterations;    // corrections applied
};

// Improves the solutions x of op(A) x = rhs (from solve(factors, ...)) by iterative refinement,
// the residual accumulated in a wider type (double for float, long double for double), and
// returns forward and backward error bounds, as LAPACK ?gtrfs. sub, diag, super and rhs in
// `layout` as for solve; factors of the same matrix.
template <class T>
RefineReport<real_t<T>> refine(const T* sub, const T* diag, const T* super,
                               const TridiagonalFactors<T>& factors, const T* rhs, T* x,
                               const BatchLayout& layout, const RefineOptions& options = {}) {
  using namespace detail;
  using R = real_t<T>;
  constexpr int W = kLanes<T>;
  require_refine_arguments(factors, sub, diag, super, rhs, x, layout, false);
  const std::ptrdiff_t stride =
      rhs_stride_of({options.apply, options.nrhs, options.rhs_stride, 0}, layout);
  const std::ptrdiff_t n = layout.n, nrhs = options.nrhs;
  const R eps = std::numeric_limits<R>::epsilon() / 2;
  RefineReport<R> report;
  report.forward_error.resize(layout.count * nrhs);
  report.backward_error.resize(layout.count * nrhs);
  report.iterations.resize(layout.count * nrhs);
  for_each_chunk<T>(
      layout.count, W, resolve_threads(options.threads),
      [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<T>&) {
        const ChunkFactors<T> f = factors.chunk(first / W);
        std::vector<T> xs(n), bs(n), r(n);
        std::vector<R> scale(n);
        for (int l = 0; l < systems; ++l) {
          const std::ptrdiff_t s = first + l;
          const ChunkFactors<T> lane = lane_of<T, W>(f, l);
          const SystemView<T> view = system_view(sub, diag, super, rhs, layout, s, false);
          for (std::ptrdiff_t j = 0; j < nrhs; ++j) {
            const Strided<T> out{x + j * stride + layout.offset(s, 0), layout.row_stride};
            for (std::ptrdiff_t i = 0; i < n; ++i) {
              xs[i] = out[i];
              bs[i] = rhs[j * stride + layout.offset(s, i)];
            }
            R backward = 0, last = 3;
            int count = 0;
            for (;;) {
              residual<wider_t<T>>(view, options.apply, xs.data(), bs.data(), r.data(),
                                   scale.data());
              backward = componentwise_backward_error(r.data(), scale.data(), n);
              // ?gtrfs: go on while the error is above eps and at least halves each step.
              if (!(backward > eps && 2 * backward <= last && count < options.max_iterations))
                break;
              solve_lane(lane, options.apply, false, n, r.data());
              for (std::ptrdiff_t i = 0; i < n; ++i) xs[i] += r[i];
              last = backward;
              ++count;
            }
            const std::ptrdiff_t k = s * nrhs + j;
            report.backward_error[k] = backward;
            report.iterations[k] = count;
            report.forward_error[k] =
                forward_error_bound(lane, options.apply, n, xs.data(), r.data(), scale.data());
            for (std::ptrdiff_t i = 0; i < n; ++i) out[i] = xs[i];
          }
        }
      });
  return report;
}

// ---------------------------------------------------------------------------------------------
// Mixed precision

enum class MixedStatus : unsigned char {
  Converged,       // backward error <= MixedOptions::target_backward_error
  IllConditioned,  // the float factors' condition estimate exceeds 1 / u_float: refinement
                   // cannot converge; solve this system in double
  Stalled,         // neither: refinement stopped improving (badly scaled or nearly singular)
};

struct MixedOptions {
  int max_iterations = 10;
  // Componentwise backward error to reach, in units of double's machine epsilon.
  double target_epsilons = 4;
  int threads = 0;
};

struct MixedReport {
  std::vector<double> backward_error;  // per system: componentwise, of the returned x
  std::vector<int> iterations;         // float solves applied (the first included)
  std::vector<MixedStatus> status;
  std::vector<float> rcond;          // the float factors' estimate, for systems not converged
  std::ptrdiff_t not_converged = 0;  // systems whose status is not Converged
};

// Solves double (or complex double) systems with single-precision factors (from
// factor_as<float>(sub, diag, super, layout) of the same data): a float solve, then corrections
// from residuals computed in double, until the componentwise backward error reaches
// target_epsilons * eps_double. Converges when cond(A) u_float < 1; systems that do not
// converge keep their best x and are reported by status (never silently accepted).
template <class F, class T>
MixedReport solve_mixed(const TridiagonalFactors<F>& factors, const T* sub, const T* diag,
                        const T* super, const T* rhs, T* x, const BatchLayout& layout,
                        const MixedOptions& options = {}) {
  using namespace detail;
  using R = real_t<T>;
  static_assert(std::is_same_v<real_t<F>, float> && std::is_same_v<R, double> &&
                    is_complex_v<F> == is_complex_v<T>,
                "solve_mixed refines double data with float factors");
  constexpr int W = kLanes<F>;
  require_refine_arguments(factors, sub, diag, super, rhs, x, layout, true);
  const std::ptrdiff_t n = layout.n;
  const R target = R(options.target_epsilons) * std::numeric_limits<R>::epsilon();
  MixedReport report;
  report.backward_error.resize(layout.count);
  report.iterations.resize(layout.count);
  report.status.resize(layout.count);
  report.rcond.assign(layout.count, -1.0f);
  constexpr int V = kMixedLanes;
  for_each_chunk<F>(layout.count, W, resolve_threads(options.threads),
                    [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<F>&) {
                      const ChunkFactors<F> f = factors.chunk(first / W);
                      static thread_local AlignedBuffer<T> slabs;
                      static thread_local AlignedBuffer<F> corrections;
                      slabs.resize(5 * n * V);
                      corrections.resize(n * V);
                      MixedLanes<F, T, V> lanes{n, slabs.data(), corrections.data()};
                      for (int group = 0; group * V < systems; ++group) {
                        const std::ptrdiff_t s0 = first + group * V;
                        const int count = int(std::min<std::ptrdiff_t>(V, systems - group * V));
                        lanes.gather(sub, diag, super, rhs, layout, s0, count);
                        R backward[V];
                        int iterations[V];
                        lanes.refine(lane_of<F, W>(f, group * V), target, options.max_iterations,
                                     backward, iterations);
                        scatter<T, V>(lanes.x, layout, s0, count, x);
                        for (int l = 0; l < count; ++l) {
                          const std::ptrdiff_t s = s0 + l;
                          report.backward_error[s] = backward[l];
                          report.iterations[s] = iterations[l];
                          report.status[s] = MixedStatus::Converged;
                          if (backward[l] > target) {
                            report.rcond[s] = estimate_lane_rcond(lane_of<F, W>(f, group * V + l),
                                                                  n, factors.norm1(s));
                            report.status[s] =
                                report.rcond[s] < std::numeric_limits<float>::epsilon() / 2
                                    ? MixedStatus::IllConditioned
                                    : MixedStatus::Stalled;
                          }
                        }
                      }
                    });
  report.not_converged = std::count_if(report.status.begin(), report.status.end(),
                                       [](MixedStatus s) { return s != MixedStatus::Converged; });
  return report;
}

// Factors in single precision and solves as above: one call for double data whose
// coefficients lie within float's range (NumericalError otherwise, from the factorization).
template <class T>
MixedReport solve_mixed(const T* sub, const T* diag, const T* super, const T* rhs, T* x,
                        const BatchLayout& layout, const MixedOptions& options = {}) {
  using F = std::conditional_t<is_complex_v<T>, std::complex<float>, float>;
  FactorOptions factor_options;
  factor_options.threads = options.threads;
  return solve_mixed(factor_as<F>(sub, diag, super, layout, factor_options), sub, diag, super, rhs,
                     x, layout, options);
}

}  // namespace tridiff
