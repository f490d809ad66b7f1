#!/usr/bin/env bash
# Counts the instructions lavapipe's shaders execute for one `raypipe render`: a measure of a shader
# change that does not move with the machine's load, where timings here move by 1.5x between runs.
#
#   scripts/count-instructions.sh [--binary PATH] RENDER_ARGS...
#   scripts/count-instructions.sh random:20000 --accel stack --width 64 --height 64
#
# It runs `raypipe render RENDER_ARGS -o TMP.png` under valgrind's callgrind on lavapipe and prints
# the instructions executed in code that valgrind cannot name: the code llvmpipe compiles at run
# time, which is the shaders (every pass: the tracer, the miss pass, the display). Two runs of one
# build agree to some thousands in a hundred million. Under valgrind, LLVM compiles for the
# processor valgrind reports (AVX2, no AVX-512), so the code differs a little from a native run's.
# It takes a minute or two, most of it LLVM compiling the shaders; keep images small.
# Needs valgrind (apt-get install valgrind) and a release build (cargo build --release).
set -euo pipefail
binary=target/release/raypipe
if [ "${1:-}" = --binary ]; then
  binary=$2
  shift 2
fi
if [ $# = 0 ]; then
  echo "usage: scripts/count-instructions.sh [--binary PATH] RENDER_ARGS..." >&2
  exit 2
fi
command -v valgrind > /dev/null || { echo "scripts/count-instructions.sh: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
[ -x "$binary" ] || { echo "scripts/count-instructions.sh: no $binary (cargo build --release)" >&2; exit 2; }
icd=/usr/share/vulkan/icd.d/lvp_icd.json
[ -f "$icd" ] || { echo "scripts/count-instructions.sh: no lavapipe ($icd; scripts/install-deps.sh)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0
VK_DRIVER_FILES=$icd WGPU_BACKEND=vulkan valgrind --tool=callgrind --callgrind-out-file="$work/callgrind.out" \
  "$binary" render "$@" -o "$work/image.png" --quiet > "$work/valgrind.log" 2>&1 || status=$?
if [ $status != 0 ]; then
  # raypipe's own words, without valgrind's (its lines start with ==PID==).
  grep -v '^==[0-9]*==' "$work/valgrind.log" >&2
  exit $status
fi
# Callgrind files name an object once and refer to it by number after: ob=(N) NAME, then ob=(N).
# Costs follow as "position cost" lines under the current object (cob= is a callee's, not ours).
awk '
  /^ob=/ { match($0, /\(([0-9]+)\)/); id = substr($0, RSTART + 1, RLENGTH - 2)
           name = $0; sub(/^ob=\([0-9]+\) ?/, "", name); if (name != "") names[id] = name
           current = names[id]; next }
  /^cob=/ { match($0, /\(([0-9]+)\)/); id = substr($0, RSTART + 1, RLENGTH - 2)
            name = $0; sub(/^cob=\([0-9]+\) ?/, "", name); if (name != "") names[id] = name; next }
  /^calls=/ { skip = 1; next }
  /^[0-9+*-]/ { if (skip) { skip = 0; next } if (current == "???") total += $NF }
  END { printf "%.0f instructions in JIT-compiled shader code\n", total }
' "$work/callgrind.out"
