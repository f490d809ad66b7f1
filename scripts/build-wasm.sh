#!/usr/bin/env bash
# Builds packages for wasm32-unknown-unknown, the browser's target, in release: the library by
# default, or the packages named (`scripts/build-wasm.sh raypipe-web`). rustup fetches the target's
# standard library where it can; elsewhere Debian's rustc-web with rust-web-src and lld builds it from
# source (-Zbuild-std).
set -euo pipefail
cd "$(dirname "$0")/.."
packages=()
for package in "${@:-raypipe}"; do packages+=(-p "$package"); done
if rustup target add wasm32-unknown-unknown > /tmp/rustup-wasm.log 2>&1; then
  cargo build "${packages[@]}" --release --target wasm32-unknown-unknown
else
  cat /tmp/rustup-wasm.log
  echo "rustup could not fetch the wasm32 standard library; building it with Debian's rustc-web"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -q rustc-web rust-web-src lld-22 > /tmp/rustc-web.log 2>&1 || { cat /tmp/rustc-web.log; exit 1; }
  PATH=/usr/bin:$PATH RUSTC_BOOTSTRAP=1 cargo build "${packages[@]}" --release \
    -Zbuild-std=std,panic_abort --target wasm32-unknown-unknown
fi
