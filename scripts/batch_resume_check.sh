#!/usr/bin/env bash
# Batch resume check (README "Batch precompute"): a --jobs 2 batch of 6 coarse
# shapes is killed (SIGKILL) once 2 files are done; its workers must die with it,
# the rerun must build only the missing rows, and every file must be
# bit-identical to an uninterrupted run's.
# The figures go to a key=value file (the last lines printed, and FILE with
# --figures FILE), judged from that file alone: `--check FILE` re-judges one.
# Exit status: 0 when every check holds; 1 when one fails (named on stderr);
# 2 when the figures file lacks a key or holds a non-integer (one line naming
# the file and the key).
# Usage: bash scripts/batch_resume_check.sh [build/sflsh] [--figures FILE]   (about a minute)
#        bash scripts/batch_resume_check.sh --check FILE
set -euo pipefail

# Judges a figures file: workers_alive_after_kill=0, rerun_exists=files_done_at_kill,
# rerun_built=rows-files_done_at_kill, identical=rows.
judge() {
  local file=$1 key value
  declare -A v
  [ -r "$file" ] || { echo "batch_resume_check: $file: cannot read" >&2; exit 2; }
  for key in rows files_done_at_kill workers_alive_after_kill rerun_exists rerun_built identical; do
    value=$(sed -n "s/^$key=//p" "$file" | head -1)
    [ -n "$value" ] || { echo "batch_resume_check: $file: key '$key' missing" >&2; exit 2; }
    [[ "$value" =~ ^[0-9]+$ ]] || { echo "batch_resume_check: $file: key '$key': '$value' is not a count" >&2; exit 2; }
    v[$key]=$value
  done
  local failed=0
  fail() { echo "batch_resume_check: FAILED: $*" >&2; failed=1; }
  [ "${v[rows]}" -ge 1 ] || fail "no rows in the batch"
  [ "${v[files_done_at_kill]}" -lt "${v[rows]}" ] || fail "the batch finished before it was killed (${v[files_done_at_kill]} of ${v[rows]} files)"
  [ "${v[workers_alive_after_kill]}" -eq 0 ] || fail "${v[workers_alive_after_kill]} worker process(es) outlived the killed batch"
  [ "${v[rerun_exists]}" -eq "${v[files_done_at_kill]}" ] ||
    fail "the rerun kept ${v[rerun_exists]} rows, ${v[files_done_at_kill]} were done before the kill"
  [ "${v[rerun_built]}" -eq $(( v[rows] - v[files_done_at_kill] )) ] ||
    fail "the rerun built ${v[rerun_built]} rows, $(( v[rows] - v[files_done_at_kill] )) were missing"
  [ "${v[identical]}" -eq "${v[rows]}" ] || fail "${v[identical]} of ${v[rows]} files bit-identical to the uninterrupted run"
  [ "$failed" -eq 0 ] || exit 1
  echo "batch_resume_check: passed"
}

if [ "${1:-}" = "--check" ]; then
  [ $# -eq 2 ] || { echo "usage: batch_resume_check.sh --check FILE" >&2; exit 2; }
  judge "$2"
  exit 0
fi
S=$(readlink -f "${1:-build/sflsh}")
FIGURES=""
if [ "${2:-}" = "--figures" ]; then FIGURES=$(readlink -f "${3:?--figures needs a file}"); fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
C="--handles 6 --cell-size 0.08 --facet-size 0.06 --facet-distance 0.004 --cache-dir $work/cache"
printf 'b0,b1\n' > k.csv
for i in 0 1 2 3 4 5; do echo "0.$i,-0.$i" >> k.csv; done
"$S" -q precompute $C --template-only > /dev/null
"$S" -q precompute $C --batch k.csv --out-dir full --jobs 2 > /dev/null
"$S" -q precompute $C --batch k.csv --out-dir killed --jobs 2 > /dev/null 2>&1 &
pid=$!
while [ "$(ls killed/*.h5 2>/dev/null | wc -l)" -lt 2 ]; do sleep 0.2; done
kill -9 $pid
wait $pid 2>/dev/null || true
done_at_kill=$(ls killed/*.h5 | wc -l)
echo "killed the batch (SIGKILL) with $done_at_kill of 6 files done"
sleep 1
alive=$(pgrep -f "out-dir killed" | wc -l || true)
echo "its worker processes still running 1 s later: $alive"
"$S" -q precompute $C --batch k.csv --out-dir killed --jobs 2 | head -1
echo "rerun manifest (row,status): $(cut -d, -f1,6 killed/manifest.csv | tail -n +2 | tr '\n' ' ')"
same=0
for f in full/*.h5; do cmp -s "$f" "killed/$(basename "$f")" && same=$((same + 1)); done
echo "files bit-identical to the uninterrupted run: $same of $(ls full/*.h5 | wc -l)"
{
  echo "rows=$(tail -n +2 k.csv | wc -l)"
  echo "files_done_at_kill=$done_at_kill"
  echo "workers_alive_after_kill=$alive"
  echo "rerun_exists=$(cut -d, -f6 killed/manifest.csv | tail -n +2 | grep -cx exists || true)"
  echo "rerun_built=$(cut -d, -f6 killed/manifest.csv | tail -n +2 | grep -cx built || true)"
  echo "identical=$same"
} > figures.txt
cat figures.txt
[ -z "$FIGURES" ] || cp figures.txt "$FIGURES"
judge figures.txt
