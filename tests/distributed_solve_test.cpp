// tridiff::distributed::solve and solve_diffusion across the ranks of MPI_COMM_WORLD (run by
// mpirun on 1 to 4 ranks): every slab of every system against the long-double dense LU of the
// whole system and against the single-process tridiff::solve; failures found on one rank
// thrown on every rank; arguments the ranks disagree on refused on every rank.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "reference.hpp"
#include "tridiff/distributed/solve.hpp"
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

// Forward error of the slab against the reference, relative to the largest reference entry.
template <class T>
long double slab_error(const Problem<T>& p, const Slab<T>& slab) {
  long double worst = 0;
  for (std::ptrdiff_t s = 0; s < p.count; ++s) {
    long double scale = 0;
    for (std::ptrdiff_t i = 0; i < p.n; ++i) scale = std::max(scale, std::abs(p.reference[s][i]));
    for (std::ptrdiff_t i = 0; i < slab.layout.n; ++i) {
      const long double error =
          std::abs(static_cast<long double>(slab.x[slab.layout.offset(s, i)]) -
                   p.reference[s][slab.first + i]);
      worst = std::max(worst, error / scale);
    }
  }
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

template <class T>
void check_every_cut(bool periodic, bool diffusion) {
  const World world;
  const int P = world.size;
  for (const std::ptrdiff_t n :
       {std::ptrdiff_t(P), std::ptrdiff_t(P + 1), std::ptrdiff_t(2 * P), std::ptrdiff_t(3 * P + 2),
        std::ptrdiff_t(33), std::ptrdiff_t(129)}) {
    const Problem<T> problem(n, kCount, periodic, diffusion);
    for (const Cut cut : {Cut::Even, Cut::LastRankOneRow, Cut::FirstRankOneRow, Cut::Skewed}) {
      const auto rows = slab_rows(n, P, cut);
      for (const bool interleaved : {true, false}) {
        Slab<T> slab(problem, first_row(rows, world.rank), rows[world.rank], interleaved);
        const auto report = solve_slab(problem, slab);
        EXPECT_EQ(report.global_n, n);
        EXPECT_EQ(report.first_row, slab.first);
        EXPECT_LE(slab_error(problem, slab), tolerance<T>(n))
            << "n " << n << ", cut " << int(cut) << ", interleaved " << interleaved << ", rank "
            << world.rank << " of " << P;
      }
    }
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
  explicit Setup(std::ptrdiff_t rows_per_rank, bool diffusion = false)
      : n(rows_per_rank * world.size),
        problem(n, kCount, false, diffusion),
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
