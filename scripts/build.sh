#!/usr/bin/env bash
# Configures (Release, warnings as errors) and builds tdf in build/: the one configuration both
# README commands use, so the second reuses what the first built.
#   scripts/build.sh            every target (tdf, libraries, tests, benchmarks)
#   scripts/build.sh tdf        only the command-line tool (README command 1): configured without
#                               the test and benchmark targets, whose packages command 1 does not
#                               install; the full build turns them on and reuses every object
# ccache, when installed (install-deps.sh installs it), compiles through a cache whose base
# directory is the checkout: a clone at another path (CI's fresh clone) reuses the objects.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${TDF_JOBS:-$(nproc)}
LAUNCHER=()
if command -v ccache >/dev/null; then
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
SUITES=ON
if [ "$*" = tdf ]; then SUITES=OFF; fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DTDF_WERROR=ON \
  -DTDF_BUILD_TESTS=$SUITES -DTDF_BUILD_BENCH=$SUITES "${LAUNCHER[@]}" >/dev/null
if [ $# -gt 0 ]; then
  cmake --build build -j"$JOBS" --target "$@"
else
  cmake --build build -j"$JOBS"
fi
