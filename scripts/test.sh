#!/usr/bin/env bash
# Builds tdf and runs every test suite. This is the README's second command and what CI runs.
#   scripts/test.sh            install dependencies, Release build, all tests, sanitizer job, fuzz job
#   TDF_SKIP_INSTALL=1 ...     skip apt-get (dependencies already present)
#   TDF_SKIP_SANITIZE=1 ...    skip the ASan/UBSan job (the whole suite again, sanitized)
#   TDF_SKIP_FUZZ=1 ...        skip the libFuzzer job (scripts/fuzz.sh, 20 s per harness in CI)
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${TDF_JOBS:-$(nproc)}
if [ "${TDF_SKIP_INSTALL:-0}" != 1 ]; then bash scripts/install-deps.sh; fi
bash scripts/build.sh
# The sanitizer build below goes through the same cache (scripts/build.sh).
LAUNCHER=()
if command -v ccache >/dev/null; then
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
ctest --test-dir build --output-on-failure -j"$JOBS" -LE slow

# The vectorised lanes' AVX2 clones (include/tdf/core/simd_clones.h): on an AVX-512 machine the
# suite above runs the AVX-512 ones. A Release build whose lanes have only AVX2 and baseline
# clones (only their two files differ from build/, the rest comes from the cache) runs the render
# unit tests, whose lanes tests compare every bit with the scalar formulas. The sanitized build
# cannot stand in: the sanitizers' checks keep the lanes from vectorising.
cmake -S . -B build-avx2 -G Ninja -DCMAKE_BUILD_TYPE=Release "-DTDF_SIMD_CLONES=avx2;default" \
  -DTDF_BUILD_BENCH=OFF -DTDF_WERROR=ON "${LAUNCHER[@]}" >/dev/null
cmake --build build-avx2 -j"$JOBS" --target tdf_render_tests
ctest --test-dir build-avx2 --output-on-failure -j"$JOBS" -L unit_render

if [ "${TDF_SKIP_SANITIZE:-0}" != 1 ]; then
  # The whole test suite again, built with AddressSanitizer + UndefinedBehaviorSanitizer (every
  # library, tdf itself, every gtest binary and the CLI tests that run tdf). Any report (memory
  # error, leak, UB) fails the test that hit it. -O1 -g1 keeps the numeric tests affordable; the
  # one CGAL file stays at -O0 (src/CMakeLists.txt: 3.4 min to compile at -O1, 37 s at -O0).
  # Left out: MaterialEndToEnd (every shared sample through the tactile pipeline: 52 s in Release,
  # 462 s sanitized; the same code runs sanitized in the smaller Pipeline and Quilting tests).
  # Warnings are not errors here (the Release build above is the warning gate): with the
  # sanitizers' instrumentation g++ 12 reports false -Wmaybe-uninitialized inside <regex>.
  # Cost: docs/measurements.md "Cost of the ASan + UBSan job".
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -g1" \
    -DTDF_SANITIZE=ON -DTDF_BUILD_BENCH=OFF -DTDF_WERROR=OFF -DCGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE=TRUE "${LAUNCHER[@]}" >/dev/null
  cmake --build build-asan -j"$JOBS"
  ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 \
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j"$JOBS" -LE slow -E '^MaterialEndToEnd\.'
fi

if [ "${TDF_SKIP_FUZZ:-0}" != 1 ]; then
  # Every reader's libFuzzer harness (clang, ASan + UBSan) for a short bounded time; any crash,
  # leak, sanitizer report, timeout or out-of-memory fails CI (docs/robustness.md).
  TDF_FUZZ_SECONDS=${TDF_FUZZ_SECONDS:-20} TDF_JOBS="$JOBS" bash scripts/fuzz.sh
fi
