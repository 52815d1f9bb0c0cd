#!/usr/bin/env bash
# Builds and runs the blur benchmarks (time and error per method, sigma, size, threads, with
# OpenCV and a copy); writes results/bench_blur.json.
#
#   bash bench/run_blur.sh                                  # everything (about 20 minutes)
#   bash bench/run_blur.sh 'sigma:(2|8)/4096/threads:2'     # a filter on the names
set -euo pipefail
cd "$(dirname "$0")/.."
bash bench/run_bench.sh tridiff_bench_blur results/bench_blur.json "$@"
