#!/usr/bin/env bash
# Builds and runs the depth-of-field benchmarks; writes results/bench_dof.json (Google
# Benchmark JSON) and prints the medians with their copy ratios.
#
#   bash bench/run_dof.sh                       # everything
#   bash bench/run_dof.sh 'adi|copy'            # a filter on the names
#   bash bench/run_dof.sh . --benchmark_repetitions=5
set -euo pipefail
cd "$(dirname "$0")/.."
filter="${1:-.}"
shift || true
build="${TRIDIFF_BENCH_BUILD_DIR:-build}"
out=results/bench_dof.json

bash scripts/deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target tridiff_bench_dof
mkdir -p results
"$build/bench/tridiff_bench_dof" \
  --benchmark_filter="$filter" \
  --benchmark_repetitions=3 \
  --benchmark_display_aggregates_only=true \
  --benchmark_enable_random_interleaving=true \
  --benchmark_out="$out" \
  --benchmark_out_format=json \
  "$@"
