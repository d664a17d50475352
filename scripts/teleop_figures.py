#!/usr/bin/python3
"""Issue 11's teleoperation figures on the built-in avatar.

  * pinch-and-lift with a coupled gripper from a recorded pose file
    (apps/scenes/figures/pinch_coupled.yaml): slip, grasp/release, rejected
    steps, NaN, the skin's return to rest, the force per step (plot);
  * real time (apps/scenes/teleop_pinch.yaml, physics at 500 Hz): `sflsh run
    --realtime` pinned to one core while scripts/replay_pose_stream.py streams
    a pinch at 1 kHz from the other: RTF, frames behind, step time, feedback
    latency (pose sent -> force received, median and p99);
  * abuse, 10,000 steps each: the gripper yanked at 5 m/s while grasping
    (figures/yank_belly.yaml); anchors of hardness 1e5 N/m pinching 8 times;
    a live stream with 10 % dropped and 1 % malformed datagrams. Each: no NaN
    (sflsh stops with an error on a non-finite state), rejected steps, and the
    elastic energy bounded (its largest value per pinch cycle does not grow).

Writes a Markdown table to stdout (scripts/results/teleop.md keeps the last one).
Usage: /usr/bin/python3 scripts/teleop_figures.py [WORK_DIR]   (default out/teleop_figures)
"""
import csv
import json
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
REPLAY = os.path.join(ROOT, "scripts", "replay_pose_stream.py")
PORT = 7001


def run(args, cwd):
    t = time.time()
    p = subprocess.run(args, cwd=cwd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(args)} failed:\n{p.stdout}\n{p.stderr}")
    return p.stdout, time.time() - t


def tool_log(path):
    """Columns of a `sflsh run --tool-log` CSV as numpy arrays (outcome as strings)."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    out = {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k not in ("tool", "outcome")}
    out["outcome"] = [r["outcome"] for r in rows]
    return out


def summary(log):
    """RTF, frames behind, accepted/damped/rejected, step median/p99 from `sflsh run`'s summary."""
    m = re.search(r"RTF ([\d.]+)", log)
    b = re.search(r"(\d+) behind", log)
    s = re.search(r"steps: (\d+) accepted, (\d+) damped, (\d+) rejected; step time median ([\d.]+) ms, p99 ([\d.]+) ms",
                  log)
    return {"rtf": float(m[1]), "behind": int(b[1]) if b else 0, "accepted": int(s[1]), "damped": int(s[2]),
            "rejected": int(s[3]), "median_ms": float(s[4]), "p99_ms": float(s[5])}


def pinch_cycles(path, cycles, period=2.5, hardness_scene=False):
    """A pose file repeating pinch.csv's close / lift 1.5 cm / hold / open every `period` s."""
    with open(path, "w") as f:
        f.write("time,x,y,z,qw,qx,qy,qz,closure\n")
        for c in range(cycles):
            t0 = c * period
            for dt, z, cl in ((0.0, 0.118, 0.8), (0.3, 0.118, 0.0), (0.8, 0.133, 0.0), (1.4, 0.133, 0.0),
                              (1.5, 0.133, 0.8), (2.0, 0.118, 0.8)):
                f.write(f"{t0 + dt:.6f},0,1.05,{z},1,0,0,0,{cl}\n")


def per_cycle_max(t, v, period):
    cycles = int(np.floor(t[-1] / period + 1e-9))
    return [float(v[(t >= c * period) & (t < (c + 1) * period)].max()) for c in range(max(cycles, 1))]


def stream_run(work, scene, seconds, poses, extra=(), count=None):
    """`sflsh run --realtime` on core 0 and the replay client on core 1; returns (run log, replay JSON)."""
    cmd = ["taskset", "-c", "0", SFLSH, "run", scene, "--realtime", "--seconds", str(seconds), "--quiet-status",
           "--tool-log", scene.replace(".yaml", "_live.csv")]
    sim = subprocess.Popen(cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.5)  # the scene loads (avatar, grasp sensors) and opens its port
    n = count or int(seconds * 1000 - 2500)
    rep = subprocess.run(["taskset", "-c", "1", "/usr/bin/python3", REPLAY, poses, "--port", str(PORT), "--rate",
                          "1000", "--count", str(n), "--json", *extra], cwd=work, capture_output=True, text=True)
    out, err = sim.communicate()
    if sim.returncode != 0 or rep.returncode != 0:
        sys.exit(f"stream run failed:\n{out}\n{err}\n{rep.stdout}\n{rep.stderr}")
    return out, json.loads(rep.stdout)


def main():
    work = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "teleop_figures"))
    os.makedirs(work, exist_ok=True)
    if not os.path.exists(os.path.join(work, "avatar.h5")):
        run([SFLSH, "precompute", "--out", "avatar.h5"], work)
    for f in ("figures/pinch_coupled.yaml", "figures/yank_belly.yaml", "figures/yank.csv", "figures/pinch.csv",
              "teleop_pinch.yaml"):
        shutil.copy(os.path.join(ROOT, "apps/scenes", f), work)
    rows = []

    def row(figure, target, value, ok, scene):
        ok = None if ok is None else bool(ok)
        rows.append(f"| {figure} | {target} | {value} | {'yes' if ok is True else '**no**' if ok is False else ''} | "
                    f"`{scene}` |")

    # Pinch-and-lift from the recorded pose file.
    log, _ = run([SFLSH, "run", "pinch_coupled.yaml", "--tool-log", "pinch_coupled_tools.csv", "--out",
                  "pinch_coupled.h5", "--quiet-status"], work)
    s = summary(log)
    L = tool_log(os.path.join(work, "pinch_coupled_tools.csv"))
    grasped = L["anchors"] > 0
    stretch = 1e3 * L["max_stretch"][grasped].max()
    grasps, releases = len(re.findall(r": grasp \d+", log)), len(re.findall(r": release \d+", log))
    with h5py.File(os.path.join(work, "pinch_coupled.h5")) as h:
        finite = bool(np.isfinite(h["/frames/positions"][:]).all())
        u = h["/frames/displacement"][:]
        t = h["/frames/time"][:]
    # The same scene with jaws that never close (no grasp): where the skin would be without the pinch.
    with open(os.path.join(work, "pinch.csv")) as f:
        never = f.read().replace(",0.0\n", ",0.8\n")
    with open(os.path.join(work, "pinch_open.csv"), "w") as f:
        f.write(never)
    with open(os.path.join(work, "pinch_coupled.yaml")) as f:
        text = f.read().replace("pose_file: pinch.csv", "pose_file: pinch_open.csv")
    with open(os.path.join(work, "pinch_open.yaml"), "w") as f:
        f.write(text.replace("pinch_coupled.h5", "pinch_open.h5"))
    run([SFLSH, "run", "pinch_open.yaml", "--out", "pinch_open.h5", "--quiet-status"], work)
    with h5py.File(os.path.join(work, "pinch_open.h5")) as h:
        u_open = h["/frames/displacement"][:]
    lift = np.abs(u - u_open).max() * 1e3
    end = np.abs(u[-1] - u_open[-1]).max() * 1e3
    force = np.sqrt(L["force_x"] ** 2 + L["force_y"] ** 2 + L["force_z"] ** 2)
    row("pinch-and-lift (coupled gripper, pose file): largest anchor stretch while grasping", "≤ 1 mm",
        f"{stretch:.2f} mm", stretch <= 1.0, "figures/pinch_coupled.yaml")
    row("  … grasp / release, rejected steps, NaN", "1 / 1, 0, none",
        f"{grasps} / {releases}, {s['rejected']}, {'none' if finite else 'NaN'}",
        grasps == 1 and releases == 1 and s["rejected"] == 0 and finite, "figures/pinch_coupled.yaml")
    row("  … skin against the same run without a grasp: largest difference (the lift) / at the end (release "
        "returns to rest)", "end ≤ 0.5 mm", f"{lift:.1f} / {end:.2f} mm", end <= 0.5, "figures/pinch_coupled.yaml")
    row("  … peak force on the gripper (per step: `pinch_coupled_tools.csv`, plot `pinch_coupled_tools.svg`)",
        "(record)", f"{force.max():.1f} N", None, "figures/pinch_coupled.yaml")

    # Real time with a live device at 1 kHz.
    pinch_cycles(os.path.join(work, "pinch_cycles.csv"), 8)
    log, rep = stream_run(work, "teleop_pinch.yaml", 8, "pinch_cycles.csv")
    s = summary(log)
    row("real time: one avatar + one coupled gripper, physics 500 Hz, one core (taskset): RTF", "≥ 1",
        f"{s['rtf']:.3f} ({s['behind']} frames behind; step median {s['median_ms']:.2f} ms, p99 {s['p99_ms']:.2f} ms)",
        s["rtf"] >= 0.995 and s["behind"] == 0, "teleop_pinch.yaml")
    row("  … device stream at 1 kHz: samples sent / answered", "answered at the device rate",
        f"{rep.get('sent')} / {rep.get('answered')}", None, "teleop_pinch.yaml")
    row("  … latency pose sent → force received: median / p99", "(record)",
        f"{rep['latency_median_ms']:.3f} / {rep['latency_p99_ms']:.3f} ms (max {rep['latency_max_ms']:.1f} ms)", None, "teleop_pinch.yaml")

    # Abuse, 10,000 steps each.
    log, _ = run([SFLSH, "run", "yank_belly.yaml", "--tool-log", "yank_tools.csv", "--quiet-status"], work)
    s = summary(log)
    L = tool_log(os.path.join(work, "yank_tools.csv"))
    e = L["elastic_energy"]
    late = e[L["time"] > 10]
    row("abuse: gripper yanked 50 cm at 5 m/s while grasping, 10,000 steps: NaN, rejected, elastic energy max / "
        "last 10 s range", "no NaN, bounded", f"none, {s['rejected']}, {e.max():.1f} J / {late.min():.1f}–{late.max():.1f} J",
        s["rejected"] == 0 and np.isfinite(e).all() and late.max() <= e.max(), "figures/yank_belly.yaml")
    row("  … the skin held by the tool: stretch, force on the tool at the end", "(record)",
        f"{1e3 * L['max_stretch'][-1]:.1f} mm, {np.sqrt(L['force_x'][-1]**2 + L['force_y'][-1]**2 + L['force_z'][-1]**2):.0f} N",
        None, "figures/yank_belly.yaml")

    with open(os.path.join(work, "pinch_coupled.yaml")) as f:
        text = f.read()
    text = text.replace("hardness: 2.0e5", "hardness: 1.0e5").replace("pose_file: pinch.csv",
                                                                      "pose_file: pinch_cycles.csv")
    text = text.replace("seconds: 2.5", "seconds: 20").replace("pinch_coupled.h5", "hard_anchor.h5")
    with open(os.path.join(work, "hard_anchor.yaml"), "w") as f:
        f.write(text)
    log, _ = run([SFLSH, "run", "hard_anchor.yaml", "--tool-log", "hard_tools.csv", "--quiet-status"], work)
    s = summary(log)
    L = tool_log(os.path.join(work, "hard_tools.csv"))
    cyc = per_cycle_max(L["time"], L["elastic_energy"], 2.5)
    grasps = len(re.findall(r": grasp \d+", log))
    row("abuse: anchors of hardness 1e5 N/m, 8 pinch-lift-release cycles, 10,000 steps: NaN, rejected, grasps, "
        "elastic energy max per cycle", "no NaN, bounded",
        f"none, {s['rejected']}, {grasps}, {min(cyc):.2f}–{max(cyc):.2f} J",
        s["rejected"] == 0 and max(cyc) <= 1.05 * cyc[0] + 1e-9, "hard_anchor.yaml (made by this script)")

    log, rep = stream_run(work, "teleop_pinch.yaml", 20, "pinch_cycles.csv", ["--drop", "0.1", "--corrupt", "0.01"],
                          count=19000)
    s = summary(log)
    L = tool_log(os.path.join(work, "teleop_pinch_live.csv"))
    cyc = per_cycle_max(L["time"], L["elastic_energy"], 2.5)
    m = re.search(r"stream \(udp://127.0.0.1:\d+\): (.*)", log)
    row("abuse: live stream, 10 % dropped and 1 % malformed datagrams, 10,000 steps in real time: NaN, rejected, "
        "elastic energy max per cycle", "no NaN, bounded",
        f"none, {s['rejected']}, {min(cyc):.2f}–{max(cyc):.2f} J (RTF {s['rtf']:.3f})",
        s["rejected"] == 0 and L["time"][-1] >= 19.9, "teleop_pinch.yaml")
    row("  … what the stream saw", "bad datagrams rejected", m[1] if m else "?", None, "teleop_pinch.yaml")

    load = os.getloadavg()
    print("# Teleoperation figures (issue 11)\n")
    print("Built-in avatar (`sflsh precompute --out avatar.h5`), kinematic bones, coupled gripper (stiffness "
          "2e4 N/m, mass 0.1 kg, critical damping), anchors 2e5 N/m unless said.")
    print(f"Reproduce: `/usr/bin/python3 scripts/teleop_figures.py` (about two minutes after the build). "
          f"Load average at the end: {load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f} on {os.cpu_count()} cores.\n")
    print("| figure | target | measured | met | scene |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(r)


if __name__ == "__main__":
    main()
