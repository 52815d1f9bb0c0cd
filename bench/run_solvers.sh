#!/usr/bin/env bash
# Builds and runs the solver benchmarks; writes results/bench_solvers.json and prints a Markdown
# table of the medians and best times with their ratios to the triad bandwidth and to LAPACK
# ?gtsv (bench/summarize_solvers.py).
#
#   bash bench/run_solvers.sh                   # everything (about 15 minutes on 2 cores)
#   bash bench/run_solvers.sh 'thomas|lapack'   # a filter: a regular expression on the names
#   bash bench/run_solvers.sh . --benchmark_repetitions=5   # further flags go to the binary
#   TRIDIFF_BENCH_BUILD_DIR=build-bench bash bench/run_solvers.sh   # another build directory
set -euo pipefail
cd "$(dirname "$0")/.."
bash bench/run_bench.sh tridiff_bench_solvers results/bench_solvers.json "$@"
python3 bench/summarize_solvers.py results/bench_solvers.json
