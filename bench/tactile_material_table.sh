#!/usr/bin/env bash
# The goal-2 statistics table of README "tdf tactile": converts every shared tactile sample with
# the defaults and measures the output against the input's textured region twice, with the
# numbers `tdf tactile convert` prints (C++) and with the measurement script given as $CHECK
# (optional; a Python script taking INPUT_NORMAL.png OUTPUT_NORMAL.png).
# Usage: bench/tactile_material_table.sh [build dir] [output dir] [extra convert options...]
set -u
BUILD=${1:-build}; OUT=${2:-out/tactile_table}; shift 2 2>/dev/null || true
DATA=$(dirname "$0")/../../shared/data
mkdir -p "$OUT"
inputs=()
for f in "$DATA"/tactile/texture_samples/*.png; do inputs+=("$f"); done
inputs+=("$DATA/heightmaps/Leather031_2K-JPG/Leather031_2K_Displacement.jpg"
         "$DATA/heightmaps/Fabric048_2K-JPG/Fabric048_2K_Displacement.jpg"
         "$DATA/tactile/gelsight_groove_scan/heightmap.tmd"
         "$DATA/tactile/gelsight_raw/strawberry_00000_gxgy.npz")
# More inputs (e.g. the issue-28 ones from tdf_make_tactile_unseen_inputs) as $EXTRA, space-separated.
for f in ${EXTRA:-}; do inputs+=("$f"); done
for f in "${inputs[@]}"; do
  name=$(basename "${f%.*}")
  line=$("$BUILD/tdf" tactile convert "$f" -o "$OUT/$name.png" --steps-png "$OUT/${name}_steps" "$@" 2>&1 | grep "tilt ratio")
  stats=$(cat "$OUT/${name}_steps/8_statistics.json")
  check=""
  if [ -n "${CHECK:-}" ]; then
    ref="$OUT/${name}_steps/0_input_normal.png"; case "$f" in *.png) ref="$f";; esac
    check=$(/usr/bin/python3 "$CHECK" "$ref" "$OUT/$name.png")
  fi
  echo "$name | $stats | $check"
done
