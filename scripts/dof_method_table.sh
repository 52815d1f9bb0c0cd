#!/usr/bin/env bash
# Regenerates dof/data/method_table.csv, the measured cost and error of every DOF method on the
# built-in scenes that `tridiff dof --method auto` chooses from. Run on a quiet machine (the
# times are absolute); a few minutes on 2 cores.
#
#   bash scripts/dof_method_table.sh [--size N] [--threads T] [--method NAME]...
#
# --method NAME (repeatable) re-measures that method alone and replaces its rows in the table,
# keeping the others (at the size and thread count its rows were measured with, unless given).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build --target tridiff_dof_method_table -j "$(nproc)"
./build/tools/tridiff_dof_method_table --output dof/data/method_table.csv "$@"
echo "wrote dof/data/method_table.csv; rebuild to compile it in"
