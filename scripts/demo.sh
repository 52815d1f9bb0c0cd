#!/usr/bin/env bash
# The main job: set up, build, and render depth of field on the built-in procedural scene
# (the default method, bokeh: isotropic heat diffusion for the body, the out-of-focus highlights
# as aperture-shaped sprites, the near field as its own layer). Writes results/dof_input.png,
# results/dof.png, results/dof_coc.png and results/dof_report.json.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target tridiff
mkdir -p results
./build/dof/tridiff dof --input-output results/dof_input.png -o results/dof.png \
  --report results/dof_report.json
