#!/usr/bin/env bash
# End-to-end check of the motion-capture path: every BVH of the CMU test set
# (../shared/data/mocap/cmu, see its README) simulated on the default avatar
# with dynamic bones at the default dt (1/60 s). Writes per file the result
# (NAME.h5), a PC2 point cache (NAME.pc2 + NAME_rest.obj) and the log
# (NAME.log) into the output folder, then mocap_check.csv (one row per file,
# data_tools/mocap_table.py) and a plot of the pelvis error over time
# (pelvis_error.png with matplotlib, else pelvis_error.svg).
#
# Exit status: 0 when every run succeeded without NaN and with the simulated
# pelvis within 20 mm of the motion's root (pelvis) in every output frame;
# 1 otherwise; 2 for bad usage; 0 with "skipped: ..." when the data is absent.
#
# usage: scripts/mocap_check.sh [options] [MOCAP_DIR] [-- SIMULATE_OPTIONS...]
#   MOCAP_DIR          folder of .bvh files (default: <repo>/../shared/data/mocap/cmu)
#   --build-dir DIR    folder holding the sflsh executable (default: $SFLSH_BUILD_DIR or <repo>/build)
#   --avatar FILE      avatar to use (default: precompute the default avatar into OUT/avatar.h5;
#                      the template stage comes from the cache, ~/.cache/sflsh)
#   --out DIR          output folder (default: <repo>/out/mocap)
#   --seconds S        simulate only the first S seconds of each file (default: all of it)
#   --max-pelvis-mm X  pelvis error limit (default 20)
#   -- ...             further options for every `sflsh simulate` (e.g. -- --max-rotation-step 1)
set -euo pipefail

REPO=$(cd "$(dirname "$0")/.." && pwd)
MOCAP_DIR="$REPO/../shared/data/mocap/cmu"
BUILD_DIR=${SFLSH_BUILD_DIR:-$REPO/build}
OUT="$REPO/out/mocap"
AVATAR=""
SECONDS_OPT=()
EXTRA=()
MAX_PELVIS_MM=20
PY=/usr/bin/python3

usage() { sed -n '/^# usage:/,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; }
need() { [[ $# -ge 2 && -n "$2" ]] || { echo "mocap_check: $1 needs a value" >&2; exit 2; }; }
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build-dir) need "$@"; BUILD_DIR=$2; shift 2 ;;
    --avatar) need "$@"; AVATAR=$2; shift 2 ;;
    --out) need "$@"; OUT=$2; shift 2 ;;
    --seconds) need "$@"; SECONDS_OPT=(--seconds "$2"); shift 2 ;;
    --max-pelvis-mm) need "$@"; MAX_PELVIS_MM=$2; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    --) shift; EXTRA=("$@"); break ;;
    -*) echo "mocap_check: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) MOCAP_DIR=$1; shift ;;
  esac
done

if [[ ! -d "$MOCAP_DIR" ]]; then
  echo "mocap_check: skipped: mocap folder $MOCAP_DIR not found"
  exit 0
fi
shopt -s nullglob
FILES=("$MOCAP_DIR"/*.bvh)
shopt -u nullglob
if [[ ${#FILES[@]} -eq 0 ]]; then
  echo "mocap_check: skipped: no .bvh files found in $MOCAP_DIR"
  exit 0
fi

SFLSH="$BUILD_DIR/sflsh"
[[ -x "$SFLSH" ]] || { echo "mocap_check: $SFLSH not found; build it (scripts/build.sh --target sflsh) or give --build-dir" >&2; exit 2; }
[[ -x "$PY" ]] || { echo "mocap_check: $PY not found (needs Debian's python3 with numpy and h5py)" >&2; exit 2; }
"$PY" -c "import numpy, h5py" 2>/dev/null || { echo "mocap_check: $PY lacks numpy or h5py (apt-get install python3-numpy python3-h5py)" >&2; exit 2; }
if [[ -n "$AVATAR" && ! -f "$AVATAR" ]]; then
  echo "mocap_check: avatar $AVATAR not found" >&2
  exit 2
fi
mkdir -p "$OUT"

echo "mocap_check: $SFLSH ($("$SFLSH" --version 2>/dev/null || echo "version unknown"))"
echo "mocap_check: ${#FILES[@]} BVH files from $MOCAP_DIR -> $OUT"
[[ ${#EXTRA[@]} -eq 0 ]] || echo "mocap_check: extra simulate options: ${EXTRA[*]}"
if [[ -z "$AVATAR" ]]; then
  AVATAR="$OUT/avatar.h5"
  echo "== precompute the default avatar -> $AVATAR (log: $OUT/precompute.log)"
  if ! "$SFLSH" -q precompute --out "$AVATAR" > "$OUT/precompute.log" 2>&1; then
    tail -n 5 "$OUT/precompute.log" >&2
    echo "mocap_check: precompute failed (log: $OUT/precompute.log)" >&2
    exit 1
  fi
fi

RESULTS=()
FAILED=()
for bvh in "${FILES[@]}"; do
  name=$(basename "$bvh" .bvh)
  rm -f "$OUT/$name.h5" "$OUT/$name.pc2" "$OUT/${name}_rest.obj"
  start=$(date +%s)
  if "$SFLSH" -q simulate --avatar "$AVATAR" --motion "$bvh" --bones dynamic --dt 1/60 "${SECONDS_OPT[@]}" "${EXTRA[@]}" \
       --out "$OUT/$name.h5" --export "$OUT/$name.pc2" > "$OUT/$name.log" 2>&1; then
    echo "== $name: $(grep -m1 '^pelvis vs motion root' "$OUT/$name.log" || echo 'no pelvis line') (wall $(( $(date +%s) - start )) s)"
    RESULTS+=("$OUT/$name.h5")
  else
    echo "== $name: FAILED: $(grep -v '^\s*$' "$OUT/$name.log" | tail -n 1) (log: $OUT/$name.log)"
    FAILED+=(--failed "$name.bvh")
  fi
done

status=0
"$PY" "$REPO/data_tools/mocap_table.py" --csv "$OUT/mocap_check.csv" --plot "$OUT/pelvis_error" \
  --max-pelvis-mm "$MAX_PELVIS_MM" "${FAILED[@]}" "${RESULTS[@]}" || status=$?
if [[ $status -ne 0 ]]; then
  echo "mocap_check: FAILED (see the status column of $OUT/mocap_check.csv)" >&2
  exit 1
fi
echo "mocap_check: all ${#FILES[@]} files passed (no NaN, pelvis max <= $MAX_PELVIS_MM mm)"
