#!/usr/bin/env bash
# Scores every DOF method against the thin-lens truth of the ray-traced scenes (procedural,
# lamps): builds tools/dof_truth_score.cpp and runs it. The truth is rendered once per scene,
# size, sample count and aperture and cached under results/truth/ (gitignored).
#
#   bash scripts/dof_truth_table.sh [--width W] [--height H] [--scene NAME]... [--samples N]
#                                   [--threads T]
#
# Defaults: 512 x 288, both scenes, 2 threads. 1920 x 1080 renders the truth for minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build --target tridiff_dof_truth_score -j 2
./build/tools/tridiff_dof_truth_score "$@"
