#!/usr/bin/python3
"""Shaped-mesh quality over the shape space, on one tet topology (slow check).

Runs the shape stage's geometry (shape_volume, default thickness map) on
  * the procedural body: beta = 0, 32 corners of [-3, 3]^10 (every sign pattern of
    the first 4 components, the others at +-3 alternating, both phases), the template
    stage's design shapes (each direction alone at +-3, all -3, all +3, the two
    alternating corners), and 100 uniform random draws (seed 2026);
  * the MakeHuman body (if ../shared/data/makehuman exists; converted into a
    temporary folder with data_tools/makehuman_to_smpl.py): beta = 0, the same 32
    corners, the design shapes, and the 12 MakeHuman targets;
and writes scripts/results/shape_quality.md: the template's tets, nodes, topology hash
and (when built by this run) its time and topology design; per shape the min dihedral
angle, the number of inverted tets, tets below 8 deg, the tet count, the time, for shapes
below the bar whether the shaped skin itself self-intersects, and whether the shape kept
the template's tets. Every shape must reach >= 8 deg with no inverted tet on the
template's tets; the exit status is 1 otherwise.

Usage: /usr/bin/python3 scripts/shape_quality_sweep.py [--build build] [--random 100]
       [--models procedural,makehuman] [--corners 32|all] [--no-directions] [--shared ../shared]
       [--out scripts/results/shape_quality.md]
--corners all takes all 1024 corners of [-3, 3]^10 (about an hour per body on one core);
the full procedural sweep's record is scripts/results/shape_quality_all_corners.md:
  /usr/bin/python3 scripts/shape_quality_sweep.py --models procedural --corners all --random 100 \
      --no-directions --out scripts/results/shape_quality_all_corners.md
Template stages come from the precompute cache (~/.cache/sflsh; built on first use). The
one-topology record scripts/results/shape_topology.md (a subset that runs in ~15 min, with the
template stage built by the run so that its time and topology design are recorded):
  SFLSH_CACHE_DIR=$(mktemp -d) /usr/bin/python3 scripts/shape_quality_sweep.py --models procedural \
      --corners 32 --random 20 --out scripts/results/shape_topology.md
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_sweep(binary, model, random, betas_csv=None, corners="32", directions=True):
    env = dict(os.environ)
    env.update(SFLSH_SWEEP_MODEL=model, SFLSH_SWEEP_RANDOM=str(random),
               SFLSH_SWEEP_DIRECTIONS="1" if directions else "0", SFLSH_SWEEP_CORNERS=corners)
    if betas_csv:
        env["SFLSH_SWEEP_BETAS"] = betas_csv
    t0 = time.time()
    # Streamed, so a long sweep shows progress (one line per shape on stderr).
    p = subprocess.Popen([binary, "--gtest_also_run_disabled_tests", "--gtest_filter=ShapeQualitySweep.*"],
                         env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    rows, tail, total, template = [], [], 0, None
    for line in p.stdout:
        line = line.rstrip("\n")
        tail = (tail + [line])[-60:]
        if line.startswith("SWEEP-TEMPLATE|"):
            template = line.split("|")[1:]
        elif line.startswith("SWEEP-TOTAL|"):
            total = int(line.split("|")[1])
        elif line.startswith("SWEEP|"):
            rows.append(line.split("|")[1:])
            elapsed = time.time() - t0
            eta = elapsed / len(rows) * (total - len(rows)) if total else 0
            print("shape_quality_sweep: %s: %d/%d shapes (%s: %s deg), elapsed %.0f s, ETA %.0f s"
                  % (os.path.basename(model), len(rows), total, rows[-1][0], rows[-1][1], elapsed, eta),
                  file=sys.stderr, flush=True)
    p.wait()
    if not rows:
        sys.exit("shape_quality_sweep: no result lines from %s for %s:\n%s" % (binary, model, "\n".join(tail)))
    return rows, time.time() - t0, template


def ok(row):
    """>= 8 deg, none inverted, and the template's tets (column 8 of a shape that did not fail)."""
    return row[1] != "failed" and float(row[1]) >= 8.0 and row[2] == "0" and len(row) > 7 and row[7] == "yes"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--random", type=int, default=100)
    ap.add_argument("--models", default="procedural,makehuman")
    ap.add_argument("--corners", default="32", choices=["32", "all", "0"],
                    help="32: every sign pattern of beta0..3, the rest alternating; all: all 1024 corners")
    ap.add_argument("--no-directions", action="store_true", help="leave out each direction alone at +-3")
    ap.add_argument("--shared", default=os.environ.get("SFLSH_SHARED_DIR", os.path.join(ROOT, "..", "shared")))
    ap.add_argument("--out", default=os.path.join(ROOT, "scripts", "results", "shape_quality.md"))
    a = ap.parse_args()
    all_ok = True
    binary = os.path.join(a.build, "test_precompute")
    if not os.path.exists(binary):
        sys.exit("shape_quality_sweep: %s not found (build it: scripts/build.sh --target test_precompute)" % binary)

    sections = []
    for model in a.models.split(","):
        if model == "procedural":
            rows, wall, tmpl = run_sweep(binary, "procedural", a.random, None, a.corners, not a.no_directions)
            sections.append(("procedural body (%d shapes: %s)" % (len(rows), what(a, a.random)), rows, wall, tmpl))
        elif model == "makehuman":
            mh = os.path.join(a.shared, "data", "makehuman")
            if not os.path.isdir(mh):
                print("shape_quality_sweep: %s absent, MakeHuman body skipped" % mh)
                continue
            with tempfile.TemporaryDirectory() as tmp:
                h5, csv = os.path.join(tmp, "mh.h5"), os.path.join(tmp, "mh_targets.csv")
                subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "data_tools", "makehuman_to_smpl.py"), mh, h5,
                                "--target-betas", csv], check=True, stdout=subprocess.DEVNULL)
                rows, wall, tmpl = run_sweep(binary, h5, 0, csv, a.corners, not a.no_directions)
            sections.append(("MakeHuman body (%d shapes: %s, 12 targets)" % (len(rows), what(a, 0)), rows, wall, tmpl))
        else:
            sys.exit("shape_quality_sweep: --models: unknown model '%s' (expected procedural, makehuman)" % model)
        all_ok = write(a.out, sections, " ".join(["/usr/bin/python3", "scripts/shape_quality_sweep.py"] + sys.argv[1:]))
    print("shape_quality_sweep: wrote %s (%s)" % (a.out, "all shapes meet the bar" if all_ok else "SOME SHAPES FAIL"))
    return 0 if all_ok else 1


def what(a, random):
    parts = ["zero"]
    if a.corners != "0":
        parts.append("%s corners" % ("all 1024" if a.corners == "all" else "32"))
    if not a.no_directions:
        parts.append("24 design shapes (20 single directions, all -3, all +3, 2 alternating)")
    if random:
        parts.append("%d random" % random)
    return ", ".join(parts)


def write(path, sections, command=None):
    all_ok = True
    out = ["# Shaped-mesh quality over the shape space, one tet topology", "",
           "Written by `scripts/shape_quality_sweep.py` (%s). Bar: every shape min dihedral >= 8 deg, 0 inverted, "
           "on the template's tets (the shape stage only moves nodes)."
           % time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
           "Time = shape_volume (geometry of the shape stage) per shape, wall, on a shared 2-core machine.", ""]
    if command:
        out += ["Command:", "", "    " + command, ""]
    for title, rows, wall, tmpl in sections:
        good = sum(ok(r) for r in rows)
        worst = min((float(r[1]) for r in rows if r[1] != "failed"), default=float("nan"))
        times = [float(r[5]) for r in rows]
        same = sum(1 for r in rows if r[1] != "failed" and len(r) > 7 and r[7] == "yes")
        out += ["## " + title, ""]
        if tmpl:
            out += ["Template: %s tets, %s nodes, topology hash `%s`; %s" % (
                tmpl[0], tmpl[1], tmpl[2], "template stage %s s: %s" % (tmpl[3], tmpl[4])
                if float(tmpl[3]) > 0 else "template stage loaded from the cache (its figures are those of the "
                "run that built it)"), ""]
        out += ["%d of %d meet the bar; %d of %d kept the template's tets; worst min dihedral %.3f deg; time per "
                "shape median %.1f s, max %.1f s; sweep wall %.0f s."
                % (good, len(rows), same, len(rows), worst, sorted(times)[len(times) // 2], max(times), wall), "",
                "| shape | min dihedral (deg) | inverted | tets < 8 deg | tets | time (s) "
                "| skin self-intersects | template's tets | ok |",
                "|---|---|---|---|---|---|---|---|---|"]
        out += ["| %s | %s | %s | %s | %s | %s | %s | %s | %s |"
                % (r[0], r[1], r[2], r[3], r[4], r[5], r[6] if len(r) > 6 else "-",
                   r[7] if r[1] != "failed" and len(r) > 7 else "-", "yes" if ok(r) else "**no**")
                for r in rows]
        invalid = [r for r in rows if not ok(r) and len(r) > 6 and r[6] == "yes"]
        if invalid:
            out += ["", "%d of the %d shapes below the bar have a self-intersecting skin: the body model gives "
                    "no valid solid there, so no tet mesh bounded by it exists (column 'skin self-intersects'; "
                    "tested only for shapes below the bar)." % (len(invalid), len(rows) - good)]
        failures = [r for r in rows if r[1] == "failed" and len(r) > 7]
        if failures:
            out += ["", "Why the failed shapes stopped (the shape stage's error):", ""]
            out += ["- %s: %s" % (r[0], r[7]) for r in failures]
        out.append("")
        all_ok = all_ok and good == len(rows)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path + ".partial", "w") as f:
        f.write("\n".join(out))
    os.replace(path + ".partial", path)
    return all_ok


if __name__ == "__main__":
    sys.exit(main())
