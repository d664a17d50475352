#!/usr/bin/env python3
"""Figures of `sflsh fit` (issue 12) -> scripts/results/fit.md (+ fit_*.svg).

Synthetic observations: the default avatar (K = 64) simulated with known
per-region materials (Young's factors and Fung c factors between x0.3 and x3
of the defaults), bones kinematic, 2 s of motion, skin with 1 mm Gaussian
noise per coordinate (--noise 0.001). Fits start from the defaults.
Cases: builtin jump; CMU 16_46 (BVH); the jump with numeric Jacobians (one
iteration, for its cost); the jump observed with the full-FEM reference (no
noise; the model is not the truth).

Usage: scripts/fit_benchmark.py [--work /tmp/fit] [--skip-fem]
(build/sflsh must exist; the avatar is precomputed into --work if missing).
"""
import argparse
import math
import os
import re
import resource
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SFLSH = os.path.join(ROOT, "build", "sflsh")
REGIONS = ["torso", "belly", "chest", "buttocks", "thigh", "calf", "upper_arm", "forearm", "neck", "head", "hand", "foot"]
E = [3e4, 8e3, 1.5e4, 1.2e4, 2e4, 3e4, 2e4, 3e4, 3e4, 1e5, 1e5, 1e5]  # volume/body_regions.cpp defaults
YOUNG = [0.3, 2.5, 1.6, 0.5, 3.0, 0.7, 1.8, 0.4, 2.0, 1.0, 1.0, 1.0]  # truth / default
FUNG = [2.0, 0.4, 0.6, 2.8, 0.35, 1.5, 0.8, 2.2, 0.5, 1.0, 1.0, 1.0]
# The shared data folder next to the repository (../shared from the main checkout, ../../shared from a worktree).
CMU = next((p for p in (os.path.join(ROOT, "..", "shared", "data", "mocap", "cmu", "16_46.bvh"),
                        os.path.join(ROOT, "..", "..", "shared", "data", "mocap", "cmu", "16_46.bvh")) if os.path.exists(p)),
           "16_46.bvh")


def run(args, log, reuse=False):
    """Runs sflsh, returns (stdout, wall s, child CPU s); with `reuse`, a log of an earlier successful run stands."""
    if reuse and os.path.exists(log):
        with open(log) as f:
            text = f.read()
        if "\nwrote " in text:
            return text, 0.0, 0.0
    t0 = time.time()
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run([SFLSH, "-q"] + args, capture_output=True, text=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall = time.time() - t0
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    with open(log, "w") as f:
        f.write(p.stdout + p.stderr)
    if p.returncode != 0:
        sys.exit(f"sflsh {' '.join(args)} failed:\n{p.stdout}{p.stderr}")
    return p.stdout, wall, cpu


def parse_fit(out):
    fit = {}
    for m in re.finditer(r"^  (young|fung_c|poisson):(\w+)\s+x([\d.]+)\s+\(start x[\d.]+\)\s+±([\d.einf]+)%", out, re.M):
        fit[(m.group(1), m.group(2))] = (float(m.group(3)), float(m.group(4)))
    d = {"fit": fit}
    d["iters"] = int(re.search(r"Iterations: (\d+)", out).group(1))
    m = re.search(r"surface error RMS per coordinate: ([\d.]+) mm before, ([\d.]+) mm after", out)
    d["rms_before"], d["rms_after"] = float(m.group(1)), float(m.group(2))
    m = re.search(r"time: ([\d.]+) s wall, ([\d.]+) s CPU; (\d+) iterations", out)
    d["wall"], d["cpu"] = float(m.group(1)), float(m.group(2))
    m = re.search(r"([\d.]+) ms per run without, ([\d.]+) ms per Jacobian evaluation; Ceres: (.*)$", out, re.M)
    d["ms_run"], d["ms_jac"], d["ceres_times"] = float(m.group(1)), float(m.group(2)), m.group(3)
    d["stopped"] = re.search(r"^Ceres stopped: (.*)$", out, re.M).group(1)
    d["warnings"] = re.findall(r"^warning: (.*)$", out, re.M)
    d["svals"] = re.search(r"^singular values of J: (.*)$", out, re.M).group(1)
    return d


def table(d, truth=True):
    rows = ["| region | Young truth | fitted | error | ±1σ | Fung c truth | fitted | error | ±1σ |",
            "|---|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(REGIONS):
        if ("young", r) not in d["fit"]:
            continue
        y, ys = d["fit"][("young", r)]
        c, cs = d["fit"][("fung_c", r)]
        if truth:
            ey, ec = 100 * (y / YOUNG[i] - 1), 100 * (c / FUNG[i] - 1)
            rows.append(f"| {r} | x{YOUNG[i]} | x{y:.4f} | {ey:+.1f}% {'ok' if abs(ey) <= 5 else 'MISSED'} | {ys:.2g}% "
                        f"| x{FUNG[i]} | x{c:.4f} | {ec:+.1f}% {'ok' if abs(ec) <= 10 else 'MISSED'} | {cs:.3g}% |")
        else:
            ey, ec = 100 * (y / YOUNG[i] - 1), 100 * (c / FUNG[i] - 1)
            rows.append(f"| {r} | x{YOUNG[i]} | x{y:.4f} | {ey:+.1f}% | {ys:.2g}% | x{FUNG[i]} | x{c:.4f} | {ec:+.1f}% | {cs:.3g}% |")
    return "\n".join(rows)


def summary(d):
    return (f"- Ceres: {d['iters']} iterations; stopped: {d['stopped']}\n"
            f"- surface error RMS per coordinate: {d['rms_before']:.3f} mm at the defaults -> {d['rms_after']:.3f} mm fitted\n"
            f"- time: {d['wall']:.1f} s wall, {d['cpu']:.1f} s CPU (process), {d['cpu'] / max(d['iters'], 1):.2f} s CPU per "
            f"iteration; one run {d['ms_run']:.0f} ms, one Jacobian evaluation {d['ms_jac']:.0f} ms wall; {d['ceres_times']}\n"
            f"- singular values of J: {d['svals']}\n"
            + "".join(f"- warning: {w}\n" for w in d["warnings"]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--work", default="/tmp/fit")
    ap.add_argument("--skip-fem", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    w = lambda name: os.path.join(a.work, name)
    res = os.path.join(ROOT, "scripts", "results")
    load0 = os.getloadavg()
    if not os.path.exists(w("avatar.h5")):
        run(["precompute", "--out", w("avatar.h5")], w("precompute.log"))
    with open(w("truth.yaml"), "w") as f:
        f.write("regions:\n")
        for r, e, y, c in zip(REGIONS, E, YOUNG, FUNG):
            f.write(f"  {r}: {{young_along: {1.5 * e * y}, young_through: {0.5 * e * y}, young_around: {e * y}, "
                    f"fung_c: {0.1 * e * c}}}\n")
    cases = {}
    for name, motion in [("jump", "builtin:jump"), ("cmu", CMU)]:
        run(["simulate", "--avatar", w("avatar.h5"), "--motion", motion, "--seconds", "2", "--bones", "kinematic",
             "--material", w("truth.yaml"), "--out", w(f"obs_{name}.h5")], w(f"simulate_{name}.log"), reuse=True)
        out, wall, cpu = run(["fit", "--avatar", w("avatar.h5"), "--observed", w(f"obs_{name}.h5"), "--noise", "0.001",
                              "--params", "young,fung_c", "--out", w(f"fitted_{name}.yaml"),
                              "--plot", os.path.join(res, f"fit_{name}.svg")], w(f"fit_{name}.log"), reuse=True)
        cases[name] = parse_fit(out)
    out, _, _ = run(["fit", "--avatar", w("avatar.h5"), "--observed", w("obs_jump.h5"), "--noise", "0.001", "--numeric",
                     "--max-iterations", "1", "--out", w("fitted_numeric.yaml"), "--plot", w("numeric.svg")],
                    w("fit_numeric.log"))
    numeric = parse_fit(out)
    if not a.skip_fem:
        if not os.path.exists(w("obs_fem.h5")):
            run(["fit", "--avatar", w("avatar.h5"), "--material", w("truth.yaml"), "--motion", "builtin:jump",
                 "--seconds", "2", "--write-reference", w("obs_fem.h5")], w("reference.log"))
        out, _, _ = run(["fit", "--avatar", w("avatar.h5"), "--observed", w("obs_fem.h5"), "--start-at-rest",
                         "--params", "young,fung_c", "--out", w("fitted_fem.yaml"),
                         "--plot", os.path.join(res, "fit_fem.svg")], w("fit_fem.log"))
        cases["fem"] = parse_fit(out)
    load1 = os.getloadavg()

    md = ["# `sflsh fit` figures (issue 12)", "",
          "Generated by `scripts/fit_benchmark.py` (logs in " + a.work + "). Default avatar (`sflsh precompute`, "
          "K = 64), bones kinematic, h = 1/60 s, 2 s of motion, observations at 30 frames/s on all 9322 skin "
          "vertices with 1 mm Gaussian noise per coordinate; truth = per-region factors below on the default "
          "materials; parameters = per region log Young's factor and log Fung c (24); fits start from the defaults.",
          f"Machine: 2 cores shared with other agents; load average {load0[0]:.1f} at the start, {load1[0]:.1f} at "
          "the end, so wall times are inflated: CPU times are the fair figure (one thread).", ""]
    titles = {"jump": "builtin jump", "cmu": "CMU 16_46 (BVH)"}
    for name in ["jump", "cmu"]:
        d = cases[name]
        md += [f"## {titles[name]}", "", summary(d), table(d), "", f"![per-frame error](fit_{name}.svg)", ""]
    md += ["## Numeric Jacobians (--numeric, one iteration)", "",
           f"- one Jacobian by central differences of whole runs (2 x 24 runs): {numeric['ms_jac']:.0f} ms wall vs "
           f"{cases['jump']['ms_jac']:.0f} ms for the analytic sensitivities (one run {numeric['ms_run']:.0f} ms)", ""]
    if "fem" in cases:
        d = cases["fem"]
        md += ["## Observations from the full-FEM reference (model is not the truth; no noise)", "",
               summary(d), "Deviation of the fitted factors from the factors the reference ran with:", "",
               table(d, truth=False), "", "![per-frame error](fit_fem.svg)", ""]
    with open(os.path.join(res, "fit.md"), "w") as f:
        f.write("\n".join(md))
    print("wrote", os.path.join(res, "fit.md"))


if __name__ == "__main__":
    main()
