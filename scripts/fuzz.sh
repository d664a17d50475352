#!/usr/bin/env bash
# Fuzz the readers with libFuzzer + AddressSanitizer + UBSan.
#   scripts/fuzz.sh [SECONDS] [TARGET...]     (default: 60 s each, every target)
#   FUZZ_RUNS=1000000 scripts/fuzz.sh 1800 ... stops a target at 10^6 executions or 30 min,
#   whichever comes first (the reliability issue's budget per target).
#   FUZZ_JOBS=N fuzzes N targets at a time (one core each).
#   The readers' crash probe (io/crash_isolation.hpp) is off (SFLSH_READ_IN_PROCESS=1) so that
#   every crash, ours or a library's, stops the fuzzer; SFLSH_READ_IN_PROCESS=0 fuzzes the
#   product as shipped: a crash in the forked child is then an error, and the child's sanitizer
#   report is in the target's log (grep it: a frame in sflsh:: above the library is ours).
#   FUZZ_TIMEOUT=S sets the per-input time limit (default 10 s); on a machine whose other jobs
#   starve the fuzzer, a 10 s wall-clock limit reports false timeouts (replay them to check).
# Targets (fuzz/fuzz_targets.hpp): bvh npz body_model_h5 avatar_h5 result_h5 material
# scene_yaml mesh stream pose_file control_message.
# Needs clang and compiler-rt (Debian: clang libclang-rt-14-dev; scripts/setup.sh).
#
# Builds into build-fuzz/ (the reader sources, instrumented; the rest from the
# normal build's libraries, which it builds if needed), seeds each corpus with valid files
# made from the project's own test data (test_fuzz with SFLSH_FUZZ_SEED_DIR,
# from the normal build) plus the committed findings in tests/fuzz_regressions/<target>/
# and earlier ones in build-fuzz/crashes/<target>/, and runs each
# target for SECONDS with a 10 s per-input timeout, a 2 GB RSS limit and a
# 256 MB single-allocation limit (a small file must not make a reader
# allocate more; 2 GB for the HDF5 targets, see run_target). A crash, leak, timeout or out-of-memory input stays in
# build-fuzz/crashes/<target>/; replay them with
# SFLSH_FUZZ_REPLAY_DIR=build-fuzz/crashes build/test_fuzz, fix the reader, and
# copy the input to tests/fuzz_regressions/<target>/ (test_fuzz replays those on every
# run). Leaks inside libhdf5's own error paths are suppressed (fuzz/lsan.supp).
# Exit status: non-zero if any target found something new. FUZZ_BUILD_ONLY=1 only builds.
set -euo pipefail
SECONDS_TO_RUN="${1:-60}"
[ $# -gt 0 ] && shift
ALL_TARGETS=(bvh npz body_model_h5 avatar_h5 result_h5 material scene_yaml mesh stream pose_file control_message)
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=("${ALL_TARGETS[@]}")
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
OUT="$ROOT/build-fuzz"
CXX="${CXX_FUZZ:-clang++}"
command -v ccache >/dev/null && CXX="ccache $CXX"
mkdir -p "$OUT/obj"

FLAGS=(-std=c++17 -g -O1 -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
       -ffunction-sections -fdata-sections -I"$ROOT/include" -I"$ROOT/fuzz")
read -r -a EIGEN <<< "$(pkg-config --cflags eigen3 2>/dev/null || echo -I/usr/include/eigen3)"
read -r -a HDF5_CFLAGS <<< "$(pkg-config --cflags hdf5)"
read -r -a LIBS <<< "$(pkg-config --libs hdf5 libzip) -lz"
SOURCES=(fuzz/fuzz_targets.cpp src/core/*.cpp src/io/crash_isolation.cpp src/io/hdf5_file.cpp src/io/npz.cpp src/io/atomic_output.cpp
         src/asset/avatar_file.cpp src/body/body_model_io.cpp src/body/body_model.cpp src/body/smpl_skeleton.cpp
         src/motion/bvh.cpp src/motion/skeleton_motion.cpp src/motion/retarget.cpp src/motion/motion_clip.cpp
         src/scene/result_file.cpp src/scene/material_file.cpp src/scene/scene_description.cpp src/io/mesh_export.cpp src/io/ply_structure.cpp
         src/meshing/mesh_sdf_bake.cpp src/meshing/surface_checks.cpp src/geometry/grid_sdf.cpp
         src/teleop/stream_message.cpp src/teleop/pose_stream_filter.cpp src/teleop/pose_file.cpp
         src/viewer/control_message.cpp)

echo "building the fuzz targets in $OUT ..."
OBJS=()
cd "$ROOT"
for src in "${SOURCES[@]}"; do
  obj="$OUT/obj/$(echo "$src" | tr / _).o"
  # Rebuild when the source, or any project header, is newer than the object.
  if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ -n "$(find include fuzz -name '*.hpp' -newer "$obj" | head -1)" ]; then
    $CXX "${FLAGS[@]}" -fsanitize=fuzzer-no-link "${EIGEN[@]}" "${HDF5_CFLAGS[@]}" -c "$src" -o "$obj"
  fi
  OBJS+=("$obj")
done
# Whatever else the instrumented objects reference (the fuzz targets never
# simulate) comes, uninstrumented, from the normal build's
# libraries, linked after (and never instead of) the instrumented objects.
BUILD="${SFLSH_BUILD_DIR:-build}"
if [ ! -x "$BUILD/test_fuzz" ]; then
  SFLSH_JOBS="${SFLSH_JOBS:-2}" bash scripts/build.sh --target test_fuzz > "$OUT/normal_build.log" 2>&1 ||
    { tail -20 "$OUT/normal_build.log"; exit 1; }
fi
NORMAL_LIBS=()
for m in scene teleop sim motion asset fem meshing geometry body mesh io core; do NORMAL_LIBS+=("$BUILD/libsflsh_$m.a"); done
for t in "${TARGETS[@]}"; do
  $CXX "${FLAGS[@]}" -fsanitize=fuzzer -DSFLSH_FUZZ_TARGET="$t" "${EIGEN[@]}" fuzz/fuzz_main.cpp "${OBJS[@]}" \
    -Wl,--gc-sections -Wl,--allow-multiple-definition "${NORMAL_LIBS[@]}" "${LIBS[@]}" \
    -lcholmod -lsuitesparseconfig -ltbb -lpng -lassimp -lyaml-cpp -lgmp -lmpfr -o "$OUT/${t}_fuzz"
done
if [ -n "${FUZZ_BUILD_ONLY:-}" ]; then echo "built ${TARGETS[*]} in $OUT"; exit 0; fi
echo "making seed files from the project's test data ..."
rm -rf "$OUT/seeds"
SFLSH_FUZZ_SEED_DIR="$OUT/seeds" "${SFLSH_BUILD_DIR:-build}/test_fuzz" \
  --gtest_filter=FuzzReplay.ValidAndMutatedProjectFiles > "$OUT/seeds.log" 2>&1 || { cat "$OUT/seeds.log"; exit 1; }

run_target() {
  local t="$1" log="$OUT/$1.log"
  mkdir -p "$OUT/corpus/$t" "$OUT/crashes/$t" "$OUT/seeds/$t"
  local max_len=65536
  for f in "$OUT/seeds/$t"/*; do
    [ -f "$f" ] && [ "$(stat -c %s "$f")" -gt "$max_len" ] && max_len=$(stat -c %s "$f")
  done
  local regressions=()
  [ -d "$ROOT/tests/fuzz_regressions/$t" ] && regressions=("$ROOT/tests/fuzz_regressions/$t")
  # libhdf5 1.10 sizes its metadata-cache buffers from the file's own headers (a local heap's
  # declared size, for one) and checks them against the end of the file only after malloc, so a
  # damaged 35 kB image can request 1.4 GB that is never touched: the read then fails and the
  # reader throws (RSS stays ~26 MB; tests/fuzz_regressions/avatar_h5/local_heap_size_1_4_gb.h5).
  # That allocation is inside the library (8 GB from another such header:
  # tests/fuzz_regressions/body_model_h5/local_heap_size_8_gb.h5), so the HDF5 targets have no
  # single-allocation limit; memory actually used stays bounded by -rss_limit_mb.
  # A declared size near 2^64 makes that malloc fail: glibc returns NULL and libhdf5 reports an
  # error (the reader throws), so ASan is told to return NULL as glibc does instead of aborting
  # (tests/fuzz_regressions/body_model_h5/hdf5-metadata-size-0xff00000000000000.h5).
  # Under ASan, though, an 8 GB malloc is not lazy: freeing it poisons 1 GB of shadow memory, and
  # such an input took over 120 s on a loaded machine (the plain build reads it in 0.1 s with
  # 25 MB RSS), which ended two 30-min runs in their seed corpus. So allocations over 4 GB
  # return NULL at once (max_allocation_size_mb), as they would on a machine without overcommit.
  local malloc_limit=256 asan_extra=""
  case "$t" in *_h5) malloc_limit=1048576 asan_extra=":allocator_may_return_null=1:max_allocation_size_mb=4096" ;; esac
  local before
  before=$(ls "$OUT/crashes/$t" | wc -l)
  local status=0
  (cd "$OUT" && SFLSH_READ_IN_PROCESS="${SFLSH_READ_IN_PROCESS:-1}" ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}$asan_extra" LSAN_OPTIONS="suppressions=$ROOT/fuzz/lsan.supp" \
     "$OUT/${t}_fuzz" -max_total_time="$SECONDS_TO_RUN" ${FUZZ_RUNS:+-runs="$FUZZ_RUNS"} \
     -max_len="$max_len" -timeout="${FUZZ_TIMEOUT:-10}" -rss_limit_mb=2048 -malloc_limit_mb="$malloc_limit" -print_final_stats=1 \
     -artifact_prefix="$OUT/crashes/$t/" "$OUT/corpus/$t" "$OUT/seeds/$t" "$OUT/crashes/$t" "${regressions[@]}" \
     > "$log" 2>&1) || status=$?
  local execs cov found
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*')
  found=$(( $(ls "$OUT/crashes/$t" | wc -l) - before ))
  echo "$t: ${execs:-?} executions, coverage ${cov:-?} edges, corpus $(ls "$OUT/corpus/$t" | wc -l) inputs, exit $status, $found new finding(s) (log: $log)"
  [ "$status" -eq 0 ] && [ "$found" -eq 0 ]
}

echo "fuzzing ${TARGETS[*]} for $SECONDS_TO_RUN s each ..."
failed=0
# FUZZ_JOBS=N runs N targets at a time (one core each; default 1).
JOBS="${FUZZ_JOBS:-1}"
running=()
for t in "${TARGETS[@]}"; do
  run_target "$t" &
  running+=($!)
  if [ ${#running[@]} -ge "$JOBS" ]; then
    wait "${running[0]}" || failed=1
    running=("${running[@]:1}")
  fi
done
for pid in "${running[@]}"; do wait "$pid" || failed=1; done
if [ "$failed" -ne 0 ]; then
  echo "findings are in $OUT/crashes/<target>/: replay with SFLSH_FUZZ_REPLAY_DIR=$OUT/crashes build/test_fuzz"
  exit 1
fi
echo "no findings"
