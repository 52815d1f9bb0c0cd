// The ADI heat-equation example (distributed/examples/heat_adi.hpp) on the ranks of
// MPI_COMM_WORLD: second-order convergence to the analytic solution (a product of sines decaying
// in time), and the N-rank result equal to the single-process one to round-off.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <limits>

#include "heat_adi.hpp"

namespace {

// Error at t = 1/4 with dt proportional to h: halving h halves dt too, so the ratio of errors
// tends to 4 only if the scheme is second order in both (first order in time would give 2).
// 3-D takes dt = h/4: Douglas's factor for the decaying mode is far from exp(-3 pi^2 dt) at
// dt = h = 1/8, so the coarsest grids would not yet be in the asymptotic range.
double error_at_quarter(int dims, std::ptrdiff_t intervals, heat::Strategy strategy) {
  const int steps_per_interval = dims == 2 ? 1 : 4;
  const double dt = 1.0 / double(intervals * steps_per_interval);
  heat::HeatAdi solver(dims, intervals - 1, dt, strategy, MPI_COMM_WORLD);
  for (std::ptrdiff_t s = 0; s < intervals * steps_per_interval / 4; ++s) solver.step();
  EXPECT_NEAR(solver.time(), 0.25, 1e-12);
  return solver.relative_error();
}

void expect_second_order(int dims, std::ptrdiff_t coarse, heat::Strategy strategy) {
  const double e1 = error_at_quarter(dims, coarse, strategy);
  const double e2 = error_at_quarter(dims, 2 * coarse, strategy);
  const double e3 = error_at_quarter(dims, 4 * coarse, strategy);
  // Measured (2 ranks): 2-D 0.138, 0.0350, 0.00878; 3-D 0.138, 0.0280, 0.00642.
  EXPECT_LT(e3, 0.01);
  EXPECT_NEAR(std::log2(e1 / e2), 2.05, 0.3) << e1 << " " << e2;
  EXPECT_NEAR(std::log2(e2 / e3), 2.0, 0.15) << e2 << " " << e3;
}

TEST(DistributedAdi, PeacemanRachford2DConvergesAtSecondOrder) {
  expect_second_order(2, 16, heat::Strategy::Distributed);
}

TEST(DistributedAdi, Douglas3DConvergesAtSecondOrder) {
  expect_second_order(3, 8, heat::Strategy::Distributed);
}

TEST(DistributedAdi, TransposeStrategyConvergesAtSecondOrder) {
  expect_second_order(3, 8, heat::Strategy::Transpose);
}

// Every rank also runs the whole grid alone (MPI_COMM_SELF: the cut axis is then solved by the
// single-process tridiff::solve) and compares its slab with the N-rank run: the partitioned
// solve differs from Thomas only by rounding.
void expect_same_as_single_process(int dims, std::ptrdiff_t n, heat::Strategy strategy) {
  const int steps = 5;
  const double dt = 0.7 / double(n + 1);
  heat::HeatAdi ranks(dims, n, dt, strategy, MPI_COMM_WORLD);
  heat::HeatAdi alone(dims, n, dt, heat::Strategy::Transpose, MPI_COMM_SELF);
  for (int s = 0; s < steps; ++s) {
    ranks.step();
    alone.step();
  }
  const auto& grid = ranks.grid();
  const std::ptrdiff_t offset = grid.first * grid.plane();
  double worst = 0, scale = 0;
  for (std::ptrdiff_t i = 0; i < grid.size(); ++i) {
    worst = std::max(worst, std::abs(ranks.field()[i] - alone.field()[offset + i]));
    scale = std::max(scale, std::abs(alone.field()[offset + i]));
  }
  // A few ulps per solve, over 5 steps of dims solves each.
  EXPECT_LE(worst, 100 * std::numeric_limits<double>::epsilon() * scale);
}

TEST(DistributedAdi, RanksMatchSingleProcessIn2D) {
  expect_same_as_single_process(2, 45, heat::Strategy::Distributed);
  expect_same_as_single_process(2, 45, heat::Strategy::Transpose);
}

TEST(DistributedAdi, RanksMatchSingleProcessIn3D) {
  expect_same_as_single_process(3, 21, heat::Strategy::Distributed);
  expect_same_as_single_process(3, 21, heat::Strategy::Transpose);
}

}  // namespace
