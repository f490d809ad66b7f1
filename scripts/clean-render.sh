#!/usr/bin/env bash
# How many path-traced samples a default glTF render needs to come out clean: for each model,
# FLIP (raypipe diff --metric flip) of renders at a few sample counts against a converged one,
# each at the page's default 160x120, and the pure white pixels the floor adds (a default render
# against --floor none).
#
#   scripts/clean-render.sh [--device cpu|gpu] [--reference SPP] [--counts "16 32 64"] MODEL...
#
# Prints one line a model and count: `MODEL SPP flip F seconds S`, then `MODEL white W% (floor
# none N%)`. Needs target/release/raypipe and Pillow (pip install pillow).
set -euo pipefail
raypipe=${RAYPIPE:-target/release/raypipe}
device=cpu
reference=2048
counts="16 32 64 128 256"
while [[ $# -gt 0 ]]; do
  case $1 in
    --device) device=$2; shift 2 ;;
    --reference) reference=$2; shift 2 ;;
    --counts) counts=$2; shift 2 ;;
    *) break ;;
  esac
done
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
size=(--width 160 --height 120 --device "$device")
# The share of pure white pixels in a PNG, in percent (Pillow, from PyPI).
white() {
  python3 -c 'import sys; from PIL import Image; px = Image.open(sys.argv[1]).convert("RGB").tobytes(); n = len(px) // 3; white = sum(px[3 * i:3 * i + 3] == b"\xff\xff\xff" for i in range(n)); print(f"{100 * white / n:.2f}")' "$1"
}
for model in "$@"; do
  name=$(basename "${model%.*}")
  "$raypipe" render "$model" "${size[@]}" --spp "$reference" -o "$out/$name-ref.png" 2>/dev/null
  for spp in $counts; do
    start=$(date +%s.%N)
    "$raypipe" render "$model" "${size[@]}" --spp "$spp" -o "$out/$name-$spp.png" 2>/dev/null
    seconds=$(echo "$(date +%s.%N) - $start" | bc)
    flip=$("$raypipe" diff --metric flip --threshold 1 "$out/$name-ref.png" "$out/$name-$spp.png" | grep -o 'FLIP mean [0-9.]*' | cut -d' ' -f3)
    printf '%s %s flip %s seconds %.1f\n' "$name" "$spp" "$flip" "$seconds"
  done
  # The white pixels at the first count, with the floor and without.
  first=${counts%% *}
  "$raypipe" render "$model" "${size[@]}" --spp "$first" --floor none -o "$out/$name-bare.png" 2>/dev/null
  printf '%s white %s%% (floor none %s%%)\n' "$name" "$(white "$out/$name-$first.png")" "$(white "$out/$name-bare.png")"
done
