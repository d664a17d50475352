#!/usr/bin/env bash
# Installs every Debian package sflsh needs to build, test and run its data tools.
# Idempotent: does nothing when all packages are present. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libsuitesparse-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libassimp-dev libhdf5-dev libceres-dev libgoogle-glog-dev libgflags-dev
  libgtest-dev libgmock-dev libcli11-dev libyaml-cpp-dev libzip-dev zlib1g-dev
  libtbb-dev libpng-dev
  libbullet-dev  # sflsh bench's peer: Bullet 3 deformable FEM (bullet-float64)
  libspectra-dev  # sflsh bench: the soft tissue's lowest vibration modes (shift-invert Lanczos)
  python3-numpy python3-scipy python3-h5py
  python3-distributed
  clang libclang-rt-14-dev  # scripts/fuzz.sh: libFuzzer, ASan, UBSan
  nlohmann-json3-dev chromium  # the browser viewer: JSON controls; its headless-browser test
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} Debian packages present"
else
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The browser viewer's page (three.js) and its headless-browser test
# (puppeteer-core drives Debian's chromium; npm never downloads a browser):
# `npm ci` from the lockfile, only when node_modules is missing or older than it.
VIEWER="$(cd "$(dirname "$0")/.." && pwd)/apps/viewer"
if command -v npm >/dev/null; then
  if [ ! -f "$VIEWER/node_modules/.package-lock.json" ] || [ "$VIEWER/package-lock.json" -nt "$VIEWER/node_modules/.package-lock.json" ]; then
    echo "setup: npm ci in apps/viewer (three.js, puppeteer-core)"
    (cd "$VIEWER" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund)
  fi
else
  echo "setup: npm not found: the viewer page is built without three.js (sflsh run --serve / view will say so)"
fi
