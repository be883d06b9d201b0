#!/usr/bin/env bash
# Issue 29's table (docs/albedo-colour.md): runs `tdf optimize` with the defaults on every shipped
# scene and prints, per scene, the texture-space albedo low-pass PSNR against the input, the
# colour-geometry correlations (whole albedo and added colour, held-out views), the largest step
# above the input's local max, the fraction of texels more than 0.05 above it, and the seconds.
# Scenes that read ../shared/data are skipped with a line when it is absent.
# Usage: bench/albedo_colour_table.sh [tdf binary] [output dir] [overrides...]
set -u
TDF=${1:-build/tdf}; OUT=${2:-out/albedo_colour}; shift 2 2>/dev/null || true
ROOT=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUT"
echo "| scene | low-pass PSNR (dB) | correlation (whole / added) | max above local max | texels > +0.05 | s |"
echo "|---|---|---|---|---|---|"
for scene in "$ROOT"/scenes/*/scene.json; do
  name=$(basename "$(dirname "$scene")")
  if grep -q "shared/data" "$scene" && [ ! -d "$ROOT/../shared/data" ]; then
    echo "| $name | skipped: ../shared/data is absent | | | | |"; continue
  fi
  "$TDF" -q optimize "$scene" -o "$OUT/$name" "$@" >"$OUT/$name.log" 2>&1 || { echo "| $name | failed: see $OUT/$name.log | | | | |"; continue; }
  report=$(ls "$OUT/$name"/*_report.json | grep -v _initialized_report)
  /usr/bin/python3 - "$report" "$name" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); c = r["colour"]; e = r["texture_space"]["albedo_local_range"]
print(f"| {sys.argv[2]} | {c['albedo_psnr_lowpass_db']:.2f} | {c['colour_geometry_correlation']:.3f} / "
      f"{c['added_colour_geometry_correlation']:.3f} | {e['max_above_local_max']:.3f} | "
      f"{100 * e['fraction_above_limit']:.2f} % | {r['seconds_total']:.0f} |")
PY
done
