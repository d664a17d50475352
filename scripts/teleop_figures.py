#!/usr/bin/python3
"""Teleoperation figures on the built-in avatar.

  * pinch-and-lift with a coupled gripper from a recorded pose file
    (apps/scenes/figures/pinch_coupled.yaml): slip, grasp/release, rejected
    steps, NaN, the skin's return to rest (against the same run without a
    grasp, 1 s and 2 s after the release: the soft tissue's damped
    oscillation decays over about half a second), the force per step (plot);
  * real time (apps/scenes/teleop_pinch.yaml, physics at 500 Hz): `sflsh run
    --realtime` pinned to one core while scripts/replay_pose_stream.py streams
    a pinch at 1 kHz from the other: frames behind (a frame whose substeps
    were clamped: the machine did not keep up; the RTF itself is ~1 by
    construction of the clock-paced loop), step time, feedback latency (pose
    sent -> force received, median and p99); the same for a coupled 1 cm
    probe pressing 10 mm into the belly through its patch
    (apps/scenes/teleop_probe.yaml), with its largest force on the device;
  * abuse, 10,000 steps each: the gripper yanked at 5 m/s while grasping
    (figures/yank_belly.yaml); anchors of hardness 1e5 N/m pinching 8 times;
    a live stream with 10 % dropped and 1 % malformed datagrams. Each: no
    non-finite value in the per-step tool log, rejected steps, and the
    elastic energy bounded (yank: the largest value over the last 10 s at
    most 1.05x the largest over the first 10 s; pinch cycles: the largest
    value of every cycle at most 1.05x the first cycle's).

Every run's log and result files stay in WORK_DIR; the verdicts are computed
from those files alone (judge()), so `--check WORK_DIR` re-judges a finished
run without simulating. Writes a Markdown table to stdout
(scripts/results/teleop.md keeps the last one). Exit status: 0 when every
stated target is met, 1 when one is missed (named on stderr), 2 when a
result file is missing or malformed (one line naming the file and the
column, dataset or log line).

Usage: /usr/bin/python3 scripts/teleop_figures.py [WORK_DIR]   (default out/teleop_figures)
       /usr/bin/python3 scripts/teleop_figures.py --check WORK_DIR
"""
import json
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from figure_check import (BadResults, FigureTable, h5_dataset, read_csv_columns, read_text,  # noqa: E402
                          run_judged, search)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SFLSH = os.path.join(ROOT, os.environ.get("SFLSH_BUILD_DIR", "build"), "sflsh")
REPLAY = os.path.join(ROOT, "scripts", "replay_pose_stream.py")
PORT = 7001
SCRIPT = "teleop_figures"
PERIOD = 2.5          # s, one pinch-lift-release cycle of pinch_cycles()
CYCLES = 8            # cycles in the 20 s runs
ENERGY_GROWTH = 1.05  # a later window's elastic energy max may be at most this times the first's
TOOL_COLUMNS = ["time", "force_x", "force_y", "force_z", "anchors", "max_stretch", "elastic_energy"]


def run(args, cwd, log):
    """Runs sflsh in `cwd`; its stdout is kept in cwd/`log` (what judge() reads)."""
    p = subprocess.run(args, cwd=cwd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(args)} failed:\n{p.stdout}\n{p.stderr}")
    with open(os.path.join(cwd, log), "w") as f:
        f.write(p.stdout)


def pinch_cycles(path, cycles, period=PERIOD):
    """A pose file repeating pinch.csv's close / lift 1.5 cm / hold / open every `period` s."""
    with open(path, "w") as f:
        f.write("time,x,y,z,qw,qx,qy,qz,closure\n")
        for c in range(cycles):
            t0 = c * period
            for dt, z, cl in ((0.0, 0.118, 0.8), (0.3, 0.118, 0.0), (0.8, 0.133, 0.0), (1.4, 0.133, 0.0),
                              (1.5, 0.133, 0.8), (2.0, 0.118, 0.8)):
                f.write(f"{t0 + dt:.6f},0,1.05,{z},1,0,0,0,{cl}\n")


def probe_cycles(path, cycles, period=PERIOD):
    """A pose file pressing the 1 cm probe of teleop_probe.yaml from 5 mm in front of the belly's skin
    (z = 0.107 m) to 10 mm into it over 1 s, holding 0.5 s and withdrawing over 1 s, every `period` s."""
    with open(path, "w") as f:
        f.write("time,x,y,z,qw,qx,qy,qz,closure\n")
        for c in range(cycles):
            for dt, z in ((0.0, 0.117), (1.0, 0.102), (1.5, 0.102)):
                f.write(f"{c * period + dt:.6f},0,1.05,{z},1,0,0,0,0\n")
        f.write(f"{cycles * period:.6f},0,1.05,0.117,1,0,0,0,0\n")


def stream_run(work, scene, seconds, poses, name, extra=(), count=None):
    """`sflsh run --realtime` on core 0 and the replay client on core 1; keeps NAME.log (the run's stdout),
    NAME_live.csv (its tool log) and NAME_replay.json (the client's summary) in `work`."""
    cmd = ["taskset", "-c", "0", SFLSH, "run", scene, "--realtime", "--seconds", str(seconds), "--quiet-status",
           "--tool-log", f"{name}_live.csv"]
    sim = subprocess.Popen(cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.5)  # the scene loads (avatar, grasp sensors) and opens its port
    n = count or int(seconds * 1000 - 2500)
    rep = subprocess.run(["taskset", "-c", "1", "/usr/bin/python3", REPLAY, poses, "--port", str(PORT), "--rate",
                          "1000", "--count", str(n), "--json", *extra], cwd=work, capture_output=True, text=True)
    out, err = sim.communicate()
    if sim.returncode != 0 or rep.returncode != 0:
        sys.exit(f"stream run failed:\n{out}\n{err}\n{rep.stdout}\n{rep.stderr}")
    with open(os.path.join(work, f"{name}.log"), "w") as f:
        f.write(out)
    with open(os.path.join(work, f"{name}_replay.json"), "w") as f:
        f.write(rep.stdout)


def measure(work):
    """Runs every scene of the figures; leaves the files judge() reads in `work`."""
    if not os.path.exists(os.path.join(work, "avatar.h5")):
        run([SFLSH, "precompute", "--out", "avatar.h5"], work, "precompute.log")
    for f in ("figures/pinch_coupled.yaml", "figures/yank_belly.yaml", "figures/yank.csv", "figures/pinch.csv",
              "teleop_pinch.yaml", "teleop_probe.yaml"):
        shutil.copy(os.path.join(ROOT, "apps/scenes", f), work)
    run([SFLSH, "run", "pinch_coupled.yaml", "--tool-log", "pinch_coupled_tools.csv", "--out", "pinch_coupled.h5",
         "--quiet-status"], work, "pinch_coupled.log")
    # The same scene with jaws that never close (no grasp): where the skin would be without the pinch.
    with open(os.path.join(work, "pinch.csv")) as f:
        never = f.read().replace(",0.0\n", ",0.8\n")
    with open(os.path.join(work, "pinch_open.csv"), "w") as f:
        f.write(never)
    with open(os.path.join(work, "pinch_coupled.yaml")) as f:
        text = f.read().replace("pose_file: pinch.csv", "pose_file: pinch_open.csv")
    with open(os.path.join(work, "pinch_open.yaml"), "w") as f:
        f.write(text.replace("pinch_coupled.h5", "pinch_open.h5"))
    run([SFLSH, "run", "pinch_open.yaml", "--out", "pinch_open.h5", "--quiet-status"], work, "pinch_open.log")

    pinch_cycles(os.path.join(work, "pinch_cycles.csv"), CYCLES)
    stream_run(work, "teleop_pinch.yaml", 8, "pinch_cycles.csv", "realtime")
    probe_cycles(os.path.join(work, "probe_cycles.csv"), 3)
    stream_run(work, "teleop_probe.yaml", 8, "probe_cycles.csv", "probe_realtime")

    run([SFLSH, "run", "yank_belly.yaml", "--tool-log", "yank_tools.csv", "--quiet-status"], work, "yank_belly.log")

    with open(os.path.join(work, "pinch_coupled.yaml")) as f:
        text = f.read()
    text = text.replace("hardness: 2.0e5", "hardness: 1.0e5").replace("pose_file: pinch.csv",
                                                                      "pose_file: pinch_cycles.csv")
    text = text.replace("seconds: 3.5", "seconds: 20").replace("pinch_coupled.h5", "hard_anchor.h5")
    with open(os.path.join(work, "hard_anchor.yaml"), "w") as f:
        f.write(text)
    run([SFLSH, "run", "hard_anchor.yaml", "--tool-log", "hard_tools.csv", "--quiet-status"], work, "hard_anchor.log")

    stream_run(work, "teleop_pinch.yaml", 20, "pinch_cycles.csv", "stream_abuse", ["--drop", "0.1", "--corrupt", "0.01"],
               count=19000)


# --- judging the files in WORK_DIR -----------------------------------------------------------

def tool_log(path):
    """Columns of a `sflsh run --tool-log` CSV as numpy arrays."""
    return {k: np.array(v) for k, v in read_csv_columns(path, TOOL_COLUMNS).items()}


def tool_log_finite(L):
    """No non-finite value in any numeric column (sflsh also stops on a non-finite state)."""
    return all(bool(np.isfinite(v).all()) for v in L.values())


def summary(path):
    """RTF, frames behind, accepted/damped/rejected, step median/p99 from `sflsh run`'s summary in `path`."""
    log = read_text(path)
    m = search(r"RTF ([\d.]+|nan|inf)", log, path, "'RTF'")
    s = search(r"steps: (\d+) accepted, (\d+) damped, (\d+) rejected; step time median ([\d.]+) ms, p99 ([\d.]+) ms",
               log, path, "'steps: N accepted, N damped, N rejected; step time median ... p99 ...'")
    b = re.search(r"(\d+) behind", log)
    return {"log": log, "rtf": float(m[1]), "behind": int(b[1]) if b else None, "accepted": int(s[1]),
            "damped": int(s[2]), "rejected": int(s[3]), "steps": int(s[1]) + int(s[2]) + int(s[3]),
            "median_ms": float(s[4]), "p99_ms": float(s[5])}


def replay_summary(path):
    text = read_text(path)
    try:
        rep = json.loads(text)
    except json.JSONDecodeError as e:
        raise BadResults(f"{path}: not JSON ({e.msg} at line {e.lineno})") from None
    for k in ("sent", "valid", "corrupted", "answered", "latency_median_ms", "latency_p99_ms", "latency_max_ms"):
        if not isinstance(rep.get(k), (int, float)):
            raise BadResults(f"{path}: field '{k}' missing or not a number")
    return rep


def per_cycle_max(t, v, period=PERIOD):
    cycles = max(int(np.floor(t[-1] / period + 1e-9)), 1)
    out = []
    for c in range(cycles):
        sel = v[(t >= c * period) & (t < (c + 1) * period)]
        out.append(float(sel.max()) if sel.size else float("nan"))
    return out


def cycles_bounded(cyc):
    """Every cycle's largest elastic energy at most ENERGY_GROWTH times the first cycle's (NaN fails)."""
    return all(np.isfinite(cyc)) and max(cyc) <= ENERGY_GROWTH * cyc[0] + 1e-9


def nan_word(finite):
    return "none" if finite else "NaN"


def judge(work):
    """The figures and verdicts from the files in `work` -> (Markdown text, FigureTable)."""
    w = lambda name: os.path.join(work, name)  # noqa: E731
    table = FigureTable()
    row = table.row

    # Pinch-and-lift from the recorded pose file.
    s = summary(w("pinch_coupled.log"))
    L = tool_log(w("pinch_coupled_tools.csv"))
    grasped = L["anchors"] > 0
    stretch = 1e3 * L["max_stretch"][grasped].max() if grasped.any() else float("nan")
    grasps, releases = len(re.findall(r": grasp \d+", s["log"])), len(re.findall(r": release \d+", s["log"]))
    positions = h5_dataset(w("pinch_coupled.h5"), "/frames/positions")
    u = h5_dataset(w("pinch_coupled.h5"), "/frames/displacement")
    u_open = h5_dataset(w("pinch_open.h5"), "/frames/displacement")
    if u.shape != u_open.shape or u.ndim != 3 or u.shape[0] == 0:
        raise BadResults(f"{w('pinch_open.h5')}: dataset '/frames/displacement' has shape {u_open.shape}, "
                         f"expected that of pinch_coupled.h5's {u.shape} (frames, vertices, 3)")
    finite = bool(np.isfinite(positions).all() and np.isfinite(u).all()) and tool_log_finite(L)
    lift = np.abs(u - u_open).max() * 1e3
    # The skin 1 s after the release (record) and 2 s after (the run's end: the target).
    t = h5_dataset(w("pinch_coupled.h5"), "/frames/time")
    if t.shape != (u.shape[0],):
        raise BadResults(f"{w('pinch_coupled.h5')}: dataset '/frames/time' has shape {t.shape}, expected "
                         f"({u.shape[0]},), one per frame of '/frames/displacement'")
    m = search(r"t = ([\d.]+) s: release", s["log"], w("pinch_coupled.log"), "'t = ... s: release'")
    released = float(m[1])
    if t[-1] < released + 2.0 - 0.05:
        raise BadResults(f"{w('pinch_coupled.h5')}: the run ends {t[-1] - released:.2f} s after the release at "
                         f"{released:.3f} s, expected 2 s")
    after = lambda dt: np.abs(u - u_open)[int(np.argmin(np.abs(t - released - dt)))].max() * 1e3  # noqa: E731
    after_1s, end = after(1.0), np.abs(u[-1] - u_open[-1]).max() * 1e3
    force = np.sqrt(L["force_x"] ** 2 + L["force_y"] ** 2 + L["force_z"] ** 2)
    row("pinch-and-lift (coupled gripper, pose file): largest anchor stretch while grasping", "≤ 1 mm",
        f"{stretch:.2f} mm", stretch <= 1.0, "figures/pinch_coupled.yaml")
    row("  … grasp / release, rejected steps, NaN", "1 / 1, 0, none",
        f"{grasps} / {releases}, {s['rejected']}, {nan_word(finite)}",
        grasps == 1 and releases == 1 and s["rejected"] == 0 and finite, "figures/pinch_coupled.yaml")
    row("  … skin against the same run without a grasp: largest difference (the lift) / 1 s after the release / "
        "2 s after (release returns to rest)", "2 s after ≤ 0.5 mm", f"{lift:.1f} / {after_1s:.2f} / {end:.2f} mm",
        end <= 0.5, "figures/pinch_coupled.yaml")
    row("  … peak force on the gripper (per step: `pinch_coupled_tools.csv`, plot `pinch_coupled_tools.svg`)",
        "(record)", f"{force.max():.1f} N", None, "figures/pinch_coupled.yaml")

    # Real time with a live device at 1 kHz: the loop paces itself by the wall clock, so its RTF is ~1 by
    # construction; a frame behind (substeps clamped, lag dropped) is what shows the machine not keeping up.
    s = summary(w("realtime.log"))
    rep = replay_summary(w("realtime_replay.json"))
    if s["behind"] is None:
        raise BadResults(f"{w('realtime.log')}: no 'N behind' (a --realtime run's summary)")
    row("real time: one avatar + one coupled gripper, physics 500 Hz, one core (taskset): frames behind",
        "0 (RTF 1)", f"{s['behind']} (RTF {s['rtf']:.3f}; step median {s['median_ms']:.2f} ms, "
        f"p99 {s['p99_ms']:.2f} ms)", s["behind"] == 0, "teleop_pinch.yaml")
    answered = rep["answered"] / rep["valid"] if rep["valid"] > 0 else float("nan")
    row("  … device stream at 1 kHz: valid samples sent / answered", "≥ 99 % answered",
        f"{rep['valid']} / {rep['answered']}", answered >= 0.99, "teleop_pinch.yaml")
    row("  … latency pose sent → force received: median / p99", "(record)",
        f"{rep['latency_median_ms']:.3f} / {rep['latency_p99_ms']:.3f} ms (max {rep['latency_max_ms']:.1f} ms)", None,
        "teleop_pinch.yaml")
    s = summary(w("probe_realtime.log"))
    if s["behind"] is None:
        raise BadResults(f"{w('probe_realtime.log')}: no 'N behind' (a --realtime run's summary)")
    L = tool_log(w("probe_realtime_live.csv"))
    force = np.sqrt(L["force_x"] ** 2 + L["force_y"] ** 2 + L["force_z"] ** 2)
    row("real time: one avatar + a coupled 1 cm probe pressing 10 mm into the belly through its patch, 500 Hz, one "
        "core: frames behind", "0 (RTF 1)", f"{s['behind']} (RTF {s['rtf']:.3f}; step median {s['median_ms']:.2f} ms, "
        f"p99 {s['p99_ms']:.2f} ms)", s["behind"] == 0 and tool_log_finite(L), "teleop_probe.yaml")
    row("  … largest force on the probe (`probe_realtime_live.csv`)", "(record)", f"{force.max():.2f} N", None,
        "teleop_probe.yaml")

    # Abuse, 10,000 steps each.
    s = summary(w("yank_belly.log"))
    L = tool_log(w("yank_tools.csv"))
    e = L["elastic_energy"]
    early, late = e[L["time"] <= 10], e[L["time"] > 10]
    if early.size == 0 or late.size == 0:
        raise BadResults(f"{w('yank_tools.csv')}: column 'time' does not cover both 0-10 s and 10-20 s "
                         f"(ends at {L['time'][-1]:g} s)")
    finite = tool_log_finite(L)
    bounded = bool(np.isfinite(e).all()) and late.max() <= ENERGY_GROWTH * early.max()
    row("abuse: gripper yanked 50 cm at 5 m/s while grasping, 10,000 steps: steps, NaN, rejected, elastic energy "
        "max over the first 10 s / the last 10 s", f"10000, no NaN, 0, last ≤ {ENERGY_GROWTH} × first",
        f"{s['steps']}, {nan_word(finite)}, {s['rejected']}, {early.max():.1f} J / {late.max():.1f} J "
        f"(last 10 s {late.min():.1f}–{late.max():.1f} J)",
        s["steps"] == 10000 and finite and s["rejected"] == 0 and bounded, "figures/yank_belly.yaml")
    row("  … the skin held by the tool: stretch, force on the tool at the end", "(record)",
        f"{1e3 * L['max_stretch'][-1]:.1f} mm, {np.sqrt(L['force_x'][-1]**2 + L['force_y'][-1]**2 + L['force_z'][-1]**2):.0f} N",
        None, "figures/yank_belly.yaml")

    s = summary(w("hard_anchor.log"))
    L = tool_log(w("hard_tools.csv"))
    cyc = per_cycle_max(L["time"], L["elastic_energy"])
    grasps = len(re.findall(r": grasp \d+", s["log"]))
    finite = tool_log_finite(L)
    row(f"abuse: anchors of hardness 1e5 N/m, {CYCLES} pinch-lift-release cycles, 10,000 steps: steps, NaN, "
        "rejected, grasps, elastic energy max per cycle (first / largest)",
        f"10000, no NaN, 0, {CYCLES}, every cycle ≤ {ENERGY_GROWTH} × the first",
        f"{s['steps']}, {nan_word(finite)}, {s['rejected']}, {grasps}, {cyc[0]:.2f} / {max(cyc):.2f} J "
        f"({len(cyc)} cycles)",
        s["steps"] == 10000 and finite and s["rejected"] == 0 and grasps == CYCLES and
        cycles_bounded(cyc), "hard_anchor.yaml (made by this script)")

    s = summary(w("stream_abuse.log"))
    rep = replay_summary(w("stream_abuse_replay.json"))
    L = tool_log(w("stream_abuse_live.csv"))
    cyc = per_cycle_max(L["time"], L["elastic_energy"])
    finite = tool_log_finite(L)
    row("abuse: live stream, 10 % dropped and 1 % malformed datagrams, 20 s (10,000 steps) in real time: simulated "
        "time, NaN, rejected, elastic energy max per cycle (first / largest)",
        f"≥ 19.9 s, no NaN, 0, every cycle ≤ {ENERGY_GROWTH} × the first",
        f"{L['time'][-1]:.2f} s, {nan_word(finite)}, {s['rejected']}, {cyc[0]:.2f} / {max(cyc):.2f} J "
        f"(RTF {s['rtf']:.3f})",
        L["time"][-1] >= 19.9 and finite and s["rejected"] == 0 and cycles_bounded(cyc), "teleop_pinch.yaml")
    m = search(r"stream \(udp://127.0.0.1:\d+\): received (\d+), accepted (\d+), rejected (\d+)(.*)", s["log"],
               w("stream_abuse.log"), "'stream (udp://...): received N, accepted N, rejected N'")
    received, accepted, rejected = int(m[1]), int(m[2]), int(m[3])
    # Every bad datagram rejected and no good one: rejected ≤ corrupted sent (the run may end before the last
    # ones arrive), at least one, and the counts add up.
    row("  … what the stream saw (the client sent " f"{rep['corrupted']:.0f} malformed)",
        "bad datagrams rejected, good ones accepted",
        f"received {received}, accepted {accepted}, rejected {rejected}{m[4]}",
        0 < rejected <= rep["corrupted"] and accepted + rejected == received, "teleop_pinch.yaml")

    load = os.getloadavg()
    text = ["# Teleoperation figures\n",
            "Built-in avatar (`sflsh precompute --out avatar.h5`), kinematic bones, coupled gripper (stiffness "
            "2e4 N/m, mass 0.1 kg, critical damping), anchors 2e5 N/m unless said.",
            f"Reproduce: `/usr/bin/python3 scripts/teleop_figures.py` (about two minutes after the build; "
            f"`--check WORK_DIR` re-judges its files). Load average when judged: {load[0]:.1f}, {load[1]:.1f}, "
            f"{load[2]:.1f} on {os.cpu_count()} cores.\n",
            table.markdown()]
    return "\n".join(text), table


def main():
    args = sys.argv[1:]
    if args[:1] == ["--check"]:
        if len(args) != 2:
            sys.exit("usage: teleop_figures.py --check WORK_DIR")
        work = os.path.abspath(args[1])
    else:
        work = os.path.abspath(args[0] if args else os.path.join(ROOT, "out", "teleop_figures"))
        os.makedirs(work, exist_ok=True)
        measure(work)
    run_judged(SCRIPT, lambda: judge(work))


if __name__ == "__main__":
    main()
