#!/usr/bin/env bash
# Batch resume check (README "Batch precompute"): a --jobs 2 batch of 6 coarse
# shapes is killed (SIGKILL) once 2 files are done; its workers must die with it,
# the rerun must build only the missing rows, and every file must be
# bit-identical to an uninterrupted run's.
# Usage: bash scripts/batch_resume_check.sh [build/sflsh]   (about a minute)
set -euo pipefail
S=$(readlink -f "${1:-build/sflsh}")
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
echo "killed the batch (SIGKILL) with $(ls killed/*.h5 | wc -l) of 6 files done"
sleep 1
echo "its worker processes still running 1 s later: $(pgrep -f "out-dir killed" | wc -l)"
"$S" -q precompute $C --batch k.csv --out-dir killed --jobs 2 | head -1
echo "rerun manifest (row,status): $(cut -d, -f1,6 killed/manifest.csv | tail -n +2 | tr '\n' ' ')"
same=0
for f in full/*.h5; do cmp -s "$f" "killed/$(basename "$f")" && same=$((same + 1)); done
echo "files bit-identical to the uninterrupted run: $same of $(ls full/*.h5 | wc -l)"
