#!/usr/bin/env bash
# Installs Mesa's software GPU drivers, so raypipe has an adapter on a machine without a GPU:
# lavapipe (Vulkan) and llvmpipe (OpenGL through EGL); and, for the viewer's tests, a virtual X
# display (Xvfb) with imagemagick to capture its screen; and a C++ compiler for FLIP (`nv-flip`, which
# `raypipe diff` builds from source); and, for the web page's tests, Chromium, Firefox ESR (run on
# the virtual display: headless, it has no WebGL2 here) and Node.js. Debian and Ubuntu; run as root.
#
# Debian 12's own Mesa (22.3) miscompiles the tracer's ray loop (it ends the loop with rays still on
# the stack, so reflections and refractions go missing); Mesa 25 from bookworm-backports is correct.
set -euo pipefail
if [ "$(id -u)" != 0 ]; then
  echo "scripts/install-deps.sh: run it as root (sudo scripts/install-deps.sh; in a container without sudo, as root)" >&2
  exit 2
fi
export DEBIAN_FRONTEND=noninteractive
packages="mesa-vulkan-drivers libgl1-mesa-dri libegl-mesa0 libglx-mesa0 libegl1"
window_packages="xvfb xauth imagemagick xdotool libxkbcommon-x11-0"
build_packages="g++"
browser_packages="chromium firefox-esr"
. /etc/os-release
if [ "${VERSION_CODENAME:-}" = bookworm ]; then
  echo "deb http://deb.debian.org/debian bookworm-backports main" > /etc/apt/sources.list.d/bookworm-backports.list
  apt-get update -q
  apt-get install -y -q -t bookworm-backports $packages
else
  apt-get update -q
  apt-get install -y -q $packages
fi
apt-get install -y -q $window_packages $build_packages $browser_packages
# node:test and npm for web/tests; where Node.js is already installed, it stays.
command -v node > /dev/null && command -v npm > /dev/null || apt-get install -y -q nodejs npm
