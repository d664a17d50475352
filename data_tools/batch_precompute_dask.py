#!/usr/bin/python3
"""Batch precompute on a Dask cluster: one task per shape (row of a shapes CSV).

Each task runs `sflsh precompute ... --batch SHAPES --out-dir OUT --task-index ROW`
on a Dask worker, which builds that row alone (skipping it when its content-keyed
file is already there), and returns its status and timing; the driver writes them
all into one CSV. The steps:

  1. one task runs `sflsh precompute --template-only` (builds the template stage
     into the cache once, so the shape tasks never race to build it) and
     `--dry-run` (the plan: which rows are pending, done, duplicate or invalid);
  2. one task per pending row;
  3. the CSV (default OUT/dask_manifest.csv): row, line, name, key, file, status,
     seconds (the sflsh process, measured by the task), shape_seconds (sflsh's
     own time for the row), peak_rss_mib (of that sflsh process), worker, error.
     Rows the plan found done, duplicate or invalid are listed with no task.

Every worker must see the same paths: the sflsh executable, the shapes CSV, the
body model file (--model), the output folder and the template cache
(--cache-dir), e.g. on one shared file system. Exit status 1 if a row failed.

Usage:
    /usr/bin/python3 data_tools/batch_precompute_dask.py --sflsh build/sflsh \\
        --batch shapes.csv --out-dir avatars/ [--scheduler tcp://host:8786 | --workers 2] \\
        [--csv results.csv] -- [sflsh precompute options: --model ... --handles ... --cache-dir ...]

Without --scheduler a LocalCluster of --workers processes (1 thread each) runs on
this machine, and each sflsh gets `--threads cores/workers`. On a cluster with one
Dask worker per core, pass `-- --threads 1` (sflsh's default is one thread per core). Needs Debian's python3-distributed.
"""
import argparse
import csv
import io
import os
import shutil
import subprocess
import sys
import tempfile
import time

MANIFEST_FIELDS = ["row", "line", "name", "key", "file", "status", "topology", "seconds", "peak_rss_mib", "error"]
# Manifests of sflsh before the topology column (the element array hash of each output).
MANIFEST_FIELDS_WITHOUT_TOPOLOGY = [f for f in MANIFEST_FIELDS if f != "topology"]
OUTPUT_FIELDS = ["row", "line", "name", "key", "file", "status", "seconds", "shape_seconds", "peak_rss_mib",
                 "worker", "error"]
# Options that select rows or outputs: the driver sets them itself.
RESERVED = {"--batch", "--out-dir", "--task-index", "--shard", "--manifest", "--jobs", "--out", "--betas",
            "--dry-run", "--template-only"}


def read_manifest(text):
    rows = list(csv.DictReader(io.StringIO(text)))
    if rows and list(rows[0].keys()) not in (MANIFEST_FIELDS, MANIFEST_FIELDS_WITHOUT_TOPOLOGY):
        raise ValueError("not an sflsh batch manifest (columns %s)" % list(rows[0].keys()))
    return rows


def last_error_line(output):
    lines = [l for l in output.splitlines() if l.strip()]
    for l in reversed(lines):
        if "error" in l:
            return l.strip()
    return lines[-1].strip() if lines else ""


def sflsh_env():
    """The environment for sflsh on a Dask worker. Dask's nanny sets
    MALLOC_TRIM_THRESHOLD_=65536 for its workers (to return memory to the OS
    sooner); sflsh, allocation-heavy C++, then spends 2x the CPU (5x the system
    time) in the shape stage, so its child processes get the default back."""
    env = dict(os.environ)
    env.pop("MALLOC_TRIM_THRESHOLD_", None)
    return env


def prepare(sflsh, options, batch, out_dir):
    """Template stage into the cache once, then the plan. Runs as one Dask task."""
    t = subprocess.run([sflsh, "-q", "precompute", "--template-only"] + options, capture_output=True, text=True,
                       env=sflsh_env())
    if t.returncode != 0:
        raise RuntimeError("template stage failed: " + last_error_line(t.stderr + t.stdout))
    with tempfile.TemporaryDirectory() as tmp:
        plan = os.path.join(tmp, "plan.csv")
        p = subprocess.run([sflsh, "-q", "precompute"] + options +
                           ["--batch", batch, "--out-dir", out_dir, "--dry-run", "--manifest", plan],
                           capture_output=True, text=True, env=sflsh_env())
        if not os.path.exists(plan):
            raise RuntimeError("planning the batch failed: " + last_error_line(p.stderr + p.stdout))
        with open(plan) as f:
            return f.read()


def run_row(sflsh, options, batch, out_dir, row):
    """One shape: `sflsh precompute --task-index row`. Runs as a Dask task; never raises."""
    try:
        from distributed import get_worker
        worker = get_worker().address
    except (ImportError, ValueError):
        worker = ""
    result = {"row": row, "status": "failed", "seconds": 0.0, "shape_seconds": 0.0, "peak_rss_mib": 0.0,
              "worker": worker, "error": "", "t_start": time.time()}
    tmp = tempfile.mkdtemp(prefix="sflsh-task-")
    try:
        manifest = os.path.join(tmp, "row.csv")
        start = time.perf_counter()
        p = subprocess.run([sflsh, "-q", "precompute"] + options +
                           ["--batch", batch, "--out-dir", out_dir, "--task-index", str(row), "--manifest", manifest],
                           capture_output=True, text=True, env=sflsh_env())
        result["seconds"] = time.perf_counter() - start
        records = []
        if os.path.exists(manifest):
            with open(manifest) as f:
                records = read_manifest(f.read())
        if len(records) == 1:
            r = records[0]
            result.update(status=r["status"], shape_seconds=float(r["seconds"]),
                          peak_rss_mib=float(r["peak_rss_mib"]), error=r["error"])
        if p.returncode != 0 and result["status"] != "failed":
            result["status"] = "failed"
        if result["status"] == "failed" and not result["error"]:
            result["error"] = "sflsh exit code %d: %s" % (p.returncode, last_error_line(p.stderr + p.stdout))
    except OSError as e:
        result["error"] = "cannot run %s: %s" % (sflsh, e)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    result["t_end"] = time.time()
    return result


def overheads(results):
    """Mean dispatch gap (a task's end to the next task's start on the same
    worker, the worker's clock), mean result latency (a task's end to the
    driver holding its result; needs synchronised clocks) and mean sflsh
    start-up (the process's time minus its own time for the row)."""
    gaps, latency, startup = [], [], []
    by_worker = {}
    for r in results:
        by_worker.setdefault(r["worker"], []).append(r)
        latency.append(r["t_result"] - r["t_end"])
        if r["status"] == "built":
            startup.append(r["seconds"] - r["shape_seconds"])
    for tasks in by_worker.values():
        tasks.sort(key=lambda r: r["t_start"])
        gaps += [b["t_start"] - a["t_end"] for a, b in zip(tasks, tasks[1:])]
    mean = lambda v: sum(v) / len(v) if v else float("nan")
    return mean(gaps), mean(latency), mean(startup)


def write_csv(rows, path):
    tmp = path + ".partial"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=OUTPUT_FIELDS, extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        for r in sorted(rows, key=lambda r: int(r["row"])):
            w.writerow(r)
    os.replace(tmp, path)


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    options = []
    if "--" in argv:
        i = argv.index("--")
        argv, options = argv[:i], argv[i + 1:]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog="Options after -- go to every `sflsh precompute`.")
    ap.add_argument("--sflsh", required=True, help="path of the sflsh executable (the same on every worker)")
    ap.add_argument("--batch", required=True, help="shapes CSV (sflsh precompute --batch)")
    ap.add_argument("--out-dir", required=True, help="output folder, shared by the workers")
    ap.add_argument("--scheduler", default="", help="address of a running Dask scheduler (default: a LocalCluster)")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="LocalCluster worker processes, 1 thread each (default: all cores)")
    ap.add_argument("--csv", default="", help="result CSV (default OUT_DIR/dask_manifest.csv)")
    args = ap.parse_args(argv)
    for o in options:
        if o.split("=")[0] in RESERVED:
            ap.error("%s is set by this driver; do not pass it after --" % o)
    if args.workers < 1:
        ap.error("--workers must be at least 1")
    sflsh = os.path.abspath(args.sflsh)
    batch, out_dir = os.path.abspath(args.batch), os.path.abspath(args.out_dir)
    if not (os.path.isfile(sflsh) and os.access(sflsh, os.X_OK)):
        ap.error("%s: not an executable file" % args.sflsh)
    if not os.path.isfile(batch):
        ap.error("%s: shapes file not found" % args.batch)
    os.makedirs(out_dir, exist_ok=True)
    out_csv = args.csv or os.path.join(out_dir, "dask_manifest.csv")
    # The local workers share this machine's cores: each sflsh solves its weights on
    # cores / workers threads unless the options say otherwise (sflsh precompute --threads).
    if not args.scheduler and not any(o.split("=")[0] == "--threads" for o in options):
        options = options + ["--threads", str(max(1, (os.cpu_count() or 1) // args.workers))]

    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        sys.exit("batch_precompute_dask: Dask distributed is not installed (Debian: apt-get install python3-distributed)")

    t0 = time.perf_counter()
    if args.scheduler:
        cluster, client = None, Client(args.scheduler)
        where = args.scheduler
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        where = "LocalCluster of %d workers" % args.workers
    t_cluster = time.perf_counter() - t0
    try:
        t1 = time.perf_counter()
        plan = read_manifest(client.submit(prepare, sflsh, options, batch, out_dir, pure=False).result())
        t_prepare = time.perf_counter() - t1
        rows = {int(r["row"]): dict(r) for r in plan}
        for r in rows.values():
            r["shape_seconds"], r["worker"] = "", ""
        pending = [row for row, r in rows.items() if r["status"] == "pending"]
        print("batch_precompute_dask: %d rows on %s (cluster start %.1f s, template + plan %.1f s): %d to build"
              % (len(rows), where, t_cluster, t_prepare, len(pending)), file=sys.stderr)
        t2 = time.perf_counter()
        futures = [client.submit(run_row, sflsh, options, batch, out_dir, row, pure=False, key="sflsh-row-%d" % row)
                   for row in pending]
        done = failed = 0
        results = []
        for fut in as_completed(futures):
            res = fut.result()
            res["t_result"] = time.time()
            results.append(res)
            r = rows[res["row"]]
            r.update({k: res[k] for k in ("status", "worker", "error")})
            r.update(seconds="%.3f" % res["seconds"], shape_seconds="%.3f" % res["shape_seconds"],
                     peak_rss_mib="%.1f" % res["peak_rss_mib"])
            done += 1
            failed += res["status"] == "failed"
            elapsed = time.perf_counter() - t2
            eta = (len(pending) - done) * elapsed / done
            print("batch_precompute_dask: %d/%d rows done%s, %.2f rows/s, ETA %.0f s"
                  % (done, len(pending), " (%d failed)" % failed if failed else "", done / elapsed, eta),
                  file=sys.stderr)
            if res["status"] == "failed":
                print("batch_precompute_dask: row %d (line %s) failed: %s" % (res["row"], r["line"], res["error"]),
                      file=sys.stderr)
            write_csv(rows.values(), out_csv)
        t_tasks = time.perf_counter() - t2
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    write_csv(rows.values(), out_csv)
    built = [r for r in rows.values() if r["status"] == "built"]
    counts = {}
    for r in rows.values():
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    task_s = sum(r["seconds"] for r in results)
    nworkers = len({r["worker"] for r in results})
    gap, latency, startup = overheads(results)
    print("summary: %d rows: %s; %d tasks in %.1f s wall on %d workers, %.2f s per task in sflsh "
          "(of which %.2f s sflsh start-up: model + cached template load); Dask overhead per task: "
          "%.3f s between tasks on a worker, %.3f s from a task's end to its result at the driver"
          % (len(rows), ", ".join("%d %s" % (n, s) for s, n in sorted(counts.items())), len(results), t_tasks,
             nworkers, task_s / max(1, len(results)), startup, gap, latency))
    peak = max([float(r["peak_rss_mib"]) for r in built] or [0.0])
    print("peak memory per worker task %.0f MiB; manifest %s" % (peak, out_csv))
    bad = sorted((row, r) for row, r in rows.items() if r["status"] == "failed")
    if bad:
        print("failed rows:\n  row   line  name  error")
        for row, r in bad:
            print("  %-5d %-5s %-5s %s" % (row, r["line"], r["name"], r["error"]))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
