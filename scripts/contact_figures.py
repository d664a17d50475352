#!/usr/bin/python3
"""Issue 10's contact figures on the built-in avatar.

Runs the example scenes (apps/scenes/*.yaml) and the figure scenes
(apps/scenes/figures/*.yaml) with `sflsh simulate`, reads what each run
prints (per-pair contact figures, step counts, momentum) and the result
files, and writes a Markdown table of the figures against the issue's
targets to stdout (scripts/results/contact_figures.md keeps the last one).

Usage: /usr/bin/python3 scripts/contact_figures.py [WORK_DIR]   (default out/contact_figures)
The avatar is precomputed into WORK_DIR/avatar.h5 unless it is there already.
"""
import os
import re
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SFLSH = os.path.join(ROOT, os.environ.get("SFLSH_BUILD_DIR", "build"), "sflsh")
G = 9.81


def run(args, cwd):
    t = time.time()
    p = subprocess.run(args, cwd=cwd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(args)} failed:\n{p.stdout}\n{p.stderr}")
    return p.stdout, time.time() - t


def contact_lines(log):
    """{(term, body): (max penetration mm, max force N, end force vector N)}"""
    out = {}
    for m in re.finditer(r"contact (\S+) on (\S+): max penetration ([\d.]+) mm, max force ([\d.]+) N, in contact "
                         r"(\d+) steps; at the end\s+(\S+)\s+(\S+)\s+(\S+) N", log):
        out[(m[1], m[2])] = (float(m[3]), float(m[4]), np.array([float(m[6]), float(m[7]), float(m[8])]))
    return out


def steps_line(log):
    m = re.search(r"steps: (\d+) accepted, (\d+) damped, (\d+) rejected; step time median ([\d.]+) ms", log)
    return int(m[1]), int(m[2]), int(m[3]), float(m[4])


def main():
    work = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "contact_figures"))
    os.makedirs(work, exist_ok=True)
    if not os.path.exists(os.path.join(work, "avatar.h5")):
        run([SFLSH, "precompute", "--out", "avatar.h5"], work)
    scenes = {}
    for folder in ("apps/scenes", "apps/scenes/figures"):
        for f in sorted(os.listdir(os.path.join(ROOT, folder))):
            if f.endswith(".csv"):
                shutil.copy(os.path.join(ROOT, folder, f), work)
        for f in sorted(os.listdir(os.path.join(ROOT, folder))):
            if f.endswith(".yaml"):
                shutil.copy(os.path.join(ROOT, folder, f), work)
                log, secs = run([SFLSH, "simulate", f], work)
                scenes[f[:-5]] = (log, secs)
                print(f"ran {f} in {secs:.1f} s", file=sys.stderr)

    rows = []

    def row(figure, target, value, ok, scene):
        rows.append(f"| {figure} | {target} | {value} | {'yes' if ok else '**no**'} | `{scene}` |")

    # Static equilibrium: contact force = weight.
    log = scenes["slab_on_belly"][0]
    f = contact_lines(log)[("contact:slab", "alice")][2]
    ratio = abs(f[2]) / (2.0 * G)
    row("slab (2 kg) resting on the belly: contact force / weight", "1 ± 0.02", f"{ratio:.4f}", abs(ratio - 1) <= 0.02,
        "figures/slab_on_belly.yaml")
    log = scenes["sphere_on_belly"][0]
    f = contact_lines(log)[("contact:ball", "alice")][2]
    with h5py.File(os.path.join(work, "sphere_on_belly.h5")) as h:
        p = h["/frames/object_poses"][:, 0, :3]
        t = h["/frames/time"][:]
    v = np.linalg.norm(p[-1] - p[-2]) / (t[-1] - t[-2])
    ratio = abs(f[2]) / (1.0 * G)
    row(f"sphere (1 kg) on the belly at t = {t[-1]:.1f} s (speed {v * 1e3:.0f} mm/s): force / weight", "1 ± 0.02",
        f"{ratio:.4f}", abs(ratio - 1) <= 0.02, "figures/sphere_on_belly.yaml")
    # Floor drop.
    log = scenes["fall_on_floor"][0]
    pen, _, fend = contact_lines(log)[("contact:floor", "alice")]
    acc, damped, rej, _ = steps_line(log)
    with h5py.File(os.path.join(work, "fall_on_floor.h5")) as h:
        finite = bool(np.isfinite(h["/frames/positions"][:]).all())
    row("avatar dropped 0.4 m on the floor: max penetration", "≤ 5 mm", f"{pen:.2f} mm", pen <= 5,
        "fall_on_floor.yaml")
    row("  … rejected steps, NaN", "0, none", f"{rej}, {'none' if finite else 'NaN'}", rej == 0 and finite,
        "fall_on_floor.yaml")
    row("  … floor force at rest (the body's weight)", "vertical", f"{fend[1]:.0f} N up, |horizontal| "
        f"{np.hypot(fend[0], fend[2]):.1f} N", fend[1] > 0, "fall_on_floor.yaml")
    # Two walkers.
    log = scenes["two_walkers"][0]
    ov = contact_lines(log)[("body_contact", "alice")][0]
    row("two avatars walking into each other: max capsule overlap", "≤ 5 mm", f"{ov:.2f} mm", ov <= 5,
        "two_walkers.yaml")
    # Momentum.
    log = scenes["momentum_bump"][0]
    m = re.search(r"linear momentum: start ([\d.]+) kg m/s, end ([\d.]+) kg m/s \(change (\S+)\)", log)
    rel = float(m[3]) / float(m[1])
    row("two-body collision, gravity off: |Δp| / |p|", "≤ 1e-6", f"{rel:.1e}", rel <= 1e-6, "figures/momentum_bump.yaml")
    # Pinch-and-lift from a recorded pose file (issue 11).
    log = scenes["pinch_from_file"][0]
    m = re.search(r"tools: peak force ([\d.]+) N, largest anchor stretch ([\d.]+) mm", log)
    grasps = len(re.findall(r": grasp (\d+) skin points", log))
    releases = len(re.findall(r": release (\d+) skin points", log))
    acc, damped, rej, _ = steps_line(log)
    with h5py.File(os.path.join(work, "pinch_from_file.h5")) as h:
        finite = bool(np.isfinite(h["/frames/positions"][:]).all())
        u = h["/frames/displacement"][:]
    stretch = float(m[2])
    row("pinch-and-lift 1.5 cm from a pose file: largest anchor stretch (slip)", "≤ 1 mm", f"{stretch:.2f} mm",
        stretch <= 1.0, "figures/pinch_from_file.yaml")
    row("  … grasp / release events, rejected steps, NaN", "1 / 1, 0, none",
        f"{grasps} / {releases}, {rej}, {'none' if finite else 'NaN'}", grasps == 1 and releases == 1 and rej == 0 and
        finite, "figures/pinch_from_file.yaml")
    row("  … peak force on the gripper; skin displacement at the end vs before the grasp", "(record)",
        f"{float(m[1]):.0f} N; {np.abs(u[-1]).max() * 1e3:.1f} mm vs {np.abs(u[int(0.2 * 30)]).max() * 1e3:.1f} mm",
        True, "figures/pinch_from_file.yaml")
    # The other examples, for the record.
    for name, term in (("ball_at_belly", "contact:ball"), ("box_press", "contact:press")):
        log = scenes[name][0]
        pen, fmax, _ = contact_lines(log)[(term, "alice")]
        acc, damped, rej, med = steps_line(log)
        rows.append(f"| {name}: max penetration, peak force, step median | (record) | {pen:.2f} mm, {fmax:.0f} N, "
                    f"{med:.2f} ms | | `{name}.yaml` |")

    print("# Contact and tool figures (issues 10 and 11)\n")
    print("Built-in avatar (`sflsh precompute --out avatar.h5`), default contact settings "
          "(stiffness 2e5 N/m per skin sample, 1e6 N/m per capsule pair, friction 0.5).")
    print("Reproduce: `/usr/bin/python3 scripts/contact_figures.py` (about two minutes after the build).\n")
    print("| figure | target | measured | met | scene |")
    print("|---|---|---|---|---|")
    print("\n".join(rows))
    print("\nPer-pair lines as `sflsh simulate` printed them:\n")
    for name, (log, secs) in scenes.items():
        print(f"- `{name}` ({secs:.1f} s wall):")
        for line in log.splitlines():
            if line.startswith(("contact ", "steps:", "linear momentum", "mean ms")):
                print(f"  - {line}")


if __name__ == "__main__":
    main()
