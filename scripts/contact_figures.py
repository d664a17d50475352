#!/usr/bin/python3
"""The contact and tool figures on the built-in avatar.

Runs the example scenes (apps/scenes/*.yaml) and the figure scenes
(apps/scenes/figures/*.yaml) with `sflsh simulate`, keeps each run's output
(NAME.log) and result file (NAME.h5) in WORK_DIR, and judges the figures
against the issue's targets from those files alone (judge()), so that
`--check WORK_DIR` re-judges a finished run without simulating. Writes a
Markdown table to stdout (scripts/results/contact_figures.md keeps the last
one). Exit status: 0 when every stated target is met, 1 when one is missed
(named on stderr), 2 when a result file is missing or malformed (one line
naming the file and the dataset or log line).

Usage: /usr/bin/python3 scripts/contact_figures.py [WORK_DIR]   (default out/contact_figures)
       /usr/bin/python3 scripts/contact_figures.py --check WORK_DIR
The avatar is precomputed into WORK_DIR/avatar.h5 unless it is there already.
"""
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from figure_check import BadResults, FigureTable, h5_dataset, read_text, run_judged, search  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SFLSH = os.path.join(ROOT, os.environ.get("SFLSH_BUILD_DIR", "build"), "sflsh")
SCRIPT = "contact_figures"
G = 9.81
# The floor's force on the body at rest: its horizontal part at most this share of the vertical one.
FLOOR_HORIZONTAL_SHARE = 0.02
# The football at the belly stepped at twice the example's time step (5 cm of travel a step): the
# patch must stay stable where the impact is not resolved. Written from ball_at_belly.yaml by measure().
BALL_COARSE = "ball_at_belly_dt120"
BALL_COARSE_PEAK_FORCE_N = 1000.0
# The scenes judge() reads (NAME.log and, where used, NAME.h5).
JUDGED = ["slab_on_belly", "sphere_on_belly", "fall_on_floor", "two_walkers", "momentum_bump", "pinch_from_file",
          "ball_at_belly", "box_press", "walker_meets_stander", "walker_meets_stander_capsules", BALL_COARSE]
# A walker meeting a standing body: targets on the skin's penetration and the peak force.
WALKER_PENETRATION_MM = 5.0
WALKER_PEAK_FORCE_N = 2000.0


def measure(work):
    """Runs every scene; leaves NAME.log (stdout, then a line 'wall seconds: S') and NAME.h5 in `work`."""
    if not os.path.exists(os.path.join(work, "avatar.h5")):
        p = subprocess.run([SFLSH, "precompute", "--out", "avatar.h5"], cwd=work, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"sflsh precompute failed:\n{p.stdout}\n{p.stderr}")
    for folder in ("apps/scenes", "apps/scenes/figures"):
        for f in sorted(os.listdir(os.path.join(ROOT, folder))):
            if f.endswith(".csv"):
                shutil.copy(os.path.join(ROOT, folder, f), work)
        for f in sorted(os.listdir(os.path.join(ROOT, folder))):
            if f.endswith(".yaml"):
                shutil.copy(os.path.join(ROOT, folder, f), work)
                t = time.time()
                p = subprocess.run([SFLSH, "simulate", f], cwd=work, capture_output=True, text=True)
                if p.returncode != 0:
                    sys.exit(f"sflsh simulate {f} failed:\n{p.stdout}\n{p.stderr}")
                secs = time.time() - t
                with open(os.path.join(work, f[:-5] + ".log"), "w") as out:
                    out.write(p.stdout + f"wall seconds: {secs:.1f}\n")
                print(f"ran {f} in {secs:.1f} s", file=sys.stderr)
    with open(os.path.join(ROOT, "apps/scenes/ball_at_belly.yaml")) as src:
        text = src.read()
    if "dt: 1/240" not in text:
        sys.exit("apps/scenes/ball_at_belly.yaml: no 'dt: 1/240' to write its 1/120 variant from")
    with open(os.path.join(work, BALL_COARSE + ".yaml"), "w") as out:
        out.write(text.replace("dt: 1/240", "dt: 1/120").replace("ball_at_belly.", BALL_COARSE + "."))
    t = time.time()
    p = subprocess.run([SFLSH, "simulate", BALL_COARSE + ".yaml"], cwd=work, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"sflsh simulate {BALL_COARSE}.yaml failed:\n{p.stdout}\n{p.stderr}")
    with open(os.path.join(work, BALL_COARSE + ".log"), "w") as out:
        out.write(p.stdout + f"wall seconds: {time.time() - t:.1f}\n")


def contact_lines(log):
    """{(term, body): (max penetration mm, max force N, end force vector N)}"""
    out = {}
    for m in re.finditer(r"contact (\S+) on (\S+): max penetration ([\d.]+) mm, max force ([\d.]+) N, in contact "
                         r"(\d+) steps; at the end\s+(\S+)\s+(\S+)\s+(\S+) N", log):
        try:
            end = np.array([float(m[6]), float(m[7]), float(m[8])])
        except ValueError:
            end = np.full(3, np.nan)
        out[(m[1], m[2])] = (float(m[3]), float(m[4]), end)
    return out


def contact(log, path, term, body):
    c = contact_lines(log).get((term, body))
    if c is None:
        raise BadResults(f"{path}: no 'contact {term} on {body}: max penetration ...' line")
    return c


def steps_line(log, path):
    m = search(r"steps: (\d+) accepted, (\d+) damped, (\d+) rejected; step time median ([\d.]+) ms", log, path,
               "'steps: N accepted, N damped, N rejected; step time median ...'")
    return int(m[1]), int(m[2]), int(m[3]), float(m[4])


def walker(logs, w, row):
    """The body-body rows: a walker meeting a standing body, two walkers, and the capsules alone for comparison."""
    name = "walker_meets_stander"
    log, path = logs[name], w(name + ".log")
    pen, fmax, _ = contact(log, path, "skin_contact", "alice")
    core = contact(log, path, "body_contact", "alice")[0]
    acc, damped, rej, med = steps_line(log, path)
    joints = h5_dataset(w(name + ".h5"), "/frames/joints")
    if joints.ndim != 3 or joints.shape[1] != 48 or joints.shape[2] != 3 or joints.shape[0] < 2:
        raise BadResults(f"{w(name + '.h5')}: dataset '/frames/joints' has shape {joints.shape}, "
                         "expected (frames >= 2, 48, 3): two bodies' 24 joints")
    # She starts behind him along +z (pelvis z −0.75 vs 0): passing through puts her pelvis ahead of his.
    lead = float(np.max(joints[:, 0, 2] - joints[:, 24, 2]))
    src = "figures/walker_meets_stander.yaml"
    row("walker (0.6 m/s) meets a standing body, skin against skin: max skin penetration",
        f"≤ {WALKER_PENETRATION_MM:g} mm", f"{pen:.2f} mm", pen <= WALKER_PENETRATION_MM, src)
    row("  … peak contact force", f"≤ {WALKER_PEAK_FORCE_N:g} N", f"{fmax:.0f} N", fmax <= WALKER_PEAK_FORCE_N, src)
    row("  … passes through (her pelvis ahead of his), rejected steps", "no, 0",
        f"{'yes' if lead >= 0 else 'no'} (closest {-lead * 1e3:.0f} mm), {rej}", lead < 0 and rej == 0, src)
    row("  … bone-capsule cores: max overlap; step median", "(record)", f"{core:.2f} mm; {med:.1f} ms", None, src)
    name = "walker_meets_stander_capsules"
    log, path = logs[name], w(name + ".log")
    ov, fcap, _ = contact(log, path, "body_contact", "alice")
    row("  … the same with bone capsules alone (rigid): max overlap, peak force", "(record)",
        f"{ov:.2f} mm, {fcap:.0f} N", None, "figures/walker_meets_stander_capsules.yaml")
    log, path = logs["two_walkers"], w("two_walkers.log")
    pen, fmax, _ = contact(log, path, "skin_contact", "alice")
    core = contact(log, path, "body_contact", "alice")[0]
    row("two avatars walking into each other: max skin penetration", "≤ 5 mm", f"{pen:.2f} mm", pen <= 5,
        "two_walkers.yaml")
    row("  … peak contact force; capsule cores' max overlap", "(record)", f"{fmax:.0f} N; {core:.2f} mm", None,
        "two_walkers.yaml")


def judge(work):
    """The figures and verdicts from the files in `work` -> (Markdown text, FigureTable)."""
    w = lambda name: os.path.join(work, name)  # noqa: E731
    logs = {name: read_text(w(name + ".log")) for name in JUDGED}
    table = FigureTable()
    row = table.row

    # Static equilibrium: contact force = weight.
    f = contact(logs["slab_on_belly"], w("slab_on_belly.log"), "contact:slab", "alice")[2]
    ratio = abs(f[2]) / (2.0 * G)
    row("slab (2 kg) resting on the belly: contact force / weight", "1 ± 0.02", f"{ratio:.4f}", abs(ratio - 1) <= 0.02,
        "figures/slab_on_belly.yaml")
    f = contact(logs["sphere_on_belly"], w("sphere_on_belly.log"), "contact:ball", "alice")[2]
    poses = h5_dataset(w("sphere_on_belly.h5"), "/frames/object_poses")
    t = h5_dataset(w("sphere_on_belly.h5"), "/frames/time")
    if poses.ndim != 3 or poses.shape[0] < 2 or poses.shape[2] < 3 or t.shape[0] != poses.shape[0]:
        raise BadResults(f"{w('sphere_on_belly.h5')}: dataset '/frames/object_poses' has shape {poses.shape}, "
                         f"expected (frames >= 2, objects, 7) with as many frames as '/frames/time' ({t.shape[0]})")
    p = poses[:, 0, :3]
    v = np.linalg.norm(p[-1] - p[-2]) / (t[-1] - t[-2])
    ratio = abs(f[2]) / (1.0 * G)
    row(f"sphere (1 kg) on the belly at t = {t[-1]:.1f} s (speed {v * 1e3:.0f} mm/s): force / weight", "1 ± 0.02",
        f"{ratio:.4f}", abs(ratio - 1) <= 0.02, "figures/sphere_on_belly.yaml")
    # Floor drop.
    log, path = logs["fall_on_floor"], w("fall_on_floor.log")
    pen, _, fend = contact(log, path, "contact:floor", "alice")
    acc, damped, rej, _ = steps_line(log, path)
    finite = bool(np.isfinite(h5_dataset(w("fall_on_floor.h5"), "/frames/positions")).all())
    row("avatar dropped 0.4 m on the floor: max penetration", "≤ 5 mm", f"{pen:.2f} mm", pen <= 5,
        "fall_on_floor.yaml")
    row("  … rejected steps, NaN", "0, none", f"{rej}, {'none' if finite else 'NaN'}", rej == 0 and finite,
        "fall_on_floor.yaml")
    horizontal = float(np.hypot(fend[0], fend[2]))
    row("  … floor force at rest (the body's weight): up, horizontal part / vertical",
        f"vertical: up, ≤ {FLOOR_HORIZONTAL_SHARE}", f"{fend[1]:.0f} N up, |horizontal| {horizontal:.1f} N "
        f"({horizontal / fend[1] if fend[1] > 0 else float('nan'):.4f})",
        fend[1] > 0 and horizontal <= FLOOR_HORIZONTAL_SHARE * fend[1], "fall_on_floor.yaml")
    # Bodies meeting skin against skin (the flesh of both gives; capsule cores behind).
    walker(logs, w, row)
    # Momentum.
    m = search(r"linear momentum: start ([\d.]+) kg m/s, end ([\d.]+) kg m/s \(change (\S+)\)",
               logs["momentum_bump"], w("momentum_bump.log"), "'linear momentum: start ... (change ...)'")
    try:
        rel = float(m[3]) / float(m[1])
    except (ValueError, ZeroDivisionError):
        raise BadResults(f"{w('momentum_bump.log')}: 'linear momentum' line: change {m[3]!r} / start {m[1]!r} "
                         "is not a ratio of numbers") from None
    row("two-body collision, gravity off: |Δp| / |p|", "≤ 1e-6", f"{rel:.1e}", rel <= 1e-6, "figures/momentum_bump.yaml")
    # Pinch-and-lift from a recorded pose file.
    log, path = logs["pinch_from_file"], w("pinch_from_file.log")
    m = search(r"tools: peak force ([\d.]+) N, largest anchor stretch ([\d.]+) mm", log, path,
               "'tools: peak force ... largest anchor stretch ...'")
    grasps = len(re.findall(r": grasp (\d+) skin points", log))
    releases = len(re.findall(r": release (\d+) skin points", log))
    acc, damped, rej, _ = steps_line(log, path)
    finite = bool(np.isfinite(h5_dataset(w("pinch_from_file.h5"), "/frames/positions")).all())
    u = h5_dataset(w("pinch_from_file.h5"), "/frames/displacement")
    if u.ndim != 3 or u.shape[0] <= 6:
        raise BadResults(f"{w('pinch_from_file.h5')}: dataset '/frames/displacement' has shape {u.shape}, "
                         "expected (frames > 6, vertices, 3)")
    stretch = float(m[2])
    row("pinch-and-lift 1.5 cm from a pose file: largest anchor stretch (slip)", "≤ 1 mm", f"{stretch:.2f} mm",
        stretch <= 1.0, "figures/pinch_from_file.yaml")
    row("  … grasp / release events, rejected steps, NaN", "1 / 1, 0, none",
        f"{grasps} / {releases}, {rej}, {'none' if finite else 'NaN'}", grasps == 1 and releases == 1 and rej == 0 and
        finite, "figures/pinch_from_file.yaml")
    row("  … peak force on the gripper; skin displacement at the end vs before the grasp", "(record)",
        f"{float(m[1]):.0f} N; {np.abs(u[-1]).max() * 1e3:.1f} mm vs {np.abs(u[int(0.2 * 30)]).max() * 1e3:.1f} mm",
        None, "figures/pinch_from_file.yaml")
    # The other examples, for the record.
    for name, term in (("ball_at_belly", "contact:ball"), ("box_press", "contact:press")):
        pen, fmax, _ = contact(logs[name], w(name + ".log"), term, "alice")
        acc, damped, rej, med = steps_line(logs[name], w(name + ".log"))
        row(f"{name}: max penetration, peak force, step median", "(record)", f"{pen:.2f} mm, {fmax:.0f} N, {med:.2f} ms",
            None, f"{name}.yaml")

    pen, fmax, _ = contact(logs[BALL_COARSE], w(BALL_COARSE + ".log"), "contact:ball", "alice")
    acc, damped, rej, med = steps_line(logs[BALL_COARSE], w(BALL_COARSE + ".log"))
    row("ball_at_belly at 1/120 s (5 cm a step): damped / rejected steps, peak force", f"0 / 0, ≤ {BALL_COARSE_PEAK_FORCE_N:g} N",
        f"{damped} / {rej}, {fmax:.0f} N", damped == 0 and rej == 0 and fmax <= BALL_COARSE_PEAK_FORCE_N,
        "ball_at_belly.yaml with dt: 1/120")

    text = ["# Contact and tool figures\n",
            "Built-in avatar (`sflsh precompute --out avatar.h5`), default contact settings "
            "(body–object: 2e5 N/m per skin sample, friction 0.5; body–body: skin against skin, pressure stiffness "
            "1e8 N/m³ sampled every 1 cm, bone-capsule cores at half radius, 1e6 N/m per pair).",
            "Reproduce: `/usr/bin/python3 scripts/contact_figures.py` (about two minutes after the build; "
            "`--check WORK_DIR` re-judges its files).\n",
            table.markdown(), "\nPer-pair lines as `sflsh simulate` printed them:\n"]
    for name in sorted(f[:-4] for f in os.listdir(work) if f.endswith(".log")):
        log = logs.get(name) or read_text(w(name + ".log"))
        wall = re.search(r"^wall seconds: ([\d.]+)", log, re.M)
        text.append(f"- `{name}`" + (f" ({wall[1]} s wall):" if wall else ":"))
        for line in log.splitlines():
            if line.startswith(("contact ", "steps:", "linear momentum", "mean ms")):
                text.append(f"  - {line}")
    return "\n".join(text), table


def main():
    args = sys.argv[1:]
    if args[:1] == ["--check"]:
        if len(args) != 2:
            sys.exit("usage: contact_figures.py --check WORK_DIR")
        work = os.path.abspath(args[1])
    else:
        work = os.path.abspath(args[0] if args else os.path.join(ROOT, "out", "contact_figures"))
        os.makedirs(work, exist_ok=True)
        measure(work)
    run_judged(SCRIPT, lambda: judge(work))


if __name__ == "__main__":
    main()
