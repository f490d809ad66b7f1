#!/usr/bin/env bash
# The web page's tests: builds the page into target/web and the npm package into target/web-package,
# and runs web/tests in headless Chromium on WebGPU and on WebGL2, against the native CPU reference
# (target/release/raypipe); then the page's and the package's tests again in Firefox ESR, on a
# virtual display (xvfb-run: headless Firefox has no WebGL2 here). Needs Chromium, Firefox ESR, Xvfb
# and Node.js (scripts/install-deps.sh installs them). Failing screenshots stay in target/web-test/.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet --release -p raypipe-cli
npm ci --prefix web --no-audit --no-fund --loglevel=error
scripts/build-web.sh target/web
scripts/build-web.sh --package target/web-package
cd web
node --test --test-concurrency=1 tests/
echo "=== the page's and the package's tests in Firefox"
RAYPIPE_BROWSER=firefox xvfb-run -a node --test --test-concurrency=1 tests/page.test.mjs tests/package.test.mjs
