#!/usr/bin/env bash
# The main job: set up, build, and render depth of field on the built-in procedural scene
# (the default method, bokeh: isotropic heat diffusion for the body, the out-of-focus highlights
# as aperture-shaped sprites, the near field as its own layer). Writes results/dof_input.png,
# results/dof.png, results/dof_coc.png and results/dof_report.json. Also builds the Python
# module and installs it for Debian's python3 (`import tridiff`; python/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build build -j"$(nproc)" --target tridiff tridiff_python
# `import tridiff` for Debian's python3: the package goes to /usr/local/lib/python3.11/dist-packages.
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
$sudo cmake --install build --component python >/dev/null
mkdir -p results
./build/dof/tridiff dof --input-output results/dof_input.png -o results/dof.png \
  --report results/dof_report.json
