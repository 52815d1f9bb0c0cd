// tridiff::distributed::solve and solve_diffusion across the ranks of MPI_COMM_WORLD (run by
// mpirun on 1 to 4 ranks): every slab of every system against the long-double dense LU of the
// whole system and against the single-process tridiff::solve; the diffusion form at large
// conductances against a subtraction-free elimination in long double; failures found on one rank
// thrown on every rank; arguments the ranks disagree on refused on every rank.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "reference.hpp"
#include "tridiff/distributed/solve.hpp"
#include "tridiff/solvers/detail/subnormals.hpp"
#include "tridiff/solvers.hpp"

namespace {

using tridiff::BatchLayout;
using tridiff::real_t;
using tridiff::test::System;

struct World {
  int rank = 0, size = 1;
  World() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
  }
};

// How the n rows of a system are cut into slabs, one per rank (each at least one row).
enum class Cut { Even, LastRankOneRow, FirstRankOneRow, Skewed };

std::vector<std::ptrdiff_t> slab_rows(std::ptrdiff_t n, int ranks, Cut cut) {
  std::vector<std::ptrdiff_t> rows(ranks);
  auto even = [&](std::ptrdiff_t total, int parts, int offset) {
    for (int q = 0; q < parts; ++q) rows[offset + q] = total * (q + 1) / parts - total * q / parts;
  };
  if (ranks == 1 || cut == Cut::Even || n < 2 * ranks) {
    even(n, ranks, 0);
  } else if (cut == Cut::LastRankOneRow) {
    even(n - 1, ranks - 1, 0);
    rows[ranks - 1] = 1;
  } else if (cut == Cut::FirstRankOneRow) {
    rows[0] = 1;
    even(n - 1, ranks - 1, 1);
  } else {  // rank q gets about (q + 1) shares: every slab a different length
    const std::ptrdiff_t shares = ranks * (ranks + 1) / 2;
    std::ptrdiff_t given = 0;
    for (int q = 0; q < ranks; ++q) {
      rows[q] = std::max<std::ptrdiff_t>(1, (n - ranks) * (q + 1) / shares + 1);
      given += rows[q];
    }
    rows[ranks - 1] += n - given;
  }
  return rows;
}

std::ptrdiff_t first_row(const std::vector<std::ptrdiff_t>& rows, int rank) {
  std::ptrdiff_t first = 0;
  for (int q = 0; q < rank; ++q) first += rows[q];
  return first;
}

// The diffusion system of beta (seed 000 eq. 3.10) as three diagonals, for the dense reference.
template <class T>
System<T> expand(const std::vector<real_t<T>>& beta, const std::vector<T>& d, bool periodic) {
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(d.size());
  System<T> s;
  s.periodic = periodic;
  s.d = d;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const real_t<T> left = i > 0 ? beta[i - 1] : (periodic ? beta[n - 1] : 0);
    const real_t<T> right = i + 1 < n || periodic ? beta[i] : 0;
    s.a.push_back(T(-left));
    s.b.push_back(T(1 + left + right));
    s.c.push_back(T(-right));
  }
  return s;
}

// `count` random systems of n rows (the same on every rank: same seeds), their conductances for
// the diffusion form, and their long-double solutions.
template <class T>
struct Problem {
  std::ptrdiff_t n = 0, count = 0;
  bool periodic = false, diffusion = false;
  std::vector<System<T>> systems;
  std::vector<std::vector<real_t<T>>> beta;
  std::vector<tridiff::test::WideVector<T>> reference;

  Problem(std::ptrdiff_t n_, std::ptrdiff_t count_, bool periodic_, bool diffusion_)
      : n(n_), count(count_), periodic(periodic_), diffusion(diffusion_) {
    for (std::ptrdiff_t s = 0; s < count; ++s) {
      const std::uint64_t seed = 1000 * n + 7 * s + (periodic ? 1 : 0);
      System<T> system = tridiff::test::random_dominant<T>(n, seed, periodic);
      if (diffusion) {
        std::mt19937_64 random(seed);
        std::uniform_real_distribution<real_t<T>> uniform(0, 3);
        beta.emplace_back(n);
        for (auto& b : beta.back()) b = uniform(random);
        system = expand<T>(beta.back(), system.d, periodic);
      }
      reference.push_back(tridiff::test::reference_solve(system));
      systems.push_back(std::move(system));
    }
  }

  // An empty batch of diffusion systems, filled by add() with conductances, rhs and reference
  // solution (of systems[s] only d is read: its diagonals, rounded to T, are not what the
  // diffusion form solves).
  Problem(std::ptrdiff_t n_, bool periodic_) : n(n_), periodic(periodic_), diffusion(true) {}

  void add(std::vector<real_t<T>> conductances, const std::vector<T>& d,
           const std::vector<long double>& solution) {
    systems.push_back(expand<T>(conductances, d, periodic));
    beta.push_back(std::move(conductances));
    reference.push_back(Eigen::Map<const tridiff::test::WideVector<T>>(solution.data(), n));
    ++count;
  }
};

// This rank's slab of every system in one of two layouts: systems interleaved (element i of
// system s at i * count + s: the lanes load as vectors) or one after another (gathered lanes).
template <class T>
struct Slab {
  BatchLayout layout;
  std::vector<T> a, b, c, d, x;
  std::vector<real_t<T>> beta;
  std::ptrdiff_t first = 0;

  Slab(const Problem<T>& p, std::ptrdiff_t first_, std::ptrdiff_t rows, bool interleaved)
      : first(first_) {
    layout = interleaved ? BatchLayout::columns(rows, p.count, p.count)
                         : BatchLayout::rows(rows, p.count, rows);
    const std::size_t size = static_cast<std::size_t>(rows * p.count);
    a.resize(size);
    b.resize(size);
    c.resize(size);
    d.resize(size);
    x.assign(size, T(0));
    beta.resize(size);
    for (std::ptrdiff_t s = 0; s < p.count; ++s)
      for (std::ptrdiff_t i = 0; i < rows; ++i) {
        const auto at = layout.offset(s, i);
        const System<T>& system = p.systems[s];
        a[at] = system.a[first + i];
        b[at] = system.b[first + i];
        c[at] = system.c[first + i];
        d[at] = system.d[first + i];
        if (p.diffusion) beta[at] = p.beta[s][first + i];
      }
  }
};

template <class T>
tridiff::distributed::Report solve_slab(const Problem<T>& p, Slab<T>& slab,
                                        tridiff::distributed::Options options = {}) {
  options.periodic = p.periodic;
  if (p.diffusion)
    return tridiff::distributed::solve_diffusion<T>(slab.beta.data(), slab.d.data(), slab.x.data(),
                                                    slab.layout, MPI_COMM_WORLD, options);
  return tridiff::distributed::solve(slab.a.data(), slab.b.data(), slab.c.data(), slab.d.data(),
                                     slab.x.data(), slab.layout, MPI_COMM_WORLD, options);
}

// Calls visit(system, global row, x) for every row of every system in the slab.
template <class T, class Visit>
void for_each_row(const Slab<T>& slab, Visit&& visit) {
  for (std::ptrdiff_t s = 0; s < slab.layout.count; ++s)
    for (std::ptrdiff_t i = 0; i < slab.layout.n; ++i)
      visit(s, slab.first + i, static_cast<long double>(slab.x[slab.layout.offset(s, i)]));
}

// Forward error of the slab against the reference, relative to the largest reference entry.
template <class T>
long double slab_error(const Problem<T>& p, const Slab<T>& slab) {
  std::vector<long double> scale;
  for (const auto& reference : p.reference) scale.push_back(reference.cwiseAbs().maxCoeff());
  long double worst = 0;
  for_each_row(slab, [&](std::ptrdiff_t s, std::ptrdiff_t i, long double x) {
    worst = std::max(worst, std::abs(x - p.reference[s][i]) / scale[s]);
  });
  return worst;
}

// Dominant systems (cond <= 3 by construction, <= ~4 for diffusion with beta <= 3): Thomas-like
// elimination errs by a few ulps per row touched; the partitioned path adds the reduced solve.
template <class T>
long double tolerance(std::ptrdiff_t n) {
  return 64 * std::numeric_limits<T>::epsilon() * std::log2(2.0 * n);
}

template <class T>
class DistributedSolve : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(DistributedSolve, Scalars);

// 70 systems: one or two full chunks of SIMD lanes and a tail solved lane by lane.
constexpr std::ptrdiff_t kCount = 70;

// Solves the problem cut into slabs in every way (each Cut, systems interleaved or not) and
// hands this rank's solved slab to check(slab).
template <class T, class Check>
void solve_every_cut(const Problem<T>& problem, Check&& check) {
  const World world;
  for (const Cut cut : {Cut::Even, Cut::LastRankOneRow, Cut::FirstRankOneRow, Cut::Skewed}) {
    const auto rows = slab_rows(problem.n, world.size, cut);
    for (const bool interleaved : {true, false}) {
      SCOPED_TRACE(::testing::Message()
                   << "n " << problem.n << ", cut " << int(cut) << ", interleaved " << interleaved
                   << ", rank " << world.rank << " of " << world.size);
      Slab<T> slab(problem, first_row(rows, world.rank), rows[world.rank], interleaved);
      tridiff::distributed::Report report;
      try {  // thrown on every rank alike, so every rank goes on to the next cut
        report = solve_slab(problem, slab);
      } catch (const tridiff::Error& e) {
        ADD_FAILURE() << e.what();
        continue;
      }
      EXPECT_EQ(report.global_n, problem.n);
      EXPECT_EQ(report.first_row, slab.first);
      check(slab);
    }
  }
}

template <class T>
void check_every_cut(bool periodic, bool diffusion) {
  const int P = World().size;
  for (const std::ptrdiff_t n :
       {std::ptrdiff_t(P), std::ptrdiff_t(P + 1), std::ptrdiff_t(2 * P), std::ptrdiff_t(3 * P + 2),
        std::ptrdiff_t(33), std::ptrdiff_t(129)}) {
    const Problem<T> problem(n, kCount, periodic, diffusion);
    solve_every_cut(problem, [&](const Slab<T>& slab) {
      EXPECT_LE(slab_error(problem, slab), tolerance<T>(n));
    });
  }
}

TYPED_TEST(DistributedSolve, GeneralFormMatchesDenseReference) {
  check_every_cut<TypeParam>(false, false);
}

TYPED_TEST(DistributedSolve, PeriodicGeneralFormMatchesDenseReference) {
  check_every_cut<TypeParam>(true, false);
}

TYPED_TEST(DistributedSolve, DiffusionFormMatchesDenseReference) {
  check_every_cut<TypeParam>(false, true);
}

TYPED_TEST(DistributedSolve, PeriodicDiffusionFormMatchesDenseReference) {
  check_every_cut<TypeParam>(true, true);
}

// The distributed solve and the single-process tridiff::solve of the whole systems agree to
// the rounding of either (both against the same slab, n a power of two plus one).
TYPED_TEST(DistributedSolve, AgreesWithSingleProcessSolve) {
  using T = TypeParam;
  const World world;
  for (const bool diffusion : {false, true}) {
    const std::ptrdiff_t n = 257;
    const Problem<T> problem(n, kCount, false, diffusion);
    const auto rows = slab_rows(n, world.size, Cut::Skewed);
    Slab<T> slab(problem, first_row(rows, world.rank), rows[world.rank], true);
    solve_slab(problem, slab);
    for (std::ptrdiff_t s = 0; s < kCount; ++s) {
      const System<T>& system = problem.systems[s];
      std::vector<T> whole(n);
      if (diffusion)
        tridiff::solve_diffusion<T>(problem.beta[s].data(), system.d.data(), whole.data(),
                                    BatchLayout::single(n));
      else
        tridiff::solve(system.a.data(), system.b.data(), system.c.data(), system.d.data(),
                       whole.data(), BatchLayout::single(n));
      for (std::ptrdiff_t i = 0; i < slab.layout.n; ++i)
        ASSERT_NEAR(slab.x[slab.layout.offset(s, i)], whole[slab.first + i], tolerance<T>(n))
            << "system " << s << ", row " << slab.first + i;
    }
  }
}

// In place (x is rhs), and with two OpenMP threads per rank: the same numbers.
TYPED_TEST(DistributedSolve, InPlaceAndThreadedGiveTheSameSolution) {
  using T = TypeParam;
  const World world;
  const Problem<T> problem(100, 3 * kCount, false, false);
  const auto rows = slab_rows(100, world.size, Cut::Even);
  Slab<T> plain(problem, first_row(rows, world.rank), rows[world.rank], true);
  solve_slab(problem, plain);
  Slab<T> other(problem, first_row(rows, world.rank), rows[world.rank], true);
  tridiff::distributed::Options options;
  options.threads = 2;
  tridiff::distributed::solve(other.a.data(), other.b.data(), other.c.data(), other.d.data(),
                              other.d.data(), other.layout, MPI_COMM_WORLD, options);
  EXPECT_EQ(other.d, plain.x);
}

// ---- Large conductances: the diffusion form keeps the 1 of 1 + beta + beta'. ----

// An open chain of m rows in long double,
//   -link[i-1] x[i-1] + (1 + link[i-1] + link[i]) x[i] - link[i] x[i+1] = d[i],
// whose end links, link[-1] = lo and link[m-1] = hi, lead to a node held at 0 (the ring's cut
// row, for a periodic system). Eliminated without a subtraction: pivot_i = g_i + link[i] with
// g_i = 1 + link[i-1] e_{i-1} and e_i = g_i / pivot_i (e_{-1} = 1), so the 1 is never added to
// a large beta, and every quantity, a sum or product of non-negative numbers, keeps its relative
// accuracy whatever beta is. Thomas on the expanded diagonal would not do as a reference: in
// long double, 1 + 2e15 holds its 1 only to 1e-4.
struct Chain {
  std::vector<long double> left, right, pivot;  // per row: its two links and its pivot

  Chain(const std::vector<long double>& links, long double lo, long double hi) {
    left.push_back(lo);
    left.insert(left.end(), links.begin(), links.end());
    right = links;
    right.push_back(hi);
    long double e = 1;  // x_{-1} is held: all of lo leaks out of row 0
    for (std::size_t i = 0; i < left.size(); ++i) {
      const long double g = 1 + left[i] * e;
      pivot.push_back(g + right[i]);
      e = g / pivot.back();
    }
  }

  std::vector<long double> solve(const std::vector<long double>& d) const {
    std::vector<long double> x(d.size());
    long double carry = 0;
    for (std::size_t i = 0; i < d.size(); ++i) x[i] = carry = (d[i] + left[i] * carry) / pivot[i];
    for (std::size_t i = d.size() - 1; i-- > 0;) x[i] += right[i] / pivot[i] * x[i + 1];
    return x;
  }
};

// The system expand() builds, solved in long double without a subtraction (independent of the
// code under test). A ring is cut at row 0: rows 1..n-1 form an open chain whose two ends link
// to x_0, so x_i = u_i + v_i x_0, u the chain's solution for d, v for the coupling (beta_0 at
// row 1, beta_{n-1} at row n-1), and row 0 reads
//   (1 + beta_{n-1} (1 - v_{n-1}) + beta_0 (1 - v_1)) x_0 = d_0 + beta_{n-1} u_{n-1} + beta_0 u_1
// where 1 - v is w, the chain's solution for all ones: solved for, not subtracted.
template <class T>
std::vector<long double> subtraction_free_solve(const std::vector<real_t<T>>& beta,
                                                const std::vector<T>& d, bool periodic) {
  const std::vector<long double> b(beta.begin(), beta.end()), rhs(d.begin(), d.end());
  const std::size_t n = rhs.size();
  if (!periodic) return Chain({b.begin(), b.end() - 1}, 0, 0).solve(rhs);
  if (n == 1) return rhs;  // the link joins row 0 to itself: 1 x = d
  const Chain chain({b.begin() + 1, b.end() - 1}, b[0], b[n - 1]);
  std::vector<long double> coupling(n - 1, 0);
  coupling.front() += b[0];
  coupling.back() += b[n - 1];  // with n = 2, both links reach row 1
  const auto u = chain.solve({rhs.begin() + 1, rhs.end()});
  const auto v = chain.solve(coupling);
  const auto w = chain.solve(std::vector<long double>(n - 1, 1));
  const long double x0 = (rhs[0] + b[n - 1] * u.back() + b[0] * u.front()) /
                         (1 + b[n - 1] * w.back() + b[0] * w.front());
  std::vector<long double> x{x0};
  for (std::size_t i = 0; i + 1 < n; ++i) x.push_back(u[i] + v[i] * x0);
  return x;
}

// n values in runs of 1 to 8 rows: each run draws a kind, uniform in [0, 1), and takes its
// values from value(kind).
template <class V, class Value>
std::vector<V> in_runs(std::ptrdiff_t n, std::mt19937_64& random, Value&& value) {
  std::uniform_real_distribution<double> unit(0, 1);
  std::uniform_int_distribution<std::ptrdiff_t> length(1, 8);
  std::vector<V> values(n);
  for (std::ptrdiff_t i = 0; i < n;) {
    const double kind = unit(random);
    for (const std::ptrdiff_t end = std::min(n, i + length(random)); i < end; ++i)
      values[i] = V(value(kind));
  }
  return values;
}

// kCount systems (the same on every rank) with conductances log-uniform over [1e-3, largest],
// and runs of exact zeros (the system falls into pieces that do not see each other) and of
// `largest` itself (where the expanded diagonal keeps the fewest digits of its 1); the rhs in
// [0, 1], with steps: runs of exact 0 and 1 between runs of random values.
template <class T>
Problem<T> large_beta_problem(std::ptrdiff_t n, double largest, bool periodic) {
  Problem<T> problem(n, periodic);
  std::mt19937_64 random(1000 * n + 10 * std::lround(std::log10(largest)) + (periodic ? 1 : 0));
  std::uniform_real_distribution<double> exponent(-3, std::log10(largest)), unit(0, 1);
  for (std::ptrdiff_t s = 0; s < kCount; ++s) {
    auto beta = in_runs<real_t<T>>(n, random, [&](double kind) {
      return kind < 0.15 ? 0 : kind < 0.25 ? largest : std::pow(10.0, exponent(random));
    });
    const auto d = in_runs<T>(n, random, [&](double kind) {
      return kind < 0.25 ? 0 : kind < 0.5 ? 1 : unit(random);
    });
    const auto solution = subtraction_free_solve<T>(beta, d, periodic);
    problem.add(std::move(beta), d, solution);
  }
  return problem;
}

// Over the slab: the largest |x - reference|, and the farthest x lies outside [min d, max d] of
// its system.
struct Deviation {
  long double error = 0, outside = 0;
};

template <class T>
Deviation large_beta_deviation(const Problem<T>& p, const Slab<T>& slab) {
  Deviation worst;
  for_each_row(slab, [&](std::ptrdiff_t s, std::ptrdiff_t i, long double x) {
    const auto [low, high] = std::minmax_element(p.systems[s].d.begin(), p.systems[s].d.end());
    worst.error = std::max(worst.error, std::abs(x - p.reference[s][i]));
    worst.outside = std::max({worst.outside, *low - x, x - *high});
  });
  return worst;
}

// The distributed diffusion form at conductances up to 1e7 (float) and 1e15 (double), and near
// max() (1e37, 1e307: two adjacent links still sum below it), every cut of every size, against
// the subtraction-free reference. Near max() the pivots' inverses are near min(): with
// subnormals flushed to zero, float at 1e36 erred by 1e4 eps, silently; with the caller
// flushing, the separators' solve did so too. The diffusion matrix is an M-matrix whose rows
// sum to 1, so its inverse is non-negative with rows summing to 1: x is a convex
// combination of d and lies in [min d, max d] (the maximum principle), and an elimination that
// forms only sums and products of non-negative numbers keeps a few epsilon whatever beta is.
// The single-process solve_diffusion, subtraction-free, measured on such systems (n from 200 to
// 998) at most 0.8 eps log2(2n) from the reference and 5 eps outside the range: the bounds leave
// it 40x and 3x. Eliminating the expanded diagonal 1 + beta + beta' loses its 1, measured here
// on 1 to 4 ranks: 35 to 560 eps log2(2n) at beta 1e3, 3e3 to 5e4 at 1e5 (float), 3e7 to 5e8
// at 1e9 (double), and as far outside the range; at 1e7 (float) and 1e15 (double) every solve
// but the open n = 1 threw (a vanishing pivot, or an overflow blamed on the rhs).
TYPED_TEST(DistributedSolve, DiffusionFormKeepsItsDigitsAtLargeBeta) {
  using T = TypeParam;
  constexpr long double eps = std::numeric_limits<T>::epsilon();
  const std::ptrdiff_t P = World().size;
  const std::vector<double> scales = std::is_same_v<T, float>
                                         ? std::vector<double>{1e3, 1e5, 1e7, 1e37}
                                         : std::vector<double>{1e3, 1e9, 1e15, 1e307};
  for (const bool periodic : {false, true})
    for (const double largest : scales)
      for (const std::ptrdiff_t n : {P, P + 1, std::ptrdiff_t(300)})
        // Near max() also with the caller flushing subnormals (-ffast-math): the solve must
        // keep them where they matter, whatever the caller's state.
        for (const bool caller_flushes : {false, true}) {
          if (caller_flushes && largest < 1e30) continue;
          SCOPED_TRACE(::testing::Message()
                       << "beta up to " << largest << (periodic ? ", periodic" : "")
                       << (caller_flushes ? ", caller flushes" : ""));
          const Problem<T> problem = large_beta_problem<T>(n, largest, periodic);
          std::optional<tridiff::detail::SubnormalsAsZero> flushing;
          if (caller_flushes) flushing.emplace();
          solve_every_cut(problem, [&](const Slab<T>& slab) {
            const Deviation deviation = large_beta_deviation(problem, slab);
            EXPECT_LE(deviation.error, 32 * eps * std::log2(2.0L * n));
            EXPECT_LE(deviation.outside, 16 * eps);
          });
        }
}

// ---- Failures: found on one rank, thrown on every rank. ----

// What expect_thrown returns when the call did not throw the exception it should have.
template <class Exception>
Exception placeholder() {
  if constexpr (std::is_same_v<Exception, tridiff::NumericalError>)
    return Exception(-2, -2, "not thrown");
  else
    return Exception("(not thrown)", "not thrown");
}

// Runs `call` on every rank and returns what it threw.
template <class Exception>
Exception expect_thrown(const std::function<void()>& call) {
  try {
    call();
  } catch (const Exception& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "threw another exception: " << e.what();
    return placeholder<Exception>();
  }
  ADD_FAILURE() << "nothing was thrown";
  return placeholder<Exception>();
}

template <class T>
struct Setup {
  World world;
  std::ptrdiff_t n;
  Problem<T> problem;
  std::vector<std::ptrdiff_t> rows;
  Slab<T> slab;
  explicit Setup(std::ptrdiff_t rows_per_rank, bool diffusion = false, bool periodic = false)
      : n(rows_per_rank * world.size),
        problem(n, kCount, periodic, diffusion),
        rows(slab_rows(n, world.size, Cut::Even)),
        slab(problem, first_row(rows, world.rank), rows[world.rank], true) {}
  // The rank where a failure is planted: rank 2 when there is one.
  int culprit() const { return std::min(2, world.size - 1); }
};

TYPED_TEST(DistributedSolve, SingularSystemOnOneRankIsReportedOnEveryRank) {
  using T = TypeParam;
  Setup<T> setup(5);
  const std::ptrdiff_t system = 5, row = first_row(setup.rows, setup.culprit()) + 2;
  if (setup.world.rank == setup.culprit()) {
    const auto at = setup.slab.layout.offset(system, 2);
    setup.slab.a[at] = setup.slab.b[at] = setup.slab.c[at] = T(0);  // a zero row
  }
  const auto error =
      expect_thrown<tridiff::NumericalError>([&] { solve_slab(setup.problem, setup.slab); });
  EXPECT_EQ(error.system(), system);
  EXPECT_EQ(error.row(), row);
  EXPECT_NE(std::string(error.what()).find("rank " + std::to_string(setup.culprit())),
            std::string::npos)
      << error.what();
}

// Every slab is regular, the whole matrix is not (rows 0 and 1 equal): only the reduced system
// sees it, on the rank that owns it; still reported everywhere, at global row 1.
TYPED_TEST(DistributedSolve, SingularReducedSystemIsReportedOnEveryRank) {
  using T = TypeParam;
  const World world;
  const std::ptrdiff_t n = std::max(world.size, 2);
  const auto rows = slab_rows(n, world.size, Cut::Even);
  const std::ptrdiff_t first = first_row(rows, world.rank), m = rows[world.rank];
  const auto layout = BatchLayout::columns(m, 1, 1);
  std::vector<T> a(m, T(0)), b(m, T(1)), c(m, T(0)), d(m, T(1)), x(m);
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    if (first + i == 0) c[i] = T(1);
    if (first + i == 1) a[i] = T(1);
  }
  const auto error = expect_thrown<tridiff::NumericalError>([&] {
    tridiff::distributed::solve(a.data(), b.data(), c.data(), d.data(), x.data(), layout,
                                MPI_COMM_WORLD);
  });
  EXPECT_EQ(error.system(), 0);
  EXPECT_EQ(error.row(), 1);
}

TYPED_TEST(DistributedSolve, NonFiniteRhsOnOneRankIsNamedOnEveryRank) {
  using T = TypeParam;
  Setup<T> setup(4);
  const std::ptrdiff_t system = 67, row = first_row(setup.rows, setup.culprit()) + 3;
  if (setup.world.rank == setup.culprit())
    setup.slab.d[setup.slab.layout.offset(system, 3)] = std::numeric_limits<T>::quiet_NaN();
  const auto error =
      expect_thrown<tridiff::InvalidArgument>([&] { solve_slab(setup.problem, setup.slab); });
  EXPECT_EQ(error.argument(), "rhs");
  EXPECT_EQ(error.system(), system);
  EXPECT_EQ(error.row(), row);
}

TYPED_TEST(DistributedSolve, NegativeConductanceOnOneRankIsNamedOnEveryRank) {
  using T = TypeParam;
  Setup<T> setup(3, true);
  const std::ptrdiff_t system = 1, row = first_row(setup.rows, setup.culprit()) + 1;
  if (setup.world.rank == setup.culprit())
    setup.slab.beta[setup.slab.layout.offset(system, 1)] = -1;
  const auto error =
      expect_thrown<tridiff::InvalidArgument>([&] { solve_slab(setup.problem, setup.slab); });
  EXPECT_EQ(error.argument(), "beta");
  EXPECT_EQ(error.system(), system);
  EXPECT_EQ(error.row(), row);
}

// The link that closes a periodic ring, beta[n-1] on the last rank, enters rank 0's first row:
// rank 0's reduction fails first and must name it (it named an overflow at its row 0).
TYPED_TEST(DistributedSolve, NonFiniteRingLinkIsNamedOnEveryRank) {
  using T = TypeParam;
  Setup<T> setup(3, true, true);
  const std::ptrdiff_t system = 40;
  if (setup.world.rank == setup.world.size - 1)
    setup.slab.beta[setup.slab.layout.offset(system, 2)] = std::numeric_limits<T>::infinity();
  const auto error =
      expect_thrown<tridiff::InvalidArgument>([&] { solve_slab(setup.problem, setup.slab); });
  EXPECT_EQ(error.argument(), "beta");
  EXPECT_EQ(error.system(), system);
  EXPECT_EQ(error.row(), setup.n - 1);
}

// Arguments refused on every rank, naming the argument, whichever rank got it wrong.
template <class T>
std::string refused_argument(const std::function<void(Setup<T>&)>& spoil) {
  Setup<T> setup(3);
  const auto error = expect_thrown<tridiff::InvalidArgument>([&] { spoil(setup); });
  return error.argument();
}

using tridiff::InvalidArgument;

TYPED_TEST(DistributedSolve, CountsThatDisagreeAreRefusedOnEveryRank) {
  using T = TypeParam;
  if (World().size == 1) GTEST_SKIP() << "needs two ranks";
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              BatchLayout layout = s.slab.layout;
              if (s.world.rank == 1) layout.count -= 1;
              tridiff::distributed::solve(s.slab.a.data(), s.slab.b.data(), s.slab.c.data(),
                                          s.slab.d.data(), s.slab.x.data(), layout, MPI_COMM_WORLD);
            }),
            "layout.count");
}

TYPED_TEST(DistributedSolve, FormsThatDisagreeAreRefusedOnEveryRank) {
  using T = TypeParam;
  if (World().size == 1) GTEST_SKIP() << "needs two ranks";
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              if (s.world.rank == 0)
                tridiff::distributed::solve_diffusion<T>(s.slab.beta.data(), s.slab.d.data(),
                                                         s.slab.x.data(), s.slab.layout,
                                                         MPI_COMM_WORLD);
              else
                solve_slab(s.problem, s.slab);
            }),
            "form");
}

TYPED_TEST(DistributedSolve, PeriodicityThatDisagreesIsRefusedOnEveryRank) {
  using T = TypeParam;
  if (World().size == 1) GTEST_SKIP() << "needs two ranks";
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              tridiff::distributed::Options options;
              options.periodic = s.world.rank == s.world.size - 1;
              tridiff::distributed::solve(s.slab.a.data(), s.slab.b.data(), s.slab.c.data(),
                                          s.slab.d.data(), s.slab.x.data(), s.slab.layout,
                                          MPI_COMM_WORLD, options);
            }),
            "options.periodic");
}

TYPED_TEST(DistributedSolve, SlabsThatDoNotAddUpAreRefusedOnEveryRank) {
  using T = TypeParam;
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              tridiff::distributed::Options options;
              options.global_n = s.n + 1;
              solve_slab(s.problem, s.slab, options);
            }),
            "layout.n");
}

TYPED_TEST(DistributedSolve, NullPointerOnOneRankIsRefusedOnEveryRank) {
  using T = TypeParam;
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              const T* sub = s.world.rank == s.world.size - 1 ? nullptr : s.slab.a.data();
              tridiff::distributed::solve(sub, s.slab.b.data(), s.slab.c.data(), s.slab.d.data(),
                                          s.slab.x.data(), s.slab.layout, MPI_COMM_WORLD);
            }),
            "sub");
}

TYPED_TEST(DistributedSolve, EmptySlabOnOneRankIsRefusedOnEveryRank) {
  using T = TypeParam;
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              BatchLayout layout = s.slab.layout;
              if (s.world.rank == 0) layout.n = 0;
              solve_slab(s.problem, s.slab);  // a clean call first: the state is not sticky
              tridiff::distributed::solve(s.slab.a.data(), s.slab.b.data(), s.slab.c.data(),
                                          s.slab.d.data(), s.slab.x.data(), layout, MPI_COMM_WORLD);
            }),
            "n");
}

// A second batch dimension (BatchLayout::outer_count, the lines of a 3-D grid) is not
// supported across ranks: refused on every rank, naming it, even when one rank alone asks.
TYPED_TEST(DistributedSolve, SecondBatchDimensionIsRefusedOnEveryRank) {
  using T = TypeParam;
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              BatchLayout layout = s.slab.layout;
              if (s.world.rank == 0) {  // the same systems, seen as one outer batch of them
                layout.outer_count = 2;
                layout.count = 1;
                layout.outer_stride = s.slab.layout.system_stride;
              }
              tridiff::distributed::solve(s.slab.a.data(), s.slab.b.data(), s.slab.c.data(),
                                          s.slab.d.data(), s.slab.x.data(), layout, MPI_COMM_WORLD);
            }),
            "outer_count");
}

TYPED_TEST(DistributedSolve, ScalarTypesThatDisagreeAreRefusedOnEveryRank) {
  using T = TypeParam;
  if (World().size == 1) GTEST_SKIP() << "needs two ranks";
  EXPECT_EQ(refused_argument<T>([](Setup<T>& s) {
              if (s.world.rank == 1) {
                std::vector<double> as_double(s.slab.b.begin(), s.slab.b.end());
                std::vector<float> as_float(s.slab.b.begin(), s.slab.b.end());
                std::vector<double> x_double(as_double.size());
                std::vector<float> x_float(as_float.size());
                // The other precision of T.
                if constexpr (std::is_same_v<T, float>)
                  tridiff::distributed::solve(as_double.data(), as_double.data(), as_double.data(),
                                              as_double.data(), x_double.data(), s.slab.layout,
                                              MPI_COMM_WORLD);
                else
                  tridiff::distributed::solve(as_float.data(), as_float.data(), as_float.data(),
                                              as_float.data(), x_float.data(), s.slab.layout,
                                              MPI_COMM_WORLD);
              } else {
                solve_slab(s.problem, s.slab);
              }
            }),
            "T");
}

TEST(DistributedSolveArguments, NullCommunicatorIsRefused) {
  std::vector<float> v(4, 1.f), x(4);
  try {
    tridiff::distributed::solve(v.data(), v.data(), v.data(), v.data(), x.data(),
                                BatchLayout::single(4), MPI_COMM_NULL);
    ADD_FAILURE() << "nothing was thrown";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.argument(), "comm");
  }
}

}  // namespace
