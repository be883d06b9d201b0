#!/usr/bin/env bash
# Throughput of `tdf batch` (docs/measurements.md, "`tdf batch` throughput"):
#   bench/batch_throughput.sh local   16 small optimize runs: one after the other with every
#                                     thread, then `tdf batch run` (local engine, default share)
#   bench/batch_throughput.sh slurm   the overhead per Slurm task: 16 tiny compare jobs through
#                                     a throw-away single-node Slurm vs the local engine
# Prints wall and CPU (user+sys of the children) seconds. Builds nothing (needs build/tdf).
set -euo pipefail
cd "$(dirname "$0")/.."
src=$(pwd)
tdf=$src/${TDF_BUILD_DIR:-build}/tdf
work=$src/${TDF_BUILD_DIR:-build}/bench-results/batch
rm -rf "$work"
mkdir -p "$work"
threads=$(nproc)
scene=$src/scenes/pebble_sphere/scene.json
small="optimize.iterations=30 optimize.init_iterations=20 optimize.resolution=64 optimize.patch_resolution=64"
small="$small optimize.batch_size=2 optimize.patch_batch_size=2 optimize.held_out_views=1 optimize.held_out_patches=1"
small="$small export.texture_size=128 export.turntable_views=1 export.turntable_resolution=64 guidance.tactile=none"

# measure <function>: runs it in a child bash under /usr/bin/time; prints "wall_s cpu_s" (CPU =
# user+sys of everything it waited for, tdf processes included).
measure() {
  /usr/bin/time -f "%e %U %S" -o "$work/time.txt" bash -c "$(declare -f "$1"); $1" > /dev/null
  awk '{printf "%.1f %.1f\n", $1, $2 + $3}' "$work/time.txt"
}
export tdf work threads scene small

if [ "${1:-local}" = local ]; then
  echo "name,command,args" > "$work/manifest.csv"
  for k in $(seq 0 15); do echo "run$k,optimize,$scene seed=$k $small --name pebble" >> "$work/manifest.csv"; done
  sequential() {
    for k in $(seq 0 15); do
      "$tdf" -q --threads "$threads" optimize "$scene" -o "$work/seq/run$k" seed=$k $small --name pebble
    done
  }
  batch() { "$tdf" -q batch run "$work/manifest.csv" -o "$work/batch" > /dev/null; }
  read -r seq_wall seq_cpu < <(measure sequential)
  read -r bat_wall bat_cpu < <(measure batch)
  echo "16 small optimize runs on $threads threads:"
  echo "  one after the other (--threads $threads): ${seq_wall} s wall, ${seq_cpu} s CPU"
  echo "  tdf batch run (local, $threads at a time x 1 thread): ${bat_wall} s wall, ${bat_cpu} s CPU"
  awk -v a="$seq_wall" -v b="$bat_wall" -v c="$seq_cpu" -v d="$bat_cpu" \
    'BEGIN { printf "  speed-up: %.2fx wall, CPU per job %.2f s vs %.2f s\n", a / b, c / 16, d / 16 }'

else
  golden=$src/reference/golden/pebble_visualizer
  echo "name,command,args" > "$work/tiny.csv"
  for k in $(seq 0 15); do echo "cmp$k,compare,$golden/view_000.exr $golden/view_001.exr --failpercent 100" >> "$work/tiny.csv"; done
  env_line=$(bash "$src/tests/batch/slurm_cluster.sh" start "$work/slurm-daemons")
  trap 'bash "$src/tests/batch/slurm_cluster.sh" stop "$work/slurm-daemons"' EXIT
  eval "$env_line"
  local_run() { "$tdf" -q batch run "$work/tiny.csv" -o "$work/local" --jobs "$threads" > /dev/null; }
  slurm_run() { "$tdf" -q batch run "$work/tiny.csv" -o "$work/slurm" --engine slurm --max-parallel "$threads" --wait > /dev/null; }
  read -r loc_wall loc_cpu < <(measure local_run)
  read -r sl_wall sl_cpu < <(measure slurm_run)
  echo "16 tiny compare jobs, $threads at a time:"
  echo "  local engine: ${loc_wall} s wall"
  echo "  slurm engine (sbatch array + summary job, --wait): ${sl_wall} s wall"
  awk -v a="$sl_wall" -v b="$loc_wall" 'BEGIN { printf "  overhead per Slurm task: %.2f s wall\n", (a - b) / 16 }'

fi
