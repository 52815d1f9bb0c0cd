// Every way a call can go wrong raises the documented exception, naming the argument, system
// and row at fault: bad sizes and pointers, overlapping arrays, non-finite or negative inputs,
// singular and non-dominant systems, overflow. And whatever the input, a call either throws a
// tridiff::Error or returns a finite solution, never a silent inf or NaN.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "reference.hpp"

namespace tridiff::test {
namespace {

using Scalars = ::testing::Types<float, double, std::complex<float>, std::complex<double>>;

// ---------------------------------------------------------------------------------------------
// Expectations on exceptions

using Call = std::function<void()>;

void expect_invalid_argument(const Call& call, const std::string& argument, std::ptrdiff_t system,
                             std::ptrdiff_t row) {
  try {
    call();
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.argument(), argument) << e.what();
    EXPECT_EQ(e.system(), system) << e.what();
    EXPECT_EQ(e.row(), row) << e.what();
    return;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InvalidArgument('" << argument << "', " << system << ", " << row
                  << "), got: " << e.what();
    return;
  }
  ADD_FAILURE() << "expected InvalidArgument('" << argument << "', " << system << ", " << row
                << "), nothing was thrown";
}

// `row` empty: any row of the system (or -1, "not tied to one row") is accepted.
void expect_numerical_error(const Call& call, std::ptrdiff_t system,
                            std::optional<std::ptrdiff_t> row, std::ptrdiff_t n) {
  try {
    call();
  } catch (const InvalidArgument& e) {
    ADD_FAILURE() << "expected NumericalError(" << system << "), got: " << e.what();
    return;
  } catch (const NumericalError& e) {
    EXPECT_EQ(e.system(), system) << e.what();
    // An index not known is left out of the message, never printed as -1.
    EXPECT_EQ(std::string(e.what()).find("row -1"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("system -1"), std::string::npos) << e.what();
    if (row) {
      EXPECT_EQ(e.row(), *row) << e.what();
    } else {
      EXPECT_GE(e.row(), -1) << e.what();
      EXPECT_LT(e.row(), n) << e.what();
    }
    return;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected NumericalError(" << system << "), got: " << e.what();
    return;
  }
  ADD_FAILURE() << "expected NumericalError(" << system << "), nothing was thrown";
}

// ---------------------------------------------------------------------------------------------
// Batches

template <class T>
struct Batch {
  BatchLayout layout;
  bool periodic = false;
  std::vector<T> a, b, c, d;
  T& at(std::vector<T>& array, std::ptrdiff_t system, std::ptrdiff_t row) {
    return array[layout.offset(system, row)];
  }
};

enum class Kind { Rows, Columns };

BatchLayout make_layout(Kind kind, std::ptrdiff_t n, std::ptrdiff_t count) {
  return kind == Kind::Rows ? BatchLayout::rows(n, count, n)
                            : BatchLayout::columns(n, count, count);
}

// `count` random strictly dominant systems in contiguous image rows or columns.
template <class T>
Batch<T> valid_batch(std::ptrdiff_t n, std::ptrdiff_t count, Kind kind = Kind::Rows,
                     bool periodic = false) {
  Batch<T> batch;
  batch.layout = make_layout(kind, n, count);
  batch.periodic = periodic;
  const std::ptrdiff_t size = batch.layout.extent();
  batch.a.assign(size, T(0));
  batch.b.assign(size, T(0));
  batch.c.assign(size, T(0));
  batch.d.assign(size, T(0));
  for (std::ptrdiff_t s = 0; s < count; ++s) {
    const auto system = random_dominant<T>(n, 1000 * n + s, periodic);
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      batch.at(batch.a, s, i) = system.a[i];
      batch.at(batch.b, s, i) = system.b[i];
      batch.at(batch.c, s, i) = system.c[i];
      batch.at(batch.d, s, i) = system.d[i];
    }
  }
  return batch;
}

template <class T>
System<T> system_of(const Batch<T>& batch, std::ptrdiff_t s) {
  System<T> system;
  system.periodic = batch.periodic;
  for (std::ptrdiff_t i = 0; i < batch.layout.n; ++i) {
    const auto o = batch.layout.offset(s, i);
    system.a.push_back(batch.a[o]);
    system.b.push_back(batch.b[o]);
    system.c.push_back(batch.c[o]);
    system.d.push_back(batch.d[o]);
  }
  return system;
}

SolveOptions with(Method method, int threads = 0, bool check_dominance = true) {
  SolveOptions options;
  options.method = method;
  options.threads = threads;
  options.check_dominance = check_dominance;
  return options;
}

enum class Placement { OutOfPlace, InPlace };

// Solves the batch; returns x (for in place: the rhs array after the call).
template <class T>
std::vector<T> run(const Batch<T>& batch, SolveOptions options,
                   Placement placement = Placement::OutOfPlace) {
  options.periodic = batch.periodic;
  if (placement == Placement::InPlace) {
    std::vector<T> x = batch.d;
    solve_in_place(batch.a.data(), batch.b.data(), batch.c.data(), x.data(), batch.layout, options);
    return x;
  }
  std::vector<T> x(batch.d.size(), T(0));
  solve(batch.a.data(), batch.b.data(), batch.c.data(), batch.d.data(), x.data(), batch.layout,
        options);
  return x;
}

// A non-finite value of T: `value` in the real part, or in the imaginary part of a complex.
template <class T>
T poisoned(real_t<T> value) {
  if constexpr (is_complex_v<T>)
    return T(real_t<T>(0.5), value);
  else
    return value;
}

template <class T>
std::vector<real_t<T>> non_finite_values() {
  using R = real_t<T>;
  return {std::numeric_limits<R>::quiet_NaN(), std::numeric_limits<R>::infinity(),
          -std::numeric_limits<R>::infinity()};
}

template <class T>
bool same_bits(const std::vector<T>& p, const std::vector<T>& q) {
  return p.size() == q.size() && std::memcmp(p.data(), q.data(), p.size() * sizeof(T)) == 0;
}

// Enough systems for a full SIMD chunk of every scalar type (at most 64 lanes) and a tail.
constexpr std::ptrdiff_t kCount = 70;
constexpr std::ptrdiff_t kN = 9;

template <class T>
class SolverErrors : public ::testing::Test {};
TYPED_TEST_SUITE(SolverErrors, Scalars);

// ---------------------------------------------------------------------------------------------
// Sizes, threads, pointers, overlap

TYPED_TEST(SolverErrors, ZeroRowsIsRejected) {
  using T = TypeParam;
  using R = real_t<T>;
  std::vector<T> v(16, T(1));
  std::vector<R> beta(16, R(1));
  const BatchLayout layout{0, 2, 1, 4};
  expect_invalid_argument([&] { validate_layout(layout); }, "n", -1, -1);
  expect_invalid_argument([&] { solve(v.data(), v.data(), v.data(), v.data(), v.data(), layout); },
                          "n", -1, -1);
  expect_invalid_argument([&] { solve_in_place(v.data(), v.data(), v.data(), v.data(), layout); },
                          "n", -1, -1);
  expect_invalid_argument([&] { solve_diffusion(beta.data(), v.data(), v.data(), layout); }, "n",
                          -1, -1);
}

TYPED_TEST(SolverErrors, ZeroSystemsIsRejected) {
  using T = TypeParam;
  using R = real_t<T>;
  std::vector<T> v(16, T(1));
  std::vector<R> beta(16, R(1));
  const BatchLayout layout{4, 0, 1, 4};
  expect_invalid_argument([&] { validate_layout(layout); }, "count", -1, -1);
  expect_invalid_argument([&] { solve(v.data(), v.data(), v.data(), v.data(), v.data(), layout); },
                          "count", -1, -1);
  expect_invalid_argument([&] { solve_diffusion(beta.data(), v.data(), v.data(), layout); },
                          "count", -1, -1);
}

TYPED_TEST(SolverErrors, NegativeThreadsIsRejected) {
  using T = TypeParam;
  using R = real_t<T>;
  auto batch = valid_batch<T>(kN, 3);
  std::vector<R> beta(batch.d.size(), R(1));
  std::vector<T> x(batch.d.size());
  for (Method method : kAllMethods) {
    SCOPED_TRACE(to_string(method));
    expect_invalid_argument([&] { run(batch, with(method, -1)); }, "threads", -1, -1);
    expect_invalid_argument(
        [&] {
          solve_diffusion(beta.data(), batch.d.data(), x.data(), batch.layout, with(method, -1));
        },
        "threads", -1, -1);
  }
}

// More than kMaxThreads (1024) is refused before any work, naming `threads` and the bound:
// a team of 2^20 overflowed the OpenMP runtime's stacks. The bound itself is accepted.
TYPED_TEST(SolverErrors, ThreadsAboveTheBoundAreRejected) {
  using T = TypeParam;
  using R = real_t<T>;
  static_assert(kMaxThreads == 1024);
  auto batch = valid_batch<T>(kN, 3);
  std::vector<R> beta(batch.d.size(), R(1));
  std::vector<T> x(batch.d.size());
  for (Method method : kAllMethods)
    for (int threads : {kMaxThreads + 1, 1 << 20, std::numeric_limits<int>::max()}) {
      SCOPED_TRACE(::testing::Message() << to_string(method) << ", threads " << threads);
      expect_invalid_argument([&] { run(batch, with(method, threads)); }, "threads", -1, -1);
      expect_invalid_argument(
          [&] {
            solve_diffusion(beta.data(), batch.d.data(), x.data(), batch.layout,
                            with(method, threads));
          },
          "threads", -1, -1);
      try {
        run(batch, with(method, threads));
      } catch (const InvalidArgument& e) {
        EXPECT_NE(e.message().find("at most 1024"), std::string::npos) << e.what();
      }
    }
  for (Method method : kAllMethods) {
    SCOPED_TRACE(to_string(method));
    const std::vector<T> expected = run(batch, with(method, 1));
    EXPECT_TRUE(same_bits(run(batch, with(method, kMaxThreads)), expected));
    EXPECT_NO_THROW(solve_diffusion(beta.data(), batch.d.data(), x.data(), batch.layout,
                                    with(method, kMaxThreads)));
  }
}

TYPED_TEST(SolverErrors, NullPointerIsNamed) {
  using T = TypeParam;
  using R = real_t<T>;
  auto batch = valid_batch<T>(kN, 3);
  std::vector<T> x(batch.d.size());
  std::vector<R> beta(batch.d.size(), R(1));
  const T* a = batch.a.data();
  const T* b = batch.b.data();
  const T* c = batch.c.data();
  const T* d = batch.d.data();
  const auto& layout = batch.layout;
  expect_invalid_argument([&] { solve<T>(nullptr, b, c, d, x.data(), layout); }, "sub", -1, -1);
  expect_invalid_argument([&] { solve<T>(a, nullptr, c, d, x.data(), layout); }, "diag", -1, -1);
  expect_invalid_argument([&] { solve<T>(a, b, nullptr, d, x.data(), layout); }, "super", -1, -1);
  expect_invalid_argument([&] { solve<T>(a, b, c, nullptr, x.data(), layout); }, "rhs", -1, -1);
  expect_invalid_argument([&] { solve<T>(a, b, c, d, nullptr, layout); }, "x", -1, -1);
  // In place the one array is both rhs and x; it is checked as rhs first.
  expect_invalid_argument([&] { solve_in_place<T>(a, b, c, nullptr, layout); }, "rhs", -1, -1);
  expect_invalid_argument([&] { solve_diffusion<T>(nullptr, d, x.data(), layout); }, "beta", -1,
                          -1);
  expect_invalid_argument([&] { solve_diffusion<T>(beta.data(), nullptr, x.data(), layout); },
                          "rhs", -1, -1);
  expect_invalid_argument([&] { solve_diffusion<T>(beta.data(), d, nullptr, layout); }, "x", -1,
                          -1);
}

// x may be rhs, but must not share a single element with sub, diag or super (or beta):
// neither the same array nor one shifted by an element.
TYPED_TEST(SolverErrors, OutputOverlappingACoefficientArrayIsRejected) {
  using T = TypeParam;
  using R = real_t<T>;
  auto batch = valid_batch<T>(kN, 3);
  // Room for x shifted by one element past the end of each array.
  for (auto* array : {&batch.a, &batch.b, &batch.c}) array->push_back(T(1));
  T* a = batch.a.data();
  T* b = batch.b.data();
  T* c = batch.c.data();
  const T* d = batch.d.data();
  const auto& layout = batch.layout;
  for (std::ptrdiff_t shift : {0, 1}) {
    SCOPED_TRACE(::testing::Message() << "shift " << shift);
    expect_invalid_argument([&] { solve<T>(a, b, c, d, a + shift, layout); }, "x", -1, -1);
    expect_invalid_argument([&] { solve<T>(a, b, c, d, b + shift, layout); }, "x", -1, -1);
    expect_invalid_argument([&] { solve<T>(a, b, c, d, c + shift, layout); }, "x", -1, -1);
    expect_invalid_argument([&] { solve_in_place<T>(a, b, c, b + shift, layout); }, "x", -1, -1);
  }
  // beta and x of another type: x laid over beta's bytes.
  std::vector<T> storage(batch.d.size() + 1, T(0));
  const R* beta = reinterpret_cast<const R*>(storage.data());
  for (std::ptrdiff_t shift : {0, 1}) {
    SCOPED_TRACE(::testing::Message() << "beta, shift " << shift);
    expect_invalid_argument([&] { solve_diffusion<T>(beta, d, storage.data() + shift, layout); },
                            "x", -1, -1);
  }
}

TYPED_TEST(SolverErrors, OutputPartiallyOverlappingRhsIsRejected) {
  using T = TypeParam;
  using R = real_t<T>;
  auto batch = valid_batch<T>(kN, 3);
  const std::ptrdiff_t extent = batch.layout.extent();
  std::vector<T> storage(3 * extent, T(1));
  std::vector<R> beta(extent, R(1));
  T* rhs = storage.data() + extent;  // room for x an extent before or after rhs
  for (std::ptrdiff_t shift : {std::ptrdiff_t(1), -std::ptrdiff_t(1), extent - 1, 1 - extent}) {
    SCOPED_TRACE(::testing::Message() << "x = rhs + " << shift);
    expect_invalid_argument(
        [&] {
          solve<T>(batch.a.data(), batch.b.data(), batch.c.data(), rhs, rhs + shift, batch.layout);
        },
        "x", -1, -1);
    expect_invalid_argument(
        [&] { solve_diffusion<T>(beta.data(), rhs, rhs + shift, batch.layout); }, "x", -1, -1);
  }
}

// The one overlap that is allowed: x is exactly rhs (an in-place solve through `solve`).
TYPED_TEST(SolverErrors, OutputExactlyAliasingRhsIsAccepted) {
  using T = TypeParam;
  auto batch = valid_batch<T>(kN, kCount);
  for (Method method : kAllMethods) {
    SCOPED_TRACE(to_string(method));
    std::vector<T> x = batch.d;
    EXPECT_NO_THROW(solve(batch.a.data(), batch.b.data(), batch.c.data(), x.data(), x.data(),
                          batch.layout, with(method)));
    EXPECT_TRUE(same_bits(x, run(batch, with(method))));
  }
}

TYPED_TEST(SolverErrors, SelfOverlappingLayoutIsRejected) {
  using T = TypeParam;
  constexpr std::ptrdiff_t kHuge = std::numeric_limits<std::ptrdiff_t>::max();
  std::vector<T> v(256, T(1));
  struct Case {
    BatchLayout layout;
    const char* argument;
  };
  const Case cases[] = {
      {BatchLayout::rows(10, 3, 9), "system_stride"},  // rows closer than n apart
      {BatchLayout::columns(10, 4, 3), "row_stride"},  // pitch smaller than the count
      {BatchLayout{10, 3, 2, 19}, "system_stride"},    // strided rows, 20 needed
      {BatchLayout{10, 3, 0, 10}, "row_stride"},       // zero strides
      {BatchLayout{10, 3, 1, 0}, "system_stride"},
      {BatchLayout{10, 3, -1, 10}, "row_stride"},  // negative strides
      {BatchLayout{10, 3, 1, -10}, "system_stride"},
      // Sizes whose overlap test would overflow (found by fuzz_solver_args: signed overflow,
      // undefined behaviour that UBSan reports): refused for their extent first.
      {BatchLayout{kHuge, kHuge, kHuge, kHuge}, "layout"},
      {BatchLayout{kHuge, 2, 1, 3}, "layout"},
      {BatchLayout{2, kHuge, kHuge / 2, 1}, "layout"},
      // The second batch dimension (the lines of a 3-D grid).
      {BatchLayout{10, 3, 1, 10, 0, 30}, "outer_count"},
      {BatchLayout{10, 3, 1, 10, 2, 29}, "outer_stride"},  // batches closer than 30 apart
      {BatchLayout{10, 3, 1, 10, 2, 0}, "outer_stride"},
      {BatchLayout{10, 3, 1, 10, 2, -30}, "outer_stride"},
      {BatchLayout{10, 3, 4, 1, 4, 2}, "outer_stride"},  // outer batches interleave with systems
      {BatchLayout{2, 2, 1, 2, kHuge, kHuge}, "layout"},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(::testing::Message()
                 << "n " << k.layout.n << " count " << k.layout.count << " row_stride "
                 << k.layout.row_stride << " system_stride " << k.layout.system_stride
                 << " outer_count " << k.layout.outer_count << " outer_stride "
                 << k.layout.outer_stride);
    expect_invalid_argument([&] { validate_layout(k.layout); }, k.argument, -1, -1);
    expect_invalid_argument(
        [&] { solve(v.data(), v.data(), v.data(), v.data(), v.data(), k.layout); }, k.argument, -1,
        -1);
  }
}

// ---------------------------------------------------------------------------------------------
// Non-finite and invalid values

// NaN, +inf or -inf in sub, diag or super at a given system and row: InvalidArgument naming
// all three, by every method, with and without the dominance check, in image rows and
// columns, in a SIMD chunk and in the tail of the batch.
TYPED_TEST(SolverErrors, NonFiniteCoefficientIsNamedWithSystemAndRow) {
  using T = TypeParam;
  struct Place {
    const char* argument;
    std::ptrdiff_t system, row;
  };
  const Place places[] = {{"sub", 0, 1},   {"sub", 37, 8},   {"sub", 69, 4},
                          {"diag", 0, 0},  {"diag", 5, 8},   {"diag", 66, 3},
                          {"super", 1, 0}, {"super", 40, 7}, {"super", 69, 2}};
  for (Kind kind : {Kind::Rows, Kind::Columns})
    for (const Place& place : places)
      for (auto value : non_finite_values<T>())
        for (Method method : kAllMethods)
          for (bool check : {true, false}) {
            SCOPED_TRACE(::testing::Message()
                         << (kind == Kind::Rows ? "rows" : "columns") << ", " << place.argument
                         << "[" << place.system << ", " << place.row << "] = " << value << ", "
                         << to_string(method) << (check ? "" : ", check_dominance off"));
            auto batch = valid_batch<T>(kN, kCount, kind);
            auto& array = std::string(place.argument) == "sub"    ? batch.a
                          : std::string(place.argument) == "diag" ? batch.b
                                                                  : batch.c;
            batch.at(array, place.system, place.row) = poisoned<T>(value);
            expect_invalid_argument([&] { run(batch, with(method, 0, check)); }, place.argument,
                                    place.system, place.row);
          }
}

// Periodic systems read sub[0] and super[n-1] (the corners): they are checked too.
TYPED_TEST(SolverErrors, NonFiniteCornerOfPeriodicSystemIsNamed) {
  using T = TypeParam;
  using R = real_t<T>;
  for (Method method : kAllMethods)
    for (bool check : {true, false}) {
      SCOPED_TRACE(::testing::Message() << to_string(method) << (check ? "" : ", unchecked"));
      auto batch = valid_batch<T>(kN, 5, Kind::Rows, true);
      batch.at(batch.a, 3, 0) = poisoned<T>(std::numeric_limits<R>::quiet_NaN());
      expect_invalid_argument([&] { run(batch, with(method, 0, check)); }, "sub", 3, 0);
      batch = valid_batch<T>(kN, 5, Kind::Rows, true);
      batch.at(batch.c, 2, kN - 1) = poisoned<T>(std::numeric_limits<R>::infinity());
      expect_invalid_argument([&] { run(batch, with(method, 0, check)); }, "super", 2, kN - 1);
    }
}

template <class T>
void check_non_finite_rhs(Placement placement) {
  const std::pair<std::ptrdiff_t, std::ptrdiff_t> places[] = {{0, 0}, {7, 5}, {69, 8}};
  for (Kind kind : {Kind::Rows, Kind::Columns})
    for (auto [system, row] : places)
      for (auto value : non_finite_values<T>())
        for (Method method : kAllMethods) {
          SCOPED_TRACE(::testing::Message()
                       << (kind == Kind::Rows ? "rows" : "columns") << ", rhs[" << system << ", "
                       << row << "] = " << value << ", " << to_string(method));
          auto batch = valid_batch<T>(kN, kCount, kind);
          batch.at(batch.d, system, row) = poisoned<T>(value);
          expect_invalid_argument([&] { run(batch, with(method), placement); }, "rhs", system, row);
        }
}

TYPED_TEST(SolverErrors, NonFiniteRhsIsNamedWithSystemAndRow) {
  check_non_finite_rhs<TypeParam>(Placement::OutOfPlace);
}

// The same in place: the row named must be the one the caller passed, not where the partial
// solution first turned non-finite.
TYPED_TEST(SolverErrors, NonFiniteRhsIsNamedWithSystemAndRowInPlace) {
  check_non_finite_rhs<TypeParam>(Placement::InPlace);
}

// Errors are deterministic: with faults in several systems, the first system is named, on
// one thread or two.
TYPED_TEST(SolverErrors, FirstFaultySystemIsNamed) {
  using T = TypeParam;
  using R = real_t<T>;
  for (int threads : {1, 2})
    for (Method method : kAllMethods) {
      SCOPED_TRACE(::testing::Message() << to_string(method) << ", threads " << threads);
      auto batch = valid_batch<T>(kN, 200);
      for (std::ptrdiff_t system : {190, 130, 41, 3})
        batch.at(batch.b, system, 2) = poisoned<T>(std::numeric_limits<R>::quiet_NaN());
      expect_invalid_argument([&] { run(batch, with(method, threads)); }, "diag", 3, 2);
    }
}

// The diffusion form: beta negative, NaN or infinite at a given system and row.
TYPED_TEST(SolverErrors, InvalidBetaIsNamedWithSystemAndRow) {
  using T = TypeParam;
  using R = real_t<T>;
  const R values[] = {R(-1), -std::numeric_limits<R>::denorm_min(),
                      std::numeric_limits<R>::quiet_NaN(), std::numeric_limits<R>::infinity()};
  const std::pair<std::ptrdiff_t, std::ptrdiff_t> places[] = {{0, 0}, {7, 5}, {69, kN - 2}};
  for (bool periodic : {false, true})
    for (Kind kind : {Kind::Rows, Kind::Columns})
      for (auto [system, row] : places)
        for (R value : values)
          for (Method method : kAllMethods)
            for (Placement placement : {Placement::OutOfPlace, Placement::InPlace}) {
              SCOPED_TRACE(::testing::Message()
                           << (kind == Kind::Rows ? "rows" : "columns") << ", beta[" << system
                           << ", " << row << "] = " << value << ", " << to_string(method)
                           << (periodic ? ", periodic" : "")
                           << (placement == Placement::InPlace ? ", in place" : ""));
              auto batch = valid_batch<T>(kN, kCount, kind);
              std::vector<R> beta(batch.d.size(), R(0.5));
              beta[batch.layout.offset(system, row)] = value;
              std::vector<T> x(batch.d.size());
              T* out = placement == Placement::InPlace ? batch.d.data() : x.data();
              SolveOptions options = with(method);
              options.periodic = periodic;
              expect_invalid_argument(
                  [&] { solve_diffusion(beta.data(), batch.d.data(), out, batch.layout, options); },
                  "beta", system, row);
            }
}

// beta[n-1] is the link x[n-1] -- x[0] of a periodic system: checked there.
TYPED_TEST(SolverErrors, InvalidPeriodicLinkBetaIsNamed) {
  using T = TypeParam;
  using R = real_t<T>;
  for (Method method : kAllMethods) {
    SCOPED_TRACE(to_string(method));
    auto batch = valid_batch<T>(kN, kCount);
    std::vector<R> beta(batch.d.size(), R(0.5));
    beta[batch.layout.offset(12, kN - 1)] = R(-2);
    std::vector<T> x(batch.d.size());
    SolveOptions options = with(method);
    options.periodic = true;
    expect_invalid_argument(
        [&] { solve_diffusion(beta.data(), batch.d.data(), x.data(), batch.layout, options); },
        "beta", 12, kN - 1);
  }
}

template <class T>
void check_non_finite_diffusion_rhs(Placement placement) {
  using R = real_t<T>;
  const std::pair<std::ptrdiff_t, std::ptrdiff_t> places[] = {{0, 0}, {7, 5}, {69, kN - 1}};
  for (bool periodic : {false, true})
    for (Kind kind : {Kind::Rows, Kind::Columns})
      for (auto [system, row] : places)
        for (auto value : non_finite_values<T>())
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << (kind == Kind::Rows ? "rows" : "columns") << ", rhs[" << system << ", "
                         << row << "] = " << value << ", " << to_string(method)
                         << (periodic ? ", periodic" : ""));
            auto batch = valid_batch<T>(kN, kCount, kind);
            batch.at(batch.d, system, row) = poisoned<T>(value);
            std::vector<R> beta(batch.d.size(), R(0.5));
            std::vector<T> x(batch.d.size());
            T* out = placement == Placement::InPlace ? batch.d.data() : x.data();
            SolveOptions options = with(method);
            options.periodic = periodic;
            expect_invalid_argument(
                [&] { solve_diffusion(beta.data(), batch.d.data(), out, batch.layout, options); },
                "rhs", system, row);
          }
}

TYPED_TEST(SolverErrors, NonFiniteDiffusionRhsIsNamedWithSystemAndRow) {
  check_non_finite_diffusion_rhs<TypeParam>(Placement::OutOfPlace);
}

TYPED_TEST(SolverErrors, NonFiniteDiffusionRhsIsNamedWithSystemAndRowInPlace) {
  check_non_finite_diffusion_rhs<TypeParam>(Placement::InPlace);
}

// ---------------------------------------------------------------------------------------------
// Singular, non-dominant, overflowing

// Row k and column k of system s are zero (sub, diag, super of row k; super of row k-1 and
// sub of row k+1), so the matrix is exactly singular and row k is the one at fault: every
// method raises NumericalError naming system s and row k. On a batch (SIMD chunks and the
// tail), on a lone system, and on one long system split across two threads.
TYPED_TEST(SolverErrors, ZeroRowAndColumnRaiseNumericalErrorAtThatRow) {
  using T = TypeParam;
  struct Case {
    std::ptrdiff_t n, count, system, row;
    int threads;
  };
  const Case cases[] = {{kN, kCount, 6, 3, 0}, {kN, kCount, 68, 4, 0},
                        {kN, 1, 0, 0, 0},      {kN, 1, 0, 5, 0},
                        {kN, 1, 0, kN - 1, 0}, {40, 3, 2, 21, 0},
                        {40, 3, 1, 22, 0},     {std::ptrdiff_t(1) << 16, 1, 0, 40000, 2}};
  for (const Case& k : cases)
    for (Kind kind : {Kind::Rows, Kind::Columns})
      for (Method method : kAllMethods) {
        SCOPED_TRACE(::testing::Message()
                     << (kind == Kind::Rows ? "rows" : "columns") << ", n " << k.n << ", count "
                     << k.count << ", zero row " << k.row << " of system " << k.system << ", "
                     << to_string(method) << ", threads " << k.threads);
        auto batch = valid_batch<T>(k.n, k.count, kind);
        batch.at(batch.a, k.system, k.row) = T(0);
        batch.at(batch.b, k.system, k.row) = T(0);
        batch.at(batch.c, k.system, k.row) = T(0);
        if (k.row > 0) batch.at(batch.c, k.system, k.row - 1) = T(0);
        if (k.row + 1 < k.n) batch.at(batch.a, k.system, k.row + 1) = T(0);
        expect_numerical_error([&] { run(batch, with(method, k.threads)); }, k.system, k.row, k.n);
      }
}

// The Neumann Laplacian [1 -1; -1 2 -1; ...; -1 1] is singular (x = 1 is in its kernel) and
// weakly dominant, so the pivot-free methods accept it: every method must report it.
TYPED_TEST(SolverErrors, SingularNeumannMatrixRaisesNumericalError) {
  using T = TypeParam;
  for (std::ptrdiff_t n : {2, 3, 16, 33, 1000})
    for (Method method : kAllMethods) {
      SCOPED_TRACE(::testing::Message() << "n " << n << ", " << to_string(method));
      auto batch = valid_batch<T>(n, 4);
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        batch.at(batch.a, 2, i) = T(i > 0 ? -1 : 0);
        batch.at(batch.c, 2, i) = T(i + 1 < n ? -1 : 0);
        batch.at(batch.b, 2, i) = T(i == 0 || i == n - 1 ? 1 : 2);
      }
      expect_numerical_error([&] { run(batch, with(method)); }, 2, std::nullopt, n);
    }
}

// The periodic Laplacian (2 on the diagonal, -1 beside it and in the corners) is singular.
TYPED_TEST(SolverErrors, SingularPeriodicMatrixRaisesNumericalError) {
  using T = TypeParam;
  for (std::ptrdiff_t n : {3, 4, 16, 33, 1000})
    for (Method method : kAllMethods) {
      SCOPED_TRACE(::testing::Message() << "n " << n << ", " << to_string(method));
      auto batch = valid_batch<T>(n, 4, Kind::Rows, true);
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        batch.at(batch.a, 1, i) = T(-1);
        batch.at(batch.b, 1, i) = T(2);
        batch.at(batch.c, 1, i) = T(-1);
      }
      expect_numerical_error([&] { run(batch, with(method)); }, 1, std::nullopt, n);
    }
}

// System 2 of 3 is dominant except at row 4 (by rows and by columns): the pivot-free methods
// refuse it with NumericalError naming system 2, row 4 ...
template <class T>
Batch<T> non_dominant_batch() {
  auto batch = valid_batch<T>(10, 3);
  batch.at(batch.a, 2, 4) = T(1);
  batch.at(batch.c, 2, 4) = T(1);
  batch.at(batch.b, 2, 4) = T(0.125);
  batch.at(batch.c, 2, 3) = T(1);  // column 4: |super of row 3| + |sub of row 5| > |diag|
  batch.at(batch.a, 2, 5) = T(1);
  return batch;
}

TYPED_TEST(SolverErrors, NonDominantMatrixIsRefusedByPivotFreeMethods) {
  using T = TypeParam;
  const auto batch = non_dominant_batch<T>();
  for (Method method : kAllMethods) {
    if (!is_pivot_free(method)) continue;
    SCOPED_TRACE(to_string(method));
    expect_numerical_error([&] { run(batch, with(method)); }, 2, 4, 10);
  }
}

// ... while Auto (and Pivoting) solve it, to the accuracy of partial pivoting.
TYPED_TEST(SolverErrors, AutoSolvesNonDominantMatrix) {
  using T = TypeParam;
  const auto batch = non_dominant_batch<T>();
  const auto system = system_of(batch, 2);
  const long double bound = 16 * unit_roundoff<T>();
  for (Method method : {Method::Auto, Method::Pivoting}) {
    SCOPED_TRACE(to_string(method));
    std::vector<T> x(batch.d.size());
    SolveReport report;
    ASSERT_NO_THROW(report = solve(batch.a.data(), batch.b.data(), batch.c.data(), batch.d.data(),
                                   x.data(), batch.layout, with(method)));
    if (method == Method::Auto) {
      EXPECT_EQ(report.pivoted_systems, 1);
    }
    const std::vector<T> xs(x.begin() + batch.layout.offset(2, 0),
                            x.begin() + batch.layout.offset(2, 0) + 10);
    EXPECT_LE(backward_error(system, xs), bound);
  }
}

// Among 2 chunks and a tail of systems of 70 unknowns, system 5 is dominant by columns only
// (row 40 is not), which Thomas accepts, and system kLanes + 3 is dominant neither way at row
// 33: Thomas refuses that one alone, leaving its rhs as it was in place and solving every other
// system; Auto pivots it. In full chunks of image rows (thomas_rows) and of interleaved columns (thomas_lanes), the
// dominance test fused into the sweep judges each lane on its own: one system dominant only by
// columns is solved, one dominant neither way is refused by Thomas (naming its row) and
// pivoted by Auto, and the other lanes of their chunks are solved. Thomas runs in place (the
// columns then go through a copy) and into a separate x (columns solved where they lie).
template <class T>
void expect_dominance_judged_per_system(Kind kind) {
  constexpr std::ptrdiff_t n = 70, lanes = detail::kLanes<T>;
  const std::ptrdiff_t count = 2 * lanes + 3, by_columns = 5, refused = lanes + 3;
  auto batch = valid_batch<T>(n, count, kind);
  for (std::ptrdiff_t i = 0; i < n; ++i) {  // [1 4 1] rows, then row 40 made 3 4 3
    batch.at(batch.a, by_columns, i) = T(i > 0 ? 1 : 0);
    batch.at(batch.b, by_columns, i) = T(4);
    batch.at(batch.c, by_columns, i) = T(i + 1 < n ? 1 : 0);
  }
  batch.at(batch.a, by_columns, 40) = T(3);  // row 40: 3 + 3 > 4 ...
  batch.at(batch.c, by_columns, 40) = T(3);
  batch.at(batch.c, by_columns, 38) = T(0.5);  // ... column 39: 0.5 + 3 <= 4
  batch.at(batch.a, by_columns, 42) = T(0.5);  // ... column 41: 3 + 0.5 <= 4
  batch.at(batch.a, refused, 33) = T(1);
  batch.at(batch.c, refused, 33) = T(1);
  batch.at(batch.b, refused, 33) = T(0.125);
  batch.at(batch.c, refused, 32) = T(1);  // column 33: 1 + 1 > 0.125
  batch.at(batch.a, refused, 34) = T(1);
  const long double bound = 16 * unit_roundoff<T>();
  auto expect_solved = [&](const std::vector<T>& x, std::ptrdiff_t s) {
    std::vector<T> xs;
    for (std::ptrdiff_t i = 0; i < n; ++i) xs.push_back(x[batch.layout.offset(s, i)]);
    EXPECT_LE(backward_error(system_of(batch, s), xs), bound) << "system " << s;
  };
  for (int threads : {1, 2}) {
    SCOPED_TRACE(::testing::Message() << threads << " threads");
    std::vector<T> rhs = batch.d;
    try {
      solve_in_place(batch.a.data(), batch.b.data(), batch.c.data(), rhs.data(), batch.layout,
                     with(Method::Thomas, threads));
      ADD_FAILURE() << "Thomas accepted system " << refused;
    } catch (const NumericalError& e) {
      EXPECT_EQ(e.system(), refused) << e.what();
      EXPECT_EQ(e.row(), 33) << e.what();
      EXPECT_EQ(e.failed_count(), 1) << e.what();
    }
    for (std::ptrdiff_t s = 0; s < count; ++s) {
      if (s != refused) {
        expect_solved(rhs, s);
        continue;
      }
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        const auto o = batch.layout.offset(s, i);
        EXPECT_EQ(std::memcmp(&rhs[o], &batch.d[o], sizeof(T)), 0) << "rhs row " << i;
      }
    }
    std::vector<T> separate(batch.d.size());
    try {
      solve(batch.a.data(), batch.b.data(), batch.c.data(), batch.d.data(), separate.data(),
            batch.layout, with(Method::Thomas, threads));
      ADD_FAILURE() << "Thomas accepted system " << refused << " (separate x)";
    } catch (const NumericalError& e) {
      EXPECT_EQ(e.system(), refused) << e.what();
      EXPECT_EQ(e.row(), 33) << e.what();
    }
    for (std::ptrdiff_t s = 0; s < count; ++s)
      if (s != refused) expect_solved(separate, s);
    SolveReport report;
    std::vector<T> x(batch.d.size());
    ASSERT_NO_THROW(report = solve(batch.a.data(), batch.b.data(), batch.c.data(), batch.d.data(),
                                   x.data(), batch.layout, with(Method::Auto, threads)));
    EXPECT_EQ(report.pivoted_systems, 1);
    for (std::ptrdiff_t s = 0; s < count; ++s) expect_solved(x, s);
  }
}

TYPED_TEST(SolverErrors, DominanceIsJudgedPerSystemInFullChunksOfRows) {
  expect_dominance_judged_per_system<TypeParam>(Kind::Rows);
}

TYPED_TEST(SolverErrors, DominanceIsJudgedPerSystemInFullChunksOfColumns) {
  expect_dominance_judged_per_system<TypeParam>(Kind::Columns);
}

// The check inside the columns kernel at its edges: one full chunk of n = 1, 2, 3 and 5
// unknowns, one system whose only flaw is its last row and column (b = 1/4 under a = c = 1),
// and NaN in every a[0] and c[n-1], which lie outside the matrices and must not be read.
// Thomas refuses that system at row n-1, in place and into a separate x; Auto pivots it; every
// other system is solved.
TYPED_TEST(SolverErrors, ColumnsKernelJudgesTheLastRowAndReadsNoEntryOutsideTheMatrix) {
  using T = TypeParam;
  constexpr std::ptrdiff_t lanes = detail::kLanes<T>, refused = 7;
  const T nan = T(std::numeric_limits<real_t<T>>::quiet_NaN());
  for (std::ptrdiff_t n : {1, 2, 3, 5}) {
    SCOPED_TRACE(::testing::Message() << "n = " << n);
    auto batch = valid_batch<T>(n, lanes, Kind::Columns);
    if (n > 1) {
      batch.at(batch.b, refused, n - 1) = T(0.25);
      batch.at(batch.a, refused, n - 1) = T(1);
      batch.at(batch.c, refused, n - 2) = T(1);
    }
    auto poisoned = batch;
    for (std::ptrdiff_t s = 0; s < lanes; ++s) {
      poisoned.at(poisoned.a, s, 0) = nan;
      poisoned.at(poisoned.c, s, n - 1) = nan;
    }
    const long double bound = 16 * unit_roundoff<T>();
    auto expect_solved = [&](const std::vector<T>& x, std::ptrdiff_t s) {
      std::vector<T> xs;
      for (std::ptrdiff_t i = 0; i < n; ++i) xs.push_back(x[batch.layout.offset(s, i)]);
      EXPECT_LE(backward_error(system_of(batch, s), xs), bound) << "system " << s;
    };
    for (bool in_place : {false, true}) {
      SCOPED_TRACE(in_place ? "in place" : "separate x");
      std::vector<T> x(batch.d.size());
      if (in_place) x = batch.d;
      auto call = [&] {
        solve(poisoned.a.data(), poisoned.b.data(), poisoned.c.data(),
              in_place ? x.data() : batch.d.data(), x.data(), batch.layout, with(Method::Thomas));
      };
      if (n > 1) {
        expect_numerical_error(call, refused, n - 1, n);
      } else {
        ASSERT_NO_THROW(call());
      }
      for (std::ptrdiff_t s = 0; s < lanes; ++s)
        if (s != refused || n == 1) expect_solved(x, s);
    }
    std::vector<T> x(batch.d.size());
    SolveReport report;
    ASSERT_NO_THROW(report = solve(poisoned.a.data(), poisoned.b.data(), poisoned.c.data(),
                                   batch.d.data(), x.data(), batch.layout, with(Method::Auto)));
    EXPECT_EQ(report.pivoted_systems, n > 1 ? 1 : 0);
    for (std::ptrdiff_t s = 0; s < lanes; ++s) expect_solved(x, s);
  }
}

// Dominance compares moduli, not LAPACK's |re| + |im|: rows b = 2 + 2i, a = c = 1.9 are
// dominant in |re| + |im| (4 > 3.8) but not in modulus (2.83 < 3.8). The pivot-free methods
// refuse that system at row 1 (row 0 has no a) in every kernel that judges dominance: the
// image-rows kernel (a full chunk of lanes), interleaved columns and the scan of one system;
// Auto pivots it, to the accuracy of partial pivoting.
template <class T>
void expect_dominance_in_modulus() {
  constexpr std::ptrdiff_t n = 40, count = detail::kLanes<T> + 2, culprit = 3;
  for (Kind kind : {Kind::Rows, Kind::Columns}) {
    auto batch = valid_batch<T>(n, count, kind);
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      batch.at(batch.a, culprit, i) = T(i > 0 ? 1.9 : 0);
      batch.at(batch.b, culprit, i) = T(2, 2);
      batch.at(batch.c, culprit, i) = T(i + 1 < n ? 1.9 : 0);
    }
    for (Method method : kAllMethods) {
      SCOPED_TRACE(std::string(to_string(method)) + (kind == Kind::Rows ? " rows" : " columns"));
      if (is_pivot_free(method)) {
        expect_numerical_error([&] { run(batch, with(method)); }, culprit, 1, n);
        continue;
      }
      const std::vector<T> x = run(batch, with(method));
      std::vector<T> xs(n);
      for (std::ptrdiff_t i = 0; i < n; ++i) xs[i] = x[batch.layout.offset(culprit, i)];
      EXPECT_LE(backward_error(system_of(batch, culprit), xs), 16 * unit_roundoff<T>());
    }
  }
}

TEST(SolverErrors, DominanceIsJudgedInModulusForComplexFloat) {
  expect_dominance_in_modulus<std::complex<float>>();
}

// Entries near the overflow threshold, where |re| + |im| overflows but the modulus does not:
// a = c = (0.6, 0.6) * max against b = 1 is still judged (and refused) as not dominant.
template <class T>
void expect_huge_entries_judged() {
  using R = real_t<T>;
  const R huge = R(0.6) * std::numeric_limits<R>::max();
  constexpr std::ptrdiff_t n = 5;
  auto batch = valid_batch<T>(n, 1);
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    batch.at(batch.a, 0, i) = T(huge, huge);
    batch.at(batch.b, 0, i) = T(1);
    batch.at(batch.c, 0, i) = T(huge, huge);
  }
  EXPECT_TRUE(std::isfinite(detail::modulus(T(huge, huge))));
  try {
    run(batch, with(Method::Thomas));
    ADD_FAILURE() << "accepted";
  } catch (const NumericalError& error) {
    EXPECT_EQ(error.row(), 0);
    EXPECT_NE(std::string(error.what()).find("not diagonally dominant"), std::string::npos)
        << error.what();
  }
}

TEST(SolverErrors, DominanceOfEntriesNearOverflowIsJudged) {
  expect_huge_entries_judged<std::complex<float>>();
  expect_huge_entries_judged<std::complex<double>>();
}

TEST(SolverErrors, DominanceIsJudgedInModulusForComplexDouble) {
  expect_dominance_in_modulus<std::complex<double>>();
}

// A dominant system whose solution exceeds the range of the type (diag ~ 1/sqrt(max),
// rhs ~ max/2, so x ~ max^1.5): NumericalError naming the system, never inf in x, out of
// place and in place (where the rhs is finite on entry, so it must not be blamed).
TYPED_TEST(SolverErrors, OverflowingSolutionRaisesNumericalError) {
  using T = TypeParam;
  using R = real_t<T>;
  const R tiny = 4 / std::sqrt(std::numeric_limits<R>::max());
  const R huge = std::numeric_limits<R>::max() / 2;
  struct Case {
    std::ptrdiff_t n, count, system;
  };
  for (const Case& k : {Case{kN, kCount, 33}, Case{kN, 1, 0}, Case{1, 5, 4}, Case{40, 3, 1}})
    for (Kind kind : {Kind::Rows, Kind::Columns})
      for (Method method : kAllMethods)
        for (Placement placement : {Placement::OutOfPlace, Placement::InPlace}) {
          SCOPED_TRACE(::testing::Message()
                       << (kind == Kind::Rows ? "rows" : "columns") << ", n " << k.n << ", count "
                       << k.count << ", system " << k.system << ", " << to_string(method)
                       << (placement == Placement::InPlace ? ", in place" : ""));
          auto batch = valid_batch<T>(k.n, k.count, kind);
          for (std::ptrdiff_t i = 0; i < k.n; ++i) {
            batch.at(batch.a, k.system, i) = T(i > 0 ? tiny / 4 : 0);
            batch.at(batch.b, k.system, i) = T(tiny);
            batch.at(batch.c, k.system, i) = T(i + 1 < k.n ? tiny / 4 : 0);
            batch.at(batch.d, k.system, i) = T(huge);
          }
          expect_numerical_error([&] { run(batch, with(method), placement); }, k.system,
                                 std::nullopt, k.n);
        }
}

// The diffusion form with rhs near the top of the range (max/2, beta = 10): the exact solution
// is a convex combination of rhs and so representable, but intermediate sums may not be. Either
// x is finite and within [min rhs, max rhs], or NumericalError: never inf or NaN.
TYPED_TEST(SolverErrors, DiffusionWithHugeRhsNeverReturnsNonFinite) {
  using T = TypeParam;
  using R = real_t<T>;
  const R huge = std::numeric_limits<R>::max() / 2;
  for (std::ptrdiff_t count : {std::ptrdiff_t(1), std::ptrdiff_t(3), kCount})
    for (Method method : kAllMethods)
      for (bool periodic : {false, true}) {
        SCOPED_TRACE(::testing::Message() << "count " << count << ", " << to_string(method)
                                          << (periodic ? ", periodic" : ""));
        const BatchLayout layout = BatchLayout::rows(kN, count, kN);
        std::vector<R> beta(layout.extent(), R(10));
        std::vector<T> rhs(layout.extent(), T(huge)), x(layout.extent());
        for (std::ptrdiff_t k = 0; k < layout.extent(); k += 3) rhs[k] = T(huge / 2);
        SolveOptions options = with(method);
        options.periodic = periodic;
        try {
          solve_diffusion(beta.data(), rhs.data(), x.data(), layout, options);
          for (const T& v : x) {
            ASSERT_TRUE(detail::is_finite(v)) << v;
            ASSERT_LE(magnitude(v), huge) << v;
          }
        } catch (const NumericalError&) {
          // refused: acceptable
        } catch (const std::exception& e) {
          ADD_FAILURE() << "finite, valid input, yet: " << e.what();
        }
      }
}

// solve.hpp: "in an in-place solve its rhs is left as it was" (of a failing system; the other
// systems are solved: solvers_hard_matrices_test checks both on batches). After a zero pivot
// or an overflow in system s, the rhs of system s holds its old bits, by every method: a lone
// system (scalar kernels), a batch (SIMD lanes for Thomas, image rows and columns), one long
// system on two threads (partitioned Thomas).
TYPED_TEST(SolverErrors, FailedInPlaceSolveLeavesRhsOfFailedSystemUnchanged) {
  using T = TypeParam;
  using R = real_t<T>;
  struct Case {
    std::ptrdiff_t n, count, system;
    int threads;
  };
  const Case cases[] = {
      {kN, 1, 0, 0}, {kN, kCount, 6, 0}, {kN, kCount, 67, 0}, {std::ptrdiff_t(1) << 16, 1, 0, 2}};
  for (bool overflow : {false, true})
    for (const Case& k : cases)
      for (Kind kind : {Kind::Rows, Kind::Columns})
        for (Method method : kAllMethods) {
          SCOPED_TRACE(::testing::Message()
                       << (kind == Kind::Rows ? "rows" : "columns") << ", n " << k.n << ", count "
                       << k.count << ", system " << k.system << ", threads " << k.threads << ", "
                       << to_string(method) << (overflow ? ", overflow" : ", zero pivot"));
          auto batch = valid_batch<T>(k.n, k.count, kind);
          const std::ptrdiff_t row = k.n / 2;  // rows before it are eliminated first
          if (overflow) {
            const R tiny = 4 / std::sqrt(std::numeric_limits<R>::max());
            for (std::ptrdiff_t i = 0; i < k.n; ++i) {
              batch.at(batch.a, k.system, i) = T(i > 0 ? tiny / 4 : 0);
              batch.at(batch.b, k.system, i) = T(tiny);
              batch.at(batch.c, k.system, i) = T(i + 1 < k.n ? tiny / 4 : 0);
              batch.at(batch.d, k.system, i) = T(std::numeric_limits<R>::max() / 2);
            }
          } else {
            batch.at(batch.a, k.system, row) = T(0);
            batch.at(batch.b, k.system, row) = T(0);
            batch.at(batch.c, k.system, row) = T(0);
            batch.at(batch.c, k.system, row - 1) = T(0);
            batch.at(batch.a, k.system, row + 1) = T(0);
          }
          std::vector<T> rhs = batch.d;
          EXPECT_THROW(solve_in_place(batch.a.data(), batch.b.data(), batch.c.data(), rhs.data(),
                                      batch.layout, with(method, k.threads)),
                       NumericalError);
          std::ptrdiff_t changed = 0, first = -1;
          for (std::ptrdiff_t i = 0; i < k.n; ++i) {
            const auto o = batch.layout.offset(k.system, i);
            if (std::memcmp(&rhs[o], &batch.d[o], sizeof(T)) != 0) {
              ++changed;
              if (first < 0) first = i;
            }
          }
          EXPECT_EQ(changed, 0) << "rows of the failed system changed, the first is row " << first;
        }
}

// ---------------------------------------------------------------------------------------------
// Whatever the input

// Random systems with entries spread over the whole exponent range of the type, some zeros,
// periodic or not, every method, dominance check on or off: each call either throws a
// tridiff::Error naming a system and row inside the batch, or returns finite numbers.
TYPED_TEST(SolverErrors, NoInputGivesNonFiniteSolutionSilently) {
  using T = TypeParam;
  using R = real_t<T>;
  std::mt19937_64 random(2024);
  const int exponent = std::numeric_limits<R>::max_exponent10 - 2;
  std::uniform_real_distribution<R> power(-exponent, exponent);
  std::uniform_real_distribution<R> unit(-1, 1);
  auto wild = [&]() -> T {
    if (random() % 8 == 0) return T(0);
    const R size = std::pow(R(10), power(random));
    if constexpr (is_complex_v<T>)
      return T(size * unit(random), size * unit(random));
    else
      return size * (unit(random) < 0 ? R(-1) : R(1));
  };
  int solved = 0, refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::ptrdiff_t n = 1 + static_cast<std::ptrdiff_t>(random() % 40);
    const std::ptrdiff_t count = 1 + static_cast<std::ptrdiff_t>(random() % 80);
    auto batch =
        valid_batch<T>(n, count, random() % 2 ? Kind::Rows : Kind::Columns, random() % 4 == 0);
    // A few systems are left dominant; the others get wild entries in some rows.
    for (std::ptrdiff_t s = 0; s < count; ++s) {
      if (random() % 3 == 0) continue;
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        if (random() % 2) continue;
        for (auto* array : {&batch.a, &batch.b, &batch.c, &batch.d})
          if (random() % 2) batch.at(*array, s, i) = wild();
      }
    }
    for (Method method : kAllMethods)
      for (bool check : {true, false}) {
        SCOPED_TRACE(::testing::Message()
                     << "trial " << trial << ", n " << n << ", count " << count << ", "
                     << to_string(method) << (batch.periodic ? ", periodic" : "")
                     << (check ? "" : ", unchecked"));
        try {
          const auto x = run(batch, with(method, 0, check));
          for (std::ptrdiff_t s = 0; s < count; ++s)
            for (std::ptrdiff_t i = 0; i < n; ++i)
              ASSERT_TRUE(detail::is_finite(x[batch.layout.offset(s, i)]))
                  << "x[" << s << ", " << i << "] = " << x[batch.layout.offset(s, i)];
          ++solved;
        } catch (const InvalidArgument& e) {
          ADD_FAILURE() << "all inputs are finite, yet: " << e.what();
        } catch (const NumericalError& e) {
          ASSERT_GE(e.system(), 0) << e.what();
          ASSERT_LT(e.system(), count) << e.what();
          ASSERT_GE(e.row(), -1) << e.what();
          ASSERT_LT(e.row(), n) << e.what();
          ++refused;
        }
      }
  }
  // The inputs are wild enough to exercise both outcomes.
  EXPECT_GT(solved, 0);
  EXPECT_GT(refused, 0);
}

// what() names the system and row when they are known and leaves out the ones that are not
// (-1): no "row -1", as InvalidArgument does.
TEST(ErrorMessages, NumericalErrorLeavesOutUnknownIndices) {
  EXPECT_STREQ(NumericalError(3, 4, "zero pivot").what(), "tridiff: system 3, row 4: zero pivot");
  EXPECT_STREQ(NumericalError(3, -1, "overflow").what(), "tridiff: system 3: overflow");
  EXPECT_STREQ(NumericalError(-1, 7, "x").what(), "tridiff: row 7: x");
  EXPECT_STREQ(NumericalError(-1, -1, "failed").what(), "tridiff: failed");
  EXPECT_EQ(NumericalError(-1, -1, "failed").row(), -1);
  EXPECT_STREQ(InvalidArgument("n", "must be >= 1").what(), "tridiff: argument 'n': must be >= 1");
}

// The method table: every Method once, names unique and found again by method_named, an
// unknown name refused with the list, an out-of-range Method (17, 42) refused by every entry
// point (solve, solve_in_place, solve_diffusion), before anything is written.
TEST(SolverMethodTable, EveryMethodOnceAndByName) {
  ASSERT_EQ(std::size(kMethodTable), 6u);
  for (std::size_t i = 0; i < std::size(kMethodTable); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(kMethodTable[i].method), i) << "rows in enum order";
    EXPECT_EQ(method_named(kMethodTable[i].name), kMethodTable[i].method);
    EXPECT_EQ(std::string(to_string(kMethodTable[i].method)), kMethodTable[i].name);
  }
  EXPECT_FALSE(is_pivot_free(Method::Auto));
  EXPECT_FALSE(is_pivot_free(Method::Pivoting));
  EXPECT_TRUE(is_pivot_free(Method::Hybrid));
  // Every row but Auto's runs on its own: a kernel for each scalar type, and a workspace.
  // (Checked here, not by a static_assert: GCC's sanitizer builds do not fold the kernels'
  // addresses to constants.)
  for (const MethodRow& row : kMethodTable) {
    const bool runs = row.kernels.complete() && row.workspace != nullptr;
    EXPECT_EQ(runs, row.method != Method::Auto) << row.name;
  }
  try {
    method_named("hybrid");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.argument(), "method");
    EXPECT_NE(std::string(e.what()).find("known: auto, thomas, cr, pcr, cr-pcr, pivoting"),
              std::string::npos)
        << e.what();
  }
  const double one[1] = {1}, beta[1] = {0}, rhs[1] = {2};
  double x[1] = {0};
  for (int value : {17, 42})
    for (int entry = 0; entry < 3; ++entry) {
      SolveOptions bad;
      bad.method = static_cast<Method>(value);
      double in_place[1] = {2};
      try {
        if (entry == 0)
          solve(one, one, one, rhs, x, BatchLayout::single(1), bad);
        else if (entry == 1)
          solve_in_place(one, one, one, in_place, BatchLayout::single(1), bad);
        else
          solve_diffusion(beta, rhs, x, BatchLayout::single(1), bad);
        ADD_FAILURE() << "no error, Method(" << value << "), entry point " << entry;
      } catch (const InvalidArgument& e) {
        EXPECT_EQ(e.argument(), "method") << e.what();
        EXPECT_NE(std::string(e.what()).find(std::to_string(value)), std::string::npos) << e.what();
      }
      EXPECT_EQ(in_place[0], 2) << "nothing written";
    }
  EXPECT_EQ(x[0], 0) << "nothing written";
}

}  // namespace
}  // namespace tridiff::test
