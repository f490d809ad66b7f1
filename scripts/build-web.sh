#!/usr/bin/env bash
# Builds the web page into OUT_DIR: index.html, its script and style, and the npm package it uses
# (web/package: raypipe.js, its types, the viewer compiled to wasm32 with its JavaScript glue).
# Serve the folder from localhost (WebGPU needs a secure context):
#   scripts/build-web.sh /tmp/raypipe-web && python3 -m http.server -d /tmp/raypipe-web 8000
# then open http://127.0.0.1:8000/?scene=random:2000&accel=threaded
# With --package DIR, builds the npm package alone into DIR (npm pack DIR makes its tarball).
# The module is shrunk by npm's binaryen (web/package.json) where `npm ci --prefix web` has run.
set -euo pipefail
usage="usage: scripts/build-web.sh OUT_DIR | --package DIR"
page=1
if [ "${1:-}" = --package ]; then
  page=0
  shift
fi
out=${1:?$usage}
[ $# -eq 1 ] || { echo "$usage" >&2; exit 2; }
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
  # wasm-opt takes half a minute or more: its output is kept by the input's hash, so the page and
  # the package (and a rebuild of an unchanged module) shrink the module once.
  shrunk="target/wasm-opt/$(sha256sum "$wasm" | cut -c1-32).wasm"
  if [ ! -f "$shrunk" ]; then
    mkdir -p target/wasm-opt
    web/node_modules/.bin/wasm-opt -Oz --strip-debug --strip-producers "$wasm" -o "$shrunk.part"
    mv "$shrunk.part" "$shrunk"
    ls -t target/wasm-opt/*.wasm | tail -n +5 | xargs -r rm -f
  fi
  cp "$shrunk" "$wasm"
  echo "wasm-opt -Oz: $before -> $(stat -c %s "$wasm") bytes"
else
  echo "web/node_modules/.bin/wasm-opt is missing (npm ci --prefix web): the module stays unshrunk, $(stat -c %s "$wasm") bytes"
fi
cp web/package/raypipe.js web/package/element.js web/package/fetch.js web/package/gestures.js web/package/raypipe.d.ts "$out"/
if [ $page = 1 ]; then
  cp web/index.html web/main.js web/style.css "$out"/
  echo "built the page in $out"
else
  # The glue's own declarations and package file are not the package's.
  rm -f "$out"/raypipe_web.d.ts "$out"/raypipe_web_bg.wasm.d.ts "$out"/package.json
  cp web/package/package.json web/package/README.md LICENSE-MIT LICENSE-APACHE "$out"/
  version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -1)
  sed -i "s/\"version\": \"[^\"]*\"/\"version\": \"$version\"/" "$out"/package.json
  echo "built the npm package raypipe $version in $out"
fi
