#!/usr/bin/env bash
# `tdf batch run` at scale (docs/commands/batch.md "Measured"; a benchmark, not a test):
#   bench/batch_1000.sh [local] [N]   N tiny optimize jobs (default 1000) on this machine, 5 % of
#                                     them bad inputs (a mesh that does not parse) and 2 % killing
#                                     themselves on their first attempt (test-only TDF_TEST_KILL_JOBS)
#   bench/batch_1000.sh slurm [N]     the same with N = 200 by default as Slurm array tasks on a
#                                     throw-away single-node Slurm (tests/batch/slurm_cluster.sh);
#                                     the killed ones come back in a retry round
# Baseline, measured in the same run: the same N command lines run directly by `xargs -P J`
# (no kills, no state, no retries). Printed: wall and CPU of both, jobs per minute, the
# scheduler's overhead per job (wall and CPU, ms), files and bytes per job, and the checks
# (every good job done exactly once, every bad one failed-input, the killed ones retried).
# Builds nothing (needs build/tdf); results in build/bench-results/batch_1000/.
set -euo pipefail
cd "$(dirname "$0")/.."
src=$(pwd)
tdf=$src/${TDF_BUILD_DIR:-build}/tdf
engine=local
case "${1:-}" in local|slurm) engine=$1; shift;; esac
n=${1:-$([ $engine = slurm ] && echo 200 || echo 1000)}
parallel=${JOBS:-$(nproc)}
work=$src/${TDF_BUILD_DIR:-build}/bench-results/batch_1000_$engine
rm -rf "$work"
mkdir -p "$work"
cd "$work"

scene=$src/scenes/pebble_sphere/scene.json
# The tiniest optimize that still runs every stage (initialize, optimize, export, report):
# about 0.4 s and 2.6 MB on one thread.
small="optimize.iterations=20 optimize.init_iterations=10 optimize.resolution=64 optimize.patch_resolution=32"
small="$small optimize.batch_size=1 optimize.patch_batch_size=1 optimize.held_out_views=1"
small="$small optimize.held_out_patches=1 export.texture_size=64 export.turntable_views=1"
small="$small export.turntable_resolution=32 export.glb=false guidance.tactile=none guidance.visual=none"
small="$small field.table_log2=12"
printf 'v 0 0 0\nv 1 0\nf 1 2 3\n' > bad.obj

# Job k: bad when k % 20 == 7 (5 %), killed once when k % 50 == 3 (2 %).
echo "name,command,args" > manifest.csv
kills=""
for k in $(seq 0 $((n - 1))); do
  name=$(printf 'j%04d' "$k")
  if [ $((k % 20)) = 7 ]; then
    echo "$name,optimize,$scene $small mesh=$work/bad.obj seed=$k --name a" >> manifest.csv
  else
    echo "$name,optimize,$scene $small seed=$k --name a" >> manifest.csv
  fi
  [ $((k % 50)) = 3 ] && kills="$kills${kills:+,}$name"
done
bad=$(awk -F, 'NR > 1 && /bad.obj/ {c++} END {print c + 0}' manifest.csv)
killed=$(echo "$kills" | tr ',' '\n' | grep -c .)

# The same command lines without tdf batch: `tdf --threads 1 optimize <args> -o base/<name>`.
tail -n +2 manifest.csv | awk -F, -v tdf="$tdf" -v out="$work/base" \
  '{printf "%s -q --threads 1 %s %s -o %s/%s\n", tdf, $2, $3, out, $1}' > baseline.txt

# measure <file> <command...>: "wall_s cpu_s" (CPU = user + sys of the command and its children)
measure() {
  local file=$1; shift
  /usr/bin/time -f "%e %U %S" -o "$file.time" "$@" > "$file.out" 2> "$file.err" || true
  tail -1 "$file.time" | awk '{printf "%.2f %.2f\n", $1, $2 + $3}'
}
echo "$n jobs ($bad bad inputs, $killed killed once), $parallel at a time, 1 thread each; $(date -u +%FT%TZ)"
read -r base_wall base_cpu < <(measure baseline xargs -P "$parallel" -I{} sh -c '{} 2>/dev/null' < baseline.txt)
if [ $engine = slurm ]; then
  env_line=$(bash "$src/tests/batch/slurm_cluster.sh" start "$work/slurm-daemons")
  trap 'bash "$src/tests/batch/slurm_cluster.sh" stop "$work/slurm-daemons"' EXIT
  eval "$env_line"
  # CPU here is only what ran under this shell (submission, waiting): the tasks run under slurmd.
  read -r bat_wall bat_cpu < <(TDF_TEST_KILL_JOBS=$kills measure batch \
    "$tdf" batch run manifest.csv -o b --engine slurm --max-parallel "$parallel" --cpus-per-task 1 --wait)
  bat_cpu=nan
else
  read -r bat_wall bat_cpu < <(TDF_TEST_KILL_JOBS=$kills measure batch \
    "$tdf" batch run manifest.csv -o b --jobs "$parallel" --threads-per-job 1)
fi

python3 - "$n" "$bad" "$kills" "$base_wall" "$base_cpu" "$bat_wall" "$bat_cpu" "$parallel" "$engine" <<'EOF'
import json, os, sys
n, bad, kills = int(sys.argv[1]), int(sys.argv[2]), set(sys.argv[3].split(","))
slurm = sys.argv[9] == "slurm"
base_wall, base_cpu, bat_wall, bat_cpu = map(float, sys.argv[4:8])
parallel = int(sys.argv[8])
s = json.load(open("b/summary.json"))
problems = []
starts = 0
for j in s["jobs"]:
    name = j["job"]
    starts += j["attempts"]
    is_bad = int(name[1:]) % 20 == 7
    if is_bad:
        if (j["class"], j["attempts"]) != ("failed-input", 1):
            problems.append(f"{name}: {j['class']} after {j['attempts']} attempts, expected failed-input after 1")
    else:
        want = 2 if name in kills else 1
        log = open(os.path.join("b", j["log"])).read()
        if j["status"] != "done" or j["attempts"] != want or log.count("=== tdf batch: job") != want:
            problems.append(f"{name}: {j['status']} after {j['attempts']} attempts, expected done after {want}")
t = s["totals"]
if (t["done"], t["failed_input"], t["failed_resource"]) != (n - bad, bad, 0):
    problems.append(f"totals {t}")
# Files the batch writes per job beside the job's own outputs: state/<name>.json and logs/<name>.log.
meta_files = sum(len(os.listdir(os.path.join("b", d))) for d in ("state", "logs"))  # slurm: + slurm-*.out
meta_bytes = sum(os.path.getsize(os.path.join("b", d, f)) for d in ("state", "logs") for f in os.listdir(os.path.join("b", d)))
out_files = out_bytes = 0
for root, _, files in os.walk("b/jobs"):
    out_files += len(files)
    out_bytes += sum(os.path.getsize(os.path.join(root, f)) for f in files)
summary_bytes = sum(os.path.getsize(os.path.join("b", f)) for f in ("summary.json", "summary.csv", "index.html"))
print(f"baseline (xargs -P {parallel}): {base_wall:.1f} s wall, {base_cpu:.1f} s CPU, {60 * n / base_wall:.0f} jobs/min")
print(f"tdf batch run ({'slurm' if slurm else 'local'}): {bat_wall:.1f} s wall, {bat_cpu:.1f} s CPU,"
      f" {60 * n / bat_wall:.0f} jobs/min ({starts} starts for {n} jobs)")
own = [l for l in open("batch.err") if l.startswith("tdf batch's own CPU time")]
if slurm:
    rounds = sum(1 for _ in open("b/slurm/submissions.jsonl"))
    own = [f"{rounds} submissions (the first and its retry rounds); per task {1000 * (bat_wall - base_wall) * parallel / n:.0f} ms of a slot's wall time over the baseline"]
print(f"scheduler overhead per job vs the baseline: {1000 * (bat_wall - base_wall) * parallel / n:.1f} ms of a"
      f" slot's wall time, {1000 * (bat_cpu - base_cpu) / n:.1f} ms CPU (machine shared: noisy)")
print("scheduler's own (getrusage of tdf batch): " + (own[0].strip() if own else "not reported"))
print(f"batch files per job: {meta_files / n:.2f} ({meta_bytes / n / 1024:.1f} KiB: state + log);"
      f" summary.json/.csv/index.html {summary_bytes / 1024:.0f} KiB in all")
print(f"job outputs per done job: {out_files / (n - bad):.1f} files, {out_bytes / (n - bad) / 2**20:.2f} MiB")
print("checks: " + ("every good job done exactly once, every bad one failed-input, killed ones retried"
                    if not problems else f"{len(problems)} problems: " + "; ".join(problems[:5])))
sys.exit(1 if problems else 0)
EOF
