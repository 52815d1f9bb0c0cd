#!/usr/bin/env bash
# Builds one benchmark binary and runs it: bench/run_bench.sh TARGET JSON [FILTER [FLAGS...]].
# Writes Google Benchmark JSON (every repetition plus mean, median, stddev, cv) to JSON; the
# console shows only the aggregates. Repetitions are randomly interleaved across benchmarks:
# the machine's memory bandwidth and cores may be shared, and interleaving spreads any slow
# period over all benchmarks instead of a few, which keeps the ratios between them honest.
# TRIDIFF_BENCH_BUILD_DIR picks the build directory (default: build).
set -euo pipefail
cd "$(dirname "$0")/.."
target="$1"
out="$2"
filter="${3:-.}"
shift 3 || shift $#
build="${TRIDIFF_BENCH_BUILD_DIR:-build}"

bash scripts/deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target "$target"
mkdir -p "$(dirname "$out")"
"$build/bench/$target" \
  --benchmark_filter="$filter" \
  --benchmark_repetitions=3 \
  --benchmark_display_aggregates_only=true \
  --benchmark_enable_random_interleaving=true \
  --benchmark_out="$out" \
  --benchmark_out_format=json \
  "$@"
