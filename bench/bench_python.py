#!/usr/bin/env python3
"""tridiff's Python module against what a numpy/scipy user has, in one process; prints times
and ratios (issue 25's targets in brackets). Needs the module (PYTHONPATH=build/python) and
Debian's numpy and scipy:

    OMP_WAIT_POLICY=passive PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py

1. 4096 systems of 4096 float64 unknowns (general form, diagonally dominant), tridiff.solve on
   2 threads against a Python loop over scipy.linalg.lapack.dgtsv (one system per call, as
   scipy offers it) and over scipy.linalg.solve_banded  [>= 10x dgtsv].
2. Blur of a 4096 x 4096 x 3 float32 image in [0, 1], tridiff.blur (method "auto", 2 threads,
   the planar copies in and out included) against scipy.ndimage.gaussian_filter with sigma
   (s, s, 0) and mode "nearest" (the replicate border), at sigma 8 [>= 50x] and 2 [>= 10x]; the error against gaussian_filter checked
   <= 1e-3.
3. The cost of a call on one system of 8 unknowns [<= 3 us], next to numpy.add on 8 elements.
4. Factor once, solve many, on the systems of 1.: Factors.solve on 2 threads against a Python
   loop over scipy.linalg.lapack.dgttrs with the factors of dgttrf (scipy's way to reuse an LU
   of tridiagonal systems), and against tridiff.solve (no target; for the record).
Times are the best of `--repeat` runs (scipy's blur: one run, it takes seconds).
"""
import argparse
import time
import timeit

import numpy as np
import scipy.linalg
from scipy.linalg import lapack
from scipy.ndimage import gaussian_filter

import tridiff


def best(function, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def dominant_systems(systems, n):
    """a, b, c, d of `systems` diagonally dominant systems of n float64 unknowns."""
    rng = np.random.default_rng(1)
    a = rng.uniform(-1, 1, (systems, n))
    c = rng.uniform(-1, 1, (systems, n))
    b = 3 + rng.uniform(0, 1, (systems, n))
    d = rng.uniform(-1, 1, (systems, n))
    return a, b, c, d


def bench_solve(systems, n, threads, repeat):
    a, b, c, d = dominant_systems(systems, n)
    out = np.empty_like(d)
    ours = best(lambda: tridiff.solve(a, b, c, d, threads=threads, out=out), repeat)

    def dgtsv_loop():
        for s in range(systems):
            lapack.dgtsv(a[s, 1:], b[s], c[s, :-1], d[s])

    def banded_loop():
        ab = np.zeros((3, n))
        for s in range(systems):
            ab[0, 1:] = c[s, :-1]
            ab[1] = b[s]
            ab[2, :-1] = a[s, 1:]
            scipy.linalg.solve_banded((1, 1), ab, d[s])

    dgtsv = best(dgtsv_loop, repeat)
    banded = best(banded_loop, 1)
    _, _, _, x0, _ = lapack.dgtsv(a[0, 1:], b[0], c[0, :-1], d[0])
    error = np.abs(out[0] - x0).max()
    print(f"solve {systems} x {n} float64, {threads} threads: tridiff {ours * 1e3:.1f} ms, "
          f"loop over dgtsv {dgtsv * 1e3:.1f} ms ({dgtsv / ours:.1f}x) [>= 10x], "
          f"loop over solve_banded {banded * 1e3:.1f} ms ({banded / ours:.1f}x); "
          f"max |x - dgtsv| on system 0: {error:.1e}")


def bench_factored(systems, n, threads, repeat):
    a, b, c, d = dominant_systems(systems, n)
    out = np.empty_like(d)
    factors = tridiff.factor(a, b, c, threads=threads)
    ours = best(lambda: factors.solve(d, threads=threads, out=out), repeat)
    unfactored = best(lambda: tridiff.solve(a, b, c, d, threads=threads, out=out), repeat)
    lu = [lapack.dgttrf(a[s, 1:], b[s], c[s, :-1])[:-1] for s in range(systems)]

    def dgttrs_loop():
        for s in range(systems):
            lapack.dgttrs(*lu[s], d[s])

    dgttrs = best(dgttrs_loop, repeat)
    x0, _ = lapack.dgttrs(*lu[0], d[0])
    factors.solve(d, threads=threads, out=out)
    error = np.abs(out[0] - x0).max()
    print(f"factored solve {systems} x {n} float64, {threads} threads: Factors.solve "
          f"{ours * 1e3:.1f} ms, loop over dgttrs {dgttrs * 1e3:.1f} ms ({dgttrs / ours:.1f}x), "
          f"tridiff.solve {unfactored * 1e3:.1f} ms ({unfactored / ours:.1f}x); "
          f"max |x - dgttrs| on system 0: {error:.1e}")


def bench_blur(size, sigma, threads, repeat):
    rng = np.random.default_rng(2)
    image = rng.random((size, size, 3), dtype=np.float32)
    method = tridiff.auto_blur_method(sigma)
    ours = best(lambda: tridiff.blur(image, sigma, threads=threads), repeat)
    result = tridiff.blur(image, sigma, threads=threads)
    start = time.perf_counter()
    reference = gaussian_filter(image, (sigma, sigma, 0), mode="nearest")  # = "replicate"
    scipy_time = time.perf_counter() - start
    error = np.abs(result - reference).max()
    target = 50 if sigma >= 8 else 10
    print(f"blur {size}^2 RGB float32, sigma {sigma:g}, {threads} threads: tridiff ('{method}', "
          f"layout conversion included) {ours * 1e3:.1f} ms, gaussian_filter "
          f"{scipy_time * 1e3:.0f} ms ({scipy_time / ours:.1f}x) [>= {target}x]; "
          f"max error vs gaussian_filter {error:.1e} [<= 1e-3]")


def bench_overhead(repeat):
    rng = np.random.default_rng(3)
    a, c, d = (rng.uniform(-1, 1, 8) for _ in range(3))
    b = 3 + rng.uniform(0, 1, 8)
    calls = 20000
    ours = min(timeit.repeat(lambda: tridiff.solve(a, b, c, d), number=calls, repeat=repeat))
    add = min(timeit.repeat(lambda: np.add(a, b), number=calls, repeat=repeat))
    print(f"call overhead, one system of 8 float64: tridiff.solve {ours / calls * 1e6:.2f} us "
          f"[<= 3 us]; numpy.add on 8 elements {add / calls * 1e6:.2f} us")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, default=4096, help="systems = n = image side")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    bench_overhead(args.repeat)
    bench_solve(args.size, args.size, args.threads, args.repeat)
    bench_factored(args.size, args.size, args.threads, args.repeat)
    for sigma in (8.0, 2.0):
        bench_blur(args.size, sigma, args.threads, args.repeat)


if __name__ == "__main__":
    main()
