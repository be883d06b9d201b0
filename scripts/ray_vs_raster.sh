#!/usr/bin/env bash
# Ray vs raster on every shipped scene (docs/commands/render.md "Ray vs raster"): renders each scene with the ray
# producer and the raster producer, each without and with dr.antialias, and compares the folders
# with `tdf compare --json`, whole images and with the mask eroded by 1 and 2 pixels. Prints one
# markdown row per scene, pass and comparison (PSNR, max error, percent of pixels over 0.004).
#   scripts/ray_vs_raster.sh [out_dir] [key=value overrides...]
# Needs a built ./build/tdf; scenes whose data (../shared/data) is absent are skipped.
set -euo pipefail
cd "$(dirname "$0")/.."
TDF=${TDF:-./build/tdf}
OUT=${1:-build/ray_vs_raster}
shift || true
EXTRA=("$@")
mkdir -p "$OUT"
for scene in scenes/*/scene.json; do
  name=$(basename "$(dirname "$scene")")
  for variant in ray:false raster:false ray:true raster:true; do
    r=${variant%%:*}
    aa=${variant##*:}
    dir="$OUT/$name/${r}_aa_${aa}"
    if ! "$TDF" --quiet render "$scene" -o "$dir" "renderer=$r" "antialias=$aa" "${EXTRA[@]}" 2>"$OUT/$name.err"; then
      echo "skipping $name: $(head -1 "$OUT/$name.err")" >&2
      continue 2
    fi
    rm -f "$dir/resolved_scene.json"
  done
  for pair in "ray_aa_false raster_aa_false" "ray_aa_false raster_aa_true" "ray_aa_true raster_aa_true" \
              "raster_aa_false raster_aa_true"; do
    read -r left right <<< "$pair"
    for erode in 0 1 2; do
      "$TDF" compare "$OUT/$name/$left" "$OUT/$name/$right" --json --fail 0.004 --erode-mask "$erode" \
        > "$OUT/$name/${left}_vs_${right}_erode$erode.json" || true
    done
  done
done
python3 - "$OUT" <<'PY'
import json, pathlib, sys
out = pathlib.Path(sys.argv[1])
print("| scene | pass | comparison | erode | PSNR dB | max error | % > 0.004 |")
print("|---|---|---|---|---|---|---|")
for f in sorted(out.glob("*/*_vs_*_erode*.json")):
    scene = f.parent.name
    stem = f.stem
    pair, erode = stem.rsplit("_erode", 1)
    report = json.loads(f.read_text())
    # Pool the views: worst PSNR and max error per pass over the files.
    rows = {}
    for file in report["files"]:
        for layer in file.get("layers", []):
            psnr = layer["psnr"] if layer["psnr"] is not None else float("inf")
            r = rows.setdefault(layer["layer"], [float("inf"), 0.0, 0.0])
            r[0] = min(r[0], psnr)
            r[1] = max(r[1], layer["max_error"])
            r[2] = max(r[2], layer["fail_percent"])
    for layer, (psnr, max_error, over) in rows.items():
        print(f"| {scene} | {layer} | {pair.replace('_aa_false', '').replace('_aa_true', '+AA')} | {erode} "
              f"| {psnr:.1f} | {max_error:.3g} | {over:.3g} |")
PY
