#!/usr/bin/env bash
# The live viewer's figures (README "Live viewer", scripts/results/viewer.md):
# `sflsh run --realtime --serve` on the default avatar (~9k skin vertices) with a
# 2 cm probe before the belly; headless Debian chromium (apps/viewer/test/e2e.mjs)
# drags the probe 3 cm sideways (input-to-photon) and Shift+wheels it 48 mm into
# the belly, holds HOLD seconds, and reports display and received frame rates,
# bandwidth, the input-to-photon median and pixel statistics; the server prints
# RTF, step times, its own bandwidth and frame-build time at exit. The page
# reports its own time per stage (decode, apply, normals, draw call). Writes
# OUT/{e2e.json,run.txt,live.png,load.txt}.
#   [GL=swiftshader|angle-swiftshader|in-process|egl] [QUERY='?aa=0'] \
#   scripts/viewer_figures.sh AVATAR.h5 [OUT=out/viewer] [HOLD=10]
# DT is the physics time step (default 1/500 s).
# GL picks chromium's GPU-less WebGL back end (apps/viewer/test/e2e.mjs);
# QUERY the page's options (?aa=0: no antialiasing; &mat=standard: PBR skin).
# Needs a built sflsh, chromium and apps/viewer/node_modules (scripts/setup.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
AVATAR="$(realpath "${1:?usage: viewer_figures.sh AVATAR.h5 [OUT] [HOLD]}")"
OUT="${2:-out/viewer}"
HOLD="${3:-10}"
PORT="${PORT:-8093}"
GL="${GL:-swiftshader}"
DT="${DT:-1/500}"
QUERY="${QUERY:-?aa=0}"
mkdir -p "$OUT"
cat > "$OUT/probe_belly.yaml" <<YAML
solver: {dt: ${DT:-1/500}, seconds: 600}
output: {fps: 30}
bodies:
  - {name: alice, avatar: $AVATAR, motion: none, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.02}
    keyframes: [{time: 0, position: [0, 1.05, 0.16]}]
YAML
"$ROOT/build/sflsh" -q run "$OUT/probe_belly.yaml" --realtime --serve --port "$PORT" --quiet-status \
  > "$OUT/run.txt" 2> "$OUT/run.err" &
SERVER=$!
trap 'kill -TERM $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q serving "$OUT/run.txt" && break; sleep 0.2; done
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg) ($(date -u +%H:%M) UTC, GL=$GL QUERY=$QUERY)" | tee "$OUT/load.txt"
node "$ROOT/apps/viewer/test/e2e.mjs" --url "http://127.0.0.1:$PORT/" --query "$QUERY" --gl "$GL" --mode live \
  --drag 0.03,0,0 --wheel 12 --seconds "$HOLD" --screenshot "$OUT/live.png" | tee "$OUT/e2e.json"
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$OUT/load.txt"
kill -TERM $SERVER
wait $SERVER || true
trap - EXIT
cat "$OUT/run.txt"
