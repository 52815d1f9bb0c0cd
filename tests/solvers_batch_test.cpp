// Batches: every system of a batch, in every layout (image rows with padding, image columns,
// both strides > 1), for counts that do and do not fill the SIMD lanes, against Eigen's LU in
// long double; the invariances a batch must have (layout, in place, threads, padding, unread
// entries); and the diffusion form against its expanded three-diagonal matrix, with the
// invariants of that matrix (column sums 1: mass conservation; M-matrix with row sums 1:
// maximum principle; beta = 0: identity).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "reference.hpp"

namespace tridiff::test {
namespace {

using Scalars = ::testing::Types<float, double, std::complex<float>, std::complex<double>>;

// Counts below, at and above the lane counts (16 to 64 systems per chunk, by scalar type),
// mostly not multiples of them, so that partial chunks and lone systems are exercised.
constexpr std::ptrdiff_t kCounts[] = {1, 3, 17, 33, 64, 100};
constexpr std::ptrdiff_t kRows[] = {1, 2, 5, 40};

// ---------------------------------------------------------------------------------------------
// Layouts and batch storage

enum class Kind { Rows, Columns, StridedRows, StridedColumns };
constexpr Kind kKinds[] = {Kind::Rows, Kind::Columns, Kind::StridedRows, Kind::StridedColumns};

const char* name(Kind kind) {
  switch (kind) {
    case Kind::Rows: return "rows";
    case Kind::Columns: return "columns";
    case Kind::StridedRows: return "strided rows";
    case Kind::StridedColumns: return "strided columns";
  }
  return "?";
}

BatchLayout make_layout(Kind kind, std::ptrdiff_t n, std::ptrdiff_t count) {
  switch (kind) {
    case Kind::Rows: return BatchLayout::rows(n, count, n + 3);  // 3 elements of padding per row
    case Kind::Columns: return BatchLayout::columns(n, count, count + 5);
    case Kind::StridedRows: return {n, count, 2, 2 * n + 3};
    case Kind::StridedColumns: return {n, count, 2 * count + 1, 2};
  }
  return {};
}

// Elements after the extent of the layout, to catch writes past its end.
constexpr std::ptrdiff_t kTail = 9;

std::ptrdiff_t storage_size(const BatchLayout& layout) { return layout.extent() + kTail; }

// What every element the layout does not reach holds: a NaN with a payload, compared bit for
// bit (a solver that read it would spread NaN; one that wrote it would change the bits).
template <class T>
T sentinel() {
  using R = real_t<T>;
  R nan;
  if constexpr (std::is_same_v<R, float>)
    nan = std::nanf("4242");
  else
    nan = std::nan("4242");
  if constexpr (is_complex_v<T>)
    return T(nan, nan);
  else
    return nan;
}

template <class T>
bool same_bits(const T& p, const T& q) {
  return std::memcmp(&p, &q, sizeof(T)) == 0;
}

// Real results are compared bit for bit. Complex ones may differ by rounding: GCC contracts
// the products of a complex multiplication or division into FMAs differently in its
// vectorised and scalar code, and which one a chunk gets depends on aliasing (in place or
// not) and strides; the difference then travels through the elimination. The test systems
// are well conditioned with solutions of order 1, so rounding stays below 64 eps.
template <class T>
bool same_result(const T& p, const T& q) {
  if constexpr (is_complex_v<T>) {
    using R = real_t<T>;
    const R scale = std::max({std::abs(p), std::abs(q), R(1)});
    return same_bits(p, q) || std::abs(p - q) <= 64 * std::numeric_limits<R>::epsilon() * scale;
  } else {
    return same_bits(p, q);
  }
}

// Index of the first element whose results differ (see same_result), or -1.
template <class T>
std::ptrdiff_t first_difference(const std::vector<T>& p, const std::vector<T>& q) {
  if (p.size() != q.size()) return 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!same_result(p[i], q[i])) return static_cast<std::ptrdiff_t>(i);
  return -1;
}

// Marks the elements of storage that belong to the layout.
std::vector<char> reached(const BatchLayout& layout) {
  std::vector<char> mask(storage_size(layout), 0);
  for (std::ptrdiff_t s = 0; s < layout.systems(); ++s)
    for (std::ptrdiff_t i = 0; i < layout.n; ++i) mask[layout.offset(s, i)] = 1;
  return mask;
}

// Lays out one vector per system in batch storage; everything else is the sentinel.
template <class T>
std::vector<T> spread(const BatchLayout& layout, const std::vector<std::vector<T>>& parts) {
  std::vector<T> out(storage_size(layout), sentinel<T>());
  for (std::ptrdiff_t s = 0; s < layout.systems(); ++s)
    for (std::ptrdiff_t i = 0; i < layout.n; ++i) out[layout.offset(s, i)] = parts[s][i];
  return out;
}

template <class T>
std::vector<T> pick(const std::vector<T>& array, const BatchLayout& layout, std::ptrdiff_t s) {
  std::vector<T> out(layout.n);
  for (std::ptrdiff_t i = 0; i < layout.n; ++i) out[i] = array[layout.offset(s, i)];
  return out;
}

// A batch of general systems: the systems one by one, and the same numbers in batch storage.
template <class T>
struct Batch {
  BatchLayout layout;
  bool periodic = false;
  std::vector<System<T>> systems;
  std::vector<T> a, b, c, d;
};

template <class T>
Batch<T> make_batch(const std::vector<System<T>>& systems, const BatchLayout& layout) {
  Batch<T> batch;
  batch.layout = layout;
  batch.periodic = systems.front().periodic;
  batch.systems = systems;
  std::vector<std::vector<T>> a, b, c, d;
  for (const auto& s : systems) {
    a.push_back(s.a);
    b.push_back(s.b);
    c.push_back(s.c);
    d.push_back(s.d);
  }
  batch.a = spread(layout, a);
  batch.b = spread(layout, b);
  batch.c = spread(layout, c);
  batch.d = spread(layout, d);
  return batch;
}

template <class T>
std::vector<System<T>> random_systems(std::ptrdiff_t n, std::ptrdiff_t count, bool periodic) {
  std::vector<System<T>> systems;
  for (std::ptrdiff_t s = 0; s < count; ++s)
    systems.push_back(random_dominant<T>(n, 7919 * n + 104729 * count + s, periodic));
  return systems;
}

enum class Placement { OutOfPlace, InPlace };

// Solves the batch and returns the whole storage of x (sentinel where the layout does not
// reach). In place, x starts as a copy of the rhs storage (sentinel padding included).
template <class T>
std::vector<T> solve_batch(const Batch<T>& batch, SolveOptions options,
                           Placement placement = Placement::OutOfPlace) {
  options.periodic = batch.periodic;
  std::vector<T> x(storage_size(batch.layout), sentinel<T>());
  if (placement == Placement::InPlace) {
    x = batch.d;
    solve_in_place(batch.a.data(), batch.b.data(), batch.c.data(), x.data(), batch.layout, options);
  } else {
    solve(batch.a.data(), batch.b.data(), batch.c.data(), batch.d.data(), x.data(), batch.layout,
          options);
  }
  return x;
}

SolveOptions with(Method method, int threads = 0) {
  SolveOptions options;
  options.method = method;
  options.threads = threads;
  return options;
}

// Every system of every layout kind, count and size, by every method, within the bounds of
// the accuracy test against Eigen's LU in long double.
template <class T>
void check_against_reference(std::initializer_list<Kind> kinds, bool periodic) {
  for (std::ptrdiff_t n : kRows) {
    for (std::ptrdiff_t count : kCounts) {
      const auto systems = random_systems<T>(n, count, periodic);
      std::vector<WideVector<T>> references;
      std::vector<long double> kappas;
      for (const auto& s : systems) {
        references.push_back(reference_solve(s));
        kappas.push_back(condition_bound(s));
      }
      for (Kind kind : kinds) {
        const auto batch = make_batch(systems, make_layout(kind, n, count));
        for (Method method : kAllMethods) {
          SCOPED_TRACE(::testing::Message() << name(kind) << ", n = " << n << ", count = " << count
                                            << ", method = " << to_string(method));
          const auto x = solve_batch(batch, with(method));
          for (std::ptrdiff_t s = 0; s < count; ++s) {
            const auto xs = pick(x, batch.layout, s);
            const long double bound = backward_bound<T>(method, n);
            ASSERT_LE(backward_error(systems[s], xs), bound) << "system " << s;
            ASSERT_LE(forward_error(xs, references[s]), kappas[s] * bound) << "system " << s;
          }
        }
      }
    }
  }
}

template <class T>
class SolverBatch : public ::testing::Test {};
TYPED_TEST_SUITE(SolverBatch, Scalars);

// Image rows: row stride 1, pitch > n.
TYPED_TEST(SolverBatch, RowsLayoutMatchesLongDoubleLu) {
  check_against_reference<TypeParam>({Kind::Rows}, false);
}

// Image columns: row stride = pitch, system stride 1.
TYPED_TEST(SolverBatch, ColumnsLayoutMatchesLongDoubleLu) {
  check_against_reference<TypeParam>({Kind::Columns}, false);
}

// Both strides > 1, systems outer or inner.
TYPED_TEST(SolverBatch, StridedLayoutsMatchLongDoubleLu) {
  check_against_reference<TypeParam>({Kind::StridedRows, Kind::StridedColumns}, false);
}

// Periodic systems (Sherman-Morrison) in a batch, every layout.
TYPED_TEST(SolverBatch, PeriodicBatchesMatchLongDoubleLu) {
  check_against_reference<TypeParam>(
      {Kind::Rows, Kind::Columns, Kind::StridedRows, Kind::StridedColumns}, true);
}

// Nothing outside the layout is written: padding between rows, gaps of strided layouts and
// the elements after the extent keep their sentinel bits, out of place and in place.
TYPED_TEST(SolverBatch, PaddingOutsideTheLayoutIsLeftUntouched) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : {1, 5, 40})
      for (std::ptrdiff_t count : kCounts)
        for (Kind kind : kKinds) {
          const auto batch =
              make_batch(random_systems<T>(n, count, periodic), make_layout(kind, n, count));
          const auto mask = reached(batch.layout);
          for (Method method : kAllMethods)
            for (Placement placement : {Placement::OutOfPlace, Placement::InPlace}) {
              SCOPED_TRACE(::testing::Message()
                           << name(kind) << ", n = " << n << ", count = " << count
                           << ", method = " << to_string(method)
                           << (placement == Placement::InPlace ? ", in place" : "")
                           << (periodic ? ", periodic" : ""));
              const auto x = solve_batch(batch, with(method), placement);
              for (std::size_t k = 0; k < x.size(); ++k)
                if (!mask[k]) {
                  ASSERT_TRUE(same_bits(x[k], sentinel<T>())) << "element " << k;
                }
            }
        }
}

// The layout only says where the numbers are: the same systems give the same bits in every
// layout (the same kernel runs on the same chunks of systems, whatever the strides).
TYPED_TEST(SolverBatch, LayoutDoesNotChangeTheResult) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : {1, 5, 40})
      for (std::ptrdiff_t count : kCounts) {
        const auto systems = random_systems<T>(n, count, periodic);
        for (Method method : kAllMethods) {
          const auto rows = make_batch(systems, make_layout(Kind::Rows, n, count));
          const auto x_rows = solve_batch(rows, with(method));
          for (Kind kind : {Kind::Columns, Kind::StridedRows, Kind::StridedColumns}) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << " vs rows, n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            const auto other = make_batch(systems, make_layout(kind, n, count));
            const auto x_other = solve_batch(other, with(method));
            for (std::ptrdiff_t s = 0; s < count; ++s) {
              const auto row =
                  first_difference(pick(x_rows, rows.layout, s), pick(x_other, other.layout, s));
              EXPECT_EQ(row, -1) << "system " << s << " (later systems not compared)";
              if (row >= 0) break;
            }
          }
        }
      }
}

// Methods that solve a batch one system at a time (everything but the SIMD-lane Thomas path)
// give a batched system the same bits as the same system solved alone. Thomas and Auto run a
// different kernel on full chunks (one SIMD lane per system) and are held to the reference
// bounds by the layout tests above instead.
TYPED_TEST(SolverBatch, BatchedEqualsSingleSystemForPerSystemMethods) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : kRows)
      for (std::ptrdiff_t count : {3, 33, 100}) {
        const auto systems = random_systems<T>(n, count, periodic);
        for (Kind kind : kKinds) {
          const auto batch = make_batch(systems, make_layout(kind, n, count));
          for (Method method : {Method::CyclicReduction, Method::ParallelCyclicReduction,
                                Method::Hybrid, Method::Pivoting}) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            const auto x = solve_batch(batch, with(method));
            for (std::ptrdiff_t s = 0; s < count; ++s) {
              const auto row = first_difference(pick(x, batch.layout, s),
                                                solve_system(systems[s], with(method)));
              EXPECT_EQ(row, -1) << "system " << s << " (later systems not compared)";
              if (row >= 0) break;
            }
          }
        }
      }
}

// solve_in_place gives the bits of solve.
TYPED_TEST(SolverBatch, InPlaceEqualsOutOfPlace) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : kRows)
      for (std::ptrdiff_t count : kCounts)
        for (Kind kind : kKinds) {
          const auto batch =
              make_batch(random_systems<T>(n, count, periodic), make_layout(kind, n, count));
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            EXPECT_EQ(first_difference(solve_batch(batch, with(method), Placement::OutOfPlace),
                                       solve_batch(batch, with(method), Placement::InPlace)),
                      -1);
          }
        }
}

// The chunks of a batch do not depend on the number of threads, so neither do the bits.
TYPED_TEST(SolverBatch, OneAndTwoThreadsGiveIdenticalResults) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : kRows)
      for (std::ptrdiff_t count : {17, 33, 100, 300})
        for (Kind kind : kKinds) {
          const auto batch =
              make_batch(random_systems<T>(n, count, periodic), make_layout(kind, n, count));
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            EXPECT_EQ(first_difference(solve_batch(batch, with(method, 1)),
                                       solve_batch(batch, with(method, 2))),
                      -1);
          }
        }
}

// sub[0] and super[n-1] are documented as not read unless periodic: NaN there changes nothing.
TYPED_TEST(SolverBatch, UnreadCornerEntriesDoNotAffectTheResult) {
  using T = TypeParam;
  for (std::ptrdiff_t n : kRows)
    for (std::ptrdiff_t count : kCounts)
      for (Kind kind : kKinds) {
        const auto systems = random_systems<T>(n, count, false);
        const auto clean = make_batch(systems, make_layout(kind, n, count));
        auto dirty = clean;
        for (std::ptrdiff_t s = 0; s < count; ++s) {
          dirty.a[dirty.layout.offset(s, 0)] = sentinel<T>();
          dirty.c[dirty.layout.offset(s, n - 1)] = sentinel<T>();
        }
        for (Method method : kAllMethods) {
          SCOPED_TRACE(::testing::Message() << name(kind) << ", n = " << n << ", count = " << count
                                            << ", method = " << to_string(method));
          EXPECT_EQ(
              first_difference(solve_batch(clean, with(method)), solve_batch(dirty, with(method))),
              -1);
        }
      }
}

// One long system is split into parts (the partitioned Thomas method, parts in SIMD lanes):
// still within the Thomas bounds against the long-double LU.
TYPED_TEST(SolverBatch, LongSystemSplitAcrossThreadsMatchesLongDoubleLu) {
  using T = TypeParam;
  const std::ptrdiff_t n = std::ptrdiff_t(1) << 17;
  const auto system = random_dominant<T>(n, 31337);
  const auto reference = reference_solve(system);
  const long double kappa = condition_bound(system);
  for (Method method : {Method::Auto, Method::Thomas}) {
    SCOPED_TRACE(to_string(method));
    std::vector<T> x(n);
    const auto report = solve(system.a.data(), system.b.data(), system.c.data(), system.d.data(),
                              x.data(), BatchLayout::single(n), with(method, 2));
    EXPECT_GT(report.parts, 1);
    const long double bound = backward_bound<T>(Method::Thomas, n);
    EXPECT_LE(backward_error(system, x), bound);
    EXPECT_LE(forward_error(x, reference), kappa * bound);
  }
}

// ---------------------------------------------------------------------------------------------
// The lines of a 3-D grid along each axis: two batch dimensions (BatchLayout::grid_lines)

struct Grid {
  std::ptrdiff_t extent[3];
  std::ptrdiff_t stride[3];
  const char* order;
};

// Odd sizes, a dimension of 1 and one of 2, padding after every line and plane, and both the
// C order (z fastest) and the Fortran order (x fastest), so each axis is in turn the
// contiguous, the middle and the outer one.
std::vector<Grid> test_grids() {
  std::vector<Grid> grids;
  const std::ptrdiff_t shapes[][3] = {{5, 7, 3}, {33, 2, 17}, {1, 4, 9}};
  for (const auto& e : shapes) {
    // x fastest, 2 elements of padding per line, 3 per plane
    const std::ptrdiff_t fx1 = e[0] + 2, fx2 = fx1 * e[1] + 3;
    grids.push_back({{e[0], e[1], e[2]}, {1, fx1, fx2}, "x fastest"});
    // z fastest, 1 element of padding per line, 5 per plane
    const std::ptrdiff_t cz1 = e[2] + 1, cz0 = cz1 * e[1] + 5;
    grids.push_back({{e[0], e[1], e[2]}, {cz0, cz1, 1}, "z fastest"});
  }
  return grids;
}

TYPED_TEST(SolverBatch, EveryAxisOfAPaddedGridMatchesLongDoubleLu) {
  using T = TypeParam;
  for (const Grid& grid : test_grids())
    for (int axis = 0; axis < 3; ++axis) {
      const BatchLayout layout = BatchLayout::grid_lines(grid.extent, grid.stride, axis);
      const auto systems = random_systems<T>(layout.n, layout.systems(), false);
      const auto batch = make_batch(systems, layout);
      const auto mask = reached(layout);
      for (Method method : kAllMethods)
        for (int threads : {1, 2}) {
          SCOPED_TRACE(::testing::Message()
                       << grid.extent[0] << " x " << grid.extent[1] << " x " << grid.extent[2]
                       << ", " << grid.order << ", axis " << axis
                       << ", method = " << to_string(method) << ", threads " << threads);
          const auto x = solve_batch(batch, with(method, threads));
          for (std::ptrdiff_t s = 0; s < layout.systems(); ++s) {
            const auto xs = pick(x, layout, s);
            const long double bound = backward_bound<T>(method, layout.n);
            ASSERT_LE(backward_error(systems[s], xs), bound) << "system " << s;
            ASSERT_LE(forward_error(xs, reference_solve(systems[s])),
                      condition_bound(systems[s]) * bound)
                << "system " << s;
          }
          for (std::size_t k = 0; k < x.size(); ++k)
            if (!mask[k]) {
              ASSERT_TRUE(same_bits(x[k], sentinel<T>())) << "padding element " << k;
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The diffusion form

// A batch of diffusion systems: beta and rhs per system, and the same in batch storage.
template <class T>
struct DiffusionBatch {
  BatchLayout layout;
  bool periodic = false;
  std::vector<std::vector<real_t<T>>> beta;
  std::vector<std::vector<T>> rhs;
  std::vector<real_t<T>> beta_storage;
  std::vector<T> rhs_storage;
};

// beta uniform in [0, beta_max] (the link n-1 too, read only when periodic), rhs in [-1, 1].
template <class T>
DiffusionBatch<T> make_diffusion(const BatchLayout& layout, bool periodic, real_t<T> beta_max,
                                 std::uint64_t seed) {
  using R = real_t<T>;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<R> conductance(0, beta_max);
  DiffusionBatch<T> batch;
  batch.layout = layout;
  batch.periodic = periodic;
  for (std::ptrdiff_t s = 0; s < layout.systems(); ++s) {
    std::vector<R> beta(layout.n);
    std::vector<T> rhs(layout.n);
    for (std::ptrdiff_t i = 0; i < layout.n; ++i) {
      beta[i] = conductance(random);
      rhs[i] = random_scalar<T>(random, -1, 1);
    }
    batch.beta.push_back(beta);
    batch.rhs.push_back(rhs);
  }
  batch.beta_storage = spread(layout, batch.beta);
  batch.rhs_storage = spread(layout, batch.rhs);
  return batch;
}

template <class T>
std::vector<T> solve_diffusion_batch(const DiffusionBatch<T>& batch, SolveOptions options,
                                     Placement placement = Placement::OutOfPlace) {
  options.periodic = batch.periodic;
  std::vector<T> x(storage_size(batch.layout), sentinel<T>());
  if (placement == Placement::InPlace) {
    x = batch.rhs_storage;
    solve_diffusion(batch.beta_storage.data(), x.data(), x.data(), batch.layout, options);
  } else {
    solve_diffusion(batch.beta_storage.data(), batch.rhs_storage.data(), x.data(), batch.layout,
                    options);
  }
  return x;
}

// The three diagonals of seed 000 eq. 3.10, formed in long double from beta (exact), as an
// independent statement of the matrix the diffusion form stands for:
//   a_i = -beta_{i-1},  b_i = 1 + beta_{i-1} + beta_i,  c_i = -beta_i,
// with beta_{-1} = beta_{n-1} = 0, or, periodic, beta_{-1} = beta_{n-1} linking x_{n-1} and x_0.
template <class T>
System<Wide<T>> expanded(const std::vector<real_t<T>>& beta, const std::vector<T>& rhs,
                         bool periodic) {
  using W = Wide<T>;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(rhs.size());
  System<W> s;
  s.periodic = periodic;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const long double left = i > 0 ? beta[i - 1] : (periodic ? beta[n - 1] : 0.0L);
    const long double right = (i + 1 < n || periodic) ? beta[i] : 0.0L;
    s.a.push_back(W(-left));
    s.b.push_back(W(1 + left + right));
    s.c.push_back(W(-right));
    s.d.push_back(static_cast<W>(rhs[i]));
  }
  return s;
}

template <class T>
std::vector<Wide<T>> widen(const std::vector<T>& x) {
  return std::vector<Wide<T>>(x.begin(), x.end());
}

template <class T>
void check_diffusion_against_reference(bool periodic) {
  for (std::ptrdiff_t n : kRows)
    for (std::ptrdiff_t count : kCounts)
      for (Kind kind : kKinds) {
        const auto batch =
            make_diffusion<T>(make_layout(kind, n, count), periodic, 4, 17 * n + count);
        for (Method method : kAllMethods) {
          SCOPED_TRACE(::testing::Message()
                       << name(kind) << ", n = " << n << ", count = " << count
                       << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
          const auto x = solve_diffusion_batch(batch, with(method));
          for (std::ptrdiff_t s = 0; s < count; ++s) {
            const auto system = expanded<T>(batch.beta[s], batch.rhs[s], periodic);
            const auto xs = pick(x, batch.layout, s);
            const long double bound = backward_bound<T>(method, n);
            ASSERT_LE(backward_error(system, widen(xs)), bound) << "system " << s;
            ASSERT_LE(forward_error(xs, reference_solve(system)), condition_bound(system) * bound)
                << "system " << s;
          }
        }
      }
}

template <class T>
class SolverDiffusionBatch : public ::testing::Test {};
TYPED_TEST_SUITE(SolverDiffusionBatch, Scalars);

TYPED_TEST(SolverDiffusionBatch, MatchesExpandedSystemInEveryLayout) {
  check_diffusion_against_reference<TypeParam>(false);
}

TYPED_TEST(SolverDiffusionBatch, PeriodicMatchesExpandedSystemInEveryLayout) {
  check_diffusion_against_reference<TypeParam>(true);
}

// The diffusion form on every axis of the padded grids: one call per axis, as an ADI step on
// a 3-D grid makes it.
TYPED_TEST(SolverDiffusionBatch, EveryAxisOfAPaddedGridMatchesExpandedSystem) {
  using T = TypeParam;
  for (const Grid& grid : test_grids())
    for (int axis = 0; axis < 3; ++axis)
      for (bool periodic : {false, true}) {
        const BatchLayout layout = BatchLayout::grid_lines(grid.extent, grid.stride, axis);
        const auto batch = make_diffusion<T>(layout, periodic, 4, 31 * axis + layout.systems());
        for (Method method : kAllMethods) {
          SCOPED_TRACE(::testing::Message()
                       << grid.extent[0] << " x " << grid.extent[1] << " x " << grid.extent[2]
                       << ", " << grid.order << ", axis " << axis
                       << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
          const auto x = solve_diffusion_batch(batch, with(method));
          for (std::ptrdiff_t s = 0; s < layout.systems(); ++s) {
            const auto system = expanded<T>(batch.beta[s], batch.rhs[s], periodic);
            const auto xs = pick(x, layout, s);
            const long double bound = backward_bound<T>(method, layout.n);
            ASSERT_LE(backward_error(system, widen(xs)), bound) << "system " << s;
            ASSERT_LE(forward_error(xs, reference_solve(system)), condition_bound(system) * bound)
                << "system " << s;
          }
        }
      }
}

// Every column of the diffusion matrix sums to 1 (a_{i+1} + b_i + c_{i-1} = 1), so
// sum(x) = sum(rhs) in exact arithmetic. Rounding: the computed x solves (A + dA) x = rhs with
// |dA| <= eta |A| (eta the backward bound; Thomas on this M-matrix is componentwise backward
// stable), so |sum(rhs) - sum(x)| = |sum(dA x)| <= eta * sum_j (sum_i |A_ij|) |x_j|.
TYPED_TEST(SolverDiffusionBatch, ConservesMass) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : {2, 5, 40, 1000})
      for (std::ptrdiff_t count : {1, 33, 100})
        for (Kind kind : {Kind::Rows, Kind::Columns}) {
          const auto batch = make_diffusion<T>(make_layout(kind, n, count), periodic, 4, n + count);
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            const auto x = solve_diffusion_batch(batch, with(method));
            for (std::ptrdiff_t s = 0; s < count; ++s) {
              const auto system = expanded<T>(batch.beta[s], batch.rhs[s], periodic);
              const auto xs = widen(pick(x, batch.layout, s));
              Wide<T> mass_x = 0, mass_rhs = 0;
              long double weight = 0;
              for (std::ptrdiff_t j = 0; j < n; ++j) {
                mass_x += xs[j];
                mass_rhs += system.d[j];
                // sum_i |A_ij| = b_j + |c_{j-1}| + |a_{j+1}| = 1 + 2 (beta_{j-1} + beta_j)
                weight += (2 * std::abs(system.b[j]) - 1) * std::abs(xs[j]);
              }
              ASSERT_LE(std::abs(mass_x - mass_rhs), backward_bound<T>(method, n) * weight)
                  << "system " << s;
            }
          }
        }
}

// Every part (real; real and imaginary for complex, A being real) of x lies within
// [min, max] of the same part of rhs, widened by `slack` (the maximum principle).
template <class T>
void expect_within_range(const std::vector<T>& x, const std::vector<T>& rhs, long double slack,
                         std::ptrdiff_t system) {
  auto parts = [](const T& v) -> std::vector<real_t<T>> {
    if constexpr (is_complex_v<T>)
      return {v.real(), v.imag()};
    else
      return {v};
  };
  for (std::size_t p = 0; p < parts(T()).size(); ++p) {
    long double low = INFINITY, high = -INFINITY;
    for (const T& v : rhs) {
      low = std::min<long double>(low, parts(v)[p]);
      high = std::max<long double>(high, parts(v)[p]);
    }
    for (std::size_t i = 0; i < x.size(); ++i) {
      EXPECT_GE(parts(x[i])[p], low - slack) << "system " << system << ", row " << i;
      EXPECT_LE(parts(x[i])[p], high + slack) << "system " << system << ", row " << i;
    }
  }
}

// The diffusion matrix is an M-matrix whose rows sum to 1, so A^-1 >= 0 and A^-1 1 = 1: x is a
// convex combination of rhs and min(rhs) <= x <= max(rhs) (for complex, separately for the
// real and imaginary parts, A being real). Rounding: ||A^-1||_inf = 1, so
// |x - x_exact| <= ||rhs - A x||_inf <= eta (||A||_inf ||x||_inf + ||rhs||_inf).
TYPED_TEST(SolverDiffusionBatch, ObeysMaximumPrinciple) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : {2, 5, 40, 1000})
      for (std::ptrdiff_t count : {1, 33, 100})
        for (Kind kind : {Kind::Rows, Kind::Columns}) {
          const auto batch =
              make_diffusion<T>(make_layout(kind, n, count), periodic, 4, 3 * n + count);
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            const auto x = solve_diffusion_batch(batch, with(method));
            for (std::ptrdiff_t s = 0; s < count; ++s) {
              const auto system = expanded<T>(batch.beta[s], batch.rhs[s], periodic);
              const auto xs = pick(x, batch.layout, s);
              long double norm_a = 0, norm_x = 0, norm_rhs = 0;
              for (std::ptrdiff_t i = 0; i < n; ++i) {
                norm_a = std::max(norm_a, 2 * std::abs(system.b[i]) - 1);  // row sum of |A|
                norm_x = std::max(norm_x, magnitude(xs[i]));
                norm_rhs = std::max(norm_rhs, magnitude(batch.rhs[s][i]));
              }
              const long double slack = backward_bound<T>(method, n) * (norm_a * norm_x + norm_rhs);
              expect_within_range(xs, batch.rhs[s], slack, s);
            }
          }
        }
}

// Large conductances (beta up to 1e6, as in a strongly blurred image) with the diffusion-form
// kernel (Thomas, Auto): its recurrences add and multiply only non-negative terms, so x stays
// a convex combination of rhs to rounding error. Each of the n forward and n backward steps
// rounds a few non-negative terms (at most 4 operations each), so the computed weights are off
// by at most 8 (n + 1) u relatively, and min(rhs) - 8 (n + 1) u max|rhs| <= x <= max(rhs) + ...
// (The expanded methods subtract, and are held only to the normwise bound above.)
TYPED_TEST(SolverDiffusionBatch, LargeBetaKeepsSolutionWithinRhsRange) {
  using T = TypeParam;
  using R = real_t<T>;
  for (std::ptrdiff_t n : {2, 40, 1000})
    for (std::ptrdiff_t count : {1, 33, 100})
      for (Kind kind : kKinds) {
        const auto batch =
            make_diffusion<T>(make_layout(kind, n, count), false, R(1e6), 5 * n + count);
        for (Method method : {Method::Auto, Method::Thomas}) {
          SCOPED_TRACE(::testing::Message() << name(kind) << ", n = " << n << ", count = " << count
                                            << ", method = " << to_string(method));
          const auto x = solve_diffusion_batch(batch, with(method));
          for (std::ptrdiff_t s = 0; s < count; ++s) {
            const auto xs = pick(x, batch.layout, s);
            long double norm_rhs = 0;
            for (const T& v : batch.rhs[s]) norm_rhs = std::max(norm_rhs, magnitude(v));
            const long double slack = 8 * (n + 1) * unit_roundoff<T>() * norm_rhs;
            expect_within_range(xs, batch.rhs[s], slack, s);
          }
        }
      }
}

// With beta = 0 the matrix is the identity: x == rhs exactly, by every method.
TYPED_TEST(SolverDiffusionBatch, ZeroBetaReturnsRhsExactly) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : kRows)
      for (std::ptrdiff_t count : kCounts)
        for (Kind kind : kKinds) {
          const auto batch = make_diffusion<T>(make_layout(kind, n, count), periodic, 0, n + count);
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            const auto x = solve_diffusion_batch(batch, with(method));
            for (std::ptrdiff_t s = 0; s < count; ++s) {
              const auto xs = pick(x, batch.layout, s);
              for (std::ptrdiff_t i = 0; i < n; ++i)
                ASSERT_EQ(xs[i], batch.rhs[s][i]) << "system " << s << ", row " << i;
            }
          }
        }
}

TYPED_TEST(SolverDiffusionBatch, InPlaceEqualsOutOfPlace) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : kRows)
      for (std::ptrdiff_t count : kCounts)
        for (Kind kind : kKinds) {
          const auto batch = make_diffusion<T>(make_layout(kind, n, count), periodic, 4, n * count);
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            EXPECT_EQ(
                first_difference(solve_diffusion_batch(batch, with(method)),
                                 solve_diffusion_batch(batch, with(method), Placement::InPlace)),
                -1);
          }
        }
}

TYPED_TEST(SolverDiffusionBatch, OneAndTwoThreadsGiveIdenticalResults) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : kRows)
      for (std::ptrdiff_t count : {17, 33, 100, 300})
        for (Kind kind : kKinds) {
          const auto batch =
              make_diffusion<T>(make_layout(kind, n, count), periodic, 4, n + 5 * count);
          for (Method method : kAllMethods) {
            SCOPED_TRACE(::testing::Message()
                         << name(kind) << ", n = " << n << ", count = " << count
                         << ", method = " << to_string(method) << (periodic ? ", periodic" : ""));
            EXPECT_EQ(first_difference(solve_diffusion_batch(batch, with(method, 1)),
                                       solve_diffusion_batch(batch, with(method, 2))),
                      -1);
          }
        }
}

// Nothing outside the layout is written by the diffusion form either (rhs and beta padding
// hold the NaN sentinel too, so reading it would also show).
TYPED_TEST(SolverDiffusionBatch, PaddingOutsideTheLayoutIsLeftUntouched) {
  using T = TypeParam;
  for (bool periodic : {false, true})
    for (std::ptrdiff_t n : {1, 5, 40})
      for (std::ptrdiff_t count : kCounts)
        for (Kind kind : kKinds) {
          const auto batch = make_diffusion<T>(make_layout(kind, n, count), periodic, 4, n + count);
          const auto mask = reached(batch.layout);
          for (Method method : kAllMethods)
            for (Placement placement : {Placement::OutOfPlace, Placement::InPlace}) {
              SCOPED_TRACE(::testing::Message()
                           << name(kind) << ", n = " << n << ", count = " << count
                           << ", method = " << to_string(method)
                           << (placement == Placement::InPlace ? ", in place" : "")
                           << (periodic ? ", periodic" : ""));
              const auto x = solve_diffusion_batch(batch, with(method), placement);
              for (std::size_t k = 0; k < x.size(); ++k)
                if (!mask[k]) {
                  ASSERT_TRUE(same_bits(x[k], sentinel<T>())) << "element " << k;
                }
            }
        }
}

// beta[n-1] is not part of a non-periodic system: NaN there changes nothing.
TYPED_TEST(SolverDiffusionBatch, UnreadLastBetaDoesNotAffectTheResult) {
  using T = TypeParam;
  using R = real_t<T>;
  for (std::ptrdiff_t n : kRows)
    for (std::ptrdiff_t count : kCounts)
      for (Kind kind : kKinds) {
        const auto clean = make_diffusion<T>(make_layout(kind, n, count), false, 4, n + 7 * count);
        auto dirty = clean;
        for (std::ptrdiff_t s = 0; s < count; ++s)
          dirty.beta_storage[dirty.layout.offset(s, n - 1)] = sentinel<R>();
        for (Method method : kAllMethods) {
          SCOPED_TRACE(::testing::Message() << name(kind) << ", n = " << n << ", count = " << count
                                            << ", method = " << to_string(method));
          EXPECT_EQ(first_difference(solve_diffusion_batch(clean, with(method)),
                                     solve_diffusion_batch(dirty, with(method))),
                    -1);
        }
      }
}

}  // namespace
}  // namespace tridiff::test
