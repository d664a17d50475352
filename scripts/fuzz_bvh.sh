#!/usr/bin/env bash
# Fuzz the BVH parser (and the retargeting of what it parses) with libFuzzer
# and AddressSanitizer/UBSan.
#   scripts/fuzz_bvh.sh [SECONDS]   (default 60)
# Needs clang and compiler-rt (Debian: apt-get install -y clang libclang-rt-14-dev).
# Builds into build-fuzz/, seeds the corpus with tests/data/motion/*.bvh and
# (when present) a CMU file cut to a few frames, and runs for SECONDS. Crashing
# inputs are written to build-fuzz/crashes/; turn each into a test in
# tests/motion/bvh_fuzz_regression_test.cpp.
set -euo pipefail
SECONDS_TO_RUN="${1:-60}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
OUT="$ROOT/build-fuzz"
CXX="${CXX_FUZZ:-clang++}"
mkdir -p "$OUT/corpus" "$OUT/crashes"

EIGEN_CFLAGS="$(pkg-config --cflags eigen3 2>/dev/null || echo -I/usr/include/eigen3)"
echo "building $OUT/bvh_fuzz ..."
"$CXX" -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -I"$ROOT/include" $EIGEN_CFLAGS \
  "$ROOT/fuzz/bvh_fuzz.cpp" "$ROOT/src/motion/bvh.cpp" "$ROOT/src/motion/skeleton_motion.cpp" \
  "$ROOT/src/motion/retarget.cpp" "$ROOT/src/body/smpl_skeleton.cpp" \
  -o "$OUT/bvh_fuzz"

cp "$ROOT"/tests/data/motion/*.bvh "$OUT/corpus/" 2>/dev/null || true
CMU="$ROOT/../shared/data/mocap/cmu/08_10.bvh"
if [ -f "$CMU" ]; then
  # Hierarchy plus the first 5 frames: a realistic seed that runs fast.
  awk '/^Frames:/{print "Frames: 5"; next} {print} /^Frame Time/{n=0; f=1; next} f{if(++n>=5) exit}' "$CMU" \
    > "$OUT/corpus/cmu_5frames.bvh"
fi

echo "fuzzing for $SECONDS_TO_RUN s ..."
cd "$OUT"
"$OUT/bvh_fuzz" -max_total_time="$SECONDS_TO_RUN" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
  -artifact_prefix="$OUT/crashes/" -print_final_stats=1 "$OUT/corpus"
echo "no crash found in $SECONDS_TO_RUN s (corpus: $(ls "$OUT/corpus" | wc -l) inputs)"
