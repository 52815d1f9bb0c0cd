#!/usr/bin/env bash
# Runs tridiff_bench_distributed on 1 and 2 ranks (the cores of this machine) and, as a check,
# 4 ranks oversubscribed; appends one JSON object a line to results/bench_distributed.jsonl.
#   bash bench/run_distributed.sh [BUILD_DIR] [extra arguments for the benchmark]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
mkdir -p results
out=results/bench_distributed.jsonl
# Open MPI refuses to run as root (CI containers) unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
for ranks in 1 2 4; do
  mpirun -n "$ranks" --oversubscribe "$build/bench/tridiff_bench_distributed" "$@" | tee -a "$out"
done
