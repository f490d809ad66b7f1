#!/usr/bin/env bash
# Builds the web page into OUT_DIR: index.html, its script and style, and the viewer compiled to
# wasm32 with its JavaScript glue. Serve the folder from localhost (WebGPU needs a secure context):
#   scripts/build-web.sh /tmp/raypipe-web && python3 -m http.server -d /tmp/raypipe-web 8000
# then open http://127.0.0.1:8000/?scene=random:2000&accel=threaded
# The module is shrunk by npm's binaryen (web/package.json) where `npm ci --prefix web` has run.
set -euo pipefail
out=${1:?usage: scripts/build-web.sh OUT_DIR}
cd "$(dirname "$0")/.."
scripts/build-wasm.sh raypipe-web
# The glue must come from the wasm-bindgen version the module was built with: tools/wasm-bindgen
# pins the one in Cargo.lock. Its profile builds it in a minute or so; it runs in seconds.
cargo build --quiet --profile tool -p raypipe-wasm-bindgen
mkdir -p "$out"
target/tool/raypipe-wasm-bindgen target/wasm32-unknown-unknown/release/raypipe_web.wasm "$out"
wasm="$out/raypipe_web_bg.wasm"
if [ -x web/node_modules/.bin/wasm-opt ]; then
  before=$(stat -c %s "$wasm")
  web/node_modules/.bin/wasm-opt -Oz --strip-debug --strip-producers "$wasm" -o "$wasm.opt"
  mv "$wasm.opt" "$wasm"
  echo "wasm-opt -Oz: $before -> $(stat -c %s "$wasm") bytes"
else
  echo "web/node_modules/.bin/wasm-opt is missing (npm ci --prefix web): the module stays unshrunk, $(stat -c %s "$wasm") bytes"
fi
cp web/index.html web/main.js web/style.css "$out"/
echo "built the page in $out"
