// The heat equation u_t = Δu on the unit square or cube, Dirichlet zero boundaries, by ADI on a
// grid cut into slabs over MPI ranks: the worked example of tridiff's solvers in PDE code.
// 2-D: Peaceman–Rachford; 3-D: Douglas (1962). Both second order in space and time.
// Solves along the axes inside a slab use tridiff::solve; along the cut axis either
// tridiff::distributed::solve (the systems cross ranks) or a transpose that makes that axis
// local for the solve and back (compared by heat_adi.cpp --compare: on this machine, 1 to 4
// ranks in shared memory, the transpose is 1.3-1.5x faster and the program's default; the
// cost model of docs/distributed.md says where the distributed solve wins).
#pragma once

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "tridiff/distributed/solve.hpp"
#include "tridiff/solvers.hpp"

namespace heat {

enum class Strategy { Distributed, Transpose };

// N interior points per axis (h = 1 / (N + 1)); the local array has shape (planes, N, inner):
// axis 0 (y in 2-D, z in 3-D) is cut into slabs, inner = 1 in 2-D and N in 3-D. Point
// (i0, i1, i2) is at (i0 * N + i1) * inner + i2, so x is axis 1 in 2-D and axis 2 in 3-D.
struct Grid {
  int dims = 2;
  std::ptrdiff_t n = 0, inner = 1;
  int rank = 0, ranks = 1;
  std::ptrdiff_t first = 0, planes = 0;  // this rank's slab of axis 0

  static std::ptrdiff_t slab_begin(std::ptrdiff_t n, int ranks, int q) { return n * q / ranks; }
  std::ptrdiff_t plane() const { return n * inner; }
  std::ptrdiff_t size() const { return planes * plane(); }
  double h() const { return 1.0 / double(n + 1); }
};

class HeatAdi {
 public:
  HeatAdi(int dims, std::ptrdiff_t n, double dt, Strategy strategy, MPI_Comm comm)
      : dt_(dt), strategy_(strategy), comm_(comm) {
    if (dims != 2 && dims != 3) throw std::invalid_argument("dims must be 2 or 3");
    grid_.dims = dims;
    grid_.n = n;
    grid_.inner = dims == 3 ? n : 1;
    MPI_Comm_rank(comm, &grid_.rank);
    MPI_Comm_size(comm, &grid_.ranks);
    if (n < grid_.ranks) throw std::invalid_argument("fewer grid points than ranks");
    grid_.first = Grid::slab_begin(n, grid_.ranks, grid_.rank);
    grid_.planes = Grid::slab_begin(n, grid_.ranks, grid_.rank + 1) - grid_.first;
    u_.resize(grid_.size());
    work_.resize(grid_.size());
    d1_.resize(grid_.size());
    d0_.resize(grid_.size());
    // (I - dt/2 D) along any axis: the same constant rows; one set of diagonals serves every
    // solve (the layouts below never reach past the local grid, or the transposed one).
    const double r = 0.5 * dt / (grid_.h() * grid_.h());
    const std::ptrdiff_t transposed = n * (Grid::slab_begin(n, grid_.ranks, 1) + 1) * grid_.inner;
    const std::size_t extent = std::max(grid_.size(), transposed);
    sub_.assign(extent, -r);
    diag_.assign(extent, 1 + 2 * r);
    super_.assign(extent, -r);
    initialise();
  }

  const Grid& grid() const { return grid_; }
  const std::vector<double>& field() const { return u_; }
  double time() const { return time_; }
  double seconds_on_cut_axis() const { return cut_axis_seconds_; }

  // u(x, 0) = prod_k sin(pi x_k): the slowest mode, which decays as exp(-dims pi^2 t).
  void initialise() {
    for_each_point([&](std::ptrdiff_t at, double x, double y, double z) {
      u_[at] = std::sin(std::numbers::pi * x) * std::sin(std::numbers::pi * y) *
               (grid_.dims == 3 ? std::sin(std::numbers::pi * z) : 1.0);
    });
    time_ = 0;
  }

  // max |u - exact| / max |exact| over every rank.
  double relative_error() const {
    const double decay = std::exp(-grid_.dims * std::numbers::pi * std::numbers::pi * time_);
    double worst = 0;
    for_each_point([&](std::ptrdiff_t at, double x, double y, double z) {
      const double exact = decay * std::sin(std::numbers::pi * x) * std::sin(std::numbers::pi * y) *
                           (grid_.dims == 3 ? std::sin(std::numbers::pi * z) : 1.0);
      worst = std::max(worst, std::abs(u_[at] - exact));
    });
    MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, comm_);
    return worst / decay;
  }

  void step() {
    if (grid_.dims == 2)
      peaceman_rachford();
    else
      douglas();
    time_ += dt_;
  }

 private:
  // 2-D: (I - dt/2 Dx) u* = (I + dt/2 Dy) u,  (I - dt/2 Dy) u' = (I + dt/2 Dx) u*.
  void peaceman_rachford() {
    work_ = u_;
    add_second_difference(0, 0.5 * dt_, u_.data(), work_.data());
    solve_inside_slab(1, work_.data());
    u_ = work_;
    add_second_difference(1, 0.5 * dt_, work_.data(), u_.data());
    solve_cut_axis(u_.data());
  }

  // 3-D (Douglas 1962): (I - dt/2 Dx) u1 = (I + dt/2 Dx + dt Dy + dt Dz) u,
  // (I - dt/2 Dy) u2 = u1 - dt/2 Dy u,  (I - dt/2 Dz) u' = u2 - dt/2 Dz u.
  void douglas() {
    std::fill(d0_.begin(), d0_.end(), 0.0);
    std::fill(d1_.begin(), d1_.end(), 0.0);
    add_second_difference(0, 1.0, u_.data(), d0_.data());  // Dz u
    add_second_difference(1, 1.0, u_.data(), d1_.data());  // Dy u
    work_ = u_;
    add_second_difference(2, 0.5 * dt_, u_.data(), work_.data());
    for (std::ptrdiff_t i = 0; i < grid_.size(); ++i) work_[i] += dt_ * (d1_[i] + d0_[i]);
    solve_inside_slab(2, work_.data());
    for (std::ptrdiff_t i = 0; i < grid_.size(); ++i) work_[i] -= 0.5 * dt_ * d1_[i];
    solve_inside_slab(1, work_.data());
    for (std::ptrdiff_t i = 0; i < grid_.size(); ++i) u_[i] = work_[i] - 0.5 * dt_ * d0_[i];
    solve_cut_axis(u_.data());
  }

  template <class Body>
  void for_each_point(Body&& body) const {
    const double h = grid_.h();
    for (std::ptrdiff_t i0 = 0; i0 < grid_.planes; ++i0)
      for (std::ptrdiff_t i1 = 0; i1 < grid_.n; ++i1)
        for (std::ptrdiff_t i2 = 0; i2 < grid_.inner; ++i2) {
          const double c0 = (grid_.first + i0 + 1) * h, c1 = (i1 + 1) * h, c2 = (i2 + 1) * h;
          // 2-D: x = axis 1, y = axis 0; 3-D: x = axis 2, y = axis 1, z = axis 0.
          if (grid_.dims == 2)
            body((i0 * grid_.n + i1) * grid_.inner + i2, c1, c0, 0.0);
          else
            body((i0 * grid_.n + i1) * grid_.inner + i2, c2, c1, c0);
        }
  }

  // y += scale * (second difference of u along `axis`) / h^2, zero beyond the box. Along the
  // cut axis the neighbouring ranks' boundary planes come first (one message each way).
  void add_second_difference(int axis, double scale, const double* u, double* y) {
    const double weight = scale / (grid_.h() * grid_.h());
    const std::ptrdiff_t plane = grid_.plane();
    const std::ptrdiff_t stride = axis == 0 ? plane : axis == 1 ? grid_.inner : 1;
    const std::ptrdiff_t length = axis == 0 ? grid_.planes : grid_.n;
    std::vector<double> below(plane, 0.0), above(plane, 0.0);
    if (axis == 0) exchange_halo(u, below.data(), above.data());
    for (std::ptrdiff_t at = 0; at < grid_.size(); ++at) {
      const std::ptrdiff_t i = (at / stride) % length;
      const double previous = i > 0 ? u[at - stride] : axis == 0 ? below[at % plane] : 0.0;
      const double next = i + 1 < length ? u[at + stride] : axis == 0 ? above[at % plane] : 0.0;
      y[at] += weight * (previous - 2 * u[at] + next);
    }
  }

  void exchange_halo(const double* u, double* below, double* above) {
    const int down = grid_.rank > 0 ? grid_.rank - 1 : MPI_PROC_NULL;
    const int up = grid_.rank + 1 < grid_.ranks ? grid_.rank + 1 : MPI_PROC_NULL;
    const int plane = static_cast<int>(grid_.plane());
    const double* last = u + (grid_.planes - 1) * grid_.plane();
    MPI_Sendrecv(last, plane, MPI_DOUBLE, up, 1, below, plane, MPI_DOUBLE, down, 1, comm_,
                 MPI_STATUS_IGNORE);
    MPI_Sendrecv(u, plane, MPI_DOUBLE, down, 2, above, plane, MPI_DOUBLE, up, 2, comm_,
                 MPI_STATUS_IGNORE);
  }

  tridiff::SolveOptions local_options() const {
    tridiff::SolveOptions options;
    options.method = tridiff::Method::Thomas;
    options.check_dominance = false;  // 1 + 2r > 2r: dominant by construction
    options.threads = 1;              // one rank per core
    return options;
  }

  // (I - dt/2 D) x = rhs along axis 1 or 2, inside the slab, in place.
  void solve_inside_slab(int axis, double* data) {
    const std::ptrdiff_t n = grid_.n;
    if ((axis == 1 && grid_.dims == 2) || axis == 2) {  // contiguous lines: x
      const auto layout = tridiff::BatchLayout::rows(n, grid_.size() / n, n);
      tridiff::solve_in_place(sub_.data(), diag_.data(), super_.data(), data, layout,
                              local_options());
      return;
    }
    // y in 3-D: lines across a plane, interleaved (one plane per call).
    const auto layout = tridiff::BatchLayout::columns(n, n, n);
    for (std::ptrdiff_t i0 = 0; i0 < grid_.planes; ++i0)
      tridiff::solve_in_place(sub_.data(), diag_.data(), super_.data(), data + i0 * grid_.plane(),
                              layout, local_options());
  }

  // (I - dt/2 D) x = rhs along the cut axis, in place.
  void solve_cut_axis(double* data) {
    const double start = MPI_Wtime();
    if (strategy_ == Strategy::Distributed) {
      // Every rank holds `planes` rows of each of the plane() systems, interleaved.
      const auto layout = tridiff::BatchLayout::columns(grid_.planes, grid_.plane(), grid_.plane());
      tridiff::distributed::solve(sub_.data(), diag_.data(), super_.data(), data, data, layout,
                                  comm_);
    } else {
      solve_transposed(data);
    }
    cut_axis_seconds_ += MPI_Wtime() - start;
  }

  // The transpose strategy: all-to-all so that each rank holds all of axis 0 for a slab of
  // axis 1, a local solve, and back.
  void solve_transposed(double* data) {
    const int ranks = grid_.ranks;
    const std::ptrdiff_t n = grid_.n, inner = grid_.inner;
    auto slab1 = [&](int q) { return Grid::slab_begin(n, ranks, q); };
    const std::ptrdiff_t mine = slab1(grid_.rank + 1) - slab1(grid_.rank);
    std::vector<int> send_counts(ranks), send_offsets(ranks), receive_counts(ranks),
        receive_offsets(ranks);
    int sent = 0, received = 0;
    for (int q = 0; q < ranks; ++q) {
      send_counts[q] = static_cast<int>(grid_.planes * (slab1(q + 1) - slab1(q)) * inner);
      receive_counts[q] = static_cast<int>((slab1(q + 1) - slab1(q)) * mine * inner);
      send_offsets[q] = sent;
      receive_offsets[q] = received;
      sent += send_counts[q];
      received += receive_counts[q];
    }
    packed_.resize(sent);
    transposed_.resize(received);
    // Pack: block q holds (i0 in this slab, i1 in q's slab of axis 1, all i2).
    for (int q = 0; q < ranks; ++q) {
      double* out = packed_.data() + send_offsets[q];
      const std::ptrdiff_t width = (slab1(q + 1) - slab1(q)) * inner;
      for (std::ptrdiff_t i0 = 0; i0 < grid_.planes; ++i0, out += width)
        std::copy_n(data + (i0 * n + slab1(q)) * inner, width, out);
    }
    // Received blocks come in rank order, i.e. in order of i0: together they are the
    // transposed array (all i0, this rank's i1, all i2), lines of axis 0 interleaved.
    MPI_Alltoallv(packed_.data(), send_counts.data(), send_offsets.data(), MPI_DOUBLE,
                  transposed_.data(), receive_counts.data(), receive_offsets.data(), MPI_DOUBLE,
                  comm_);
    const auto layout = tridiff::BatchLayout::columns(n, mine * inner, mine * inner);
    tridiff::solve_in_place(sub_.data(), diag_.data(), super_.data(), transposed_.data(), layout,
                            local_options());
    MPI_Alltoallv(transposed_.data(), receive_counts.data(), receive_offsets.data(), MPI_DOUBLE,
                  packed_.data(), send_counts.data(), send_offsets.data(), MPI_DOUBLE, comm_);
    for (int q = 0; q < ranks; ++q) {
      const double* in = packed_.data() + send_offsets[q];
      const std::ptrdiff_t width = (slab1(q + 1) - slab1(q)) * inner;
      for (std::ptrdiff_t i0 = 0; i0 < grid_.planes; ++i0, in += width)
        std::copy_n(in, width, data + (i0 * n + slab1(q)) * inner);
    }
  }

  Grid grid_;
  double dt_, time_ = 0, cut_axis_seconds_ = 0;
  Strategy strategy_;
  MPI_Comm comm_;
  std::vector<double> u_, work_, d0_, d1_, sub_, diag_, super_, packed_, transposed_;
};

}  // namespace heat
