// libFuzzer target: arbitrary arguments for tridiff::solve and tridiff::solve_diffusion.
//
// The input chooses a batch layout (sizes and strides including 0, negatives and overlaps), the
// options (every method plus an out-of-range one, odd thread counts), the scalar type and the
// coefficients (zeros, NaN, infinities, huge and subnormal values). A call may throw
// tridiff::Error; anything else is a finding: a crash, a sanitizer report, another exception,
// or a broken promise of solve.hpp (checked below, each one cheap and stated by the header or
// by tests/solvers_errors_test.cpp).
//
// Every array has exactly layout.extent() elements, so AddressSanitizer reports any access
// outside the span the layout describes; the gaps inside it (strides > 1) hold a marker that
// must come back untouched.
#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "tridiff/solvers.hpp"

namespace {

using namespace tridiff;
using Index = std::ptrdiff_t;

// Batches spanning more elements are skipped: they find nothing the small ones do not, and
// cost page faults and instrumented loops (2^17 elements: a fifth of the speed). The bound
// still admits one dense system on the partitioned path (detail::kPartitionedMinRows rows).
constexpr Index kMaxElements = detail::kPartitionedMinRows + 64;

// The call being made, for the report of a finding.
std::string current_call;

// A broken promise: reported like a crash, so libFuzzer saves the input.
[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz_solver_args: %s\n  in %s\n", what.c_str(), current_call.c_str());
  std::abort();
}

// ---------------------------------------------------------------------------------------------
// Choosing the call

// Saturates instead of overflowing: the harness must not have undefined behaviour of its own.
Index saturate(__int128 value) {
  constexpr auto lo = std::numeric_limits<Index>::min(), hi = std::numeric_limits<Index>::max();
  return static_cast<Index>(std::clamp<__int128>(value, lo, hi));
}

// Sizes the validation must refuse or survive, besides the small ones.
constexpr Index kOddSizes[] = {0,
                               -1,
                               detail::kPartitionedMinRows,  // one long system, split
                               detail::kPartitionedMinRows + 3,
                               Index(1) << 31,
                               Index(1) << 40,
                               -(Index(1) << 40),
                               std::numeric_limits<Index>::max(),
                               std::numeric_limits<Index>::min()};

// n or count: mostly -2..65 (enough for a full and a partial SIMD chunk of 64 floats).
Index pick_size(FuzzedDataProvider& in) {
  const auto k = in.ConsumeIntegral<std::uint8_t>();
  constexpr int odd = std::size(kOddSizes);
  return k >= 256 - odd ? kOddSizes[k - (256 - odd)] : Index(k % 68) - 2;
}

// A stride relative to the layout's sizes: dense rows and columns, padded ones, overlapping
// ones (one short), and values that are invalid or overflow the extent.
Index pick_stride(FuzzedDataProvider& in, Index n, Index count) {
  const __int128 wide_n = n, wide_count = count;
  switch (in.ConsumeIntegralInRange(0, 15)) {
    case 0: return 0;
    case 1: return -1;
    case 2: return 2;
    case 3: return 3;
    case 4: return saturate(wide_n);
    case 5: return saturate(wide_n + 1);
    case 6: return saturate(wide_n - 1);
    case 7: return saturate(2 * wide_n);
    case 8: return saturate(wide_count);
    case 9: return saturate(wide_count + 1);
    case 10: return saturate(wide_count - 1);
    case 11: return saturate(wide_n * wide_count);
    case 12: return Index(1) << 40;
    case 13: return std::numeric_limits<Index>::max();
    case 14: return std::numeric_limits<Index>::min();
    default: return 1;
  }
}

BatchLayout pick_layout(FuzzedDataProvider& in) {
  BatchLayout layout;
  layout.n = pick_size(in);
  layout.count = pick_size(in);
  layout.row_stride = pick_stride(in, layout.n, layout.count);
  layout.system_stride = pick_stride(in, layout.n, layout.count);
  return layout;
}

SolveOptions pick_options(FuzzedDataProvider& in) {
  // 1024 is solve.hpp's kMaxThreads, the most a call accepts.
  constexpr int kThreads[] = {0,
                              1,
                              2,
                              3,
                              4,
                              -1,
                              1024,
                              1025,
                              std::numeric_limits<int>::max(),
                              std::numeric_limits<int>::min()};
  constexpr Index kPcrBelow[] = {
      32, 0, 1, 2, 3, -1, std::numeric_limits<Index>::max(), std::numeric_limits<Index>::min()};
  SolveOptions options;
  // Past the last enumerator too: an enum class holds any int.
  options.method = static_cast<Method>(in.ConsumeIntegralInRange(-1, 7));
  options.threads = kThreads[in.ConsumeIntegralInRange<int>(0, std::size(kThreads) - 1)];
  options.periodic = in.ConsumeBool();
  options.check_dominance = in.ConsumeBool();
  options.hybrid_pcr_below = kPcrBelow[in.ConsumeIntegralInRange<int>(0, std::size(kPcrBelow) - 1)];
  return options;
}

// Which array x is: its own, rhs (in place, allowed), or a coefficient array (refused).
enum class Alias { None, InPlace, Sub, Diag, Super, Beta };

struct Call {
  BatchLayout layout;
  SolveOptions options;
  bool diffusion;  // solve_diffusion rather than solve
  bool dominant;   // raise the diagonal (or |beta|) so that most systems are solvable
  Alias alias;
  unsigned nulls;  // null pointers passed: bit 0 sub and beta, 1 diag, 2 super, 3 rhs, 4 x
};

Call pick_call(FuzzedDataProvider& in) {
  Call call;
  call.layout = pick_layout(in);
  call.options = pick_options(in);
  call.diffusion = in.ConsumeBool();
  call.dominant = in.ConsumeBool();
  // Mostly separate or in place; the refused cases and null pointers now and then.
  const int alias = in.ConsumeIntegralInRange(0, 15);
  call.alias = alias < 12 ? static_cast<Alias>(alias % 2) : static_cast<Alias>(alias - 10);
  call.nulls = in.ConsumeIntegralInRange(0, 15) == 0 ? in.ConsumeIntegralInRange(1, 31) : 0;
  return call;
}

std::string describe(const Call& call, const char* scalar) {
  const BatchLayout& l = call.layout;
  const SolveOptions& o = call.options;
  const char* aliases[] = {"separate", "in place", "x = sub", "x = diag", "x = super", "x = beta"};
  return std::string(call.diffusion ? "solve_diffusion<" : "solve<") + scalar + ">, layout {n " +
         std::to_string(l.n) + ", count " + std::to_string(l.count) + ", row_stride " +
         std::to_string(l.row_stride) + ", system_stride " + std::to_string(l.system_stride) +
         "}, method " + std::to_string(static_cast<int>(o.method)) + " (" + to_string(o.method) +
         "), threads " + std::to_string(o.threads) + (o.periodic ? ", periodic" : "") +
         (o.check_dominance ? "" : ", unchecked") + ", hybrid_pcr_below " +
         std::to_string(o.hybrid_pcr_below) + ", " + aliases[static_cast<int>(call.alias)] +
         (call.dominant ? ", dominant" : "") + ", null mask " + std::to_string(call.nulls);
}

// ---------------------------------------------------------------------------------------------
// Values

template <class R>
R special_value(int k) {
  using L = std::numeric_limits<R>;
  const R table[] = {R(0),
                     -R(0),
                     R(1),
                     R(-1),
                     R(0.5),
                     R(4),
                     R(-3),
                     L::quiet_NaN(),
                     L::infinity(),
                     -L::infinity(),
                     R(1e38),
                     R(-1e38),
                     L::denorm_min(),
                     L::min(),
                     L::max(),
                     L::epsilon()};
  return table[k % std::size(table)];
}

// One real from the input: a special value, a small integer, or raw bits. `fallback` once the
// input is used up, so short inputs give mostly well-posed systems with a few odd entries.
template <class R>
R next_real(FuzzedDataProvider& in, R fallback) {
  if (in.remaining_bytes() == 0) return fallback;
  const auto k = in.ConsumeIntegral<std::uint8_t>();
  if (k < 128) return special_value<R>(k);
  if (k < 192) return R(int(k) - 160);
  const auto bytes = in.ConsumeBytes<std::uint8_t>(sizeof(R));
  if (bytes.size() < sizeof(R)) return fallback;
  R raw;
  std::memcpy(&raw, bytes.data(), sizeof(R));
  return raw;
}

template <class T>
T next_value(FuzzedDataProvider& in, real_t<T> fallback) {
  using R = real_t<T>;
  if constexpr (is_complex_v<T>) {
    const R re = next_real<R>(in, fallback);
    return T(re, next_real<R>(in, R(0)));
  } else {
    return next_real<R>(in, fallback);
  }
}

// Marks the elements no (system, row) of the layout names; they must survive every call.
template <class T>
T gap_marker() {
  const auto nan = std::numeric_limits<real_t<T>>::quiet_NaN();
  if constexpr (is_complex_v<T>)
    return T(nan, -nan);
  else
    return -nan;
}

template <class T>
bool same_bits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// ---------------------------------------------------------------------------------------------
// The arrays of one call

template <class T>
struct Batch {
  using R = real_t<T>;
  BatchLayout layout;
  bool valid = false;  // validate_layout accepts the layout: the arrays have its extent
  std::vector<T> sub, diag, super, rhs, x;
  std::vector<R> beta;

  T& at(std::vector<T>& v, Index s, Index i) { return v[layout.offset(s, i)]; }
  R& beta_at(Index s, Index i) { return beta[layout.offset(s, i)]; }
};

// Whether the solver reads entry (row i, column off the diagonal) of a system: the corner
// entries sub[0] and super[n-1] only when periodic.
bool reads_sub(Index i, bool periodic) { return i > 0 || periodic; }
bool reads_super(Index i, Index n, bool periodic) { return i + 1 < n || periodic; }

template <class T>
void fill_general(Batch<T>& b, FuzzedDataProvider& in, bool dominant, bool periodic) {
  using R = real_t<T>;
  const Index n = b.layout.n;
  for (Index s = 0; s < b.layout.count; ++s)
    for (Index i = 0; i < n; ++i) {
      T& sub = b.at(b.sub, s, i);
      T& diag = b.at(b.diag, s, i);
      T& super = b.at(b.super, s, i);
      sub = next_value<T>(in, R(-1));
      diag = next_value<T>(in, R(4));
      super = next_value<T>(in, R(-1));
      b.at(b.rhs, s, i) = next_value<T>(in, R(1 + (s + i) % 7));
      if (dominant) {  // in |re| + |im|, never below the modulus: dominant with room to spare
        const R off = (reads_sub(i, periodic) ? detail::magnitude(sub) : R(0)) +
                      (reads_super(i, n, periodic) ? detail::magnitude(super) : R(0));
        diag = T(detail::magnitude(diag) + off);
      }
    }
}

template <class T>
void fill_diffusion(Batch<T>& b, FuzzedDataProvider& in, bool dominant) {
  using R = real_t<T>;
  for (Index s = 0; s < b.layout.count; ++s)
    for (Index i = 0; i < b.layout.n; ++i) {
      R& beta = b.beta_at(s, i);
      beta = next_real<R>(in, R(0.5));
      if (dominant) beta = std::abs(beta);  // a conductance is >= 0
      b.at(b.rhs, s, i) = next_value<T>(in, R(1 + (s + i) % 7));
    }
}

// Arrays of the layout's extent, gaps marked; or, for a layout the solver must refuse before
// touching memory, small dummies. False when the batch is too large to be worth solving.
template <class T>
bool make_batch(Batch<T>& b, const Call& call, FuzzedDataProvider& in) {
  b.layout = call.layout;
  try {
    validate_layout(b.layout);
    b.valid = true;
  } catch (const InvalidArgument&) {
  }
  if (b.valid && b.layout.extent() > kMaxElements) return false;
  const auto size = static_cast<std::size_t>(b.valid ? b.layout.extent() : 4);
  for (auto* v : {&b.sub, &b.diag, &b.super, &b.rhs, &b.x}) v->assign(size, gap_marker<T>());
  b.beta.assign(size, gap_marker<real_t<T>>());
  if (!b.valid) return true;
  if (call.diffusion)
    fill_diffusion(b, in, call.dominant);
  else
    fill_general(b, in, call.dominant, call.options.periodic);
  return true;
}

// ---------------------------------------------------------------------------------------------
// The promises checked after the call

bool names_coefficient(const InvalidArgument& e) {
  for (const char* name : {"sub", "diag", "super", "rhs", "beta"})
    if (e.argument() == name) return true;
  return false;
}

using Wide = std::complex<long double>;

template <class T>
Wide wide(const T& v) {
  return Wide(std::real(v), std::imag(v));
}

template <class T>
long double modulus(const T& v) {
  return std::abs(wide(v));
}

// Every value within [2^-20, 2^20] or zero: no overflow or underflow is possible on the way to
// a solution of a dominant system, so the solver has no reason to refuse it.
template <class T>
bool moderate(const T& v) {
  const long double m = modulus(v);
  return m == 0 || (m >= 0x1p-20L && m <= 0x1p20L);
}

// A system every method must solve, accurately: moderate finite entries and strict diagonal
// dominance by rows with a factor 2 margin, not periodic. (Elimination, with or without
// partial pivoting, and the reductions are backward stable on such a matrix; the margin also
// covers the solver's dominance test, which measures complex entries by |re| + |im|.)
template <class T>
bool well_posed(Batch<T>& b, const Call& call, Index s) {
  if (call.options.periodic) return false;
  const Index n = b.layout.n;
  for (Index i = 0; i < n; ++i) {
    if (call.diffusion) {
      const real_t<T> left = i > 0 ? b.beta_at(s, i - 1) : 0;
      const real_t<T> right = i + 1 < n ? b.beta_at(s, i) : 0;
      if (!(left >= 0 && right >= 0)) return false;  // a conductance must be >= 0
      if (!moderate(left) || !moderate(right) || !moderate(b.at(b.rhs, s, i))) return false;
      continue;  // 1 + left + right against left + right: always strictly dominant
    }
    const T sub = reads_sub(i, false) ? b.at(b.sub, s, i) : T(0);
    const T super = reads_super(i, n, false) ? b.at(b.super, s, i) : T(0);
    const T diag = b.at(b.diag, s, i);
    for (const T& v : {sub, diag, super, b.at(b.rhs, s, i)})
      if (!moderate(v)) return false;
    if (!(modulus(diag) > 0 && modulus(diag) >= 2 * (modulus(sub) + modulus(super)))) return false;
  }
  return true;
}

std::string number(long double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6Lg", v);
  return text;
}

// Row i of system s of the matrix, as (sub, diag, super) in long double.
template <class T>
void matrix_row(Batch<T>& b, const Call& call, Index s, Index i, Wide row[3]) {
  const Index n = b.layout.n;
  if (call.diffusion) {
    const long double left = i > 0 ? b.beta_at(s, i - 1) : 0;
    const long double right = i + 1 < n ? b.beta_at(s, i) : 0;
    row[0] = -left, row[1] = 1 + left + right, row[2] = -right;
    return;
  }
  row[0] = i > 0 ? wide(b.at(b.sub, s, i)) : Wide(0);
  row[1] = wide(b.at(b.diag, s, i));
  row[2] = i + 1 < n ? wide(b.at(b.super, s, i)) : Wide(0);
}

std::string text(const Wide& v) {
  return v.imag() == 0 ? number(v.real()) : "(" + number(v.real()) + ", " + number(v.imag()) + ")";
}

// Rows "sub diag super | rhs -> x" of system s, for the report of a wrong solution.
template <class T>
std::string dump_system(Batch<T>& b, const Call& call, const std::vector<T>& rhs, const T* solution,
                        Index s) {
  std::string dump;
  for (Index i = 0; i < b.layout.n; ++i) {
    Wide row[3];
    matrix_row(b, call, s, i, row);
    const Index o = b.layout.offset(s, i);
    dump += "    " + text(row[0]) + " " + text(row[1]) + " " + text(row[2]) + " | " +
            text(wide(rhs[o])) + " -> " + text(wide(solution[o])) + "\n";
  }
  return dump;
}

// Normwise backward error test: max |rhs - A x| <= tol (||A|| ||x|| + ||rhs||), infinity norms,
// plus a little absolute slack for subnormal intermediate values. (Not row by row: partial
// pivoting swaps rows, and a row whose exact answer is 0 then gets rounding noise of the size
// of its neighbour.) `rhs` is the right-hand side as passed, `solution` the array the solver
// wrote x to.
template <class T>
void check_residual(Batch<T>& b, const Call& call, const std::vector<T>& rhs, const T* solution,
                    Index s) {
  using R = real_t<T>;
  const Index n = b.layout.n;
  const auto x = [&](Index i) { return wide(solution[b.layout.offset(s, i)]); };
  long double norm_a = 0, norm_x = 0, norm_rhs = 0, worst = 0;
  Index worst_row = 0;
  for (Index i = 0; i < n; ++i) {
    Wide row[3];
    matrix_row(b, call, s, i, row);
    Wide r = wide(rhs[b.layout.offset(s, i)]);
    norm_rhs = std::max(norm_rhs, std::abs(r));
    norm_x = std::max(norm_x, std::abs(x(i)));
    long double row_sum = 0;
    for (int k = 0; k < 3; ++k) {
      const Index j = i + k - 1;
      if (j < 0 || j >= n) continue;
      r -= row[k] * x(j);
      row_sum += std::abs(row[k]);
    }
    norm_a = std::max(norm_a, row_sum);
    if (std::abs(r) > worst) worst = std::abs(r), worst_row = i;
  }
  const long double tol =
      64 * (std::log2(static_cast<long double>(n)) + 2) * std::numeric_limits<R>::epsilon();
  const long double scale = norm_a * norm_x + norm_rhs;
  const long double bound = tol * scale + 1e3L * std::numeric_limits<R>::min() * (1 + scale);
  if (!(worst <= bound))
    finding("residual of system " + std::to_string(s) + " is " + number(worst) + " in row " +
            std::to_string(worst_row) + ", more than " + number(bound) +
            " (||A|| ||x|| + ||rhs|| = " + number(scale) + "); the system:\n" +
            dump_system(b, call, rhs, solution, s));
}

// The array passed as x may change only where the layout names an element; every other array
// (the inputs, and rhs unless in place) must come back bit for bit.
template <class U>
void check_untouched(const std::vector<U>& after, const std::vector<U>& before,
                     const BatchLayout& layout, const void* x, bool valid, const char* name) {
  const bool is_x = after.data() == x;
  std::vector<char> inside(after.size(), 0);
  if (is_x && valid)
    for (Index s = 0; s < layout.count; ++s)
      for (Index i = 0; i < layout.n; ++i) inside[layout.offset(s, i)] = 1;
  for (std::size_t k = 0; k < after.size(); ++k)
    if (!inside[k] && !same_bits(after[k], before[k]))
      finding(std::string(name) + "[" + std::to_string(k) + "] was changed, though " +
              (is_x ? "no (system, row) of the layout names it" : "it is not the output"));
}

template <class T>
void check_arrays_untouched(const Batch<T>& b, const Batch<T>& before, const void* x) {
  check_untouched(b.sub, before.sub, b.layout, x, b.valid, "sub");
  check_untouched(b.diag, before.diag, b.layout, x, b.valid, "diag");
  check_untouched(b.super, before.super, b.layout, x, b.valid, "super");
  check_untouched(b.beta, before.beta, b.layout, x, b.valid, "beta");
  check_untouched(b.rhs, before.rhs, b.layout, x, b.valid, "rhs");
  check_untouched(b.x, before.x, b.layout, x, b.valid, "x");
}

template <class T>
void check_system_unchanged(const std::vector<T>& after, const std::vector<T>& before,
                            const BatchLayout& layout, Index s, const std::string& error) {
  for (Index i = 0; i < layout.n; ++i) {
    const Index o = layout.offset(s, i);
    if (!same_bits(after[o], before[o]))
      finding("failed in-place solve changed rhs of the failed system at row " + std::to_string(i) +
              ": " + error);
  }
}

// ---------------------------------------------------------------------------------------------
// The call

template <class T>
struct Pointers {
  const T *sub, *diag, *super, *rhs;
  const real_t<T>* beta;
  T* x;
};

template <class T>
Pointers<T> pointers(Batch<T>& b, const Call& call) {
  Pointers<T> p{b.sub.data(), b.diag.data(), b.super.data(),
                b.rhs.data(), b.beta.data(), b.x.data()};
  switch (call.alias) {
    case Alias::None: break;
    case Alias::InPlace: p.x = b.rhs.data(); break;
    case Alias::Sub: p.x = b.sub.data(); break;
    case Alias::Diag: p.x = b.diag.data(); break;
    case Alias::Super: p.x = b.super.data(); break;
    // solve_diffusion's beta is real: a complex x cannot alias it with the same extent.
    case Alias::Beta:
      if constexpr (!is_complex_v<T>) p.x = b.beta.data();
      break;
  }
  if (call.nulls & 1) {
    p.sub = nullptr;
    p.beta = nullptr;
  }
  if (call.nulls & 2) p.diag = nullptr;
  if (call.nulls & 4) p.super = nullptr;
  if (call.nulls & 8) p.rhs = nullptr;
  if (call.nulls & 16) p.x = nullptr;
  return p;
}

// Whether the solver must refuse the call with InvalidArgument, whatever the values.
template <class T>
bool must_refuse(const Batch<T>& b, const Call& call, const Pointers<T>& p) {
  const int method = static_cast<int>(call.options.method);
  if (!b.valid || call.options.threads < 0 || method < 0 || method >= int(std::size(kMethodTable)))
    return true;
  if (!p.rhs || !p.x) return true;
  if (call.diffusion) return !p.beta || p.x == static_cast<const void*>(p.beta);
  return !p.sub || !p.diag || !p.super || p.x == p.sub || p.x == p.diag || p.x == p.super;
}

// For a corner entry that is not part of the matrix, or a beta link that does not exist.
template <class T>
void check_named_entry(const InvalidArgument& e, const Batch<T>& b, const Call& call) {
  if (e.system() >= b.layout.count || e.row() >= b.layout.n)
    finding(std::string("error names an element outside the batch: ") + e.what());
  if (call.options.periodic || e.row() < 0) return;
  const bool unread = (e.argument() == "sub" && e.row() == 0) ||
                      (e.argument() == "super" && e.row() == b.layout.n - 1) ||
                      (e.argument() == "beta" && e.row() == b.layout.n - 1);
  if (unread) finding(std::string("error names an entry that is not read: ") + e.what());
}

// The checks after InvalidArgument: a refusal must name a real element, and not a well-posed
// system.
template <class T>
void check_refusal(const InvalidArgument& e, const Batch<T>& b, const Batch<T>& before,
                   const Call& call, const std::vector<Index>& posed, bool in_place) {
  if (names_coefficient(e) && std::binary_search(posed.begin(), posed.end(), e.system()))
    finding(std::string("a well-posed system was refused: ") + e.what());
  check_named_entry(e, b, call);
  if (in_place && !call.diffusion && e.system() >= 0)
    check_system_unchanged(b.rhs, before.rhs, b.layout, e.system(), e.what());
}

template <class T>
void check_breakdown(const NumericalError& e, const Batch<T>& b, const Batch<T>& before,
                     const Call& call, const std::vector<Index>& posed, bool in_place) {
  if (e.system() < 0 || e.system() >= b.layout.count || e.row() < -1 || e.row() >= b.layout.n)
    finding(std::string("error names an element outside the batch: ") + e.what());
  if (std::binary_search(posed.begin(), posed.end(), e.system()))
    finding(std::string("a well-posed system was refused: ") + e.what());
  if (in_place && !call.diffusion)
    check_system_unchanged(b.rhs, before.rhs, b.layout, e.system(), e.what());
}

template <class T>
void check_solution(Batch<T>& b, const Batch<T>& before, const Call& call,
                    const std::vector<Index>& posed, const T* x) {
  const auto solution = [&](Index s, Index i) { return x[b.layout.offset(s, i)]; };
  for (Index s = 0; s < b.layout.count; ++s)
    for (Index i = 0; i < b.layout.n; ++i)
      if (!detail::is_finite(solution(s, i)))
        finding("returned normally with a non-finite x at system " + std::to_string(s) + ", row " +
                std::to_string(i));
  for (const Index s : posed) check_residual(b, call, before.rhs, x, s);
}

template <class T>
void run(const Call& call, FuzzedDataProvider& in) {
  Batch<T> b;
  if (!make_batch(b, call, in)) return;
  const Pointers<T> p = pointers(b, call);
  const bool refuse = must_refuse(b, call, p);
  const bool in_place = p.x != nullptr && p.x == p.rhs;
  const Batch<T> before = b;
  std::vector<Index> posed;  // ascending
  if (!refuse)
    for (Index s = 0; s < b.layout.count; ++s)
      if (well_posed(b, call, s)) posed.push_back(s);

  try {
    if (call.diffusion)
      solve_diffusion<T>(p.beta, p.rhs, p.x, b.layout, call.options);
    else
      solve<T>(p.sub, p.diag, p.super, p.rhs, p.x, b.layout, call.options);
    if (refuse) finding("the call should have been refused with InvalidArgument");
    check_solution(b, before, call, posed, p.x);
  } catch (const InvalidArgument& e) {
    if (!refuse) check_refusal(e, b, before, call, posed, in_place);
  } catch (const NumericalError& e) {
    if (refuse) finding(std::string("expected InvalidArgument, got: ") + e.what());
    check_breakdown(e, b, before, call, posed, in_place);
  }
  check_arrays_untouched(b, before, p.x);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  const Call call = pick_call(in);
  try {
    constexpr const char* kScalars[] = {"float", "double", "complex<float>", "complex<double>"};
    const int scalar = in.ConsumeIntegralInRange(0, 3);
    current_call = describe(call, kScalars[scalar]);
    switch (scalar) {
      case 0: run<float>(call, in); break;
      case 1: run<double>(call, in); break;
      case 2: run<std::complex<float>>(call, in); break;
      default: run<std::complex<double>>(call, in); break;
    }
  } catch (const tridiff::Error&) {
    // Refused: allowed. Any other exception escapes, and libFuzzer reports it.
  }
  return 0;
}
