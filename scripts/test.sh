#!/usr/bin/env bash
# Builds tdf and runs every test suite. This is the README's second command and what CI runs.
#   scripts/test.sh            install dependencies, Release build, all tests, sanitizer job
#   TDF_SKIP_INSTALL=1 ...     skip apt-get (dependencies already present)
#   TDF_SKIP_SANITIZE=1 ...    skip the ASan/UBSan loader job
#   TDF_SKIP_FUZZ=1 ...        skip the libFuzzer job (scripts/fuzz.sh, 20 s per harness in CI)
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${TDF_JOBS:-$(nproc)}
if [ "${TDF_SKIP_INSTALL:-0}" != 1 ]; then bash scripts/install-deps.sh; fi

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DTDF_WERROR=ON >/dev/null
cmake --build build -j"$JOBS"
ctest --test-dir build --output-on-failure -j"$JOBS" -LE slow

if [ "${TDF_SKIP_SANITIZE:-0}" != 1 ]; then
  # Loaders and image I/O under AddressSanitizer + UndefinedBehaviorSanitizer, fed bad input.
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DTDF_SANITIZE=ON -DTDF_BUILD_BENCH=OFF >/dev/null
  cmake --build build-asan -j"$JOBS" --target tdf_io_tests tdf_mesh_tests
  ctest --test-dir build-asan --output-on-failure -j"$JOBS" -R '^(ImageIo|ObjIo|GltfIo|PlyIo)\.'
fi

if [ "${TDF_SKIP_FUZZ:-0}" != 1 ]; then
  # Every reader's libFuzzer harness (clang, ASan + UBSan) for a short bounded time; any crash,
  # leak, sanitizer report, timeout or out-of-memory fails CI (README "Robustness").
  TDF_FUZZ_SECONDS=${TDF_FUZZ_SECONDS:-20} TDF_JOBS="$JOBS" bash scripts/fuzz.sh
fi
