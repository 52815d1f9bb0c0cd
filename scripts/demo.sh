#!/usr/bin/env bash
# The main job: set up, build, and run the solver demo on its built-in batch.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target tridiff_solver_demo
./build/tools/tridiff_solver_demo
