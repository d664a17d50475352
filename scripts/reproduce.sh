#!/usr/bin/env bash
# Regenerates the results tables the README links (README "Reproducing the figures").
#
#   bash scripts/reproduce.sh [--quick] [--out DIR] [--only STEP,...] [--no-build] [--list]
#
# Full run (default): every step below on the recorded settings, into scripts/results/ (hours on
# 2 cores: the full-FEM references of bench, bench-contact and the Hertz table dominate), with its
# work files (avatars, logs, result files) in out/reproduce/.
# --quick: a small subset on short settings (a few minutes on 2 cores once the template stage is
# cached; the first run builds it) into build/results-quick/ (or --out DIR), never scripts/results/.
# Every generated table starts with a stamp: the step, its exact command, the git commit (and
# "dirty" when tracked files differ from it), the date, the host, nproc and /proc/loadavg at the
# step's start and end. Steps run one after the other, with progress on stdout and each step's
# output in WORK/logs/STEP.log. A step that fails, or a figure script whose check misses a target
# (exit 1; its table is still written and stamped), is reported and the run goes on; the exit
# status is then 1, with the failed steps listed at the end.
# Environment: SFLSH_BUILD_DIR (default build), SFLSH_JOBS (build parallelism),
# SFLSH_SHARED_DIR (default ../shared: the CMU clips; steps that need it skip without it).
set -uo pipefail
cd "$(dirname "$0")/.."
REPO=$(pwd)
PY=/usr/bin/python3
BUILD=${SFLSH_BUILD_DIR:-build}
case $BUILD in /*) BUILD_ABS=$BUILD ;; *) BUILD_ABS="$REPO/$BUILD" ;; esac
SFLSH="$BUILD_ABS/sflsh"
SHARED=${SFLSH_SHARED_DIR:-$REPO/../shared}
MOCAP="$SHARED/data/mocap/cmu"

QUICK=0 OUT="" ONLY="" BUILD_FIRST=1 LIST=0
while [ $# -gt 0 ]; do
  case $1 in
    --quick) QUICK=1; shift ;;
    --out) [ $# -ge 2 ] || { echo "reproduce: --out needs a folder" >&2; exit 2; }; OUT=$2; shift 2 ;;
    --only) [ $# -ge 2 ] || { echo "reproduce: --only needs step names" >&2; exit 2; }; ONLY=$2; shift 2 ;;
    --no-build) BUILD_FIRST=0; shift ;;
    --list) LIST=1; shift ;;
    -h|--help) sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "reproduce: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

# Steps: name | what it writes into OUT | in --quick.
STEPS_FULL="avatar bench contact hertz stress stress_suite throughput contact_figures teleop fit fit_dynamic mocap batch batch_resume shapes readme"
STEPS_QUICK="avatar bench stress stress_suite throughput batch_resume"
describe() {
  case $1 in
    avatar) echo "the default avatar (work file; quick: K = 16)" ;;
    bench) echo "bench.md bench.csv bench.svg: sflsh bench against the full FEM" ;;
    contact) echo "contact_patch.md contact_patch_probe.svg: sflsh bench-contact, three probes, a pressed sphere, an impact, a box press, a pinch" ;;
    hertz) echo "hertz.md: the full FEM against Hertz (test_reference)" ;;
    stress) echo "stress.csv stress.svg: sflsh stress, shake at dt 1/30" ;;
    stress_suite) echo "stress_suite.md .csv .svg: sflsh stress-suite" ;;
    throughput) echo "throughput.md throughput.csv: sflsh bench-throughput" ;;
    contact_figures) echo "contact_figures.md: scripts/contact_figures.py" ;;
    teleop) echo "teleop.md: scripts/teleop_figures.py" ;;
    fit) echo "fit.md fit_*.svg: scripts/fit_benchmark.py (writes scripts/results/ itself: full run only)" ;;
    fit_dynamic) echo "fit_dynamic_bones.md: scripts/fit_dynamic_bones.py, fitting a run with dynamic bones" ;;
    mocap) echo "mocap_check.csv pelvis_error.svg: scripts/mocap_check.sh" ;;
    batch) echo "batch_benchmark.md .csv, batch_manifest_*.csv: scripts/batch_benchmark.py" ;;
    batch_resume) echo "batch_resume_check.md: scripts/batch_resume_check.sh" ;;
    shapes) echo "shape_topology.md: scripts/shape_quality_sweep.py, template stage built by the run" ;;
    readme) echo "(nothing) scripts/check_readme_figures.py --require-stamp: the README quotes regenerated files" ;;
  esac
}
if [ "$QUICK" = 1 ]; then STEPS=$STEPS_QUICK; else STEPS=$STEPS_FULL; fi
if [ "$LIST" = 1 ]; then
  for s in $STEPS_FULL; do
    q=""; [[ " $STEPS_QUICK " == *" $s "* ]] && q=" [quick]"
    printf '  %-16s %s%s\n' "$s" "$(describe "$s")" "$q"
  done
  exit 0
fi
if [ -n "$ONLY" ]; then
  for s in ${ONLY//,/ }; do
    [[ " $STEPS_FULL " == *" $s "* ]] || { echo "reproduce: unknown step '$s' (--list shows them)" >&2; exit 2; }
  done
  sel=""
  for s in $STEPS; do [[ ",$ONLY," == *",$s,"* ]] && sel="$sel $s"; done
  for s in ${ONLY//,/ }; do [[ " $sel " == *" $s "* ]] || sel="$sel $s"; done
  STEPS=$sel
fi

if [ -z "$OUT" ]; then
  if [ "$QUICK" = 1 ]; then OUT="$BUILD_ABS/results-quick"; else OUT=scripts/results; fi
fi
mkdir -p "$OUT" || exit 2
OUT=$(cd "$OUT" && pwd)
if [ "$QUICK" = 1 ]; then WORK="$OUT/work"; else WORK="$REPO/out/reproduce"; fi
mkdir -p "$WORK/logs" || exit 2
MODE=""; [ "$QUICK" = 1 ] && MODE=" --quick"

# The commit, and "dirty" when tracked files differ from it (untracked files are not looked at, nor
# scripts/results: the tables a step writes there would make the step's own later stamps dirty).
git_state() {
  local c
  c=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
  if ! git diff --quiet HEAD -- . ':(exclude)scripts/results' 2>/dev/null; then
    c="$c (dirty: tracked files differ from it)"
  fi
  echo "$c"
}
COMMIT=$(git_state)
NPROC=$(nproc)
HOST=$(hostname)
loadavg() { cut -d' ' -f1-3 /proc/loadavg; }

FAILED=()
STEP="" CMD="" T0="" LOAD0="" STEP_COMMIT=""
# Stamps SRC into DEST (Markdown, CSV or SVG), for the step that just ran.
stamp() {
  local src=$1 dest=$2 t1 load1 text tmp
  t1=$(date -u '+%Y-%m-%d %H:%M UTC'); load1=$(loadavg)
  local commit=$STEP_COMMIT now
  now=$(git_state)
  [ "$now" = "$STEP_COMMIT" ] || commit="$STEP_COMMIT at the step's start, $now at its end"
  text="Generated by \`scripts/reproduce.sh$MODE\` (step $STEP) at commit $commit, $T0 – $t1, host $HOST, nproc $NPROC, /proc/loadavg (1, 5, 15 min) at start $LOAD0, at end $load1. Command: $CMD"
  [ -f "$src" ] || { echo "   (missing output: $src)"; return 1; }
  tmp="$dest.tmp.$$"
  case $dest in
    *.md) { printf '<!-- %s -->\n> %s\n\n' "Generated file: edit scripts/reproduce.sh or the command, not this file" "$text"; cat "$src"; } > "$tmp" ;;
    *.csv) { printf '# %s\n' "$text"; cat "$src"; } > "$tmp" ;;
    *.svg) awk -v t="$text" 'NR == 1 && /^<\?xml/ { print; print "<!-- " t " -->"; next }
                             NR == 1 { print "<!-- " t " -->" } { print }' "$src" > "$tmp" ;;
    *) cp "$src" "$tmp" ;;
  esac
  mv "$tmp" "$dest"
  echo "   wrote $dest"
}

# begin STEP starts a step (time, load); run COMMAND... runs it with its output in the step's log
# (stdout into $RUN_STDOUT instead when set), records a failure and returns the exit status.
begin() { STEP=$1; T0=$(date -u '+%Y-%m-%d %H:%M UTC'); LOAD0=$(loadavg); STEP_COMMIT=$(git_state); }
run() {
  local log="$WORK/logs/$STEP.log" start=$SECONDS rc
  CMD="$*"
  CMD=${CMD//"$REPO/"/}   # paths relative to the repository
  echo "== [$STEP] $(date -u +%H:%M:%S) $CMD"
  echo "   (log: $log)"
  if [ -n "${RUN_STDOUT:-}" ]; then "$@" > "$RUN_STDOUT" 2> "$log"; else "$@" > "$log" 2>&1; fi
  rc=$?
  if [ $rc -eq 0 ]; then
    echo "   ok in $((SECONDS - start)) s"
  else
    echo "   FAILED (exit $rc) after $((SECONDS - start)) s; last lines of $log:"
    tail -n 8 "$log" | sed 's/^/     | /'
    FAILED+=("$STEP (exit $rc)")
  fi
  return $rc
}

echo "reproduce:$MODE into $OUT (work files: $WORK), commit $COMMIT, nproc $NPROC, load $(loadavg)"
echo "steps:$(printf ' %s' $STEPS)"
START=$SECONDS

if [ "$BUILD_FIRST" = 1 ]; then
  targets=(--target sflsh)
  [[ " $STEPS " == *" hertz "* ]] && targets+=(--target test_reference)
  [[ " $STEPS " == *" shapes "* ]] && targets+=(--target test_precompute)
  begin build
  run env SFLSH_BUILD_DIR="$BUILD" bash scripts/build.sh "${targets[@]}" || {
    echo "reproduce: the build failed; nothing was run" >&2; exit 1; }
fi
[ -x "$SFLSH" ] || { echo "reproduce: $SFLSH missing (build it, or drop --no-build)" >&2; exit 1; }

AVATAR="$WORK/avatar.h5"
need_avatar() {
  [ -f "$AVATAR" ] && return 0
  echo "   (no $AVATAR: the step 'avatar' makes it)"; FAILED+=("$STEP (no avatar)"); return 1
}
have_mocap() { [ -d "$MOCAP" ] && ls "$MOCAP"/*.bvh > /dev/null 2>&1; }

for step in $STEPS; do
  begin "$step"
  case $step in
  avatar)
    if [ "$QUICK" = 1 ]; then run "$SFLSH" precompute --handles 16 --out "$AVATAR"
    else run "$SFLSH" precompute --out "$AVATAR"; fi ;;
  bench)
    d="$WORK/bench"; rm -rf "$d"
    if [ "$QUICK" = 1 ]; then
      run "$SFLSH" bench --quick --handles 16 --variants-handles 16 --seconds 0.25 --no-peer --only no-variant --out "$d"
    else
      run "$SFLSH" bench --out "$d"
    fi
    for f in bench.md bench.csv bench.svg; do stamp "$d/$f" "$OUT/$f"; done ;;
  contact)
    d="$WORK/contact"; rm -rf "$d"
    if [ "$QUICK" = 1 ]; then
      run "$SFLSH" bench-contact --quick --handles 16 --scenes probe --out "$d"
    else
      run "$SFLSH" bench-contact --handles 96 --scenes probe,probe-belly,probe-calf-1cm,pressed,impact --cpu-time \
        --scene apps/scenes/figures/box_press_belly.yaml --scene apps/scenes/figures/pinch_from_file.yaml \
        --scene apps/scenes/figures/probe_coupled_belly.yaml --out "$d"
    fi
    stamp "$d/contact_bench.md" "$OUT/contact_patch.md"
    stamp "$d/contact_probe.svg" "$OUT/contact_patch_probe.svg" ;;
  hertz)
    tmp="$WORK/hertz.md"; rm -f "$tmp"
    run env SFLSH_HERTZ_MD="$tmp" "$BUILD_ABS/test_reference" --gtest_filter=FullFemHertz.DISABLED_ConvergenceTable \
      --gtest_also_run_disabled_tests
    stamp "$tmp" "$OUT/hertz.md" ;;
  stress)
    need_avatar || continue
    d="$WORK/stress"; rm -rf "$d"
    if [ "$QUICK" = 1 ]; then run "$SFLSH" stress --avatar "$AVATAR" --steps 300 --dt 1/30 --out "$d"
    else run "$SFLSH" stress --avatar "$AVATAR" --steps 10000 --dt 1/30 --out "$d"; fi
    stamp "$d/stress.csv" "$OUT/stress.csv"; stamp "$d/stress.svg" "$OUT/stress.svg" ;;
  stress_suite)
    need_avatar || continue
    d="$WORK/stress_suite"; rm -rf "$d"
    if [ "$QUICK" = 1 ]; then
      run "$SFLSH" stress-suite --avatar "$AVATAR" --cases shake@1/30,box_press --steps 200 --window 50 \
        --scenes-dir apps/scenes --out "$d"
    else
      have_mocap || echo "   (no $MOCAP: the CMU cases are skipped)"
      run "$SFLSH" stress-suite --avatar "$AVATAR" --mocap-dir "$MOCAP" --scenes-dir apps/scenes --steps 10000 \
        --out "$d"
    fi
    for f in stress_suite.md stress_suite.csv stress_suite.svg; do stamp "$d/$f" "$OUT/$f"; done ;;
  throughput)
    need_avatar || continue
    d="$WORK/throughput"; rm -rf "$d"
    if [ "$QUICK" = 1 ]; then
      run "$SFLSH" bench-throughput --avatar "$AVATAR" --avatars 1,4 --threads 1,2 --steps 30 --out "$d"
    else
      run "$SFLSH" bench-throughput --avatar "$AVATAR" --avatars 1,4,16 --threads 1,2 --steps 120 --out "$d"
    fi
    for f in throughput.md throughput.csv; do stamp "$d/$f" "$OUT/$f"; done ;;
  contact_figures)
    d="$WORK/contact_figures"; mkdir -p "$d"; [ -f "$AVATAR" ] && cp -f "$AVATAR" "$d/avatar.h5"
    RUN_STDOUT="$WORK/contact_figures.md" run "$PY" scripts/contact_figures.py "$d"
    stamp "$WORK/contact_figures.md" "$OUT/contact_figures.md" ;;
  teleop)
    d="$WORK/teleop"; mkdir -p "$d"; [ -f "$AVATAR" ] && cp -f "$AVATAR" "$d/avatar.h5"
    RUN_STDOUT="$WORK/teleop.md" run "$PY" scripts/teleop_figures.py "$d"
    stamp "$WORK/teleop.md" "$OUT/teleop.md" ;;
  fit)
    if [ "$OUT" != "$REPO/scripts/results" ]; then
      echo "== [fit] skipped: scripts/fit_benchmark.py writes scripts/results/ itself (full run into it only)"
      continue
    fi
    run "$PY" scripts/fit_benchmark.py --work "$WORK/fit"
    cp -f "$OUT/fit.md" "$WORK/fit.md" 2>/dev/null && stamp "$WORK/fit.md" "$OUT/fit.md"
    for f in "$OUT"/fit_*.svg; do [ -f "$f" ] && cp -f "$f" "$WORK/$(basename "$f")" && stamp "$WORK/$(basename "$f")" "$f"; done ;;
  fit_dynamic)
    d="$WORK/fit_dynamic"; mkdir -p "$d"; [ -f "$AVATAR" ] && cp -f "$AVATAR" "$d/avatar.h5"
    RUN_STDOUT="$WORK/fit_dynamic_bones.md" run "$PY" scripts/fit_dynamic_bones.py "$d"
    stamp "$WORK/fit_dynamic_bones.md" "$OUT/fit_dynamic_bones.md" ;;
  mocap)
    need_avatar || continue
    d="$WORK/mocap"; rm -rf "$d"
    if ! have_mocap; then echo "== [mocap] skipped: no $MOCAP"; FAILED+=("mocap (no data)"); continue; fi
    run bash scripts/mocap_check.sh --build-dir "$BUILD" --avatar "$AVATAR" --out "$d" "$MOCAP"
    stamp "$d/mocap_check.csv" "$OUT/mocap_check.csv"
    if [ -f "$d/pelvis_error.svg" ]; then stamp "$d/pelvis_error.svg" "$OUT/pelvis_error.svg"; fi ;;
  batch)
    d="$WORK/batch"; rm -rf "$d"; mkdir -p "$d"
    run "$PY" scripts/batch_benchmark.py --sflsh "$SFLSH" --shapes 16 --handles 16 --out "$d"
    for f in "$d"/batch_benchmark.md "$d"/batch_benchmark.csv "$d"/batch_manifest_*.csv; do
      [ -f "$f" ] && stamp "$f" "$OUT/$(basename "$f")"
    done ;;
  batch_resume)
    d="$WORK/batch_resume"; rm -rf "$d"; mkdir -p "$d"
    run bash scripts/batch_resume_check.sh "$SFLSH" --figures "$d/figures.txt"
    { echo "# Batch resume check"; echo; echo '```'; grep -v '^\s*$' "$WORK/logs/$step.log" | tail -n 12; echo '```'; } \
      > "$d/batch_resume_check.md"
    stamp "$d/batch_resume_check.md" "$OUT/batch_resume_check.md" ;;
  shapes)
    cache=$(mktemp -d)
    run env SFLSH_CACHE_DIR="$cache" "$PY" scripts/shape_quality_sweep.py --build "$BUILD_ABS" --models procedural \
      --corners 32 --random 20 --out "$WORK/shape_topology.md"
    rm -rf "$cache"
    stamp "$WORK/shape_topology.md" "$OUT/shape_topology.md" ;;
  readme)
    if [ "$OUT" != "$REPO/scripts/results" ]; then
      echo "== [readme] skipped: the README links scripts/results/, not $OUT"
      continue
    fi
    run "$PY" scripts/check_readme_figures.py --require-stamp ;;
  esac
done

echo
echo "reproduce:$MODE finished in $((SECONDS - START)) s; load $(loadavg); tables in $OUT"
if [ ${#FAILED[@]} -gt 0 ]; then
  echo "reproduce: ${#FAILED[@]} step(s) failed or missed a target: ${FAILED[*]}" >&2
  exit 1
fi
echo "reproduce: every step passed"
