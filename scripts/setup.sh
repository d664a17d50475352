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
  python3-numpy python3-scipy python3-h5py
  python3-distributed
  clang libclang-rt-14-dev  # scripts/fuzz.sh: libFuzzer, ASan, UBSan
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi
echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
