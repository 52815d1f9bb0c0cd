// The one entry point of the tridiagonal solvers: batches of systems in any strided layout,
// in the general form (three diagonals) or the diffusion form (beta only), any method.
#pragma once

#include <algorithm>
#include <array>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <limits>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "tridiff/solvers/detail/checks.hpp"
#include "tridiff/solvers/detail/cyclic_reduction.hpp"
#include "tridiff/solvers/detail/diffusion_form.hpp"
#include "tridiff/solvers/detail/partitioned_diffusion.hpp"
#include "tridiff/solvers/detail/partitioned_lanes.hpp"
#include "tridiff/solvers/detail/periodic.hpp"
#include "tridiff/solvers/detail/pivoting.hpp"
#include "tridiff/solvers/detail/subnormals.hpp"
#include "tridiff/solvers/detail/thomas.hpp"
#include "tridiff/solvers/detail/workspace.hpp"
#include "tridiff/solvers/error.hpp"
#include "tridiff/solvers/layout.hpp"
#include "tridiff/threads.hpp"

namespace tridiff {

enum class Method {
  Auto,                     // pivoting where pivot-free is unsafe, otherwise the fastest
  Thomas,                   // elimination without pivoting; batches run one SIMD lane per system
  CyclicReduction,          // odd-even reduction (seed 000 §3.5.3), any n
  ParallelCyclicReduction,  // every row reduced at once, log2(n) steps
  Hybrid,                   // CR down to a small system, finished by PCR
  Pivoting,                 // partial pivoting, the algorithm of LAPACK ?gtsv
};

namespace detail {

// One system by a method's scalar kernel (detail/): the arguments every kernel takes, and
// pcr_below, which only the reductions read. Returns -1, or the row where the numbers broke
// down. `work` holds MethodRow::workspace(n) scalars.
template <class T>
using Kernel = std::ptrdiff_t (*)(std::ptrdiff_t n, Strided<const T> a, Strided<const T> b,
                                  Strided<const T> c, Strided<const T> d, Strided<T> x, T* work,
                                  std::ptrdiff_t pcr_below);

// A method's kernel for each scalar type the solvers take.
struct KernelSet {
  Kernel<float> for_float = nullptr;
  Kernel<double> for_double = nullptr;
  Kernel<std::complex<float>> for_complex_float = nullptr;
  Kernel<std::complex<double>> for_complex_double = nullptr;

  template <class T>
  constexpr Kernel<T> get() const {
    if constexpr (std::is_same_v<T, float>)
      return for_float;
    else if constexpr (std::is_same_v<T, double>)
      return for_double;
    else if constexpr (std::is_same_v<T, std::complex<float>>)
      return for_complex_float;
    else
      return for_complex_double;
  }
  constexpr bool complete() const {
    return for_float && for_double && for_complex_float && for_complex_double;
  }
};

// The KernelSet of a kernel written once for every type: a generic lambda with Kernel's
// parameters, instantiated for each.
template <class Solve>
constexpr KernelSet kernel_set(Solve solve) {
  return {solve, solve, solve, solve};
}

}  // namespace detail

// The solver methods, one row each: the name the command line, the benchmarks and the error
// messages use, whether the method pivots, what it is, and how it runs: its kernel, its
// workspace, and whether it is a reduction (its bound and its cancellation check). Everything
// that dispatches on a method reads this table (to_string, method_named, kAllMethods,
// detail::solve_one, the benchmarks' names and shapes, the tests' bounds and method lists):
// adding a method is its kernel header (detail/), its name in Method, and one row here.
struct MethodRow {
  Method method;
  const char* name;
  bool pivot_free;  // stable only for diagonally dominant matrices (SolveOptions::check_dominance)
  const char* summary;
  detail::KernelSet kernels = {};                           // none for Auto: it picks another row's
  std::ptrdiff_t (*workspace)(std::ptrdiff_t n) = nullptr;  // scalars the kernel needs
  // A reduction (the cyclic-reduction family): each row passes through log2(n) levels of
  // updates, so its backward-error bound carries that factor (reduction_backward_bound; the
  // tests' and the README's bounds read it), and every answer is checked against it: each
  // level passes the vanishing-pivot test while cancellation builds up over the levels (PCR
  // on gallery('dorr', 512, 1e-4), dominant, returned x with a backward error of 0.5).
  bool reduction = false;
};

inline constexpr MethodRow kMethodTable[] = {
    {.method = Method::Auto,
     .name = "auto",
     .pivot_free = false,
     .summary = "Thomas (SIMD lanes) for diagonally dominant systems, pivoting for the rest"},
    {.method = Method::Thomas,
     .name = "thomas",
     .pivot_free = true,
     .summary = "elimination without pivoting; batches run one SIMD lane per system",
     .kernels =
         detail::kernel_set([](std::ptrdiff_t n, auto a, auto b, auto c, auto d, auto x, auto* work,
                               std::ptrdiff_t) { return detail::thomas(n, a, b, c, d, x, work); }),
     .workspace = detail::thomas_workspace},
    {.method = Method::CyclicReduction,
     .name = "cr",
     .pivot_free = true,
     .summary = "odd-even cyclic reduction (seed 000 §3.5.3), any n",
     .kernels = detail::kernel_set(
         [](std::ptrdiff_t n, auto a, auto b, auto c, auto d, auto x, auto* work, std::ptrdiff_t) {
           return detail::cyclic_reduction(n, a, b, c, d, x, work, 1);
         }),
     .workspace = detail::cyclic_reduction_workspace,
     .reduction = true},
    {.method = Method::ParallelCyclicReduction,
     .name = "pcr",
     .pivot_free = true,
     .summary = "parallel cyclic reduction: every row reduced at once, log2(n) steps",
     .kernels = detail::kernel_set(
         [](std::ptrdiff_t n, auto a, auto b, auto c, auto d, auto x, auto* work, std::ptrdiff_t) {
           return detail::cyclic_reduction(n, a, b, c, d, x, work, n);
         }),
     .workspace = detail::cyclic_reduction_workspace,
     .reduction = true},
    {.method = Method::Hybrid,
     .name = "cr-pcr",
     .pivot_free = true,
     .summary = "cyclic reduction down to hybrid_pcr_below rows, finished by PCR",
     .kernels = detail::kernel_set([](std::ptrdiff_t n, auto a, auto b, auto c, auto d, auto x,
                                      auto* work, std::ptrdiff_t pcr_below) {
       return detail::cyclic_reduction(n, a, b, c, d, x, work, pcr_below);
     }),
     .workspace = detail::cyclic_reduction_workspace,
     .reduction = true},
    {.method = Method::Pivoting,
     .name = "pivoting",
     .pivot_free = false,
     .summary = "partial pivoting, the algorithm of LAPACK ?gtsv",
     .kernels = detail::kernel_set(
         [](std::ptrdiff_t n, auto a, auto b, auto c, auto d, auto x, auto* work, std::ptrdiff_t) {
           return detail::pivoting(n, a, b, c, d, x, work);
         }),
     .workspace = detail::pivoting_workspace},
};

inline constexpr auto kAllMethods = [] {
  std::array<Method, std::size(kMethodTable)> methods{};
  for (std::size_t i = 0; i < methods.size(); ++i) methods[i] = kMethodTable[i].method;
  return methods;
}();

inline const MethodRow& method_row(Method method) {
  for (const MethodRow& row : kMethodTable)
    if (row.method == method) return row;
  throw InvalidArgument("method",
                        "is not a Method (" + std::to_string(static_cast<int>(method)) + ")");
}

inline const char* to_string(Method method) {
  for (const MethodRow& row : kMethodTable)
    if (row.method == method) return row.name;
  return "unknown";  // for messages about a bad value: never throws
}

inline bool is_pivot_free(Method method) { return method_row(method).pivot_free; }

// The method called `name` ("thomas", "cr-pcr", ...); InvalidArgument listing the names otherwise.
inline Method method_named(std::string_view name) {
  std::string known;
  for (const MethodRow& row : kMethodTable) {
    if (row.name == name) return row.method;
    known += (known.empty() ? "" : ", ") + std::string(row.name);
  }
  throw InvalidArgument("method",
                        "unknown solver method '" + std::string(name) + "' (known: " + known + ")");
}

struct SolveOptions {
  Method method = Method::Auto;
  int threads = 0;        // 0: all cores; at most kMaxThreads (tridiff/threads.hpp)
  bool periodic = false;  // sub[0] is entry (0, n-1) and super[n-1] entry (n-1, 0)
  // The pivot-free methods are stable only for diagonally dominant matrices (by rows or by
  // columns). With this set they refuse other matrices (NumericalError naming system and row);
  // clear it to skip the check when dominance is known, e.g. built into the problem.
  bool check_dominance = true;
  std::ptrdiff_t hybrid_pcr_below = 32;  // Hybrid: rows left when CR hands over to PCR
  // Status per system instead of an exception, as LAPACK's INFO (and Kokkos' batched solvers):
  // when given, `info` has one entry per system of the batch and the call throws no error for
  // a single system; it writes info[s] = 0 for a solved system s, and for a system it could
  // not solve (its x left unspecified, its rhs as it was in an in-place solve)
  //   k > 0: the numbers broke down at row k - 1 (k is 1-based, as LAPACK's): a zero or
  //          vanishing pivot, an overflowing solution, a matrix the chosen pivot-free method
  //          refuses (not diagonally dominant) or whose answer failed the backward-error check;
  //   k < 0: an input of the system is wrong (kInfoBadSub ... kInfoBadBeta below: a non-finite
  //          coefficient or rhs, a negative beta).
  // Every other system is solved. Errors of the call as a whole (a null pointer, a bad layout,
  // an unknown method, an `info` of the wrong size) still throw InvalidArgument.
  std::span<std::ptrdiff_t> info = {};
};

// The codes of SolveOptions::info for a system with a wrong input, after LAPACK's "-i: the
// i-th argument had an illegal value" (the row is in what() of the error the call would throw
// without `info`).
inline constexpr std::ptrdiff_t kInfoBadSub = -1;    // sub (a coefficient not finite)
inline constexpr std::ptrdiff_t kInfoBadDiag = -2;   // diag
inline constexpr std::ptrdiff_t kInfoBadSuper = -3;  // super
inline constexpr std::ptrdiff_t kInfoBadRhs = -4;    // rhs
inline constexpr std::ptrdiff_t kInfoBadBeta = -5;   // beta (not finite, or negative)

struct SolveReport {
  Method method = Method::Auto;        // the method that solved the dominant systems
  std::ptrdiff_t pivoted_systems = 0;  // systems Auto solved by pivoting (not dominant, or
                                       // Thomas broke down on them)
  int parts = 1;                       // parts of a single long system solved in parallel
  std::ptrdiff_t failed_systems = 0;   // systems not solved (non-zero only with options.info)
};

namespace detail {

// Systems solved side by side in the lane kernels: four 64-byte vectors of scalars, enough
// independent work per row to hide the latency of the division chain, and 256 contiguous
// bytes per row of an image column, enough for the prefetchers. (Measured on 4096 x 4096
// float, 2 threads, AMD EPYC Zen 5: 16 lanes 3x slower on columns, 128 lanes 1.5x slower.)
template <class T>
inline constexpr int kLanes = static_cast<int>(256 / sizeof(T));

// A chunk with few systems (a single system, the tail of a batch) is solved one system at a
// time: padding lanes would cost more than the vectors gain.
template <class T>
inline bool fills_lanes(std::ptrdiff_t systems) {
  return 4 * systems >= kLanes<T>;
}

template <class T>
void require_pointer(const T* p, const char* name) {
  if (p == nullptr) throw InvalidArgument(name, "is a null pointer");
}

// The output may coincide with `input` (in place) but must not otherwise share memory with it.
template <class In, class Out>
void require_disjoint(const In* input, const char* input_name, const Out* output,
                      const BatchLayout& layout, bool may_alias) {
  const auto begin_in = reinterpret_cast<std::uintptr_t>(input);
  const auto begin_out = reinterpret_cast<std::uintptr_t>(output);
  if (may_alias && begin_in == begin_out) return;
  const auto end_in = begin_in + static_cast<std::uintptr_t>(layout.extent()) * sizeof(In);
  const auto end_out = begin_out + static_cast<std::uintptr_t>(layout.extent()) * sizeof(Out);
  if (begin_in < end_out && begin_out < end_in)
    throw InvalidArgument("x",
                          std::string("overlaps '") + input_name +
                              "' (only rhs may be the same array as x, for an in-place solve)");
}

// Per-thread scratch, kept between calls (like BLAS buffers) so batches of small calls do
// not pay for allocation and page faults; released after a call that needed more than 64 MiB.
template <class T>
struct Scratch {
  AlignedBuffer<T> work, slab;
  AlignedBuffer<real_t<T>> real_work;
  static constexpr std::ptrdiff_t kKeepBytes = std::ptrdiff_t(64) << 20;
  void trim() {
    if ((work.size() + slab.size()) * std::ptrdiff_t(sizeof(T)) +
            real_work.size() * std::ptrdiff_t(sizeof(real_t<T>)) >
        kKeepBytes)
      *this = Scratch{};
  }
};

template <class T>
Scratch<T>& thread_scratch() {
  static thread_local Scratch<T> scratch;
  return scratch;
}

// Runs body(first_system, systems, scratch) over chunks of the batch on `threads` threads.
// A chunk never crosses from one outer batch to the next, so within it systems are
// system_stride apart, as the lane kernels assume. Every chunk runs even when one throws; the
// exception of the lowest chunk is rethrown after the loop, so errors are deterministic.
template <class T, class Body>
void for_each_chunk(const BatchLayout& layout, std::ptrdiff_t chunk, int threads, Body&& body) {
  const std::ptrdiff_t count = layout.count;
  const std::ptrdiff_t per_batch = (count + chunk - 1) / chunk;
  const std::ptrdiff_t chunks = per_batch * layout.outer_count;
  std::exception_ptr error;
  std::ptrdiff_t error_chunk = std::numeric_limits<std::ptrdiff_t>::max();
  std::mutex guard;
  auto run = [&](std::ptrdiff_t k, Scratch<T>& scratch) {
    const std::ptrdiff_t batch = k / per_batch, first = (k % per_batch) * chunk;
    try {
      body(batch * count + first, std::min(chunk, count - first), scratch);
    } catch (...) {
      std::lock_guard<std::mutex> lock(guard);
      if (k < error_chunk) {
        error_chunk = k;
        error = std::current_exception();
      }
    }
  };
  const int team = static_cast<int>(std::min<std::ptrdiff_t>(threads, chunks));
  if (team <= 1) {
    // No OpenMP region for one thread: entering one, even with if(false), costs a futex round
    // trip in libgomp, several microseconds, more than a small system's solve (measured from
    // Python on 8 unknowns, shared 2-core machine: 24 us a call with the region, 3.8 without).
    Scratch<T>& scratch = thread_scratch<T>();
    for (std::ptrdiff_t k = 0; k < chunks; ++k) run(k, scratch);
    scratch.trim();
  } else {
#pragma omp parallel num_threads(team)
    {
      Scratch<T>& scratch = thread_scratch<T>();
#pragma omp for schedule(static)
      for (std::ptrdiff_t k = 0; k < chunks; ++k) run(k, scratch);
      scratch.trim();
    }
  }
  if (error) std::rethrow_exception(error);
}

// for_each_chunk over `count` systems in one batch dimension.
template <class T, class Body>
void for_each_chunk(std::ptrdiff_t count, std::ptrdiff_t chunk, int threads, Body&& body) {
  BatchLayout systems;
  systems.count = count;
  for_each_chunk<T>(systems, chunk, threads, std::forward<Body>(body));
}

// The SolveOptions::info code of a system whose solve threw `error`.
inline std::ptrdiff_t info_code(const std::exception_ptr& error, std::ptrdiff_t n) {
  try {
    std::rethrow_exception(error);
  } catch (const InvalidArgument& e) {
    const std::string& name = e.argument();
    return name == "sub"     ? kInfoBadSub
           : name == "diag"  ? kInfoBadDiag
           : name == "super" ? kInfoBadSuper
           : name == "beta"  ? kInfoBadBeta
                             : kInfoBadRhs;
  } catch (const NumericalError& e) {
    return e.row() >= 0 ? e.row() + 1 : n;
  }
}

// The outcome of every system of one call. A system that fails is recorded and the others go
// on: with SolveOptions::info its code is written there, otherwise finish() throws the error
// of the lowest failing system, naming the others. Errors that are not tridiff::Error (out of
// memory) are not a system's fault and propagate at once.
class BatchStatus {
 public:
  BatchStatus(std::span<std::ptrdiff_t> info, const BatchLayout& layout)
      : info_(info), n_(layout.n), count_(layout.systems()) {
    if (!info.empty() && std::ptrdiff_t(info.size()) != layout.systems())
      throw InvalidArgument("info", "has " + std::to_string(info.size()) +
                                        " entries for a batch of " +
                                        std::to_string(layout.systems()) + " systems");
    std::fill(info.begin(), info.end(), 0);
  }

  // Runs solve() for system s, recording the tridiff::Error it throws against s.
  template <class Solve>
  void run(std::ptrdiff_t s, Solve&& solve) {
    try {
      solve();
    } catch (const Error&) {
      record(s, std::current_exception());
    }
  }

  // After the batch: the number of failed systems, or, without info, the first one's error.
  std::ptrdiff_t finish() {
    if (failed_.empty() || !info_.empty()) return std::ptrdiff_t(failed_.size());
    std::sort(failed_.begin(), failed_.end());
    const auto total = std::ptrdiff_t(failed_.size());
    const auto listed = std::min<std::size_t>(failed_.size(), Error::kListedFailures);
    std::vector<std::ptrdiff_t> first(failed_.begin(), failed_.begin() + listed);
    std::string others;
    if (total > 1) {
      others = " (" + std::to_string(total) + " of " + std::to_string(count_) + " systems failed: ";
      for (std::size_t k = 0; k < listed; ++k) others += (k ? ", " : "") + std::to_string(first[k]);
      others += std::string(total > std::ptrdiff_t(listed) ? ", ..." : "") +
                "; every other system is solved)";
    }
    try {
      std::rethrow_exception(first_);
    } catch (const InvalidArgument& e) {
      InvalidArgument named(e.argument(), e.system(), e.row(), e.message() + others);
      named.set_failures(std::move(first), total);
      throw named;
    } catch (const NumericalError& e) {
      NumericalError named(e.system(), e.row(), e.message() + others);
      named.set_failures(std::move(first), total);
      throw named;
    }
  }

 private:
  void record(std::ptrdiff_t s, std::exception_ptr error) {
    if (!info_.empty()) info_[s] = info_code(error, n_);  // one thread per system: no race
    std::lock_guard<std::mutex> lock(guard_);
    failed_.push_back(s);
    if (s < first_system_) {
      first_system_ = s;
      first_ = std::move(error);
    }
  }

  std::span<std::ptrdiff_t> info_;
  std::ptrdiff_t n_, count_;
  std::mutex guard_;
  std::vector<std::ptrdiff_t> failed_;
  std::exception_ptr first_;
  std::ptrdiff_t first_system_ = std::numeric_limits<std::ptrdiff_t>::max();
};

template <class T>
SystemView<T> system_view(const T* a, const T* b, const T* c, const T* d, const BatchLayout& layout,
                          std::ptrdiff_t s, bool periodic) {
  const std::ptrdiff_t o = layout.offset(s, 0), rs = layout.row_stride;
  return {{a + o, rs}, {b + o, rs}, {c + o, rs}, {d + o, rs}, layout.n, periodic};
}

inline std::string scientific(long double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2Le", value);
  return text;
}

// The normwise backward error the reduction methods promise (README, "Methods"):
// 16u (1 + ceil(log2(n + 1))), one round of updates per level; 16u = 8 eps.
template <class T>
real_t<T> reduction_backward_bound(std::ptrdiff_t n) {
  int levels = 0;
  while ((std::ptrdiff_t(1) << levels) < n + 1) ++levels;
  return 8 * epsilon<T> * real_t<T>(1 + levels);
}

// Solves one system with one non-Auto method (its row's kernel); throws on breakdown.
template <class T>
void solve_one(const SystemView<T>& s, Strided<T> x, Method method, bool periodic,
               std::ptrdiff_t pcr_below, AlignedBuffer<T>& work, std::ptrdiff_t system) {
  const MethodRow& row = method_row(method);
  const Kernel<T> kernel = row.kernels.template get<T>();
  if (!kernel) throw InvalidArgument("method", std::string(row.name) + " has no kernel of its own");
  auto inner = [&](std::ptrdiff_t n, Strided<const T> a, Strided<const T> b, Strided<const T> c,
                   Strided<const T> d, Strided<T> out,
                   T* w) { return kernel(n, a, b, c, d, out, w, pcr_below); };
  const std::ptrdiff_t n = s.n;
  // Inputs are checked up front: pivoting and the reductions can turn an infinite coefficient
  // into a finite, meaningless answer, and a NaN in rhs is named here rather than after it has
  // spread. A small cost next to these scalar kernels.
  require_finite_matrix(s, system);
  require_finite_rhs(s, system);
  const std::ptrdiff_t inner_work = row.workspace(n);
  // The solution is built in the workspace and copied out only on success, so a failed
  // in-place solve leaves rhs as it was.
  work.resize(2 * n + (periodic ? periodic_workspace(n, inner_work) : inner_work));
  T* result = work.data();
  T* scaled_rhs = result + n;
  T* kernel_work = scaled_rhs + n;
  const std::ptrdiff_t bad =
      solve_rescaling_on_overflow(n, s.d, result, scaled_rhs, [&](Strided<const T> d, T* out) {
        return periodic
                   ? detail::periodic(n, s.a, s.b, s.c, d, Strided<T>{out, 1}, kernel_work, inner)
                   : inner(n, s.a, s.b, s.c, d, Strided<T>{out, 1}, kernel_work);
      });
  if (bad >= 0) report_breakdown(s, system, bad, to_string(method));
  require_finite_solution(result, n, system, to_string(method));
  if (row.reduction) {
    // Every level of a reduction passes the vanishing-pivot test, yet cancellation can build
    // up over the levels (MethodRow::reduction). One pass, less than a level.
    const BackwardError error = backward_error(s, Strided<const T>{result, 1});
    const long double bound = reduction_backward_bound<T>(n);
    if (!(error.value <= bound))
      throw NumericalError(system, error.row,
                           std::string("cancellation in ") + to_string(method) +
                               ": the normwise backward error of its answer, " +
                               scientific(error.value) + ", exceeds the method's bound " +
                               scientific(bound) +
                               " (largest residual at this row); Thomas, CR or Pivoting may "
                               "solve it");
  }
  for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = result[i];
}

// Throws unless the matrix may go to a pivot-free method: for non-finite coefficients always,
// and for a matrix that is not diagonally dominant when `refuse` is set. Returns whether it
// is dominant.
template <class T>
bool accept_dominance(const Dominance& d, std::ptrdiff_t system, Method method, bool refuse) {
  if (!d.holds() && refuse)
    throw NumericalError(system, d.first_row_failure,
                         std::string("the matrix is not diagonally dominant, so ") +
                             to_string(method) +
                             " (no pivoting) is unsafe; use Method::Pivoting or Method::Auto");
  return d.holds();
}

// Classifies one system for the pivot-free methods; see accept_dominance.
template <class T>
bool check_system(const SystemView<T>& s, std::ptrdiff_t system, Method method, bool refuse) {
  require_finite_matrix(s, system);
  return accept_dominance<T>(dominance(s, 0, s.n), system, method, refuse);
}

// check_system for one long system, its rows split over `threads`.
template <class T>
bool check_system_parallel(const SystemView<T>& s, std::ptrdiff_t system, Method method,
                           bool refuse, int threads) {
  std::vector<Dominance> parts(threads);
  std::vector<std::exception_ptr> errors(threads);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int p = 0; p < threads; ++p) {
    const std::ptrdiff_t begin = s.n * p / threads, end = s.n * (p + 1) / threads;
    try {
      require_finite_matrix(s, system, begin, end);
      parts[p] = dominance(s, begin, end);
    } catch (...) {
      errors[p] = std::current_exception();
    }
  }
  Dominance whole;
  for (int p = 0; p < threads; ++p) {
    if (errors[p]) std::rethrow_exception(errors[p]);
    whole.merge(parts[p]);
  }
  return accept_dominance<T>(whole, system, method, refuse);
}

// From this many rows on, one system is solved by parts in SIMD lanes (on any number of
// threads) rather than by one scalar Thomas sweep: the parts read the arrays twice, but with
// the division chain spread over the lanes they run several times faster.
inline constexpr std::ptrdiff_t kPartitionedMinRows = std::ptrdiff_t(1) << 15;

// Thomas on one long system, cut into parts that run side by side in SIMD lanes, groups of
// parts shared by the threads (detail/partitioned_lanes.hpp). With `check`, the matrix is
// tested in the same pass; if that test does not pass, the exact one (check_system_parallel)
// decides: it throws (non-finite, or not dominant and `method` refuses that), returns false
// (Auto: pivot), or accepts what the conservative fused test did not, and the parts run
// unchecked. Returns the number of parts; 0 if a pivot vanished or the solution overflowed
// (rhs is then untouched: the caller re-solves by a method that names the row, or pivots); -1
// if Auto must pivot (not dominant).
template <class T>
std::ptrdiff_t solve_partitioned(const SystemView<T>& s, Strided<T> x, Method method, bool check,
                                 int threads) {
  PartOutcome outcome = partitioned_lanes(s, x, threads, check);
  if (outcome == PartOutcome::NotChecked) {
    if (!check_system_parallel(s, 0, method, method != Method::Auto, threads)) return -1;
    outcome = partitioned_lanes(s, x, threads, false);
  }
  if (outcome != PartOutcome::Solved) return 0;
  return make_part_layout<T, kPartLanes<T>>(s.n, threads).parts;
}

// Pivoting on one system, without the batch path's copies: the result goes straight into x
// unless the solve is in place, and the inputs are checked for finite values by vectorised
// passes. Throws like solve_one.
template <class T>
void solve_single_pivoting(const SystemView<T>& s, Strided<T> x, std::ptrdiff_t system) {
  using R = real_t<T>;
  const std::ptrdiff_t n = s.n;
  require_finite_matrix(s, system);
  R probe = 0;
  if (s.d.stride == 1) {
    const T* d = s.d.data;
#pragma omp simd reduction(+ : probe)
    for (std::ptrdiff_t i = 0; i < n; ++i) probe += magnitude(d[i]) * 0;
  }
  if (!(probe == 0) || s.d.stride != 1) require_finite_rhs(s, system);
  const bool in_place = x.data == s.d.data;
  static thread_local AlignedBuffer<T> work;
  work.resize(pivoting_workspace(n) + (in_place ? n : 0));
  const Strided<T> result = in_place ? Strided<T>{work.data() + pivoting_workspace(n), 1} : x;
  const std::ptrdiff_t bad = pivoting(n, s.a, s.b, s.c, s.d, result, work.data());
  if (bad >= 0) report_breakdown(s, system, bad, to_string(Method::Pivoting));
  probe = 0;
  if (result.stride == 1) {
    const T* values = result.data;
#pragma omp simd reduction(+ : probe)
    for (std::ptrdiff_t i = 0; i < n; ++i) probe += magnitude(values[i]) * 0;
  } else {
    for (std::ptrdiff_t i = 0; i < n; ++i) probe += magnitude(result[i]) * 0;
  }
  if (!(probe == 0)) report_breakdown(s, system, -1, to_string(Method::Pivoting));
  if (in_place)
    for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = result[i];
  if (work.size() * std::ptrdiff_t(sizeof(T)) > (std::ptrdiff_t(256) << 20)) work = {};
}

// One long system (count == 1, not periodic) by Thomas, Auto or Pivoting. Thomas and Auto run
// the parts in lanes on dominant matrices; where that breaks down, Thomas re-solves with the
// scalar kernel (which solves it or names the row) and Auto pivots.
template <class T>
SolveReport solve_single(const SystemView<T>& view, Strided<T> x, Method method, bool check,
                         int threads) {
  const SubnormalsKept gradual_underflow;  // see subnormals.hpp
  const Method fast = method == Method::Auto ? Method::Thomas : method;
  if (fast == Method::Thomas) {
    const std::ptrdiff_t parts = solve_partitioned(view, x, method, check, threads);
    if (parts > 0) return {fast, 0, static_cast<int>(parts)};
    if (parts == 0 && method == Method::Thomas) {
      AlignedBuffer<T> work;
      solve_one(view, x, Method::Thomas, false, 0, work, 0);
      return {fast, 0, 1};
    }
  }
  solve_single_pivoting(view, x, 0);
  return {fast, method == Method::Auto ? 1 : 0, 1};
}

// Thomas on a chunk of up to W systems, one SIMD lane each. Interleaved systems (image
// columns) are solved where they lie; other layouts, partial chunks and in-place solves go
// through a lane-contiguous slab, so that a failed in-place solve leaves rhs intact. (Full
// chunks of image rows go to solve_rows instead.)
// With `check`, the lanes are also checked for finite, dominant matrices, in the sweep. Returns
// false if some lane failed the check or broke down: the caller then goes system by system.
template <class T>
bool solve_lanes(const T* a, const T* b, const T* c, const T* d, T* x, const BatchLayout& layout,
                 std::ptrdiff_t first, std::ptrdiff_t systems, bool check, Scratch<T>& scratch) {
  constexpr int W = kLanes<T>;
  const std::ptrdiff_t n = layout.n, o = layout.offset(first, 0);
  const auto solve = check ? thomas_lanes<T, W, true> : thomas_lanes<T, W, false>;
  if (layout.system_stride == 1 && systems == W && x != d) {
    scratch.work.resize(n * W);
    return solve(n, a + o, b + o, c + o, d + o, x + o, layout.row_stride, scratch.work.data());
  }
  scratch.slab.resize(6 * n * W);
  T* sa = scratch.slab.data();
  T* sb = sa + n * W;
  T* sc = sb + n * W;
  T* sd = sc + n * W;
  T* sw = sd + n * W;
  const int lanes = static_cast<int>(systems);
  gather<T, W>(a, layout, first, lanes, T(0), sa);
  gather<T, W>(b, layout, first, lanes, T(1), sb);
  gather<T, W>(c, layout, first, lanes, T(0), sc);
  gather<T, W>(d, layout, first, lanes, T(0), sd);
  if (!solve(n, sa, sb, sc, sd, sd, W, sw)) return false;
  scatter<T, W>(sd, layout, first, lanes, x);
  return true;
}

// Lanes per thomas_rows call: one 512-bit vector. The rows kernel reads its W rows of all four
// arrays side by side, and 4 x W streams are what the prefetchers and DRAM pages serve well
// only for small W; its per-lane state (nine values) also stays in registers.
template <class T>
inline constexpr int kRowLanes = static_cast<int>(64 / sizeof(T));

// Thomas on kRowLanes contiguous systems (image rows) from `first`; false if a lane failed,
// with x untouched.
template <class T>
bool solve_rows(const T* a, const T* b, const T* c, const T* d, T* x, const BatchLayout& layout,
                std::ptrdiff_t first, bool check, Scratch<T>& scratch) {
  constexpr int V = kRowLanes<T>;
  const std::ptrdiff_t n = layout.n, o = layout.offset(first, 0);
  scratch.work.resize(thomas_rows_workspace<T>(n, V));
  return check ? thomas_rows<T, V, true>(n, a + o, b + o, c + o, d + o, x + o, layout.system_stride,
                                         scratch.work.data())
               : thomas_rows<T, V, false>(n, a + o, b + o, c + o, d + o, x + o,
                                          layout.system_stride, scratch.work.data());
}

// The diffusion-form counterpart of solve_lanes. Returns how many of the systems from `first`
// it solved: all, or those before the group whose lane failed (x of the others untouched).
template <class T>
std::ptrdiff_t solve_diffusion_lanes(const real_t<T>* beta, const T* d, T* x,
                                     const BatchLayout& layout, std::ptrdiff_t first,
                                     std::ptrdiff_t systems, Scratch<T>& scratch) {
  using R = real_t<T>;
  constexpr int W = kLanes<T>;
  const std::ptrdiff_t n = layout.n, o = layout.offset(first, 0);
  const std::ptrdiff_t work_size = diffusion_lanes_workspace<T>(n, W);
  scratch.real_work.resize(
      std::max(work_size + n * W, diffusion_rows_workspace<T>(n, kRowLanes<T>)));
  R* work = scratch.real_work.data();
  if (layout.system_stride == 1 && systems == W)  // image columns: lanes in place
    return diffusion_thomas_lanes<T, W>(n, beta + o, d + o, x + o, layout.row_stride, work) ? W : 0;
  if (layout.row_stride == 1 && systems == W) {
    // Image rows, transposed block by block, kRowLanes at a time: with W = kLanes the kept
    // multipliers and the staging copy of 4096-row systems (4 MiB in float) left L2, and
    // 4096 x 4096 floats took 1.25x as long (41.7 -> 33.8 ms on 1 thread).
    constexpr int V = kRowLanes<T>;
    const std::ptrdiff_t stride = layout.system_stride;
    for (int g = 0; g < W; g += V)
      if (!diffusion_thomas_rows<T, V>(n, beta + o + g * stride, d + o + g * stride,
                                       x + o + g * stride, stride, work))
        return g;
    return W;
  }
  scratch.slab.resize(n * W);
  T* sd = scratch.slab.data();
  R* sbeta = work + work_size;
  const int lanes = static_cast<int>(systems);
  gather<R, W>(beta, layout, first, lanes, R(0), sbeta);
  gather<T, W>(d, layout, first, lanes, T(0), sd);
  if (!diffusion_thomas_lanes<T, W>(n, sbeta, sd, sd, W, work)) return 0;
  scatter<T, W>(sd, layout, first, lanes, x);
  return systems;
}

template <class R>
void require_valid_beta(Strided<const R> beta, std::ptrdiff_t n, bool periodic,
                        std::ptrdiff_t system) {
  const std::ptrdiff_t links = periodic ? n : n - 1;
  for (std::ptrdiff_t i = 0; i < links; ++i) {
    if (!std::isfinite(beta[i])) throw InvalidArgument("beta", system, i, "is not finite");
    if (beta[i] < 0)
      throw InvalidArgument(
          "beta", system, i,
          "is negative (" + std::to_string(beta[i]) + "): a conductance must be >= 0");
  }
}

// One diffusion system by the scalar kernel (periodic_diffusion_thomas if `periodic`), into x
// only if the solution is finite. With rhs near max() the forward sweep's d[i] + beta x[i-1]
// can overflow where x, a convex combination of rhs, cannot: the system is then solved again
// with rhs scaled down.
template <class T>
void solve_diffusion_one(Strided<const real_t<T>> beta, Strided<const T> d, Strided<T> x,
                         std::ptrdiff_t n, Scratch<T>& scratch, std::ptrdiff_t system,
                         bool periodic = false) {
  for (std::ptrdiff_t i = 0; i < n; ++i)
    if (!is_finite(d[i])) throw InvalidArgument("rhs", system, i, "is not finite");
  scratch.real_work.resize(periodic ? 3 * n : n);  // the kernels' workspace
  scratch.work.resize(2 * n);
  T* result = scratch.work.data();
  const std::ptrdiff_t bad = solve_rescaling_on_overflow(
      n, d, result, result + n, [&](Strided<const T> rhs, T* out) -> std::ptrdiff_t {
        if (periodic)
          periodic_diffusion_thomas(n, beta, rhs, Strided<T>{out, 1}, scratch.real_work.data());
        else
          diffusion_thomas(n, beta, rhs, Strided<T>{out, 1}, scratch.real_work.data());
        return -1;
      });
  static_cast<void>(bad);  // the diffusion matrix has no vanishing pivot (every pivot >= 1)
  for (std::ptrdiff_t i = 0; i < n; ++i)
    if (!is_finite(result[i]))
      throw NumericalError(system, i, "the solution overflowed: rhs is too large for this type");
  for (std::ptrdiff_t i = 0; i < n; ++i) x[i] = result[i];
}

// The three diagonals of the diffusion system (seed 000 eq. 3.10).
template <class R, class T>
void expand_diffusion(Strided<const R> beta, std::ptrdiff_t n, bool periodic, T* a, T* b, T* c) {
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const R left = i > 0 ? beta[i - 1] : (periodic ? beta[n - 1] : R(0));
    const R right = i + 1 < n || periodic ? beta[i] : R(0);
    a[i] = T(-left);
    b[i] = T(1 + left + right);
    c[i] = T(-right);
  }
}

}  // namespace detail

// Solves the batch  sub[i] x[i-1] + diag[i] x[i] + super[i] x[i+1] = rhs[i]  for every system
// of `layout`. sub[0] and super[n-1] are not read unless options.periodic. x may be rhs
// (in place) but must not overlap the diagonals. Throws InvalidArgument for bad arguments and
// NumericalError for a singular system or a method that is unsafe for it.
// A system that fails does not stop the others: every other system is solved, and then the
// error of the lowest failing system is thrown, naming up to Error::kListedFailures failing
// systems (what(), failed_systems(), failed_count()). The x of a failing system is
// unspecified; in an in-place solve its rhs is left as it was. With options.info nothing is
// thrown for a failing system: its code is written there instead.
// The solvers run with gradual underflow on their threads, whatever the caller's FTZ/DAZ
// state (detail/subnormals.hpp), and restore that state on return.
template <class T>
SolveReport solve(const T* sub, const T* diag, const T* super, const T* rhs, T* x,
                  const BatchLayout& layout, const SolveOptions& options = {}) {
  static_assert(is_supported_scalar_v<T>, "tridiff solvers support float, double and complex");
  using namespace detail;
  validate_layout(layout);
  require_pointer(sub, "sub");
  require_pointer(diag, "diag");
  require_pointer(super, "super");
  require_pointer(rhs, "rhs");
  require_pointer(x, "x");
  require_disjoint(sub, "sub", x, layout, false);
  require_disjoint(diag, "diag", x, layout, false);
  require_disjoint(super, "super", x, layout, false);
  require_disjoint(rhs, "rhs", x, layout, true);
  const int threads = resolve_threads(options.threads);
  const Method method = method_row(options.method).method;  // an out-of-range value is refused
  const Method fast = method == Method::Auto ? Method::Thomas : method;
  const bool check = method == Method::Auto || (options.check_dominance && is_pivot_free(method));
  constexpr int W = kLanes<T>;
  const bool lanes = fast == Method::Thomas && !options.periodic;
  BatchStatus status(options.info, layout);
  std::ptrdiff_t pivoted = 0;
  std::mutex count_guard;

  if (layout.systems() == 1 && !options.periodic && layout.n >= kPartitionedMinRows &&
      (fast == Method::Thomas || fast == Method::Pivoting)) {
    try {
      return solve_single(system_view(sub, diag, super, rhs, layout, 0, false),
                          Strided<T>{x, layout.row_stride}, method, check, threads);
    } catch (const Error&) {
      // With info the failure is recorded, not thrown: the system path below solves the
      // system again and records it.
      if (options.info.empty()) throw;
    }
  }

  // Systems [first, first + systems) one by one: where a lane broke down (so that each failure
  // names its system and row and the others are solved), or for the per-system methods.
  auto solve_each = [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<T>& scratch) {
    std::ptrdiff_t local_pivoted = 0;
    for (std::ptrdiff_t l = 0; l < systems; ++l) {
      const std::ptrdiff_t s = first + l;
      status.run(s, [&] {
        const auto view = system_view(sub, diag, super, rhs, layout, s, options.periodic);
        const Strided<T> out{x + layout.offset(s, 0), layout.row_stride};
        auto solve_by = [&](Method by) {
          solve_one(view, out, by, options.periodic, options.hybrid_pcr_below, scratch.work, s);
        };
        if (check && !check_system(view, s, method, method != Method::Auto)) {
          solve_by(Method::Pivoting);
          ++local_pivoted;
        } else if (method != Method::Auto) {
          solve_by(fast);
        } else {
          try {
            solve_by(Method::Thomas);
          } catch (const NumericalError&) {
            // Thomas can break down on a dominant matrix that is ill conditioned (float
            // gallery('dorr', 4096, 1e-5) overflows) where pivoting, as ?gtsv, solves it.
            solve_by(Method::Pivoting);
            ++local_pivoted;
          }
        }
      });
    }
    if (local_pivoted > 0) {
      std::lock_guard<std::mutex> lock(count_guard);
      pivoted += local_pivoted;
    }
  };
  auto solve_chunk = [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<T>& scratch) {
    const SubnormalsKept gradual_underflow;                 // see subnormals.hpp
    if (lanes && systems == W && layout.row_stride == 1) {  // image rows
      for (std::ptrdiff_t part = first; part < first + W; part += kRowLanes<T>)
        if (!solve_rows(sub, diag, super, rhs, x, layout, part, check, scratch))
          solve_each(part, kRowLanes<T>, scratch);
      return;
    }
    if (!lanes || !fills_lanes<T>(systems) ||
        !solve_lanes(sub, diag, super, rhs, x, layout, first, systems, check, scratch))
      solve_each(first, systems, scratch);
  };
  for_each_chunk<T>(layout, lanes ? W : 1, threads, solve_chunk);
  const std::ptrdiff_t failed = status.finish();
  return {fast, pivoted, 1, failed};
}

// In-place form: rhs_then_x holds the right-hand side on entry and the solution on return.
template <class T>
SolveReport solve_in_place(const T* sub, const T* diag, const T* super, T* rhs_then_x,
                           const BatchLayout& layout, const SolveOptions& options = {}) {
  return solve(sub, diag, super, rhs_then_x, rhs_then_x, layout, options);
}

// Solves the implicit diffusion systems of seed 000 eq. 3.10,
//   -beta[i-1] x[i-1] + (1 + beta[i-1] + beta[i]) x[i] - beta[i] x[i+1] = rhs[i],
// with beta[-1] = beta[n-1] = 0 (insulated ends); with options.periodic, beta[n-1] links
// x[n-1] to x[0] instead. beta is the conductance of the link from i to i+1, >= 0 and finite
// (checked: InvalidArgument naming the system and row otherwise); the matrix is then strictly
// diagonally dominant and every method is safe. beta has the layout of rhs and x. Failing
// systems, options.info and the floating-point state as in solve().
template <class T>
SolveReport solve_diffusion(const real_t<T>* beta, const T* rhs, T* x, const BatchLayout& layout,
                            const SolveOptions& options = {}) {
  static_assert(is_supported_scalar_v<T>, "tridiff solvers support float, double and complex");
  using namespace detail;
  using R = real_t<T>;
  validate_layout(layout);
  require_pointer(beta, "beta");
  require_pointer(rhs, "rhs");
  require_pointer(x, "x");
  require_disjoint(beta, "beta", x, layout, false);
  require_disjoint(rhs, "rhs", x, layout, true);
  const int threads = resolve_threads(options.threads);
  method_row(options.method);  // an out-of-range value is refused
  const Method fast = options.method == Method::Auto ? Method::Thomas : options.method;
  constexpr int W = kLanes<T>;
  const bool lanes = fast == Method::Thomas && !options.periodic;
  const std::ptrdiff_t n = layout.n;
  BatchStatus status(options.info, layout);

  // One long system: by parts in lanes, on every thread (detail/partitioned_diffusion.hpp).
  // Bad input and an overflowing rhs go on to the scalar kernel, which names the row or
  // rescales.
  if constexpr (!is_complex_v<T>) {
    if (lanes && layout.systems() == 1 && n >= kPartitionedMinRows) {
      const SubnormalsKept gradual_underflow;  // see subnormals.hpp
      const std::ptrdiff_t o = layout.offset(0, 0);
      const std::ptrdiff_t parts =
          partitioned_diffusion(Strided<const R>{beta + o, layout.row_stride},
                                Strided<const T>{rhs + o, layout.row_stride}, n,
                                Strided<T>{x + o, layout.row_stride}, threads);
      if (parts > 0) return {fast, 0, static_cast<int>(parts), 0};
    }
  }

  auto solve_chunk = [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<T>& scratch) {
    const SubnormalsKept gradual_underflow;  // see subnormals.hpp
    const std::ptrdiff_t solved =
        lanes && fills_lanes<T>(systems)
            ? solve_diffusion_lanes(beta, rhs, x, layout, first, systems, scratch)
            : 0;
    for (std::ptrdiff_t l = solved; l < systems; ++l) {
      const std::ptrdiff_t s = first + l;
      const std::ptrdiff_t o = layout.offset(s, 0);
      const Strided<const R> b{beta + o, layout.row_stride};
      const Strided<const T> d{rhs + o, layout.row_stride};
      const Strided<T> out{x + o, layout.row_stride};
      status.run(s, [&] {
        require_valid_beta(b, n, options.periodic, s);
        if (lanes) {  // a system on its own, or the lanes broke down: the scalar kernel
          solve_diffusion_one(b, d, out, n, scratch, s);
          return;
        }
        if (fast == Method::Thomas) {  // periodic: the ring cut at row 0, no subtraction
          solve_diffusion_one(b, d, out, n, scratch, s, true);
          return;
        }
        // Other methods: expand to three diagonals.
        scratch.slab.resize(3 * n);
        T* a = scratch.slab.data();
        T* diag = a + n;
        T* c = diag + n;
        expand_diffusion(b, n, options.periodic, a, diag, c);
        const SystemView<T> view{{a, 1}, {diag, 1}, {c, 1}, d, n, options.periodic};
        solve_one(view, out, fast, options.periodic, options.hybrid_pcr_below, scratch.work, s);
      });
    }
  };
  for_each_chunk<T>(layout, lanes ? W : 1, threads, solve_chunk);
  const std::ptrdiff_t failed = status.finish();
  return {fast, 0, 1, failed};
}

}  // namespace tridiff
