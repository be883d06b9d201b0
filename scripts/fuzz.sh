#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang, ASan + UBSan, -DTDF_FUZZ=ON) and runs each one.
#   scripts/fuzz.sh                  every harness for $TDF_FUZZ_SECONDS (default 25) seconds
#   scripts/fuzz.sh obj npy          only these harnesses
#   TDF_FUZZ_SECONDS=600 scripts/fuzz.sh image     a longer run
#   TDF_FUZZ_RUNS=1000000 TDF_FUZZ_SECONDS=3600 scripts/fuzz.sh   stop each at 1 M executions
# Harnesses: obj gltf ply image npy tmd scene (tests/fuzz/fuzz_targets.cpp).
# Each run starts from the generated seeds (make_fuzz_seeds), the committed regression inputs
# (tests/fuzz/regressions/<name>) and the dictionary tests/fuzz/dict/<name>.dict when present;
# the corpus grown by the run stays in build-fuzz/corpus/<name>. A crash, leak, sanitizer report,
# timeout (10 s per input) or out-of-memory (2 GB) fails the script; the input is saved to
# build-fuzz/crashes/<name>/ -- fix the reader, then copy the file into
# tests/fuzz/regressions/<name>/ so that tdf_fuzz_regression_tests replays it forever.
# A summary line per harness (executions, coverage, corpus) goes to build-fuzz/fuzz_summary.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BUILD=${TDF_FUZZ_BUILD:-build-fuzz}
SECONDS_EACH=${TDF_FUZZ_SECONDS:-25}
JOBS=${TDF_JOBS:-$(nproc)}
ALL=(obj gltf ply image npy tmd scene)
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=("${ALL[@]}")

if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ -DTDF_FUZZ=ON -DTDF_BUILD_TESTS=OFF -DTDF_BUILD_BENCH=OFF \
    ${CMAKE_CXX_COMPILER_LAUNCHER:+-DCMAKE_CXX_COMPILER_LAUNCHER=$CMAKE_CXX_COMPILER_LAUNCHER} >/dev/null
fi
cmake --build "$BUILD" -j"$JOBS" --target fuzz_all

rm -rf "$BUILD/seeds"
"$BUILD/fuzz/make_fuzz_seeds" "$BUILD/seeds"
SUMMARY=$BUILD/fuzz_summary.txt
: >"$SUMMARY"
failed=()
for t in "${TARGETS[@]}"; do
  corpus=$BUILD/corpus/$t
  crashes=$BUILD/crashes/$t
  mkdir -p "$corpus" "$crashes"
  seeds=("$BUILD/seeds/$t")
  [ -d "tests/fuzz/regressions/$t" ] && seeds+=("tests/fuzz/regressions/$t")
  dict=()
  [ -f "tests/fuzz/dict/$t.dict" ] && dict=(-dict="tests/fuzz/dict/$t.dict")
  log=$BUILD/fuzz_$t.log
  # Image inputs may legally decode to 4096 bytes per file byte (docs/robustness.md "Limits"), so long
  # image inputs spend their time in memset; 2 KB inputs (up to 8 MB decoded) keep the
  # harness fast. Other readers take up to 64 KB.
  max_len=65536
  [ "$t" = image ] && max_len=2048
  runs=()
  [ -n "${TDF_FUZZ_RUNS:-}" ] && runs=(-runs="$TDF_FUZZ_RUNS")
  echo "fuzz $t: ${SECONDS_EACH} s"
  # Warnings of the readers go to stderr on every input; -close_fd_mask=2 silences them while
  # sanitizer and libFuzzer reports still print.
  set +e
  (cd "$BUILD" && ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 \
     UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
     "./fuzz/fuzz_$t" "$ROOT/$corpus" "${seeds[@]/#/$ROOT/}" "${dict[@]/#-dict=/-dict=$ROOT/}" \
       -max_total_time="$SECONDS_EACH" "${runs[@]}" -timeout=10 -rss_limit_mb=2048 -max_len="$max_len" \
       -print_final_stats=1 -close_fd_mask=2 -artifact_prefix="$ROOT/$crashes/") >"$log" 2>&1
  rc=$?
  set -e
  executed=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -E '^#[0-9]+.*(DONE|cov:)' "$log" | tail -1 | grep -o 'cov: [0-9]*' | grep -o '[0-9]*' || echo "?")
  ft=$(grep -E '^#[0-9]+.*(DONE|cov:)' "$log" | tail -1 | grep -o 'ft: [0-9]*' | grep -o '[0-9]*' || echo "?")
  files=$(ls "$corpus" | wc -l)
  took=$(grep -oE 'Done [0-9]+ runs in [0-9]+ second' "$log" | grep -oE '[0-9]+ second' | grep -oE '[0-9]+' || echo "$SECONDS_EACH")
  line="$t: ${executed} executions in ${took} s, coverage ${cov} edges (${ft} features), corpus ${files} files, exit ${rc}"
  echo "  $line"
  echo "$line" >>"$SUMMARY"
  if [ $rc -ne 0 ]; then
    failed+=("$t")
    grep -E 'ERROR|SUMMARY|runtime error|Test unit written' "$log" | head -20 || true
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzzing found problems in: ${failed[*]} (logs: $BUILD/fuzz_<name>.log, inputs: $BUILD/crashes/)"
  exit 1
fi
echo "fuzzing: no crash, leak or sanitizer report (summary: $SUMMARY)"
