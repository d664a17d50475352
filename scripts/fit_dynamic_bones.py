#!/usr/bin/python3
"""Fitting a default `sflsh simulate` run (dynamic bones) -> scripts/results/fit_dynamic_bones.md.

The built-in avatar runs `builtin:jump` with the belly's Young's moduli doubled
(`simulate`'s defaults: dynamic bones, so the bones the run takes are not the
motion's). `sflsh fit --params young --regions belly` then recovers the factor
twice: from the result file as written (the fit prescribes the run's own
bones, /steps/bones) and from a copy without the bones (the fit prescribes the
motion's). Target: the factor within 5 % of the truth (x2) with the run's own
bones. Judged from the two fit logs alone (`--check WORK` re-judges them).

Exit status: 0 when the target is met, 1 when it is missed (named on stderr),
2 when a log is missing or malformed (one line naming the file and the line).

Usage: /usr/bin/python3 scripts/fit_dynamic_bones.py [WORK]   (default out/fit_dynamic_bones)
       /usr/bin/python3 scripts/fit_dynamic_bones.py --check WORK
The avatar is precomputed into WORK/avatar.h5 unless it is there already.
"""
import os
import subprocess
import sys

import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from figure_check import FigureTable, read_text, run_judged, search  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SFLSH = os.path.join(ROOT, os.environ.get("SFLSH_BUILD_DIR", "build"), "sflsh")
SCRIPT = "fit_dynamic_bones"
TRUTH = 2.0          # the belly's Young's factor in the observed run
TOLERANCE_PCT = 5.0  # the target on the fit with the run's own bones
RUN_BONES = ("/steps/bones", "/meta/start_bones")


def run(args, work, log):
    p = subprocess.run([SFLSH] + args, cwd=work, capture_output=True, text=True)
    with open(os.path.join(work, log), "w") as f:
        f.write(p.stdout + p.stderr)
    if p.returncode != 0:
        sys.exit(f"sflsh {' '.join(args)} failed:\n{p.stdout}\n{p.stderr}")


def measure(work):
    """Leaves obs.h5, obs_without_bones.h5, fit_own.log and fit_motion.log in `work`."""
    os.makedirs(work, exist_ok=True)
    if not os.path.exists(os.path.join(work, "avatar.h5")):
        run(["precompute", "--out", "avatar.h5"], work, "precompute.log")
    with open(os.path.join(work, "belly_x2.yaml"), "w") as f:
        # The default belly: E = 8 kPa, along : around : through = 1.5 : 1 : 0.5 (volume/body_regions.cpp).
        f.write("regions:\n  belly: {" + ", ".join(f"young_{d}: {TRUTH * k * 8.0e3:g}" for d, k in
                                                     (("along", 1.5), ("around", 1.0), ("through", 0.5))) + "}\n")
    run(["simulate", "--avatar", "avatar.h5", "--motion", "builtin:jump", "--seconds", "2", "--material",
         "belly_x2.yaml", "--out", "obs.h5"], work, "simulate.log")
    with h5py.File(os.path.join(work, "obs.h5"), "r") as src, \
            h5py.File(os.path.join(work, "obs_without_bones.h5"), "w") as dst:
        def copy(name, obj):  # returns None: visititems goes on
            if isinstance(obj, h5py.Dataset) and "/" + name not in RUN_BONES:
                dst.create_dataset(name, data=obj[()])
        src.visititems(copy)
    for obs, log in (("obs.h5", "fit_own.log"), ("obs_without_bones.h5", "fit_motion.log")):
        run(["fit", "--avatar", "avatar.h5", "--observed", obs, "--params", "young", "--regions", "belly", "--out",
             log.replace(".log", ".yaml")], work, log)


def parse(path):
    """(fitted factor, bones line, RMS before, RMS after) of one fit log."""
    log = read_text(path)
    factor = float(search(r"^  young:belly\s+x([\d.]+)", log, path, "'  young:belly  xF ...'").group(1))
    bones = search(r"^bones: (.*)$", log, path, "'bones: ...'").group(1)
    m = search(r"surface error RMS per coordinate: ([\d.]+) mm before, ([\d.]+) mm after", log, path,
               "'surface error RMS per coordinate: ... before, ... after'")
    return factor, bones, float(m.group(1)), float(m.group(2))


def judge(work):
    table = FigureTable()
    own = parse(os.path.join(work, "fit_own.log"))
    motion = parse(os.path.join(work, "fit_motion.log"))
    err_own, err_motion = (100 * (x[0] / TRUTH - 1) for x in (own, motion))
    table.row("belly Young's factor (truth x2), fitted under the run's own bones (`/steps/bones`)",
              f"within ±{TOLERANCE_PCT:g} %", f"x{own[0]:.4f} ({err_own:+.1f} %)", abs(err_own) <= TOLERANCE_PCT,
              "simulate --motion builtin:jump, dynamic bones")
    table.row("  … the same skin without the run's bones (the motion's prescribed)", "(record)",
              f"x{motion[0]:.4f} ({err_motion:+.1f} %)", None, "obs_without_bones.h5")
    table.row("  … surface error RMS per coordinate, at the defaults → fitted: own bones / the motion's", "(record)",
              f"{own[2]:.3f} → {own[3]:.3f} mm / {motion[2]:.3f} → {motion[3]:.3f} mm", None, "fit logs")
    text = "\n".join([
        "# Fitting a run with dynamic bones",
        "",
        "Built-in avatar, `sflsh simulate --motion builtin:jump --seconds 2` (dynamic bones, the default) with the "
        "belly's Young's moduli doubled; `sflsh fit --params young --regions belly` from the defaults.",
        f"Bones the fits prescribe: own — {own[1]}; without — {motion[1]}.",
        "Reproduce: `/usr/bin/python3 scripts/fit_dynamic_bones.py` (about a minute after the build; `--check WORK` "
        "re-judges its logs).",
        "",
        table.markdown(),
        "",
    ])
    return text, table


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--check":
        work = sys.argv[2]
    elif len(sys.argv) <= 2 and not (len(sys.argv) == 2 and sys.argv[1].startswith("-")):
        work = os.path.abspath(sys.argv[1] if len(sys.argv) == 2 else os.path.join(ROOT, "out", SCRIPT))
        measure(work)
    else:
        sys.exit(__doc__.split("\n\n")[-2])
    run_judged(SCRIPT, lambda: judge(work))


if __name__ == "__main__":
    main()
