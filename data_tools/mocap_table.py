#!/usr/bin/python3
"""Table and plot of `sflsh simulate` result files (scripts/mocap_check.sh).

Reads result HDF5 files (dataset names: include/sflsh/scene/simulation_run.hpp)
and writes one CSV row per file:

  file, frames, seconds, steps, accepted, damped, rejected, median_step_ms,
  pelvis_mean_mm, pelvis_max_mm, max_soft_displacement_mm, any_nan, status

  file          motion file name (/meta/motion, without folders)
  frames        output frames in the result (/frames/time)
  seconds       simulated time (last /steps/time)
  steps ...     time steps and their outcomes (/steps/outcome: 0 accepted, 1 damped, 2 rejected)
  median_step_ms  median of /steps/ms
  pelvis_*_mm   |/frames/joints[:, 0] - /frames/target_pelvis| over the output frames (mm)
  max_soft_displacement_mm  max over frames and skin vertices of |/frames/displacement|
  any_nan       1 if any frame or step dataset holds a non-finite value
  status        ok, or why the file fails the check (run failed, nan, pelvis max > limit,
                no target pelvis)

and a plot of the pelvis error over time per file: PNG with matplotlib when it
is installed, else an SVG written directly. Exit status 1 when a file fails
the check (or a --failed run is given), 0 otherwise.

  /usr/bin/python3 data_tools/mocap_table.py --csv out/mocap/mocap_check.csv \\
      --plot out/mocap/pelvis_error --max-pelvis-mm 20 out/mocap/*.h5
"""
import argparse
import csv
import math
import os
import sys

import h5py
import numpy as np

COLUMNS = ["file", "frames", "seconds", "steps", "accepted", "damped", "rejected", "median_step_ms",
           "pelvis_mean_mm", "pelvis_max_mm", "max_soft_displacement_mm", "any_nan", "status"]


def read_string(ds):
    v = ds[()]
    if isinstance(v, bytes):
        return v.decode("utf-8")
    if isinstance(v, np.ndarray):
        v = v.reshape(-1)[0]
        return v.decode("utf-8") if isinstance(v, bytes) else str(v)
    return str(v)


def summarize(path, max_pelvis_mm):
    """Row (dict) and pelvis error curve (time s, error mm) of one result file."""
    with h5py.File(path, "r") as f:
        for name in ("/meta/motion", "/frames/time", "/frames/joints", "/frames/displacement", "/steps/outcome",
                     "/steps/ms", "/steps/time"):
            if name not in f:
                raise SystemExit(f"{path}: not an sflsh result file (dataset {name} is missing)")
        motion = read_string(f["/meta/motion"])
        time = np.asarray(f["/frames/time"][()], dtype=float).reshape(-1)
        joints = np.asarray(f["/frames/joints"][()], dtype=float)
        outcome = np.asarray(f["/steps/outcome"][()]).reshape(-1)
        step_ms = np.asarray(f["/steps/ms"][()], dtype=float).reshape(-1)
        step_time = np.asarray(f["/steps/time"][()], dtype=float).reshape(-1)
        finite = True
        max_disp = 0.0
        # Frame by frame: a long run's displacement does not need to fit in memory at once.
        for name in ("/frames/positions", "/frames/displacement"):
            ds = f[name]
            for i in range(ds.shape[0]):
                frame = np.asarray(ds[i], dtype=float)
                if not np.all(np.isfinite(frame)):
                    finite = False
                    continue
                if name == "/frames/displacement" and frame.size:
                    max_disp = max(max_disp, float(np.sqrt((frame ** 2).sum(axis=1)).max()))
        for name in ("/frames/joints", "/frames/reduced", "/steps/energy", "/steps/grad_norm"):
            if name in f and not np.all(np.isfinite(np.asarray(f[name][()], dtype=float))):
                finite = False
        target = np.asarray(f["/frames/target_pelvis"][()], dtype=float) if "/frames/target_pelvis" in f else None

    row = {
        "file": os.path.basename(motion),
        "frames": len(time),
        "seconds": f"{step_time[-1] if len(step_time) else 0.0:.3f}",
        "steps": len(outcome),
        "accepted": int((outcome == 0).sum()),
        "damped": int((outcome == 1).sum()),
        "rejected": int((outcome == 2).sum()),
        "median_step_ms": f"{float(np.median(step_ms)) if len(step_ms) else 0.0:.2f}",
        "max_soft_displacement_mm": f"{1e3 * max_disp:.1f}" if finite else "nan",
        "any_nan": 0 if finite else 1,
    }
    curve = None
    problems = []
    if target is None or target.shape != (len(time), 3):
        row["pelvis_mean_mm"] = row["pelvis_max_mm"] = ""
        problems.append("no target pelvis")
    else:
        err = 1e3 * np.sqrt(((joints[:, 0, :] - target) ** 2).sum(axis=1))
        if np.all(np.isfinite(err)) and len(err):
            row["pelvis_mean_mm"] = f"{float(err.mean()):.2f}"
            row["pelvis_max_mm"] = f"{float(err.max()):.2f}"
            if err.max() > max_pelvis_mm:
                problems.append(f"pelvis max > {max_pelvis_mm:g} mm")
        else:
            row["pelvis_mean_mm"] = row["pelvis_max_mm"] = "nan"
        curve = (time, err)
    if not finite:
        problems.insert(0, "nan")
    row["status"] = "ok" if not problems else "; ".join(problems)
    return row, curve


def failed_row(name):
    row = {c: "" for c in COLUMNS}
    row["file"] = name
    row["status"] = "run failed"
    return row


def write_csv(path, rows):
    tmp = path + ".partial"
    with open(tmp, "w", newline="") as out:
        w = csv.DictWriter(out, fieldnames=COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    os.replace(tmp, path)


def print_table(rows):
    widths = [max(len(c), *(len(str(r[c])) for r in rows)) for c in COLUMNS]
    print("  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(COLUMNS, widths))))
    for r in rows:
        print("  ".join(str(r[c]).rjust(w) if i else str(r[c]).ljust(w)
                        for i, (c, w) in enumerate(zip(COLUMNS, widths))))


PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
           "#17becf"]


def plot_png(path, curves, limit_mm):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 4.5), dpi=110)
    for i, (name, (t, e)) in enumerate(curves):
        ax.plot(t, e, color=PALETTE[i % len(PALETTE)], lw=1.2, label=name)
    ax.axhline(limit_mm, color="k", ls="--", lw=0.8, label=f"{limit_mm:g} mm")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pelvis error (mm)")
    ax.set_title("simulated pelvis vs. motion root")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    tmp = path + ".partial.png"
    fig.savefig(tmp)
    os.replace(tmp, path)


def nice_step(span, ticks=6):
    raw = span / ticks if span > 0 else 1.0
    mag = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 5, 10):
        if raw <= m * mag:
            return m * mag
    return 10 * mag


def plot_svg(path, curves, limit_mm):
    W, H, L, R, T, B = 900, 450, 70, 170, 40, 50
    t_max = max([float(t[-1]) for _, (t, _) in curves if len(t)] + [1e-3])
    finite = [float(np.nanmax(e)) for _, (_, e) in curves if len(e) and np.any(np.isfinite(e))]
    y_max = max(finite + [limit_mm]) * 1.05
    sx = lambda t: L + (W - L - R) * t / t_max
    sy = lambda y: H - B - (H - T - B) * min(y, y_max) / y_max
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" '
           f'font-size="12"><rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{(W - R + L) / 2}" y="22" text-anchor="middle" font-size="14">simulated pelvis vs. motion '
           f'root</text>']
    ys = nice_step(y_max)
    y = 0.0
    while y <= y_max + 1e-9:
        out.append(f'<line x1="{L}" x2="{W - R}" y1="{sy(y):.1f}" y2="{sy(y):.1f}" stroke="#ddd"/>'
                   f'<text x="{L - 6}" y="{sy(y) + 4:.1f}" text-anchor="end">{y:g}</text>')
        y += ys
    xs = nice_step(t_max)
    x = 0.0
    while x <= t_max + 1e-9:
        out.append(f'<line x1="{sx(x):.1f}" x2="{sx(x):.1f}" y1="{T}" y2="{H - B}" stroke="#eee"/>'
                   f'<text x="{sx(x):.1f}" y="{H - B + 16}" text-anchor="middle">{x:g}</text>')
        x += xs
    out.append(f'<rect x="{L}" y="{T}" width="{W - L - R}" height="{H - T - B}" fill="none" stroke="black"/>')
    out.append(f'<text x="{(W - R + L) / 2}" y="{H - 12}" text-anchor="middle">time (s)</text>')
    out.append(f'<text x="18" y="{(H - B + T) / 2}" text-anchor="middle" transform="rotate(-90 18 '
               f'{(H - B + T) / 2})">pelvis error (mm)</text>')
    out.append(f'<line x1="{L}" x2="{W - R}" y1="{sy(limit_mm):.1f}" y2="{sy(limit_mm):.1f}" stroke="black" '
               f'stroke-dasharray="6,4"/>')
    for i, (name, (t, e)) in enumerate(curves):
        color = PALETTE[i % len(PALETTE)]
        pts = " ".join(f"{sx(float(a)):.1f},{sy(float(b)):.1f}" for a, b in zip(t, e) if np.isfinite(b))
        out.append(f'<polyline fill="none" stroke="{color}" stroke-width="1.3" points="{pts}"/>')
        ly = T + 16 * (i + 1)
        out.append(f'<line x1="{W - R + 10}" x2="{W - R + 30}" y1="{ly - 4}" y2="{ly - 4}" stroke="{color}" '
                   f'stroke-width="2"/><text x="{W - R + 35}" y="{ly}">{name}</text>')
    ly = T + 16 * (len(curves) + 1)
    out.append(f'<line x1="{W - R + 10}" x2="{W - R + 30}" y1="{ly - 4}" y2="{ly - 4}" stroke="black" '
               f'stroke-dasharray="6,4"/><text x="{W - R + 35}" y="{ly}">{limit_mm:g} mm</text>')
    out.append("</svg>\n")
    tmp = path + ".partial"
    with open(tmp, "w") as f:
        f.write("\n".join(out))
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results", nargs="*", help="result files of `sflsh simulate`")
    ap.add_argument("--csv", required=True, help="table to write")
    ap.add_argument("--plot", help="plot path without extension (.png with matplotlib, else .svg)")
    ap.add_argument("--max-pelvis-mm", type=float, default=20.0, help="pelvis max error limit (mm)")
    ap.add_argument("--failed", action="append", default=[], help="name of a run that failed (a row saying so)")
    a = ap.parse_args()

    rows, curves = [], []
    for path in a.results:
        row, curve = summarize(path, a.max_pelvis_mm)
        rows.append(row)
        if curve is not None:
            curves.append((row["file"], curve))
    rows += [failed_row(n) for n in a.failed]
    rows.sort(key=lambda r: r["file"])
    if not rows:
        raise SystemExit("mocap_table: no result files given")
    write_csv(a.csv, rows)
    print_table(rows)
    print(f"wrote {a.csv}")
    if a.plot and curves:
        try:
            import matplotlib  # noqa: F401
            path = a.plot + ".png"
            plot_png(path, curves, a.max_pelvis_mm)
        except ImportError:
            path = a.plot + ".svg"
            plot_svg(path, curves, a.max_pelvis_mm)
        print(f"wrote {path}")
    bad = [r for r in rows if r["status"] != "ok"]
    for r in bad:
        print(f"FAIL {r['file']}: {r['status']}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
