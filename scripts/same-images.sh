#!/usr/bin/env bash
# Checks that a change left raypipe's images alone: renders every built-in scene and the Bunny with
# two builds (say, before and after a restructuring) on the CPU reference, on Vulkan and on GL, in
# storage and texture memory, with every BVH walk (or those in $WALKS, say WALKS=stack), and the
# scenes or model files in $SCENES besides (say three glTF samples); compares each pair with
# `raypipe diff --tolerance exact` (every channel of every pixel equal). Prints one line per image and
# exits 1 if any differs.
#
#   scripts/same-images.sh OLD_RAYPIPE NEW_RAYPIPE [WIDTH HEIGHT]
#
# Build the old one from a worktree, e.g.:
#   git worktree add /tmp/old REV && CARGO_TARGET_DIR=/tmp/old-target cargo build --release -p raypipe-cli
#   scripts/same-images.sh /tmp/old-target/release/raypipe target/release/raypipe
set -euo pipefail
old=${1:?usage: scripts/same-images.sh OLD_RAYPIPE NEW_RAYPIPE [WIDTH HEIGHT]}
new=${2:?usage: scripts/same-images.sh OLD_RAYPIPE NEW_RAYPIPE [WIDTH HEIGHT]}
width=${3:-160}
height=${4:-120}
cd "$(dirname "$0")/.."
bunny=../shared/models/bunny.ply
[ -f "$bunny" ] || { echo "$bunny is missing (the shared models)"; exit 2; }

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
scenes=(whitted sphere-8k torus-5k random:2000 bounce:100 "$bunny")
# More scenes or model files (glTF samples, say), separated by spaces, in $SCENES.
read -r -a more <<< "${SCENES:-}"
scenes+=("${more[@]}")
# device, backend (for WGPU_BACKEND), memory
routes=("cpu - storage" "gpu vulkan storage" "gpu vulkan texture" "gpu gl storage" "gpu gl texture")
read -r -a walks <<< "${WALKS:-threaded stack stackless}"
failed=0
for scene in "${scenes[@]}"; do
  for walk in "${walks[@]}"; do
    for route in "${routes[@]}"; do
      read -r device backend memory <<< "$route"
      name="$(basename "$scene" | tr ':' '_')-$walk-$device-$backend-$memory"
      for build in old new; do
        binary=$old
        [ $build = new ] && binary=$new
        WGPU_BACKEND=${backend/-/vulkan} "$binary" render "$scene" --device "$device" --memory "$memory" \
          --accel "$walk" --width "$width" --height "$height" -q -o "$out/$name-$build.png"
      done
      if "$new" diff "$out/$name-old.png" "$out/$name-new.png" --tolerance exact > "$out/diff.txt" 2>&1; then
        echo "same:    $scene, $walk, on $device $backend $memory"
      else
        echo "DIFFERS: $scene, $walk, on $device $backend $memory: $(tr '\n' ' ' < "$out/diff.txt")"
        failed=1
      fi
    done
  done
done
exit $failed
