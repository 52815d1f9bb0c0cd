#!/usr/bin/env bash
# Builds and runs the solver benchmarks; writes results/bench_solvers.json (Google Benchmark
# JSON: every repetition plus mean, median, stddev and cv) and prints a Markdown table of the
# medians and best times with their ratios to the triad bandwidth and to LAPACK ?gtsv
# (bench/summarize_solvers.py). The console shows only the aggregates.
#
#   bash bench/run_solvers.sh                   # everything (about 15 minutes on 2 cores)
#   bash bench/run_solvers.sh 'thomas|lapack'   # a filter: a regular expression on the names
#   bash bench/run_solvers.sh . --benchmark_repetitions=5   # further flags go to the binary
#   TRIDIFF_BENCH_BUILD_DIR=build-bench bash bench/run_solvers.sh   # another build directory
#
# Repetitions are randomly interleaved across benchmarks: the machine's memory bandwidth and
# cores may be shared, and interleaving spreads any slow period over all benchmarks instead of
# concentrating it on a few, which keeps the ratios between them honest.
set -euo pipefail
cd "$(dirname "$0")/.."
filter="${1:-.}"
shift || true
build="${TRIDIFF_BENCH_BUILD_DIR:-build}"
out=results/bench_solvers.json

bash scripts/deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target tridiff_bench_solvers
mkdir -p results
"$build/bench/tridiff_bench_solvers" \
  --benchmark_filter="$filter" \
  --benchmark_repetitions=3 \
  --benchmark_display_aggregates_only=true \
  --benchmark_enable_random_interleaving=true \
  --benchmark_out="$out" \
  --benchmark_out_format=json \
  "$@"
python3 bench/summarize_solvers.py "$out"
