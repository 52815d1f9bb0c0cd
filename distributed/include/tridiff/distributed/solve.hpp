// Batched tridiagonal solves across MPI ranks: every rank holds a contiguous slab of rows of
// every system (the solve direction of a grid cut into slabs). The algorithm of PaScaL_TDMA
// (Kim et al., Comput. Phys. Commun. 2021): each rank reduces its slab to two boundary rows per
// system (modified Thomas), the reduced systems (2 rows per rank) are redistributed by one
// all-to-all so that each rank solves a share of them, their solutions go back by a second
// all-to-all, and each rank finishes its slab.
#pragma once

#include <mpi.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "tridiff/distributed/detail/agree.hpp"
#include "tridiff/distributed/detail/diffusion_slab.hpp"
#include "tridiff/distributed/detail/slab_lanes.hpp"
#include "tridiff/solvers/detail/periodic.hpp"
#include "tridiff/solvers/detail/subnormals.hpp"
#include "tridiff/solvers/detail/thomas.hpp"
#include "tridiff/solvers/detail/workspace.hpp"
#include "tridiff/solvers/solve.hpp"

namespace tridiff::distributed {

struct Options {
  bool periodic = false;  // row 0 couples to row n-1 (sub[0] and super[n-1], on ranks 0 and P-1)
  // The rows every system has across the ranks; 0 accepts what the slabs add up to. Set it to
  // have slabs that do not add up refused (InvalidArgument "layout.n" on every rank).
  std::ptrdiff_t global_n = 0;
  // OpenMP threads of this rank (over groups of systems). 1, not "all cores": MPI programs
  // usually place one rank per core, and more threads would then oversubscribe it.
  int threads = 1;
};

struct Report {
  std::ptrdiff_t global_n = 0;   // rows of each system across all ranks
  std::ptrdiff_t first_row = 0;  // global index of this rank's first row
  int ranks = 1;
  // Where this rank's time went (MPI_Wtime), for cost models: the reduction of the slab, the
  // two all-to-alls with the agreements (waiting for slower ranks included), the share of
  // reduced systems, the finish.
  double reduce_seconds = 0, exchange_seconds = 0, reduced_seconds = 0, finish_seconds = 0;
};

namespace detail {

using tridiff::detail::Strided;

enum class Form : long long { General = 1, Diffusion = 2 };

inline const char* to_string(Form form) {
  return form == Form::General ? "solve (general form)" : "solve_diffusion";
}

// What every rank knows about every other after the handshake.
struct Plan {
  int rank = 0, size = 1;
  std::vector<std::ptrdiff_t> rows, first;  // per rank: slab rows, first global row
  std::ptrdiff_t global_n = 0, count = 0;
  bool periodic = false;

  std::ptrdiff_t block_begin(int q) const { return count * q / size; }  // reduced systems of q
  std::ptrdiff_t reduced_rows(int q) const { return std::min<std::ptrdiff_t>(rows[q], 2); }
  bool open_first() const { return !periodic && rank == 0; }
  bool open_last() const { return !periodic && rank == size - 1; }
  Report report() const { return {global_n, first[rank], size}; }
};

// Collective, first of every call: exchanges each rank's slab shape and the outcome of its own
// argument checks, then refuses on every rank what does not match (the same decision from the
// same gathered numbers, so no further message is needed).
template <class T>
Plan handshake(const BatchLayout& layout, Form form, const Options& options, const Failure& local,
               MPI_Comm comm) {
  Plan plan;
  MPI_Comm_rank(comm, &plan.rank);
  MPI_Comm_size(comm, &plan.size);
  enum { kOk, kRows, kCount, kForm, kPeriodic, kScalar, kGlobal, kFields };
  const long long mine[kFields] = {local ? 0 : 1,
                                   layout.n,
                                   layout.count,
                                   static_cast<long long>(form),
                                   options.periodic ? 1 : 0,
                                   static_cast<long long>(sizeof(T)) * (is_complex_v<T> ? -1 : 1),
                                   options.global_n};
  std::vector<long long> all(static_cast<std::size_t>(kFields) * plan.size);
  MPI_Allgather(mine, kFields, MPI_LONG_LONG, all.data(), kFields, MPI_LONG_LONG, comm);
  auto field = [&](int q, int f) { return all[static_cast<std::size_t>(q) * kFields + f]; };
  for (int q = 0; q < plan.size; ++q)
    if (!field(q, kOk)) agree(local, comm);  // throws on every rank
  for (int q = 1; q < plan.size; ++q) {
    const std::string r = "rank " + std::to_string(q), z = ", rank 0 ";
    if (field(q, kForm) != field(0, kForm))
      throw InvalidArgument("form", r + " calls " + to_string(Form(field(q, kForm))) + z +
                                        "calls " + to_string(Form(field(0, kForm))));
    if (field(q, kScalar) != field(0, kScalar))
      throw InvalidArgument("T", r + " solves with another scalar type than rank 0");
    if (field(q, kCount) != field(0, kCount))
      throw InvalidArgument("layout.count", r + " holds " + std::to_string(field(q, kCount)) +
                                                " systems" + z + "holds " +
                                                std::to_string(field(0, kCount)) +
                                                ": every rank holds a slab of every system");
    if (field(q, kPeriodic) != field(0, kPeriodic))
      throw InvalidArgument("options.periodic", r + " and rank 0 disagree");
    if (field(q, kGlobal) != field(0, kGlobal))
      throw InvalidArgument("options.global_n", r + " and rank 0 disagree");
  }
  plan.count = layout.count;
  plan.periodic = options.periodic;
  for (int q = 0; q < plan.size; ++q) {
    plan.first.push_back(plan.global_n);
    plan.rows.push_back(field(q, kRows));
    plan.global_n += plan.rows.back();
  }
  if (options.global_n > 0 && plan.global_n != options.global_n)
    throw InvalidArgument(
        "layout.n", "the slabs of the ranks add up to " + std::to_string(plan.global_n) +
                        " rows, but " + "options.global_n is " + std::to_string(options.global_n));
  return plan;
}

// Checks every rank makes on its own arguments (their outcome goes into the handshake).
inline void require_comm(MPI_Comm comm) {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) throw InvalidArgument("comm", "MPI is not initialised (call MPI_Init first)");
  if (comm == MPI_COMM_NULL) throw InvalidArgument("comm", "is MPI_COMM_NULL");
}

inline void require_options(const Options& options) {
  resolve_threads(options.threads);
  if (options.global_n < 0)
    throw InvalidArgument("options.global_n", "must be >= 0 (0: what the slabs add up to)");
}

// The arrays of each form, and how W systems of them are read as lanes.
template <class T>
struct GeneralInputs {
  const T *a, *b, *c, *d;
};
template <class T>
struct DiffusionInputs {
  const real_t<T>* beta;
  const T* d;
  const real_t<T>* ghost;  // per system: the link into this slab's first row
};

template <bool kUnit, class T>
GeneralRows<T, kUnit> rows_at(const GeneralInputs<T>& in, const BatchLayout& layout,
                              std::ptrdiff_t system, const Plan& plan) {
  const std::ptrdiff_t o = layout.offset(system, 0);
  return {in.a + o,
          in.b + o,
          in.c + o,
          in.d + o,
          {layout.row_stride, layout.system_stride},
          layout.n,
          plan.open_first(),
          plan.open_last()};
}

template <bool kUnit, class T>
DiffusionRows<T, kUnit> rows_at(const DiffusionInputs<T>& in, const BatchLayout& layout,
                                std::ptrdiff_t system, const Plan& plan) {
  const std::ptrdiff_t o = layout.offset(system, 0);
  return {in.beta + o,       in.d + o,
          in.ghost + system, {layout.row_stride, layout.system_stride},
          layout.n,          plan.open_last()};
}

// After a lane of the reduction failed: throws what is wrong with `system`, naming the global
// row — a coefficient that is not finite (or a negative conductance), else the vanishing pivot.
template <class T, class Rows>
[[noreturn]] void report_pivot(const Rows& rows, std::ptrdiff_t system, const Plan& plan) {
  const std::ptrdiff_t row = plan.first[plan.rank] + first_vanishing_pivot<T>(rows.rows, rows);
  throw NumericalError(system, row,
                       "the pivot vanished: the system is singular, or not diagonally dominant "
                       "(the distributed solve does not pivot)");
}

template <class T>
[[noreturn]] void report_reduction(const GeneralInputs<T>& in, const BatchLayout& layout,
                                   std::ptrdiff_t system, const Plan& plan) {
  const auto rows = rows_at<false>(in, layout, system, plan);
  const std::ptrdiff_t first = plan.first[plan.rank];
  for (std::ptrdiff_t i = 0; i < layout.n; ++i) {
    const auto at = rows.lanes.at(i, 0);
    if (!(i == 0 && rows.open_first) && !tridiff::detail::is_finite(rows.a[at]))
      throw InvalidArgument("sub", system, first + i, "is not finite");
    if (!tridiff::detail::is_finite(rows.b[at]))
      throw InvalidArgument("diag", system, first + i, "is not finite");
    if (!(i == layout.n - 1 && rows.open_last) && !tridiff::detail::is_finite(rows.c[at]))
      throw InvalidArgument("super", system, first + i, "is not finite");
    if (!tridiff::detail::is_finite(rows.d[at]))
      throw InvalidArgument("rhs", system, first + i, "is not finite");
  }
  report_pivot<T>(rows, system, plan);
}

template <class T>
[[noreturn]] void report_reduction(const DiffusionInputs<T>& in, const BatchLayout& layout,
                                   std::ptrdiff_t system, const Plan& plan) {
  const auto rows = rows_at<false>(in, layout, system, plan);
  const std::ptrdiff_t first = plan.first[plan.rank];
  for (std::ptrdiff_t i = 0; i < layout.n; ++i) {
    const auto beta = rows.link(i, 0);
    if (!std::isfinite(beta)) throw InvalidArgument("beta", system, first + i, "is not finite");
    if (beta < 0)
      throw InvalidArgument(
          "beta", system, first + i,
          "is negative (" + std::to_string(beta) + "): a conductance must be >= 0");
    if (!tridiff::detail::is_finite(rows.rhs(i, 0)))
      throw InvalidArgument("rhs", system, first + i, "is not finite");
  }
  // The link into the first row is the previous rank's beta (the last rank's, into rank 0 of
  // a periodic system): a lower rank's failure wins the agreement, so name it here too.
  if (!std::isfinite(rows.link(-1, 0)))
    throw InvalidArgument("beta", system, first > 0 ? first - 1 : plan.global_n - 1,
                          "is not finite");
  // An overflow remains (of a pivot, for two links above max() / 2).
  throw NumericalError(system, first,
                       "the reduction overflowed: beta or rhs is too large for this type");
}

// The reduced rows of one system, as sent: (a', c', d') of its first row, then of its last.
inline constexpr int kReducedValues = 3;

// Values per system that rank q sends to the owner of the system's reduced system, and that
// the owner returns to q: the general form's reduced rows (3 values a row, 1 or 2 rows) and
// their solutions; the diffusion form's nine numbers of the separator's row (SlabEnds) and
// two separators (the previous rank's and q's own).
template <class T>
std::ptrdiff_t sent_per_system(const GeneralInputs<T>&, const Plan& plan, int q) {
  return kReducedValues * plan.reduced_rows(q);
}
template <class T>
std::ptrdiff_t returned_per_system(const GeneralInputs<T>&, const Plan& plan, int q) {
  return plan.reduced_rows(q);
}
template <class T>
std::ptrdiff_t sent_per_system(const DiffusionInputs<T>&, const Plan&, int) {
  return DiffusionPartEnds<T>::kArrays;
}
template <class T>
std::ptrdiff_t returned_per_system(const DiffusionInputs<T>&, const Plan&, int) {
  return 2;
}

template <class T>
struct Workspace {
  // Three values a row, W lanes per chunk: d', a', c' (general form) or y, l, f (diffusion).
  tridiff::detail::AlignedBuffer<T> eliminated;
  std::vector<T> send, receive, solved, boundary;
  // Per system, the boundary values of the finish: x_0 and x_{m-1} (general form), or the
  // previous rank's separator and this rank's (diffusion form).
  std::vector<T> first, last;
  std::vector<char> keep_subnormals;  // per chunk (diffusion form: see its reduce_slab)
};

// Runs chunk(k, first, lanes, probe) on every chunk of W systems, shared by `threads`, and
// returns the first system whose probe is not 0, or -1. Chunks run with subnormals flushed to
// zero unless keep_subnormals(k) (subnormals.hpp): the general form's couplings a' decay
// geometrically along the slab, and as subnormals every operation on them would cost ~100
// cycles (the reduction of 4096 x 4096 floats took 658 ms, against 191 ms for tridiff::solve).
template <class T, int W, class Keep, class Chunk>
std::ptrdiff_t for_each_chunk(std::ptrdiff_t count, int threads, Keep&& keep_subnormals,
                              Chunk&& chunk) {
  using R = real_t<T>;
  const std::ptrdiff_t chunks = (count + W - 1) / W;
  std::vector<std::ptrdiff_t> failed(chunks, -1);
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
  for (std::ptrdiff_t k = 0; k < chunks; ++k) {
    const std::ptrdiff_t first = k * W, lanes = std::min<std::ptrdiff_t>(W, count - first);
    R probe[W] = {};
    if (keep_subnormals(k)) {
      const tridiff::detail::SubnormalsKept state;
      chunk(k, first, lanes, probe);
    } else {
      const tridiff::detail::SubnormalsAsZero state;
      chunk(k, first, lanes, probe);
    }
    for (std::ptrdiff_t l = 0; l < lanes && failed[k] < 0; ++l)
      if (probe[l] != R(0)) failed[k] = first + l;
  }
  for (const std::ptrdiff_t system : failed)
    if (system >= 0) return system;
  return -1;
}

// Step 1, general form, on every chunk of W systems: reduce, pack the boundary rows for the
// all-to-all. Returns the first system whose lane failed, or -1.
template <class T, int W>
std::ptrdiff_t reduce_slab(const GeneralInputs<T>& in, const BatchLayout& layout, const Plan& plan,
                           int threads, Workspace<T>& work) {
  const std::ptrdiff_t m = layout.n, r = plan.reduced_rows(plan.rank);
  const bool unit = layout.system_stride == 1;
  return for_each_chunk<T, W>(
      layout.count, threads, [](std::ptrdiff_t) { return false; },
      [&](std::ptrdiff_t k, std::ptrdiff_t first, std::ptrdiff_t lanes, real_t<T>* probe) {
        T* dp = work.eliminated.data() + 3 * m * W * k;
        T* ap = dp + m * W;
        T* cp = ap + m * W;
        if (lanes == W && unit)
          reduce_lanes<T, W>(m, rows_at<true>(in, layout, first, plan), dp, ap, cp, W, probe);
        else if (lanes == W)
          reduce_lanes<T, W>(m, rows_at<false>(in, layout, first, plan), dp, ap, cp, W, probe);
        else  // the tail of the batch, system by system in the same workspace format
          for (std::ptrdiff_t l = 0; l < lanes; ++l)
            reduce_lanes<T, 1>(m, rows_at<true>(in, layout, first + l, plan), dp + l, ap + l,
                               cp + l, W, probe + l);
        for (std::ptrdiff_t l = 0; l < lanes; ++l) {
          T* out = work.send.data() + kReducedValues * r * (first + l);
          for (std::ptrdiff_t row = 0; row < r; ++row) {
            const std::ptrdiff_t i = row == 0 ? 0 : m - 1;
            out[kReducedValues * row + 0] = ap[i * W + l];
            out[kReducedValues * row + 1] = cp[i * W + l];
            out[kReducedValues * row + 2] = dp[i * W + l];
          }
        }
      });
}

// The kept rows of chunk k in the diffusion form: y (T), l and f (reals; for complex T they
// use the first half of their T arrays).
template <class T, int W>
struct DiffusionKept {
  T* y;
  real_t<T>*l, *f;
  DiffusionKept(T* eliminated, std::ptrdiff_t m, std::ptrdiff_t k)
      : y(eliminated + 3 * m * W * k),
        l(reinterpret_cast<real_t<T>*>(y + m * W)),
        f(reinterpret_cast<real_t<T>*>(y + 2 * m * W)) {}
};

// Step 1, diffusion form (diffusion_slab.hpp): reduce, pack the separator rows' numbers.
// A chunk runs with subnormals flushed, unless one of its links reaches epsilon / min()
// (1e31 in float, 1e292 in double): then it runs again, and finishes, with subnormals kept.
// Below that, a value flushed (< min()) changes what a link multiplies it into by less than
// epsilon against a pivot or leak >= 1; above, the pivots' inverses and the responses to the
// separators are themselves near min() and matter (flushed, a link of 1e37 in float returned
// x off by 1.3e-2 without an error). Kept throughout, a solution that decays into subnormals
// would stick at the smallest one and cost a microcode assist per operation (4096 x 4096
// floats with a step rhs at beta 10: 598 ms against 69 to reduce).
template <class T, int W>
std::ptrdiff_t reduce_slab(const DiffusionInputs<T>& in, const BatchLayout& layout,
                           const Plan& plan, int threads, Workspace<T>& work) {
  using R = real_t<T>;
  constexpr int V = SlabEnds<T, W>::kValues;
  constexpr R kFlushSafeLink = epsilon<T> / std::numeric_limits<R>::min();
  const std::ptrdiff_t m = layout.n;
  const bool unit = layout.system_stride == 1;
  work.keep_subnormals.assign((layout.count + W - 1) / W, 0);
  // One pass over chunk k; returns its largest link.
  auto reduce = [&](std::ptrdiff_t k, std::ptrdiff_t first, std::ptrdiff_t lanes, R* probe) {
    const DiffusionKept<T, W> kept(work.eliminated.data(), m, k);
    T* out = work.send.data() + V * first;
    R largest[W] = {};
    if (lanes == W) {
      SlabEnds<T, W> ends;
      if (unit)
        reduce_diffusion_lanes<T, W>(m, rows_at<true>(in, layout, first, plan), kept.y, kept.l,
                                     kept.f, W, ends, probe, largest);
      else
        reduce_diffusion_lanes<T, W>(m, rows_at<false>(in, layout, first, plan), kept.y, kept.l,
                                     kept.f, W, ends, probe, largest);
      for (int l = 0; l < W; ++l) ends.pack(l, out + V * l);
    } else {  // the tail of the batch, system by system in the same workspace format
      for (std::ptrdiff_t l = 0; l < lanes; ++l) {
        SlabEnds<T, 1> ends;
        reduce_diffusion_lanes<T, 1>(m, rows_at<true>(in, layout, first + l, plan), kept.y + l,
                                     kept.l + l, kept.f + l, W, ends, probe + l, largest + l);
        ends.pack(0, out + V * l);
      }
    }
    return *std::max_element(largest, largest + W);
  };
  return for_each_chunk<T, W>(
      layout.count, threads, [](std::ptrdiff_t) { return false; },
      [&](std::ptrdiff_t k, std::ptrdiff_t first, std::ptrdiff_t lanes, R* probe) {
        if (!(reduce(k, first, lanes, probe) >= kFlushSafeLink)) return;  // NaN: probe says
        work.keep_subnormals[k] = 1;
        const tridiff::detail::SubnormalsKept state;
        std::fill(probe, probe + W, R(0));
        reduce(k, first, lanes, probe);
      });
}

// Byte counts and displacements of an all-to-all in which rank q's part holds
// `per_system(q) * systems(q)` scalars.
template <class T, class Size>
void alltoall_counts(const Plan& plan, Size&& size, std::vector<int>& counts,
                     std::vector<int>& displacements) {
  counts.assign(plan.size, 0);
  displacements.assign(plan.size, 0);
  long long offset = 0;
  for (int q = 0; q < plan.size; ++q) {
    const long long bytes = static_cast<long long>(size(q)) * static_cast<long long>(sizeof(T));
    if (offset + bytes > INT_MAX)
      throw Error("tridiff: the reduced systems exceed 2 GiB per rank; use more ranks");
    counts[q] = static_cast<int>(bytes);
    displacements[q] = static_cast<int>(offset);
    offset += bytes;
  }
}

// Step 2 on this rank's share of the reduced systems: every rank's rows of system j, in rank
// order, form one tridiagonal system with unit diagonal (periodic if the systems are).
template <class T>
void solve_reduced(const GeneralInputs<T>&, const Plan& plan, Workspace<T>& work) {
  using tridiff::detail::periodic;
  using tridiff::detail::thomas;
  const std::ptrdiff_t begin = plan.block_begin(plan.rank);
  const std::ptrdiff_t systems = plan.block_begin(plan.rank + 1) - begin;
  std::ptrdiff_t m = 0;
  std::vector<std::ptrdiff_t> received(plan.size + 1, 0), solved(plan.size + 1, 0);
  for (int q = 0; q < plan.size; ++q) {
    m += plan.reduced_rows(q);
    received[q + 1] = received[q] + kReducedValues * plan.reduced_rows(q) * systems;
    solved[q + 1] = solved[q] + plan.reduced_rows(q) * systems;
  }
  std::vector<T> buffer(4 * m + tridiff::detail::periodic_workspace(m, m));
  T *sub = buffer.data(), *diag = sub + m, *super = diag + m, *x = super + m, *scratch = x + m;
  work.solved.resize(solved[plan.size]);
  auto inner = [](std::ptrdiff_t n, Strided<const T> a, Strided<const T> b, Strided<const T> c,
                  Strided<const T> d, Strided<T> out,
                  T* w) { return thomas(n, a, b, c, d, out, w); };
  for (std::ptrdiff_t j = 0; j < systems; ++j) {
    std::ptrdiff_t k = 0;
    for (int q = 0; q < plan.size; ++q)
      for (std::ptrdiff_t row = 0; row < plan.reduced_rows(q); ++row, ++k) {
        const T* in =
            work.receive.data() + received[q] + kReducedValues * (j * plan.reduced_rows(q) + row);
        sub[k] = in[0];
        super[k] = in[1];
        x[k] = in[2];
        diag[k] = T(1);
      }
    const Strided<const T> a{sub, 1}, b{diag, 1}, c{super, 1}, d{x, 1};
    const std::ptrdiff_t bad = plan.periodic
                                   ? periodic(m, a, b, c, d, Strided<T>{x, 1}, scratch, inner)
                                   : thomas(m, a, b, c, d, Strided<T>{x, 1}, scratch);
    if (bad >= 0) {  // the reduced row back to its rank and global row
      std::ptrdiff_t q = 0, before = 0;
      while (before + plan.reduced_rows(q) <= bad) before += plan.reduced_rows(q++);
      const std::ptrdiff_t row = plan.first[q] + (bad == before ? 0 : plan.rows[q] - 1);
      throw NumericalError(begin + j, row,
                           "the pivot of the reduced system vanished: the system is singular, or "
                           "not diagonally dominant (the distributed solve does not pivot)");
    }
    k = 0;
    for (int q = 0; q < plan.size; ++q)
      for (std::ptrdiff_t row = 0; row < plan.reduced_rows(q); ++row, ++k)
        work.solved[solved[q] + j * plan.reduced_rows(q) + row] = x[k];
  }
}

// Step 2, diffusion form, on this rank's share: every rank's separator row of system j, in rank
// order, forms an M-matrix in leak form (a ring if the systems are periodic). Rank q gets back
// the separator before its slab (0 before the first row of an open system) and its own.
template <class T>
void solve_reduced(const DiffusionInputs<T>&, const Plan& plan, Workspace<T>& work) {
  using R = real_t<T>;
  // The separators' rows carry the values near min() that huge links multiply (see the
  // reduction): they must not be flushed, whatever the caller's state (-ffast-math).
  const tridiff::detail::SubnormalsKept gradual_underflow;
  constexpr int V = DiffusionPartEnds<T>::kArrays;
  const std::ptrdiff_t begin = plan.block_begin(plan.rank);
  const std::ptrdiff_t systems = plan.block_begin(plan.rank + 1) - begin, P = plan.size;
  std::vector<T> values(3 * P), x(P);
  std::vector<R> reals(6 * P + 3 * P);  // the ends' reals, then the elimination's workspace
  const DiffusionPartEnds<T> ends(values.data(), reals.data(), P);
  work.solved.resize(2 * P * systems);
  for (std::ptrdiff_t j = 0; j < systems; ++j) {
    for (std::ptrdiff_t q = 0; q < P; ++q)
      unpack_slab_ends(work.receive.data() + V * (q * systems + j), q, ends);
    if (!tridiff::detail::solve_separators(P, ends, x.data(), reals.data() + 6 * P, plan.periodic))
      throw NumericalError(begin + j, -1,
                           "the system of the slabs' last rows overflowed: beta or rhs is too "
                           "large for this type");
    for (std::ptrdiff_t q = 0; q < P; ++q) {
      T* out = work.solved.data() + 2 * (q * systems + j);
      out[0] = q > 0 ? x[q - 1] : (plan.periodic ? x[P - 1] : T(0));
      out[1] = x[q];
    }
  }
}

// Step 3 on every chunk of W systems: finish.template operator()<V>(k, l, first, last, store,
// probe) writes V lanes of chunk k from lane l on (V = W for a full chunk, 1 lane by lane for
// the tail) through store(i, lane, value); first and last are the boundary values of its
// systems (Workspace). Returns the first system whose solution is not finite, or -1.
template <class T, int W, class Keep, class Finish>
std::ptrdiff_t finish_chunks(T* x, const BatchLayout& layout, int threads, const Workspace<T>& work,
                             Keep&& keep_subnormals, Finish&& finish) {
  const bool unit = layout.system_stride == 1;
  return for_each_chunk<T, W>(
      layout.count, threads, keep_subnormals,
      [&](std::ptrdiff_t k, std::ptrdiff_t first, std::ptrdiff_t lanes, real_t<T>* probe) {
        T* out = x + layout.offset(first, 0);
        const T* xf = work.first.data() + first;
        const T* xl = work.last.data() + first;
        if (lanes == W && unit)
          finish.template operator()<W>(
              k, 0, xf, xl,
              [&](std::ptrdiff_t i, int l, T v) { out[i * layout.row_stride + l] = v; }, probe);
        else if (lanes == W)
          finish.template operator()<W>(
              k, 0, xf, xl, [&](std::ptrdiff_t i, int l, T v) { out[layout.offset(l, i)] = v; },
              probe);
        else
          for (std::ptrdiff_t l = 0; l < lanes; ++l)
            finish.template operator()<1>(
                k, l, xf + l, xl + l,
                [&](std::ptrdiff_t i, int, T v) { out[layout.offset(l, i)] = v; }, probe + l);
      });
}

// Step 3, general form: every row of the slab from its two boundary unknowns.
template <class T, int W>
std::ptrdiff_t finish_slab(const GeneralInputs<T>&, T* x, const BatchLayout& layout, int threads,
                           Workspace<T>& work) {
  const std::ptrdiff_t m = layout.n;
  return finish_chunks<T, W>(
      x, layout, threads, work, [](std::ptrdiff_t) { return false; },
      [&]<int V>(std::ptrdiff_t k, std::ptrdiff_t l, const T* first, const T* last, auto&& store,
                 real_t<T>* probe) {
        const T* dp = work.eliminated.data() + 3 * m * W * k + l;
        finish_lanes<T, V>(m, dp, dp + m * W, dp + 2 * m * W, W, first, last, store, probe);
      });
}

// Step 3, diffusion form: the slab's interior rows by back substitution from the separators.
template <class T, int W>
std::ptrdiff_t finish_slab(const DiffusionInputs<T>&, T* x, const BatchLayout& layout, int threads,
                           Workspace<T>& work) {
  const std::ptrdiff_t m = layout.n;
  return finish_chunks<T, W>(
      x, layout, threads, work, [&](std::ptrdiff_t k) { return work.keep_subnormals[k] != 0; },
      [&]<int V>(std::ptrdiff_t k, std::ptrdiff_t l, const T* left, const T* own, auto&& store,
                 real_t<T>* probe) {
        const DiffusionKept<T, W> kept(work.eliminated.data(), m, k);
        finish_diffusion_lanes<T, V>(m, kept.y + l, kept.l + l, kept.f + l, W, left, own, store,
                                     probe);
      });
}

// The three steps and the two all-to-alls, with the ranks agreeing on any failure before the
// solutions go back (stages 1, 2) and before returning (stage 3).
template <class T, class Inputs>
Report solve_planned(const Inputs& in, T* x, const BatchLayout& layout, const Plan& plan,
                     int threads, MPI_Comm comm) {
  constexpr int W = tridiff::detail::kLanes<T>;
  static thread_local Workspace<T> work;  // kept between calls, like the solvers' Scratch
  Report report = plan.report();
  double clock = MPI_Wtime();
  auto lap = [&clock](double& seconds) {
    const double now = MPI_Wtime();
    seconds += now - clock;
    clock = now;
  };
  // Values per system: sent by rank q (and received by the owner), returned to rank q.
  auto sent = [&](int q) { return sent_per_system(in, plan, q); };
  auto returned = [&](int q) { return returned_per_system(in, plan, q); };
  const std::ptrdiff_t chunks = (layout.count + W - 1) / W;
  Failure failure;
  capture(failure, 1, [&] {
    work.eliminated.resize(3 * layout.n * W * chunks);
    work.send.resize(sent(plan.rank) * layout.count);
    const std::ptrdiff_t bad = reduce_slab<T, W>(in, layout, plan, threads, work);
    if (bad >= 0) report_reduction(in, layout, bad, plan);
  });
  work.send.resize(sent(plan.rank) * layout.count);
  lap(report.reduce_seconds);
  // A rank whose reduction failed still takes part (its rows are garbage; the agreement below
  // names its failure, the earliest stage, rather than what the garbage does elsewhere).
  std::vector<int> send_counts, send_displacements, receive_counts, receive_displacements;
  const std::ptrdiff_t mine = plan.block_begin(plan.rank + 1) - plan.block_begin(plan.rank);
  auto block = [&](int q) { return plan.block_begin(q + 1) - plan.block_begin(q); };
  alltoall_counts<T>(
      plan, [&](int q) { return sent(plan.rank) * block(q); }, send_counts, send_displacements);
  alltoall_counts<T>(
      plan, [&](int q) { return sent(q) * mine; }, receive_counts, receive_displacements);
  std::ptrdiff_t received = 0;
  for (int q = 0; q < plan.size; ++q) received += sent(q) * mine;
  work.receive.resize(received);
  MPI_Alltoallv(work.send.data(), send_counts.data(), send_displacements.data(), MPI_BYTE,
                work.receive.data(), receive_counts.data(), receive_displacements.data(), MPI_BYTE,
                comm);
  lap(report.exchange_seconds);
  capture(failure, 2, [&] { solve_reduced(in, plan, work); });
  lap(report.reduced_seconds);
  agree(failure, comm);

  // The solved boundary values go back along the reverse paths.
  alltoall_counts<T>(
      plan, [&](int q) { return returned(q) * mine; }, send_counts, send_displacements);
  alltoall_counts<T>(
      plan, [&](int q) { return returned(plan.rank) * block(q); }, receive_counts,
      receive_displacements);
  const std::ptrdiff_t r = returned(plan.rank);
  work.boundary.resize(r * layout.count);
  MPI_Alltoallv(work.solved.data(), send_counts.data(), send_displacements.data(), MPI_BYTE,
                work.boundary.data(), receive_counts.data(), receive_displacements.data(), MPI_BYTE,
                comm);
  work.first.resize(layout.count);
  work.last.resize(layout.count);
  for (std::ptrdiff_t s = 0; s < layout.count; ++s) {
    work.first[s] = work.boundary[r * s];
    work.last[s] = work.boundary[r * s + r - 1];
  }
  lap(report.exchange_seconds);
  capture(failure, 3, [&] {
    const std::ptrdiff_t bad = finish_slab<T, W>(in, x, layout, threads, work);
    if (bad >= 0)
      throw NumericalError(bad, -1, "the solution overflowed: rhs is too large for this type");
  });
  lap(report.finish_seconds);
  agree(failure, comm);
  lap(report.exchange_seconds);
  if (work.eliminated.size() * std::ptrdiff_t(sizeof(T)) > (std::ptrdiff_t(256) << 20)) work = {};
  return report;
}

}  // namespace detail

// Solves  sub[i] x[i-1] + diag[i] x[i] + super[i] x[i+1] = rhs[i]  for every system, rows
// spread over the ranks of `comm`: this rank holds rows [first_row, first_row + layout.n) of
// each of the layout.count systems (first_row: the rows of the lower ranks), in `layout`.
// Collective: every rank of comm calls it with the same count, form and options. sub of global
// row 0 and super of global row n-1 are not read unless options.periodic. x may be rhs.
// Pivot-free (like PaScaL_TDMA): for diagonally dominant systems; a vanishing pivot is a
// NumericalError. Every error is thrown on every rank, naming the global system and row and
// the rank that found it. On an exception x is unspecified.
template <class T>
Report solve(const T* sub, const T* diag, const T* super, const T* rhs, T* x,
             const BatchLayout& layout, MPI_Comm comm, const Options& options = {}) {
  static_assert(is_supported_scalar_v<T>, "tridiff solvers support float, double and complex");
  using namespace detail;
  require_comm(comm);
  Failure local;
  capture(local, 0, [&] {
    validate_layout(layout);
    tridiff::detail::require_one_batch_dimension(layout, "the distributed solve");
    require_options(options);
    tridiff::detail::require_pointer(sub, "sub");
    tridiff::detail::require_pointer(diag, "diag");
    tridiff::detail::require_pointer(super, "super");
    tridiff::detail::require_pointer(rhs, "rhs");
    tridiff::detail::require_pointer(x, "x");
    tridiff::detail::require_disjoint(sub, "sub", x, layout, false);
    tridiff::detail::require_disjoint(diag, "diag", x, layout, false);
    tridiff::detail::require_disjoint(super, "super", x, layout, false);
    tridiff::detail::require_disjoint(rhs, "rhs", x, layout, true);
  });
  const Plan plan = handshake<T>(layout, Form::General, options, local, comm);
  return solve_planned(GeneralInputs<T>{sub, diag, super, rhs}, x, layout, plan, options.threads,
                       comm);
}

// The diffusion form (seed 000 eq. 3.10, as tridiff::solve_diffusion):
//   -beta[i-1] x[i-1] + (1 + beta[i-1] + beta[i]) x[i] - beta[i] x[i+1] = rhs[i]
// with global indices; beta[n-1] (on the last rank) links row n-1 to row 0 if options.periodic
// and is not read otherwise. The link into a slab's first row is the previous rank's last beta:
// one message to the next rank brings it. beta >= 0 and finite (InvalidArgument otherwise).
template <class T>
Report solve_diffusion(const real_t<T>* beta, const T* rhs, T* x, const BatchLayout& layout,
                       MPI_Comm comm, const Options& options = {}) {
  static_assert(is_supported_scalar_v<T>, "tridiff solvers support float, double and complex");
  using namespace detail;
  using R = real_t<T>;
  require_comm(comm);
  Failure local;
  capture(local, 0, [&] {
    validate_layout(layout);
    tridiff::detail::require_one_batch_dimension(layout, "the distributed solve");
    require_options(options);
    tridiff::detail::require_pointer(beta, "beta");
    tridiff::detail::require_pointer(rhs, "rhs");
    tridiff::detail::require_pointer(x, "x");
    tridiff::detail::require_disjoint(beta, "beta", x, layout, false);
    tridiff::detail::require_disjoint(rhs, "rhs", x, layout, true);
  });
  const Plan plan = handshake<T>(layout, Form::Diffusion, options, local, comm);
  // The ghost links: this slab's last beta of every system to the next rank.
  std::vector<R> last(layout.count), ghost(layout.count, R(0));
  for (std::ptrdiff_t s = 0; s < layout.count; ++s) last[s] = beta[layout.offset(s, layout.n - 1)];
  const int next = plan.rank + 1 < plan.size ? plan.rank + 1 : (plan.periodic ? 0 : MPI_PROC_NULL);
  const int previous =
      plan.rank > 0 ? plan.rank - 1 : (plan.periodic ? plan.size - 1 : MPI_PROC_NULL);
  constexpr int kGhostTag = 0x7d1f;
  MPI_Sendrecv(last.data(), static_cast<int>(layout.count * sizeof(R)), MPI_BYTE, next, kGhostTag,
               ghost.data(), static_cast<int>(layout.count * sizeof(R)), MPI_BYTE, previous,
               kGhostTag, comm, MPI_STATUS_IGNORE);
  return solve_planned(DiffusionInputs<T>{beta, rhs, ghost.data()}, x, layout, plan,
                       options.threads, comm);
}

}  // namespace tridiff::distributed
