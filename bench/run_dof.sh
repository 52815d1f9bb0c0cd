#!/usr/bin/env bash
# Builds and runs the depth-of-field benchmarks; writes results/bench_dof.json.
#
#   bash bench/run_dof.sh                       # everything
#   bash bench/run_dof.sh 'adi|copy'            # a filter on the names
#   bash bench/run_dof.sh . --benchmark_repetitions=5
set -euo pipefail
cd "$(dirname "$0")/.."
bash bench/run_bench.sh tridiff_bench_dof results/bench_dof.json "$@"
