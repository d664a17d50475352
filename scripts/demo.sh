#!/usr/bin/env bash
# The README's first command: installs what is missing (Debian packages),
# builds sflsh in Release and runs the main job on the built-in procedural
# body: prints what the body is, exports it in a few shapes and poses (OBJ,
# PLY, glTF) with its joints, renders a picture of it, precomputes the default
# avatar (the template stage is cached in ~/.cache/sflsh), simulates the
# built-in `jump` motion and writes the result cache, a PC2 point cache and a
# picture of the soft-tissue displacement, then runs a contact scene (a ball
# thrown at the belly) and renders it.
# Outputs go to out/demo/ (or $SFLSH_DEMO_OUT).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh --target sflsh

SFLSH="${SFLSH_BUILD_DIR:-build}/sflsh"
OUT=${SFLSH_DEMO_OUT:-out/demo}
mkdir -p "$OUT"

echo
echo "== sflsh body info (built-in procedural body, beta = 0)"
"$SFLSH" body info

echo
echo "== exports"
"$SFLSH" body export --pose-preset tpose --out "$OUT/body_tpose.obj" --joints "$OUT/joints_tpose.csv"
"$SFLSH" body export --pose-preset tpose --out "$OUT/body_tpose.glb"
# Two other shapes: taller and heavier (beta0 = size, beta1 = girth), and
# shorter and slimmer with longer legs (beta7 = leg length).
"$SFLSH" body export --betas 2,1.5 --pose-preset tpose --out "$OUT/body_tall_heavy.ply"
"$SFLSH" body export --betas -1.5,-1,0,0,0,0,0,1.5 --pose-preset tpose --out "$OUT/body_short_slim.obj"
"$SFLSH" body export --pose-preset apose --out "$OUT/body_apose.glb" --joints "$OUT/joints_apose.json"
"$SFLSH" body export --pose-preset walk --out "$OUT/body_walk.obj"

echo
echo "== render"
"$SFLSH" body render --pose-preset tpose --out "$OUT/body.png"
"$SFLSH" body render --betas 2,1.5 --pose-preset walk --out "$OUT/body_tall_heavy_walk.png"

echo
echo "== precompute the default avatar (first run: a few minutes; then cached)"
"$SFLSH" precompute --out "$OUT/avatar.h5"

echo
echo "== simulate builtin:jump for 3 s"
"$SFLSH" simulate --avatar "$OUT/avatar.h5" --motion builtin:jump --seconds 3 --out "$OUT/jump.h5" \
  --export "$OUT/jump.pc2" --render "$OUT/jump.png"

echo
echo "== a scene with contact: a ball thrown at the belly (apps/scenes/ball_at_belly.yaml)"
# avatar: default in the scene: the built-in body, precomputed on first use and cached
"$SFLSH" simulate apps/scenes/ball_at_belly.yaml --out "$OUT/ball_at_belly.h5" --export "$OUT/ball_at_belly.glb" \
  --render "$OUT/ball_at_belly.png"

echo
echo "Done. Outputs in $(cd "$OUT" && pwd):"
ls -1 "$OUT" | sed 's/^/  /'
echo "Open the .obj/.ply/.glb files in Blender, MeshLab or any glTF viewer; body.png is the body,"
echo "jump.png the simulation (skin coloured by soft displacement), jump.h5 the result cache,"
echo "jump.pc2 + jump_rest.obj the animation for Blender (README: File formats, 'Blender');"
echo "ball_at_belly.png/.glb the contact scene (the ball is a separate node in the glTF)."
