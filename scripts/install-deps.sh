#!/usr/bin/env bash
# Installs tdf's dependencies from Debian packages (Debian 12), and the report pages' scripts from npm.
#   scripts/install-deps.sh tool   what `tdf` itself needs: the compiler, the libraries it links and
#                                  three.js for the report pages (README command 1)
#   scripts/install-deps.sh        that, and what the tests need: GoogleTest, Google Benchmark,
#                                  OpenImageIO's tools, Chromium, Slurm + munge, clang for the
#                                  libFuzzer job, the browser and glTF-validator scripts (command 2)
# The tool set is a subset, so command 2 only adds packages. slurm-wlm and munge: `tdf batch
# --engine slurm` and its test (tests/batch/), which starts a throw-away single-node Slurm; their
# postinst scripts cannot start services here, which is fine.
# Safe to run again: apt-get skips what is already installed.
set -euo pipefail
what=${1:-all}
case "$what" in tool|all) ;; *) echo "install-deps: unknown set '$what' (tool or nothing)" >&2; exit 2 ;; esac
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
TOOL_PACKAGES=(build-essential cmake ninja-build pkg-config git ccache
  libembree-dev libopenexr-dev libcgal-dev libeigen3-dev libtbb-dev libfftw3-dev
  nlohmann-json3-dev libcli11-dev libfmt-dev libtinygltf-dev libpng-dev libjpeg-dev zlib1g-dev)
TEST_PACKAGES=(libgtest-dev libgmock-dev libbenchmark-dev libopenimageio-dev openimageio-tools chromium
  slurm-wlm munge clang libclang-rt-14-dev)  # clang: the libFuzzer job (scripts/fuzz.sh)
packages=("${TOOL_PACKAGES[@]}")
if [ "$what" = all ]; then packages+=("${TEST_PACKAGES[@]}"); fi
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
# Node for the HTML reports' scripts and their browser tests (Debian's, unless a node is present).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  $SUDO apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
# three.js (copied beside every report page), and for the tests puppeteer-core (drives Debian's
# chromium, downloads no browser), pngjs and gltf-validator, at the versions pinned in
# web/package-lock.json, into web/node_modules.
(cd "$(dirname "$0")/../web" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error >/dev/null)
echo "install-deps: the $what packages are present"
