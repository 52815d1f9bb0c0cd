#!/usr/bin/env python3
"""Cost model of tridiff::distributed (docs/distributed.md): time per solve and per ADI step of a
1024^3 float grid at 8..1024 ranks, from per-row work, latency and bandwidth measured on this
machine by tridiff_bench_distributed (bench/run_distributed.sh) and tridiff_heat_adi.

    python3 bench/distributed_model.py            # prints the markdown tables of the doc

Terms (s = 4 bytes, N = 1024, P ranks):
  slab (the ADI example: axis 0 cut into P slabs, the other axes local)
    distributed solve = w_r N^3/P + w_s 2 N^2 + 2(P-1) alpha + 3 log2(P) alpha_ar + 8 N^2 s/beta
        (reduce + finish; the 2P-row reduced systems of N^2/P systems; two all-to-alls, the
        second a third of the first: 3 values x 2 rows out, 1 x 2 back; three agreements)
    transpose solve   = w_t N^3/P + c_copy N^3/P + 2(P-1) alpha + 2 (N^3/P) s (P-1)/P / beta
    ADI step          = one cut-axis solve + c_other N^3/P + halo (2 alpha + 2 N^2 s / beta)
  cube (PaScaL_TDMA's layout: P = p^3, each line of systems spread over p ranks)
    solve per axis    = w_r N^3/P + w_s 2 M + 2(p-1) alpha + 3 log2(p) alpha_ar + 8 M s/beta,
                        M = N^2/p^2 systems per rank
    ADI step          = 3 solves + c_rhs N^3/P + 6 faces (6 alpha + 6 (N/p)^2 s / beta)
"""
import math

N = 1024
S = 4  # bytes per float

# Measured on this machine (2 cores of an AMD EPYC, load average 8-9 from other builds:
# per-row work from CPU time, which the load does not inflate as it does the wall time).
W_R = 9.2e-9  # reduction + finish per row per system (1 rank, 4096 x 4096, CPU time)
W_T = 3.8e-9  # tridiff::solve Thomas lanes per row (1 thread, same systems, CPU time)
W_S = 4.6e-9  # reduced solve per reduced row (2 ranks: 8192 rows in 0.038 ms)
C_COPY = 0.43e-9  # pack + unpack of a point: 16 bytes at 37 GB/s (ANCHORS.md copy bandwidth)
C_OTHER = 57e-9  # the example's right-hand sides and two local solves per point (double)
C_RHS = C_OTHER - 2 * 2 * W_T  # without the local solves (double: twice the float work)

LOOPBACK = dict(name="loopback here", alpha=0.45e-6, alpha_ar=0.67e-6, beta=0.69e9)
NETWORK = dict(name="cluster (assumed)", alpha=2e-6, alpha_ar=2e-6, beta=1e9)


def slab_distributed(P, net):
    return (W_R * N**3 / P + W_S * 2 * N**2 + 2 * (P - 1) * net["alpha"]
            + 3 * math.log2(max(P, 2)) * net["alpha_ar"] + 8 * N**2 * S * (P - 1) / P / net["beta"])


def slab_transpose(P, net):
    return (W_T * N**3 / P + C_COPY * N**3 / P + 2 * (P - 1) * net["alpha"]
            + 2 * (N**3 / P) * S * (P - 1) / P / net["beta"])


def slab_step(P, net, solve):
    return solve(P, net) + C_OTHER * N**3 / P + 2 * net["alpha"] + 2 * N**2 * S / net["beta"]


def cube_solve(P, net):
    p = P ** (1 / 3)  # 1024 = 8 x 8 x 16 is taken as its geometric mean, p = 10.1
    M = N**2 / p**2
    return (W_R * N**3 / P + W_S * 2 * M + 2 * (p - 1) * net["alpha"]
            + 3 * math.log2(max(p, 2)) * net["alpha_ar"] + 8 * M * S * (p - 1) / p / net["beta"])


def cube_step(P, net):
    p = P ** (1 / 3)
    return 3 * cube_solve(P, net) + C_RHS * N**3 / P + 6 * net["alpha"] + 6 * (N / p) ** 2 * S / net["beta"]


def ms(seconds):
    return f"{1e3 * seconds:,.1f}"


for net in (LOOPBACK, NETWORK):
    print(f"\n{net['name']}: alpha {net['alpha'] * 1e6:.2f} us, all-reduce {net['alpha_ar'] * 1e6:.2f} us, "
          f"beta {net['beta'] / 1e9:.2f} GB/s\n")
    print("| ranks | slab: distributed solve | slab: transpose solve | slab: ADI step (faster solve) "
          "| cube: solve per axis | cube: ADI step |")
    print("|---:|---:|---:|---:|---:|---:|")
    for P in (8, 64, 512, 1024):
        d, t = slab_distributed(P, net), slab_transpose(P, net)
        step = slab_step(P, net, slab_distributed if d <= t else slab_transpose)
        print(f"| {P} | {ms(d)} ms | {ms(t)} ms | {ms(step)} ms | {ms(cube_solve(P, net))} ms "
              f"| {ms(cube_step(P, net))} ms |")
