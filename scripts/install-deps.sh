#!/usr/bin/env bash
# Installs every build and test dependency of tdf from Debian packages (Debian 12).
# Safe to run again: apt-get skips what is already installed.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  build-essential cmake ninja-build pkg-config git \
  libembree-dev libopenimageio-dev openimageio-tools libopenexr-dev libcgal-dev libeigen3-dev \
  libtbb-dev libgtest-dev libgmock-dev libbenchmark-dev libfftw3-dev nlohmann-json3-dev libcli11-dev \
  libfmt-dev libtinygltf-dev libpng-dev libjpeg-dev zlib1g-dev \
  clang libclang-rt-14-dev >/dev/null  # clang: the libFuzzer job (scripts/fuzz.sh)
echo "install-deps: all packages present"
