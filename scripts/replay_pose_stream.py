#!/usr/bin/python3
"""Replays a pose file into sflsh's teleoperation stream, like a haptic device.

Reads a pose file (CSV with header time,x,y,z,qw,qx,qy,qz,closure, or JSON
lines {"t":..,"p":[x,y,z],"q":[w,x,y,z],"closure":..}), resamples it at
--rate Hz (position and closure linear, orientation slerp, held after the
end) and sends one pose datagram per sample to 127.0.0.1:PORT on the wall
clock. It reads the simulator's feedback datagrams as they come and matches
each to the pose it echoes (the sequence number), giving the latency from
sending a pose to receiving the force computed with it.

The message format (README "Teleoperation stream";
include/sflsh/teleop/stream_message.hpp):
  pose      device -> simulator, 88 bytes, struct "<IHHQd3d4dd":
            magic 0x50544653 ("SFTP"), version 2, type 1, sequence, device time (s),
            x y z (m), qw qx qy qz, closure (jaw opening angle, rad, 0..pi)
  feedback  simulator -> device, 80 bytes, struct "<IHHQd3d3dII":
            magic, version 2, type 2, echoed sequence, sim time (s),
            force x y z (N), torque x y z (N m), status (0 running, 1 ramping
            in, 2 ended: zero force), reserved

Abuse options: --drop F skips a fraction F of the samples (the sequence
number still advances, as with a lossy link); --corrupt F replaces a fraction
F by bad datagrams (garbage, wrong magic, truncated, NaN position, non-unit
quaternion), which the simulator must reject while holding the last good pose.

Prints a summary; with --json, one JSON object instead. Standard library only.

Usage: /usr/bin/python3 scripts/replay_pose_stream.py POSES.csv --port PORT
         [--rate 1000] [--count N] [--drop 0.1] [--corrupt 0.01] [--seed 1] [--json]
"""
import argparse
import bisect
import json
import math
import random
import socket
import struct
import sys
import time

MAGIC = 0x50544653
VERSION = 2
POSE = struct.Struct("<IHHQd3d4dd")
FEEDBACK = struct.Struct("<IHHQd3d3dII")
assert POSE.size == 88 and FEEDBACK.size == 80
CSV_COLUMNS = ["time", "x", "y", "z", "qw", "qx", "qy", "qz", "closure"]


def fail(msg):
    sys.exit(f"replay_pose_stream: {msg}")


def read_pose_file(path):
    """Rows of (t, [x, y, z], [w, x, y, z], closure), times strictly increasing."""
    rows = []
    try:
        lines = open(path, encoding="utf-8").read().splitlines()
    except OSError as e:
        fail(f"{path}: cannot read: {e.strerror}")
    header = None
    for n, raw in enumerate(lines, 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        try:
            if path.endswith(".csv"):
                cells = [c.strip() for c in line.split(",")]
                if header is None:
                    header = cells
                    missing = [c for c in CSV_COLUMNS if c not in header]
                    if missing:
                        fail(f"{path} line {n}: header lacks the column '{missing[0]}'")
                    continue
                v = dict(zip(header, (float(c) for c in cells)))
                row = (v["time"], [v["x"], v["y"], v["z"]], [v["qw"], v["qx"], v["qy"], v["qz"]], v["closure"])
            else:
                o = json.loads(line)
                row = (float(o["t"]), [float(c) for c in o["p"]], [float(c) for c in o["q"]], float(o["closure"]))
        except (ValueError, KeyError, TypeError) as e:
            fail(f"{path} line {n}: {e!r}")
        if len(row[1]) != 3 or len(row[2]) != 4:
            fail(f"{path} line {n}: p needs 3 numbers and q 4")
        if rows and not row[0] > rows[-1][0]:
            fail(f"{path} line {n}: time {row[0]} not after {rows[-1][0]}")
        rows.append(row)
    if not rows:
        fail(f"{path}: no pose samples")
    return rows


def slerp(a, b, u):
    d = sum(x * y for x, y in zip(a, b))
    if d < 0:  # the shorter arc
        b, d = [-x for x in b], -d
    if d > 0.9995:
        q = [x + u * (y - x) for x, y in zip(a, b)]
    else:
        th = math.acos(d)
        s = math.sin(th)
        q = [(math.sin((1 - u) * th) * x + math.sin(u * th) * y) / s for x, y in zip(a, b)]
    n = math.sqrt(sum(x * x for x in q))
    return [x / n for x in q]


def pose_at(rows, times, t):
    i = bisect.bisect_right(times, t)
    if i == 0:
        return rows[0]
    if i == len(rows):
        return rows[-1]
    (t0, p0, q0, c0), (t1, p1, q1, c1) = rows[i - 1], rows[i]
    u = (t - t0) / (t1 - t0)
    return (t, [x + u * (y - x) for x, y in zip(p0, p1)], slerp(q0, q1, u), c0 + u * (c1 - c0))


def pose_bytes(seq, t, p, q, closure):
    return POSE.pack(MAGIC, VERSION, 1, seq, t, *p, *q, closure)


def corrupt_bytes(kind, seq, t, p, q, closure, rng):
    if kind == 0:  # garbage
        return bytes(rng.randrange(256) for _ in range(88))
    if kind == 1:  # wrong magic
        return b"XXXX" + pose_bytes(seq, t, p, q, closure)[4:]
    if kind == 2:  # truncated
        return pose_bytes(seq, t, p, q, closure)[:50]
    if kind == 3:  # NaN position
        return pose_bytes(seq, t, [p[0], float("nan"), p[2]], q, closure)
    return pose_bytes(seq, t, p, [2 * x for x in q], closure)  # |q| = 2


def percentile(values, p):
    """numpy's default (linear) percentile, p in [0, 100]."""
    if not values:
        return float("nan")
    v = sorted(values)
    k = (len(v) - 1) * p / 100.0
    lo = math.floor(k)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (k - lo) * (v[hi] - v[lo])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("poses", help="pose file (.csv or .jsonl/.ndjson)")
    ap.add_argument("--port", type=int, required=True, help="the simulator's UDP port on 127.0.0.1")
    ap.add_argument("--rate", type=float, default=1000.0, help="samples per second (default 1000)")
    ap.add_argument("--count", type=int, default=0,
                    help="number of samples to send (default: as many as span the file at --rate)")
    ap.add_argument("--drop", type=float, default=0.0, help="fraction of samples not sent (default 0)")
    ap.add_argument("--corrupt", type=float, default=0.0, help="fraction of samples sent corrupted (default 0)")
    ap.add_argument("--seed", type=int, default=1, help="random seed of --drop and --corrupt (default 1)")
    ap.add_argument("--wait", type=float, default=0.2, help="seconds to wait for late feedback at the end (default 0.2)")
    ap.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    a = ap.parse_args()
    if a.rate <= 0:
        fail(f"--rate {a.rate}: expected > 0")
    if not (0 <= a.drop <= 1 and 0 <= a.corrupt <= 1 and a.drop + a.corrupt <= 1):
        fail("--drop and --corrupt: expected fractions in [0, 1] with a sum <= 1")

    rows = read_pose_file(a.poses)
    times = [r[0] for r in rows]
    period = 1.0 / a.rate
    count = a.count or int(math.floor((times[-1] - times[0]) * a.rate)) + 1
    rng = random.Random(a.seed)

    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.setblocking(False)
    dest = ("127.0.0.1", a.port)

    sent_at = {}      # sequence -> send time (perf_counter) of valid poses
    latency = []      # seconds, first feedback echoing each valid pose
    stats = dict(samples=count, sent=0, dropped=0, corrupted=0, feedback=0, bad_feedback=0)
    last_force = None

    def drain():
        nonlocal last_force
        while True:
            try:
                data = sock.recv(256)
            except BlockingIOError:
                return
            now = time.perf_counter()
            if len(data) != FEEDBACK.size:
                stats["bad_feedback"] += 1
                continue
            f = FEEDBACK.unpack(data)
            if f[0] != MAGIC or f[1] != VERSION or f[2] != 2 or f[11] > 2:
                stats["bad_feedback"] += 1
                continue
            stats["feedback"] += 1
            last_force = f[5:8]
            t_send = sent_at.pop(f[3], None)
            if t_send is not None:
                latency.append(now - t_send)

    start = time.perf_counter()
    for i in range(count):
        seq = i + 1
        t = times[0] + i * period
        _, p, q, c = pose_at(rows, times, t)
        due = start + i * period
        while True:  # sleep coarsely, then spin for the last half millisecond
            drain()
            left = due - time.perf_counter()
            if left <= 0:
                break
            if left > 0.0015:
                time.sleep(left - 0.001)
        r = rng.random()
        if r < a.drop:
            stats["dropped"] += 1
            continue
        valid = r >= a.drop + a.corrupt
        if valid:
            data = pose_bytes(seq, t, p, q, c)
        else:
            data = corrupt_bytes(rng.randrange(5), seq, t, p, q, c, rng)
            stats["corrupted"] += 1
        if valid:
            sent_at[seq] = time.perf_counter()
        try:
            sock.sendto(data, dest)
        except OSError as e:
            fail(f"cannot send to 127.0.0.1:{a.port}: {e.strerror}")
        stats["sent"] += 1
    elapsed = time.perf_counter() - start
    end = time.perf_counter() + a.wait
    while time.perf_counter() < end:
        drain()
        time.sleep(0.001)

    ms = [1e3 * x for x in latency]
    stats.update(
        valid=stats["sent"] - stats["corrupted"],
        answered=len(latency),
        unanswered=len(sent_at),
        rate_achieved=count / elapsed if elapsed > 0 else float("nan"),
        latency_median_ms=percentile(ms, 50),
        latency_p99_ms=percentile(ms, 99),
        latency_max_ms=max(ms) if ms else float("nan"),
        last_force=list(last_force) if last_force else None,
    )
    if a.json:
        print(json.dumps(stats))
        return
    print(f"{count} samples at {a.rate:g} Hz in {elapsed:.3f} s ({stats['rate_achieved']:.0f} Hz achieved): "
          f"sent {stats['sent']} (valid {stats['valid']}, corrupted {stats['corrupted']}), dropped {stats['dropped']}")
    print(f"feedback: {stats['feedback']} datagrams, {stats['answered']} valid poses answered, "
          f"{stats['unanswered']} not echoed (superseded before the simulator polled, or lost), "
          f"{stats['bad_feedback']} malformed")
    print(f"latency send -> feedback: median {stats['latency_median_ms']:.3f} ms, "
          f"p99 {stats['latency_p99_ms']:.3f} ms, max {stats['latency_max_ms']:.3f} ms")


if __name__ == "__main__":
    main()
