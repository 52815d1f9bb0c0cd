#!/usr/bin/env bash
# Installs the Debian packages tridiff needs that are not installed yet (run as root, or with
# sudo available). Installs nothing when everything is present.
set -euo pipefail

packages=(
  g++ cmake make            # toolchain (OpenMP comes with g++)
  libeigen3-dev             # tests: the long-double LU reference
  libgtest-dev              # tests
  libbenchmark-dev          # benchmarks
  liblapack-dev             # tests and benchmarks only: LAPACK ?gtsv as the yardstick
  libopenimageio-dev        # image reading and writing
  openimageio-tools         # Debian 12: OpenImageIO's CMake config fails without the tools
)

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
