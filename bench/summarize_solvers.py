#!/usr/bin/env python3
"""Prints a Markdown table from the JSON of tridiff_bench_solvers (results/bench_solvers.json).

One row per benchmark, grouped by scalar, shape and thread count, with the median over the
repetitions and the best repetition (the fastest: on a shared machine noise only ever adds
time): wall-clock time, bandwidth as counted in the binary, ratio to the STREAM triad of the same
thread count, and speed-up over LAPACK ?gtsv looped over the same systems (its time / this
time, median / median and best / best).

The triad reference here is the best triad bandwidth seen anywhere in the file for that thread
count: the binary's own measurement at startup (the triad_bytes_per_second counter) or any
repetition of BM_solvers_stream_triad, whichever is higher. The binary's triad_ratio counter uses
the startup measurement alone, which a busy moment at startup can lower.

    python3 bench/summarize_solvers.py [results/bench_solvers.json] ['regex on names']
"""
import json
import re
import statistics
import sys
from collections import defaultdict


def fields(run_name):
    """(method, scalar, form, shape, threads) of BM_solvers_<method>/<scalar>/[<form>/]<shape>/threads:<t>"""
    parts = run_name.removesuffix("/real_time").split("/")
    method = parts[0].removeprefix("BM_solvers_")
    if len(parts) == 4:  # the STREAM kernels have no form
        return method, parts[1], "", parts[2], parts[3]
    return method, parts[1], parts[2], parts[3], parts[4]


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "results/bench_solvers.json"
    pattern = re.compile(sys.argv[2] if len(sys.argv) > 2 else ".")
    with open(path) as f:
        benchmarks = json.load(f)["benchmarks"]

    repetitions = defaultdict(list)  # run_name -> the records of its repetitions
    medians = {}  # run_name -> the median aggregate, when there were repetitions
    for b in benchmarks:
        if b.get("error_occurred"):
            print(f"ERROR {b['run_name']}: {b.get('error_message', '')}", file=sys.stderr)
        elif b["run_type"] == "iteration":
            assert b["time_unit"] == "ms"
            repetitions[b["run_name"]].append(b)
        elif b.get("aggregate_name") == "median":
            medians[b["run_name"]] = b
    if not repetitions:
        sys.exit("no repetitions in the file: run without --benchmark_report_aggregates_only")

    def median(name, key):
        if name in medians:
            return medians[name][key]
        return statistics.median(r[key] for r in repetitions[name])

    def best(name):
        return min(repetitions[name], key=lambda r: r["real_time"])

    triad = defaultdict(float)  # threads:<t> -> best triad bandwidth seen (bytes/s)
    for name, runs in repetitions.items():
        method, _, _, _, threads = fields(name)
        for r in runs:
            triad[threads] = max(triad[threads], r["triad_bytes_per_second"])
            if method == "stream_triad":
                triad[threads] = max(triad[threads], r["bytes_per_second"])
    for threads, bandwidth in sorted(triad.items()):
        print(f"triad reference, {threads}: {bandwidth / 1e9:.1f} GB/s")
    print()

    peers = {}
    for name in repetitions:
        method, scalar, _, shape, threads = fields(name)
        if method == "lapack_gtsv":
            peers[(scalar, shape, threads)] = name

    def order(name):
        method, scalar, form, shape, threads = fields(name)
        return (scalar, shape, threads, method != "lapack_gtsv", form, method)

    print("| benchmark | ms median | ms best | GB/s median | GB/s best | / triad median "
          "| / triad best | vs ?gtsv median | vs ?gtsv best |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in sorted(repetitions, key=order):
        if not pattern.search(name):
            continue
        method, scalar, _, shape, threads = fields(name)
        peer = peers.get((scalar, shape, threads))
        speedups = ["", ""]
        if peer:
            speedups = [f"{median(peer, 'real_time') / median(name, 'real_time'):.2f}x",
                        f"{best(peer)['real_time'] / best(name)['real_time']:.2f}x"]
        print(f"| {name.removesuffix('/real_time')} "
              f"| {median(name, 'real_time'):.2f} | {best(name)['real_time']:.2f} "
              f"| {median(name, 'bytes_per_second') / 1e9:.1f} "
              f"| {best(name)['bytes_per_second'] / 1e9:.1f} "
              f"| {median(name, 'bytes_per_second') / triad[threads]:.3f} "
              f"| {best(name)['bytes_per_second'] / triad[threads]:.3f} "
              f"| {speedups[0]} | {speedups[1]} |")


if __name__ == "__main__":
    main()
