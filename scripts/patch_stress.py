#!/usr/bin/env python3
"""Stress of the contact patch: a 1 cm probe tool on the built-in body's belly,
10,000 steps at 500 Hz with `contact.patch` on, patches created and dropped
all the time:
  * 0-1 s the probe waits 5 cm away (the body sags to rest),
  * 1-10 s it taps: 8 mm into the skin and 2 mm out again on alternate steps
    (a patch appears and is released every other step), sliding 5 cm sideways,
  * 10-19 s it is yanked: 25 mm deep, dragged sideways at up to 1 m/s and pulled
    out every 0.5 s (and pushed back in, through the skin in one step),
  * 19-20 s it is away again.
Targets: every step taken (10,000), none rejected, every logged value finite,
the elastic energy bounded (at most MAX_ENERGY J at any time) and, with the
probe away at the end, no higher than before the first contact (1 s; the body
is still settling from its sag then) by more than REST_TOLERANCE.

The run's log and tool log stay in WORK_DIR; the verdicts are computed from
those files alone, so `--check WORK_DIR` re-judges a finished run. Writes a
Markdown table to stdout (scripts/results/patch_stress.md keeps the last one).
Exit status: 0 when every target is met, 1 when one is missed, 2 when a result
file is missing or malformed.

Usage: /usr/bin/python3 scripts/patch_stress.py [WORK_DIR]   (default out/patch_stress; about 4 min)
       /usr/bin/python3 scripts/patch_stress.py --check WORK_DIR
"""
import math
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from figure_check import BadResults, FigureTable, read_csv_columns, read_text, run_judged, search  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SFLSH = os.path.join(ROOT, os.environ.get("SFLSH_BUILD_DIR", "build"), "sflsh")
SCRIPT = "patch_stress"
RATE = 500            # Hz
SECONDS = 20
MAX_ENERGY = 5.0      # J: the body at rest holds ~0.5 J, a 25 mm dent of a 1 cm probe well under 1 J
REST_TOLERANCE = 0.05
SKIN_Z = 0.11         # the built-in body's belly front near x = 0, y = 1.05 (m)

SCENE = """# Written by scripts/patch_stress.py: a 1 cm probe tapped and yanked through the belly.
solver: {dt: 1/500, seconds: 20}
output: {out: patch_stress.h5, fps: 30}
contact: {patch: true, friction: 0}
bodies:
  - {name: alice, avatar: default, motion: none, bones: kinematic}
tools:
  - name: probe
    shape: {type: sphere, radius: 0.01}
    pose_file: probe_path.csv
"""


def probe_path(path):
    """The probe centre per step (see the module comment); the probe's front is 1 cm ahead of it."""
    with open(path, "w") as f:
        f.write("time,x,y,z,qw,qx,qy,qz,closure\n")
        for i in range(RATE * SECONDS + 1):
            t = i / RATE
            x, depth = 0.0, -0.05
            if 1 <= t < 10:
                x = 0.05 * math.sin(2 * math.pi * (t - 1) / 4.0)
                depth = 0.008 if i % 2 == 0 else -0.002
            elif 10 <= t < 19:
                x = 0.08 * math.sin(2 * math.pi * (t - 10) / 0.5)
                depth = 0.025 if (t - 10) % 0.5 < 0.3 else -0.01
            f.write(f"{t:.6f},{x:.6f},1.05,{SKIN_Z + 0.01 - depth:.6f},1,0,0,0,0\n")


def measure(work):
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "patch_stress.yaml"), "w") as f:
        f.write(SCENE)
    probe_path(os.path.join(work, "probe_path.csv"))
    p = subprocess.run([SFLSH, "run", "patch_stress.yaml", "--tool-log", "tools.csv", "--quiet-status"], cwd=work,
                       capture_output=True, text=True)
    with open(os.path.join(work, "run.log"), "w") as f:
        f.write(p.stdout + p.stderr)
    if p.returncode != 0:
        sys.exit(f"sflsh run patch_stress.yaml failed (exit {p.returncode}); see {work}/run.log:\n{p.stderr}")


def judge(work):
    log_path, tools_path = os.path.join(work, "run.log"), os.path.join(work, "tools.csv")
    log = read_text(log_path)
    m = search(r"steps: (\d+) accepted, (\d+) damped, (\d+) rejected; step time median ([\d.]+) ms, p99 ([\d.]+) ms",
               log, log_path, "'steps: N accepted, N damped, N rejected; step time median ... p99 ...'")
    accepted, damped, rejected = int(m[1]), int(m[2]), int(m[3])
    s = search(r"simulated ([\d.]+) s in [\d.]+ s of wall time \((\d+) steps\)", log, log_path,
               "'simulated T s in W s of wall time (N steps)'")
    steps = int(s[2])
    L = {k: np.asarray(v) for k, v in read_csv_columns(tools_path, ["time", "force_x", "force_y", "force_z",
                                                                     "elastic_energy"]).items()}
    t, e = L["time"], L["elastic_energy"]
    force = np.sqrt(L["force_x"] ** 2 + L["force_y"] ** 2 + L["force_z"] ** 2)
    finite = all(bool(np.all(np.isfinite(v))) for v in L.values())
    if t[0] > 1.0 or t[-1] < SECONDS - 1e-6:
        raise BadResults(f"{tools_path}: column 'time' does not cover 1 s to {SECONDS} s")
    rest = float(np.interp(1.0, t, e))
    end = float(e[-1])
    tapping = force[(t >= 1) & (t < 10)]
    yanking = force[(t >= 10) & (t < 19)]
    if tapping.size == 0 or yanking.size == 0:
        raise BadResults(f"{tools_path}: no rows in 1-10 s or in 10-19 s")

    tab = FigureTable()
    scene = "patch_stress.yaml"
    tab.row("steps taken / rejected", f"{RATE * SECONDS} / 0", f"{steps} / {rejected}",
            steps == RATE * SECONDS and rejected == 0, scene)
    tab.row("  … Newton iterations accepted / damped (an added iteration counts)", "(record)",
            f"{accepted} / {damped}", None, scene)
    tab.row("every logged value finite", "yes", "yes" if finite else "no", finite, scene)
    tab.row("elastic energy: largest over the run", f"≤ {MAX_ENERGY:g} J", f"{np.max(e):.3f} J",
            bool(np.max(e) <= MAX_ENERGY), scene)
    tab.row("elastic energy at the end (probe away) against before the first contact (1 s)",
            f"≤ {1 + REST_TOLERANCE:g} ×", f"{end:.4f} J / {rest:.4f} J", bool(end <= (1 + REST_TOLERANCE) * rest), scene)
    tab.row("probe force: largest while tapping / yanking", "(record)",
            f"{tapping.max():.1f} N / {yanking.max():.1f} N", None, scene)
    tab.row("step time median / p99 (one core)", "(record)", f"{float(m[4]):.2f} / {float(m[5]):.2f} ms", None,
            scene)
    load = os.getloadavg()
    text = ["# Contact patch under stress: a probe tapped and yanked through the belly\n",
            f"Built-in body, kinematic bones, a 1 cm probe tool on a pose file, `contact.patch` (defaults), "
            f"{RATE} Hz for {SECONDS} s: waits (0-1 s), taps 8 mm in and 2 mm out on alternate steps (1-10 s), "
            "is yanked 25 mm deep at up to 1 m/s and pulled out every 0.5 s (10-19 s), waits (19-20 s).",
            f"Reproduce: `/usr/bin/python3 scripts/patch_stress.py` (about 4 min; `--check WORK_DIR` re-judges "
            f"its files). Load average when judged: {load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f} on "
            f"{os.cpu_count()} cores.\n",
            tab.markdown()]
    return "\n".join(text), tab


def main():
    args = sys.argv[1:]
    if args[:1] == ["--check"]:
        if len(args) != 2:
            sys.exit("usage: patch_stress.py --check WORK_DIR")
        work = os.path.abspath(args[1])
    else:
        work = os.path.abspath(args[0] if args else os.path.join(ROOT, "out", "patch_stress"))
        measure(work)
    run_judged(SCRIPT, lambda: judge(work))


if __name__ == "__main__":
    main()
