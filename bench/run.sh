#!/usr/bin/env bash
# Runs the Google Benchmark programs already built in build/bench (builds nothing) and prints,
# for each program, every benchmark's throughput and its ratio to that program's baseline
# measured in the same run: the benchmark whose name starts with BM_Baseline and has the same
# arguments (e.g. threads:2). Numbers on a shared machine are noisy; the CPU-time column of
# single-thread runs is the steadiest.
#   bench/run.sh                  all tdf_*_bench programs
#   bench/run.sh render           only tdf_render_bench
#   BENCH_ARGS="--benchmark_repetitions=5" bench/run.sh render    (medians are reported)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${TDF_BUILD_DIR:-build}
OUT="$BUILD/bench-results"
mkdir -p "$OUT"
shopt -s nullglob
programs=("$BUILD"/bench/tdf_${1:-*}_bench)
if [ ${#programs[@]} -eq 0 ]; then
  echo "no benchmark programs in $BUILD/bench (build first: cmake --build $BUILD)" >&2
  exit 1
fi
for program in "${programs[@]}"; do
  name=$(basename "$program")
  echo "== $name"
  "$program" --benchmark_format=json --benchmark_out="$OUT/$name.json" --benchmark_out_format=json \
    ${BENCH_ARGS:-} >/dev/null
  python3 - "$OUT/$name.json" <<'PY'
import json, sys
all_runs = json.load(open(sys.argv[1]))["benchmarks"]
# With --benchmark_repetitions, report the medians.
runs = [b for b in all_runs if b.get("aggregate_name") == "median"]
for b in runs:
    b["name"] = b["name"].removesuffix("_median")
if not runs:
    runs = [b for b in all_runs if b.get("run_type", "iteration") == "iteration"]
def split(name):
    base, _, args = name.partition("/")
    # How the time was taken (real, manual, process CPU) does not make another configuration.
    args = "/".join(a for a in args.split("/") if a not in ("real_time", "manual_time", "process_time"))
    return base, args
def rate(b):
    return b.get("rays_per_s") or b.get("items_per_second") or 1.0 / b["real_time"]
baselines = {split(b["name"])[1]: b for b in runs if split(b["name"])[0].startswith("BM_Baseline")}
print(f"{'benchmark':<60} {'real ms':>9} {'cpu ms':>9} {'rays/s (M)':>11} {'x baseline':>11} {'cpu x base':>11}")
for b in runs:
    base = baselines.get(split(b["name"])[1])
    ratio = f"{rate(base) / rate(b):11.2f}" if base else f"{'-':>11}"
    cpu_ratio = f"{b['cpu_time'] / base['cpu_time']:11.2f}" if base else f"{'-':>11}"
    print(f"{b['name']:<60} {b['real_time']:9.2f} {b['cpu_time']:9.2f} {rate(b) / 1e6:11.2f} {ratio} {cpu_ratio}")
    # Per-stage seconds (counters s_<stage>), partial CPU times (cpu_ms_<part>) and peak memory,
    # when a benchmark reports them.
    extra = [f"{k}={b[k]:.4g}" for k in sorted(b) if k.startswith(("s_", "cpu_ms_")) or k == "peak_RSS_MB"]
    if extra:
        print(f"    {' '.join(extra)}")
print("(x baseline = slowdown against the BM_Baseline benchmark with the same arguments; 1.00 = as fast;"
      " s_<stage> = seconds per iteration)")
PY
done
