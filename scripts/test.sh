#!/usr/bin/env bash
# Set up, build with warnings as errors, and run every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
# The Python module is built for Debian's interpreter, for which deps.sh installs numpy and scipy.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTRIDIFF_WERROR=ON -DTRIDIFF_BUILD_TESTS=ON \
      -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build build -j"$(nproc)"
# Tests run side by side, each with OpenMP threads: waiting threads must sleep, not spin.
OMP_WAIT_POLICY=passive ctest --test-dir build --output-on-failure --no-tests=error -j"$(nproc)"
# The Python module (python/tests, against scipy), straight from the build folder.
OMP_WAIT_POLICY=passive PYTHONPATH=build/python /usr/bin/python3 -m pytest -q -p no:cacheprovider \
  python/tests
