#!/usr/bin/env bash
# Installs the Debian packages tridiff needs that are not installed yet (run as root, or with
# sudo available). Installs nothing when everything is present.
#   bash scripts/deps.sh              # the build, tests and benchmarks
#   bash scripts/deps.sh notebooks    # those plus the notebooks' Python (scripts/notebooks.sh)
#   bash scripts/deps.sh fuzz         # those plus clang and libFuzzer (scripts/fuzz.sh)
#   bash scripts/deps.sh format       # those plus clang-format 14 (scripts/format.sh --check)
set -euo pipefail

packages=(
  g++ cmake make            # toolchain (OpenMP comes with g++)
  libeigen3-dev             # tests: the long-double LU reference
  libgtest-dev              # tests
  libbenchmark-dev          # benchmarks
  libfftw3-dev              # blur: FFT convolution (single precision, OpenMP threads)
  liblapack-dev             # tests and benchmarks only: LAPACK ?gtsv as the yardstick
  libopencv-dev             # benchmarks only: cv::GaussianBlur as the blur yardstick
  libopenimageio-dev        # image reading and writing
  openimageio-tools         # Debian 12: OpenImageIO's CMake config fails without the tools
  libopenmpi-dev openmpi-bin  # distributed/: solves and ADI across MPI ranks, and mpirun
  pybind11-dev python3-dev  # the Python module (python/), built for Debian's /usr/bin/python3
  python3-numpy python3-scipy python3-pytest  # its tests: scipy is the reference
)
# The notebooks (notebooks/*.ipynb) run on Debian's Python: no other package index is needed.
notebook_packages=(
  python3-numpy python3-matplotlib
  python3-nbformat python3-nbclient python3-ipykernel jupyter-nbconvert
)
# The fuzz targets (fuzz/) need clang: libFuzzer ships in clang's runtime package, and clang's
# -fopenmp needs LLVM's OpenMP (libomp), not GCC's.
fuzz_packages=(clang libclang-rt-14-dev libomp-dev)
# The format check (scripts/format.sh, .clang-format): Debian 12's clang-format is version 14,
# the version the configuration was measured with.
format_packages=(clang-format)
for group in "$@"; do
  case "$group" in
    notebooks) packages+=("${notebook_packages[@]}") ;;
    fuzz) packages+=("${fuzz_packages[@]}") ;;
    format) packages+=("${format_packages[@]}") ;;
    *) echo "scripts/deps.sh: unknown group '$group' (expected: notebooks, fuzz, format)" >&2
       exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "tridiff: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
