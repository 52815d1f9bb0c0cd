#!/usr/bin/env bash
# Set up, build with warnings as errors, and run every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTRIDIFF_WERROR=ON -DTRIDIFF_BUILD_TESTS=ON >/dev/null
cmake --build build -j"$(nproc)"
# Tests run side by side, each with OpenMP threads: waiting threads must sleep, not spin.
OMP_WAIT_POLICY=passive ctest --test-dir build --output-on-failure --no-tests=error -j"$(nproc)"
