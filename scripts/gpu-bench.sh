#!/usr/bin/env bash
# Measures one GPU in one command: Figure 4 (frames per second against sphere count) at 1920x1080
# and 256x256 for every mode and both pipelines, the Bunny as 20K spheres and as its 69K triangles
# at 1920x1080 with the BVH rebuilt every frame (and its triangles over a tree built once by the
# LBVH and by binned SAH), the GPU and CPU LBVH builds from 100K to 16M primitives with 30- and
# 63-bit Morton codes, and an animated skinned mesh of 10K to 1M triangles (scripts/skinned-mesh.py)
# posed, rebuilt and refitted every frame at 640x360. Where the adapter has ray queries, the driver's
# acceleration structures beside the walks (rayquery, rebuilt every frame): Figure 4 at the larger
# size, the Bunny's triangles in Morton and in file order, and the animated mesh.
#
#   scripts/gpu-bench.sh OUT_DIR            # on a real GPU: at most 9.5 minutes
#   scripts/gpu-bench.sh --quick OUT_DIR    # the same steps at small sizes (CI runs it on lavapipe)
#
# Writes under OUT_DIR: info.txt (`raypipe info`), a folder per benchmark with results.csv,
# results.json, fps.png and fps.svg (motion.csv, motion.json and refit.csv for the animated
# mesh), builds.jsonl and builds.csv, summary.md (each performance
# target judged where the run measured it, the pipelines and the builds side by side:
# scripts/gpu-bench-summary.py), and log.txt with each step's command, time and outcome. Each step
# has a time limit; a step that fails or runs out of time is logged, the others still run (a
# benchmark keeps the points it finished), and the script exits 1.
#
# RAYPIPE names the binary (default target/release/raypipe); RAYPIPE_MODELS the folder holding
# bunny.ply (default ../shared/models, else .models). WGPU_BACKEND picks the backend as usual.
set -uo pipefail

quick=0
if [[ ${1:-} == --quick ]]; then
  quick=1
  shift
fi
if [[ $# -ne 1 ]]; then
  echo "usage: scripts/gpu-bench.sh [--quick] OUT_DIR" >&2
  exit 2
fi
out=$1
raypipe=${RAYPIPE:-target/release/raypipe}
models=${RAYPIPE_MODELS:-}
if [[ -z $models ]]; then
  for dir in ../shared/models .models; do
    [[ -f $dir/bunny.ply ]] && models=$dir && break
  done
fi
[[ -x $raypipe ]] || { echo "gpu-bench: $raypipe is not an executable (cargo build --release)" >&2; exit 2; }
mkdir -p "$out" || exit 2
log=$out/log.txt
: > "$log"
failed=0

# step NAME SECONDS COMMAND...: runs COMMAND under a time limit, logging how it went; its standard
# output goes to $step_stdout where that is set, else to the log.
step() {
  local name=$1 limit=$2
  shift 2
  echo "== $name: $*" | tee -a "$log"
  local start=$SECONDS
  timeout --kill-after=10 "$limit" "$@" >> "${step_stdout:-$log}" 2>> "$log"
  local rc=$?
  local took=$((SECONDS - start))
  if [[ $rc -eq 0 ]]; then
    echo "   ok in ${took} s" | tee -a "$log"
  elif [[ $rc -eq 124 || $rc -eq 137 ]]; then
    echo "   out of time after ${took} s (limit ${limit} s)" | tee -a "$log"
    failed=1
  else
    echo "   failed (exit $rc) after ${took} s" | tee -a "$log"
    failed=1
  fi
}

if [[ $quick -eq 1 ]]; then
  sizes=(32x24 16x12)
  brute_counts=200,1000
  bvh_counts=200,1000
  frames=(--frames 2 --warmup 1)
  bunny_size=(--width 32 --height 24)
  bunny_spheres=2000
  build_counts=(10000 100000)
  build_runs=2
  motion_counts=(3000)
  motion_frames=(--frames 2 --warmup 1 --width 64 --height 36)
  # Seconds for: Figure 4's BVH modes and its brute force (each size), the Bunny's spheres and its
  # triangles, one build, one build of the largest count, one animated mesh, the Bunny's
  # triangles over a tree built once (each builder), Figure 4 with ray queries, and the Bunny's
  # triangles with ray queries (each order).
  limits=(300 300 300 300 120 120 300 300 300 300)
else
  sizes=(1920x1080 256x256)
  brute_counts=1000,2000,5000,10000,20000
  bvh_counts=1000,2000,5000,10000,20000,50000,100000,200000,500000,1000000
  frames=(--frames 10 --warmup 2)
  bunny_size=(--width 1920 --height 1080)
  bunny_spheres=20000
  build_counts=(100000 1000000 4000000 16000000)
  build_runs=5
  motion_counts=(10000 100000 1000000)
  motion_frames=(--frames 30 --warmup 3 --width 640 --height 360)
  # As above; at most 2 x (80 + 25) + 2 x 25 + 12 x 8 + 4 x 25 + 3 x 20 + 2 x 12 + 20 + 2 x 10
  # = 580 seconds in all.
  limits=(80 25 25 25 8 25 20 12 20 10)
fi

"$raypipe" info > "$out/info.txt" 2>&1 || { cat "$out/info.txt"; exit 2; }
cat "$out/info.txt"
# Ray queries where an adapter has them (a benchmark on another adapter says it refused them).
rayquery=0
grep -Eq 'ray queries: +true' "$out/info.txt" && rayquery=1

for size in "${sizes[@]}"; do
  w=${size%x*}
  h=${size#*x}
  step "figure 4, $size, BVH modes, rebuilt every frame" "${limits[0]}" \
    "$raypipe" bench random --counts "$bvh_counts" --accel stack,stackless,threaded --pipeline fragment,compute \
    --width "$w" --height "$h" --rebuild "${frames[@]}" --out "$out/figure4-$size-bvh"
  step "figure 4, $size, brute force" "${limits[1]}" \
    "$raypipe" bench random --counts "$brute_counts" --accel brute --pipeline fragment,compute \
    --width "$w" --height "$h" "${frames[@]}" --out "$out/figure4-$size-brute"
done
if [[ $rayquery -eq 1 ]]; then
  size=${sizes[0]}
  step "figure 4, $size, ray queries, rebuilt every frame" "${limits[8]}" \
    "$raypipe" bench random --counts "$bvh_counts" --accel rayquery --pipeline fragment,compute \
    --width "${size%x*}" --height "${size#*x}" --rebuild "${frames[@]}" --out "$out/figure4-$size-rayquery"
fi

if [[ -n $models ]]; then
  step "Bunny, $bunny_spheres spheres, rebuilt every frame" "${limits[2]}" \
    "$raypipe" bench "$models/bunny.ply" --counts "$bunny_spheres" --accel stack,stackless,threaded \
    --pipeline fragment,compute "${bunny_size[@]}" --rebuild "${frames[@]}" --out "$out/bunny-spheres"
  step "Bunny, triangles, rebuilt every frame" "${limits[3]}" \
    "$raypipe" bench "$models/bunny.ply" --as triangles --accel stack,stackless,threaded \
    --pipeline fragment,compute "${bunny_size[@]}" --rebuild "${frames[@]}" --out "$out/bunny-triangles"
  # A still model's tree built once on the host, by the LBVH and by binned SAH (--builder).
  for builder in lbvh sah; do
    step "Bunny, triangles, $builder tree built once" "${limits[7]}" \
      "$raypipe" bench "$models/bunny.ply" --as triangles --builder "$builder" --accel stack,threaded \
      --pipeline fragment "${bunny_size[@]}" "${frames[@]}" --out "$out/bunny-triangles-$builder"
  done
  # The driver's structures over the Bunny's triangles, sorted along the Morton curve and in the
  # file's order: what the sort buys the driver's builder.
  if [[ $rayquery -eq 1 ]]; then
    for order in morton scene; do
      step "Bunny, triangles, ray queries, $order order, rebuilt every frame" "${limits[9]}" \
        "$raypipe" bench "$models/bunny.ply" --as triangles --accel rayquery --blas-order "$order" \
        --pipeline fragment,compute "${bunny_size[@]}" --rebuild "${frames[@]}" --out "$out/bunny-triangles-rayquery-$order"
    done
  fi
else
  echo "== Bunny: skipped, no bunny.ply in ../shared/models or .models (set RAYPIPE_MODELS)" | tee -a "$log"
  failed=1
fi

# One JSON object per build in builds.jsonl, the GPU's and the CPU's, then a CSV of them all.
builds=$out/builds.jsonl
: > "$builds"
largest=${build_counts[-1]}
for n in "${build_counts[@]}"; do
  limit=${limits[4]}
  [[ $n == "$largest" ]] && limit=${limits[5]}
  for bits in 30 63; do
    for device in gpu cpu; do
      step_stdout=$builds step "LBVH build, $n primitives, $bits-bit codes, $device" "$limit" \
        "$raypipe" bvh "random:$n" --device "$device" --morton-bits "$bits" --runs "$build_runs" --json
    done
  done
done
python3 - "$builds" "$out/builds.csv" <<'EOF' || failed=1
import csv, json, sys
rows = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
phases = ["morton", "sort", "hierarchy", "bounds", "links", "total"]
with open(sys.argv[2], "w", newline="") as f:
    out = csv.writer(f)
    out.writerow(["primitives", "device", "builder", "nodes", "max_depth", "sah_cost"]
                 + [p + "_ms" for p in phases] + ["mprims_per_s"])
    for r in rows:
        out.writerow([r["primitives"], r["device"], r["builder"], r["nodes"], r["max_depth"],
                      round(r["sah_cost"], 3)] + [r["build_ms"][p] for p in phases]
                     + [round(r["mprims_per_s"], 2)])
print(f"builds.csv: {len(rows)} builds")
EOF
# The animated mesh: each frame evaluated, skinned and rebuilt on the GPU, and a second tree refitted;
# with ray queries, the driver's structures rebuilt over the skinned triangles too.
motion_accels=threaded
[[ $rayquery -eq 1 ]] && motion_accels=threaded,rayquery
for n in "${motion_counts[@]}"; do
  mesh=$out/skinned-$n.glb
  if python3 "$(dirname "$0")/skinned-mesh.py" --triangles "$n" -o "$mesh" >> "$log" 2>&1; then
    step "animated skinned mesh, $n triangles, skinned and rebuilt every frame" "${limits[6]}" \
      "$raypipe" bench "$mesh" --motion --refit --memory storage --accel "$motion_accels" --pipeline fragment,compute \
      "${motion_frames[@]}" --out "$out/motion-$n"
    rm -f "$mesh"
  else
    echo "== animated skinned mesh, $n triangles: scripts/skinned-mesh.py failed (see above)" | tee -a "$log"
    failed=1
  fi
done

python3 "$(dirname "$0")/gpu-bench-summary.py" "$out" || failed=1

echo "results in $out (log.txt lists every step)"
exit "$failed"
