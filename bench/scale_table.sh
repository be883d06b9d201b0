#!/usr/bin/env bash
# How the main job grows with the mesh and the texture size (issue 25, "Scale"): runs
# `tdf optimize` with its defaults on
#   - the main job (scenes/pebble_sphere, 1024^2 maps), and the same at 2048^2 and 4096^2;
#   - the mug (scenes/mug, 24.5k triangles; needs ../shared/data, skipped without it);
#   - a generated 1,000,000-triangle UV sphere with the pebble sphere's textures;
# and prints, per run, wall and CPU seconds, peak memory, and the job's own per-stage wall times
# and the peak memory at the end of each (`stages` in <name>_report.json). Builds nothing: run after `bash scripts/build.sh tdf`.
#   bench/scale_table.sh                 every run (about 10 minutes on a quiet 2-core machine)
#   bench/scale_table.sh main mug        only those (names: main main_2k main_4k mug million)
set -euo pipefail
cd "$(dirname "$0")/.."
TDF=${TDF:-build/tdf}
WORK=${TDF_SCALE_DIR:-build/scale}
[ -x "$TDF" ] || { echo "no $TDF (build first: bash scripts/build.sh tdf)" >&2; exit 1; }
mkdir -p "$WORK"
runs=("$@")
[ ${#runs[@]} -eq 0 ] && runs=(main main_2k main_4k mug million)

million_scene() {
  local dir="$WORK/million_scene"
  if [ ! -f "$dir/scene.json" ]; then
    mkdir -p "$dir"
    # 1000 segments x 500 rings: 998,000 triangles, UVs with a seam at u = 0/1.
    python3 - "$dir/sphere.obj" <<'PY'
import math, sys
S, R = 1000, 500
with open(sys.argv[1] + ".tmp", "w") as f:
    for r in range(R + 1):
        th = math.pi * r / R
        for s in range(S + 1):
            ph = 2 * math.pi * s / S
            f.write(f"v {math.sin(th)*math.cos(ph):.6f} {math.cos(th):.6f} {math.sin(th)*math.sin(ph):.6f}\n")
    for r in range(R + 1):
        for s in range(S + 1):
            f.write(f"vt {s/S:.6f} {1 - r/R:.6f}\n")
    row = S + 1
    for r in range(R):
        for s in range(S):
            a, b = r * row + s + 1, r * row + s + 2
            c, d = a + row, b + row
            if r > 0: f.write(f"f {a}/{a} {c}/{c} {b}/{b}\n")
            if r < R - 1: f.write(f"f {b}/{b} {c}/{c} {d}/{d}\n")
import os; os.replace(sys.argv[1] + ".tmp", sys.argv[1])
PY
    local pebble; pebble=$(cd scenes/pebble_sphere && pwd)
    sed -e "s#\"sphere.obj\"#\"sphere.obj\"#" -e "s#\"albedo.png\"#\"$pebble/albedo.png\"#" \
        -e "s#\"tactile_normal.png\"#\"$pebble/tactile_normal.png\"#" scenes/pebble_sphere/scene.json > "$dir/scene.json"
  fi
  echo "$dir/scene.json"
}

printf "%-8s %9s %9s %9s  %s\n" run wall_s cpu_s peak_MB "stages (wall s / peak MB at its end)"
for run in "${runs[@]}"; do
  extra=()
  case "$run" in
    main) scene=scenes/pebble_sphere/scene.json ;;
    main_2k) scene=scenes/pebble_sphere/scene.json; extra=(export.texture_size=2048) ;;
    main_4k) scene=scenes/pebble_sphere/scene.json; extra=(export.texture_size=4096) ;;
    mug)
      if [ ! -f ../shared/data/meshes/mug/mug.obj ]; then echo "mug: skipped (../shared/data absent)"; continue; fi
      scene=scenes/mug/scene.json ;;
    million) scene=$(million_scene) ;;
    *) echo "unknown run '$run' (main main_2k main_4k mug million)" >&2; exit 2 ;;
  esac
  out="$WORK/$run"
  rm -rf "$out"
  /usr/bin/time -f "%e %U %S %M" -o "$WORK/$run.time" "$TDF" optimize "$scene" -o "$out" --name "$run" \
    "${extra[@]}" >"$WORK/$run.log" 2>&1 || { echo "$run: failed, see $WORK/$run.log" >&2; continue; }
  python3 - "$WORK/$run.time" "$out/${run}_report.json" "$run" <<'PY'
import json, sys
wall, user, sys_s, rss = open(sys.argv[1]).read().split()[-4:]
report = json.load(open(sys.argv[2]))
stages = report.get("stages", [])
text = " ".join(f"{s['stage']} {s['seconds']:.1f}s/{s['peak_mb']:.0f}MB" for s in stages)
print(f"{sys.argv[3]:<8} {float(wall):9.1f} {float(user) + float(sys_s):9.1f} {int(rss) / 1024:9.0f}  {text}")
PY
done
