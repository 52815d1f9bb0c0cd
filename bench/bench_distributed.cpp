// tridiff::distributed on this machine: strong and weak scaling of the batched solve, the
// single-process tridiff::solve on the same systems (the peer, in this binary), where the time
// goes (Report's phases), and the loopback latency and bandwidth of one message: the numbers
// the cost model of docs/distributed.md is built from. Rank 0 prints one JSON object a line.
//   mpirun -n K tridiff_bench_distributed [--reps R] [--n N] [--systems M]
// Not Google Benchmark: its repetition loop runs in each process on its own, while a
// distributed solve must start together on every rank (a barrier) and lasts as long as the
// slowest rank (the maximum over ranks of each repetition; the median of those is reported).
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <ctime>
#include <string>
#include <vector>

#include "tridiff/distributed/solve.hpp"
#include "tridiff/solvers.hpp"

namespace {

struct World {
  int rank = 0, size = 1;
};

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// The CPU time the slowest rank spent in the last median_seconds (seconds per repetition).
// On a shared machine the wall time of 2 ranks on 2 cores includes the time the ranks were
// descheduled; the CPU time per rank shows how the work itself divides over the ranks.
double last_cpu_seconds = 0;

// Median over repetitions of the slowest rank's wall time of `run` (seconds).
double median_seconds(int reps, const std::function<void()>& run) {
  run();  // warm-up: first-touch of the workspace, connections
  std::vector<double> times, cpu;
  for (int r = 0; r < reps; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double start = MPI_Wtime(), cpu_start = cpu_seconds();
    run();
    double seconds[2] = {MPI_Wtime() - start, cpu_seconds() - cpu_start};
    MPI_Allreduce(MPI_IN_PLACE, seconds, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    times.push_back(seconds[0]);
    cpu.push_back(seconds[1]);
  }
  std::sort(times.begin(), times.end());
  std::sort(cpu.begin(), cpu.end());
  last_cpu_seconds = cpu[cpu.size() / 2];
  return times[times.size() / 2];
}

// This rank's slab of `systems` diagonally dominant systems of `n` rows (interleaved: the
// layout of the cut axis of a grid), coefficients from a cheap hash of the global position.
struct Slab {
  tridiff::BatchLayout layout;
  std::vector<float> a, b, c, d, x, beta;

  Slab(std::ptrdiff_t first, std::ptrdiff_t rows, std::ptrdiff_t systems) {
    layout = tridiff::BatchLayout::columns(rows, systems, systems);
    const std::size_t size = static_cast<std::size_t>(rows * systems);
    a.resize(size), b.resize(size), c.resize(size), d.resize(size), x.resize(size);
    beta.resize(size);
    for (std::ptrdiff_t i = 0; i < rows; ++i)
      for (std::ptrdiff_t s = 0; s < systems; ++s) {
        const auto at = static_cast<std::size_t>(layout.offset(s, i));
        const std::uint64_t h =
            (std::uint64_t(first + i) * 2654435761u) ^ (std::uint64_t(s) * 40503u);
        const float u = float(h % 1000) / 1000.f, v = float((h / 1000) % 1000) / 1000.f;
        beta[at] = 0.1f + 9.9f * u;  // as in ANCHORS.md: beta in [0.1, 10]
        a[at] = -u;
        c[at] = -v;
        b[at] = 1.f + u + v;
        d[at] = v - 0.5f;
      }
  }
};

std::ptrdiff_t slab_begin(std::ptrdiff_t n, int ranks, int q) { return n * q / ranks; }

void print_solve(const World& world, const char* name, std::ptrdiff_t n, std::ptrdiff_t systems,
                 double seconds, const tridiff::distributed::Report& phases) {
  // The phases of the last repetition, slowest rank each.
  double p[4] = {phases.reduce_seconds, phases.exchange_seconds, phases.reduced_seconds,
                 phases.finish_seconds};
  MPI_Allreduce(MPI_IN_PLACE, p, 4, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (world.rank != 0) return;
  std::printf(
      "{\"name\": \"%s\", \"ranks\": %d, \"n\": %td, \"systems\": %td, \"ms\": %.3f, "
      "\"cpu_ms_per_rank\": %.3f, \"ns_per_row_per_rank\": %.3f, \"reduce_ms\": %.3f, "
      "\"exchange_ms\": %.3f, \"reduced_ms\": %.3f, \"finish_ms\": %.3f}\n",
      name, world.size, n, systems, 1e3 * seconds, 1e3 * last_cpu_seconds,
      1e9 * seconds * world.size / double(n * systems), 1e3 * p[0], 1e3 * p[1], 1e3 * p[2],
      1e3 * p[3]);
}

void bench_solve(const World& world, const char* name, std::ptrdiff_t n, std::ptrdiff_t systems,
                 bool diffusion, int reps) {
  const std::ptrdiff_t first = slab_begin(n, world.size, world.rank);
  Slab slab(first, slab_begin(n, world.size, world.rank + 1) - first, systems);
  tridiff::distributed::Report report;
  const double seconds = median_seconds(reps, [&] {
    report = diffusion
                 ? tridiff::distributed::solve_diffusion<float>(
                       slab.beta.data(), slab.d.data(), slab.x.data(), slab.layout, MPI_COMM_WORLD)
                 : tridiff::distributed::solve(slab.a.data(), slab.b.data(), slab.c.data(),
                                               slab.d.data(), slab.x.data(), slab.layout,
                                               MPI_COMM_WORLD);
  });
  print_solve(world, name, n, systems, seconds, report);
}

// The single-process solver on the whole batch (rank 0 alone), 1 and 2 threads.
void bench_peer(const World& world, std::ptrdiff_t n, std::ptrdiff_t systems, int reps) {
  if (world.rank != 0) return;
  Slab whole(0, n, systems);
  for (const bool diffusion : {false, true})
    for (const int threads : {1, 2}) {
      tridiff::SolveOptions options;
      options.threads = threads;
      options.method = tridiff::Method::Thomas;
      options.check_dominance = false;  // as the distributed solve: no dominance scan
      std::vector<double> times, cpu;
      for (int r = 0; r <= reps; ++r) {
        const double start = MPI_Wtime(), cpu_start = cpu_seconds();
        if (diffusion)
          tridiff::solve_diffusion<float>(whole.beta.data(), whole.d.data(), whole.x.data(),
                                          whole.layout, options);
        else
          tridiff::solve(whole.a.data(), whole.b.data(), whole.c.data(), whole.d.data(),
                         whole.x.data(), whole.layout, options);
        if (r > 0) {  // the first is the warm-up
          times.push_back(MPI_Wtime() - start);
          cpu.push_back(cpu_seconds() - cpu_start);
        }
      }
      std::sort(times.begin(), times.end());
      std::sort(cpu.begin(), cpu.end());
      std::printf(
          "{\"name\": \"tridiff_solve_%s\", \"threads\": %d, \"n\": %td, \"systems\": %td, "
          "\"ms\": %.3f, \"cpu_ms_per_thread\": %.3f, \"ns_per_row_per_thread\": %.3f}\n",
          diffusion ? "diffusion" : "general", threads, n, systems, 1e3 * times[times.size() / 2],
          1e3 * cpu[cpu.size() / 2] / threads,
          1e9 * times[times.size() / 2] * threads / double(n * systems));
    }
}

// Half the round trip of a message between ranks 0 and 1, for each size.
void bench_ping_pong(const World& world, int reps) {
  if (world.size < 2) return;
  for (const int bytes : {8, 1024, 65536, 1 << 20, 16 << 20}) {
    std::vector<char> buffer(bytes);
    const int trips = bytes <= 65536 ? 1000 : 20;
    const double seconds = median_seconds(reps, [&] {
      for (int t = 0; t < trips; ++t) {
        if (world.rank == 0) {
          MPI_Send(buffer.data(), bytes, MPI_BYTE, 1, 0, MPI_COMM_WORLD);
          MPI_Recv(buffer.data(), bytes, MPI_BYTE, 1, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        } else if (world.rank == 1) {
          MPI_Recv(buffer.data(), bytes, MPI_BYTE, 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
          MPI_Send(buffer.data(), bytes, MPI_BYTE, 0, 0, MPI_COMM_WORLD);
        }
      }
    });
    const double one_way = seconds / (2.0 * trips);
    if (world.rank == 0)
      std::printf(
          "{\"name\": \"ping_pong\", \"ranks\": %d, \"bytes\": %d, \"one_way_us\": %.3f, "
          "\"GB_per_s\": %.3f}\n",
          world.size, bytes, 1e6 * one_way, bytes / one_way / 1e9);
  }
  // One MPI_Allreduce of one value: the agreements' cost.
  double value = 1;
  const double seconds = median_seconds(reps, [&] {
    for (int t = 0; t < 1000; ++t)
      MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  });
  if (world.rank == 0)
    std::printf("{\"name\": \"allreduce_8_bytes\", \"ranks\": %d, \"us\": %.3f}\n", world.size,
                1e6 * seconds / 1000);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  World world;
  MPI_Comm_rank(MPI_COMM_WORLD, &world.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &world.size);
  int reps = 7;
  std::ptrdiff_t n = 4096, systems = 4096;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--reps") reps = std::atoi(argv[i + 1]);
    if (flag == "--n") n = std::atol(argv[i + 1]);
    if (flag == "--systems") systems = std::atol(argv[i + 1]);
  }
  bench_solve(world, "strong_general", n, systems, false, reps);
  bench_solve(world, "strong_diffusion", n, systems, true, reps);
  bench_solve(world, "weak_general", n / 2 * world.size, systems, false, reps);
  if (world.size == 1) bench_peer(world, n, systems, reps);
  bench_ping_pong(world, reps);
  MPI_Finalize();
  return 0;
}
