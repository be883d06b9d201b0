#!/usr/bin/env bash
# Installs every build and test dependency of tdf from Debian packages (Debian 12).
# slurm-wlm and munge: `tdf batch --engine slurm` and its test (tests/batch/), which starts a
# throw-away single-node Slurm; the postinst scripts cannot start services here, which is fine.
# Safe to run again: apt-get skips what is already installed.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  build-essential cmake ninja-build pkg-config git ccache \
  libembree-dev libopenimageio-dev openimageio-tools libopenexr-dev libcgal-dev libeigen3-dev \
  libtbb-dev libgtest-dev libgmock-dev libbenchmark-dev libfftw3-dev nlohmann-json3-dev libcli11-dev \
  libfmt-dev libtinygltf-dev libpng-dev libjpeg-dev zlib1g-dev chromium \
  slurm-wlm munge clang libclang-rt-14-dev >/dev/null  # clang: the libFuzzer job (scripts/fuzz.sh)
# Node for the HTML reports' scripts and their browser tests (Debian's, unless a node is present).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  $SUDO apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
# three.js (copied beside every report page), puppeteer-core (drives Debian's chromium, downloads
# no browser), pngjs and gltf-validator, at the versions pinned in web/package-lock.json, into
# web/node_modules.
(cd "$(dirname "$0")/../web" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error >/dev/null)
echo "install-deps: all packages present"
