#!/usr/bin/env bash
# Installs what is missing, builds in Release and runs every test with ctest.
# Tests that need ../shared/data skip with a message when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
cd "${SFLSH_BUILD_DIR:-build}"
ctest --output-on-failure -j "${SFLSH_JOBS:-$(nproc)}" "$@"
