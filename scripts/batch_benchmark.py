#!/usr/bin/python3
"""Batch precompute benchmark (README "Batch precompute"): N shapes of the default
procedural body built four ways, each into an empty folder, the template stage
cached once beforehand:
  serial   sflsh precompute --batch --jobs 1   (in one process, the existing loop; each
           shape's weights on one thread per core)
  serial1  the same loop with --threads 1      (each shape on one thread)
  jobs2    sflsh precompute --batch --jobs 2   (2 worker processes, 1 thread each)
  dask1    data_tools/batch_precompute_dask.py, LocalCluster of 1 worker
  dask2    the same with 2 workers
Writes scripts/results/batch_benchmark.csv (one line per way), the manifests
(batch_manifest_<way>.csv) and batch_benchmark.md. Also checks that the four
ways wrote bit-identical files and that the template cache entry was not rebuilt.
The checks' figures (per way: shapes built and each file's SHA-256; whether
the template cache entry was rewritten) go to batch_benchmark_checks.json and
are judged from that file alone: `--check FILE` re-judges one. Exit status: 0
when every way built every shape, the ways' files are bit-identical and the
template cache entry was not rewritten (the .md is written either way); 1
otherwise (named on stderr); 2 when the checks file is missing or malformed
(one line naming the file and the field).

Usage: /usr/bin/python3 scripts/batch_benchmark.py [--sflsh build/sflsh] [--shapes 16] [--handles 16]
       /usr/bin/python3 scripts/batch_benchmark.py --check scripts/results/batch_benchmark_checks.json
"""
import argparse
import csv
import hashlib
import json
import os
import random
import resource
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from figure_check import EXIT_BAD_INPUT, EXIT_MISSED, BadResults, read_text  # noqa: E402


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def load():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def judge_checks(path):
    """The failed checks (list of strings) of a batch_benchmark_checks JSON file; BadResults if malformed."""
    try:
        c = json.loads(read_text(path))
    except json.JSONDecodeError as e:
        raise BadResults(f"{path}: not JSON ({e.msg} at line {e.lineno})") from None
    if not isinstance(c, dict):
        raise BadResults(f"{path}: expected an object")
    for key, kind in (("shapes", int), ("template_cache_rewritten", bool), ("ways", dict)):
        if not isinstance(c.get(key), kind):
            raise BadResults(f"{path}: field '{key}' missing or not {kind.__name__}")
    if not c["ways"]:
        raise BadResults(f"{path}: field 'ways' is empty")
    failures = []
    reference = None
    for way, w in c["ways"].items():
        if not isinstance(w, dict) or not isinstance(w.get("built"), int) or not isinstance(w.get("files"), dict):
            raise BadResults(f"{path}: ways.{way}: expected {{\"built\": N, \"files\": {{name: sha256}}}}")
        if w["built"] != c["shapes"]:
            failures.append(f"{way} built {w['built']} of {c['shapes']} shapes")
        if reference is None:
            reference = (way, w["files"])
        elif w["files"] != reference[1]:
            names = sorted(set(w["files"]) | set(reference[1]))
            differ = [n for n in names if w["files"].get(n) != reference[1].get(n)]
            failures.append(f"{way} wrote files different from {reference[0]}'s: {', '.join(differ[:3])}"
                            + (f" and {len(differ) - 3} more" if len(differ) > 3 else ""))
    if c["template_cache_rewritten"]:
        failures.append("the template cache entry was rewritten during the runs")
    return failures


def report(failures):
    for f in failures:
        print("batch_benchmark: FAILED: " + f, file=sys.stderr)
    return EXIT_MISSED if failures else 0


def main():
    if sys.argv[1:2] == ["--check"]:
        if len(sys.argv) != 3:
            sys.exit("usage: batch_benchmark.py --check CHECKS.json")
        try:
            failures = judge_checks(sys.argv[2])
        except BadResults as e:
            print(f"batch_benchmark: {e}", file=sys.stderr)
            sys.exit(EXIT_BAD_INPUT)
        if not failures:
            print("batch_benchmark: passed")
        sys.exit(report(failures))
    ap = argparse.ArgumentParser()
    ap.add_argument("--sflsh", default=os.path.join(ROOT, "build", "sflsh"))
    ap.add_argument("--shapes", type=int, default=16)
    ap.add_argument("--handles", type=int, default=16)
    ap.add_argument("--out", default=os.path.join(ROOT, "scripts", "results"))
    ap.add_argument("--ways", default="serial,serial1,jobs2,dask1,dask2")
    ap.add_argument("--suffix", default="", help="appended to the result file names (e.g. _omp1)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    sflsh = os.path.abspath(args.sflsh)
    opts = ["--handles", str(args.handles)]
    work = tempfile.mkdtemp(prefix="sflsh-batch-bench-")
    shapes = os.path.join(work, "shapes.csv")
    rng = random.Random(14)
    with open(shapes, "w") as f:
        f.write("name," + ",".join("b%d" % i for i in range(10)) + "\n")
        for i in range(args.shapes):
            f.write("s%02d," % i + ",".join("%.3f" % rng.uniform(-2, 2) for _ in range(10)) + "\n")
    t = subprocess.run([sflsh, "-q", "precompute", "--template-only"] + opts, capture_output=True, text=True, check=True)
    cache = t.stdout.strip().split(": ", 1)[1]
    cache_mtime = os.stat(cache).st_mtime_ns
    print("template stage:", t.stdout.strip(), file=sys.stderr)

    rows = []
    checks = {"shapes": args.shapes, "ways": {}}
    for way in args.ways.split(","):
        out_dir = os.path.join(work, way)
        if way in ("serial", "serial1", "jobs2"):
            cmd = [sflsh, "-q", "precompute"] + opts + ["--batch", shapes, "--out-dir", out_dir,
                                                        "--jobs", "2" if way == "jobs2" else "1"]
            if way == "serial1":
                cmd += ["--threads", "1"]
            manifest = os.path.join(out_dir, "manifest.csv")
        else:
            cmd = ["/usr/bin/python3", os.path.join(ROOT, "data_tools", "batch_precompute_dask.py"), "--sflsh", sflsh,
                   "--workers", way[-1], "--batch", shapes, "--out-dir", out_dir, "--"] + opts
            manifest = os.path.join(out_dir, "dask_manifest.csv")
        load_before = load()
        cpu0, t0 = children_cpu(), time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall, cpu = time.perf_counter() - t0, children_cpu() - cpu0
        if p.returncode != 0:
            sys.exit("%s failed:\n%s%s" % (way, p.stdout, p.stderr))
        with open(manifest) as f:
            m = list(csv.DictReader(f))
        built = [r for r in m if r.get("status") == "built"]
        checks["ways"][way] = {"built": len(built), "files": {n: sha256(os.path.join(out_dir, n))
                                                              for n in sorted(os.listdir(out_dir)) if n.endswith(".h5")}}
        if not built:
            continue
        summary = [l for l in p.stdout.splitlines() if l.startswith("summary:") or l.startswith("batch summary:")]
        row = {"way": way, "shapes": args.shapes, "handles": args.handles, "wall_s": round(wall, 2),
               "wall_per_shape_s": round(wall / args.shapes, 2), "cpu_s": round(cpu, 2),
               "row_seconds_mean": round(sum(float(r["seconds"]) for r in built) / len(built), 2),
               "peak_rss_mib_max": max(float(r["peak_rss_mib"]) for r in built),
               "load_before": load_before, "load_after": load(), "summary": summary[0] if summary else ""}
        if way.startswith("dask"):
            row["shape_seconds_mean"] = round(sum(float(r["shape_seconds"]) for r in built) / len(built), 2)
        rows.append(row)
        shutil.copy(manifest, os.path.join(args.out, "batch_manifest_%s%s.csv" % (way, args.suffix)))
        print(row, file=sys.stderr)

    checks["template_cache_rewritten"] = os.stat(cache).st_mtime_ns != cache_mtime
    checks_path = os.path.join(args.out, "batch_benchmark_checks%s.json" % args.suffix)
    with open(checks_path, "w") as f:
        json.dump(checks, f, indent=1)
    failures = judge_checks(checks_path)
    if not rows:
        sys.exit(report(failures) or EXIT_MISSED)
    rebuilt = checks["template_cache_rewritten"]
    identical = not any("different" in f for f in failures)
    by = {r["way"]: r for r in rows}
    for r in rows:
        ref = by.get("serial", r) if r["way"] in ("serial", "serial1", "jobs2") else by.get("dask1", r)
        r["speedup"] = round(ref["wall_s"] / r["wall_s"], 2)
        if "serial1" in by:
            r["speedup_vs_serial1"] = round(by["serial1"]["wall_s"] / r["wall_s"], 2)
    fields = ["way", "shapes", "handles", "wall_s", "wall_per_shape_s", "cpu_s", "row_seconds_mean",
              "shape_seconds_mean", "peak_rss_mib_max", "speedup", "speedup_vs_serial1", "load_before", "load_after", "summary"]
    with open(os.path.join(args.out, "batch_benchmark%s.csv" % args.suffix), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow(r)
    with open(os.path.join(args.out, "batch_benchmark%s.md" % args.suffix), "w") as f:
        f.write("# Batch precompute benchmark\n\n")
        f.write("`%s/usr/bin/python3 scripts/batch_benchmark.py --shapes %d --handles %d%s` on %s, %d cores "
                "(1-min load average %.1f-%.1f during the runs, this benchmark's own processes included).\n\n"
                % ("OMP_NUM_THREADS=%s " % os.environ["OMP_NUM_THREADS"] if "OMP_NUM_THREADS" in os.environ else "",
                   args.shapes, args.handles, " --ways %s --suffix %s" % (args.ways, args.suffix) if args.suffix else "",
                   os.uname().nodename, os.cpu_count(),
                   min(r["load_before"] for r in rows), max(r["load_after"] for r in rows)))
        f.write("| way | wall (s) | wall per shape (s) | CPU (s) | row time, mean (s) | peak RSS per worker (MiB) "
                "| speed-up | vs serial1 |\n|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            ref = "serial" if r["way"] in ("serial", "serial1", "jobs2") else "dask1"
            f.write("| %s | %.1f | %.2f | %.1f | %.2f | %.0f | %.2f× (vs %s) | %s |\n"
                    % (r["way"], r["wall_s"], r["wall_per_shape_s"], r["cpu_s"], r["row_seconds_mean"],
                       r["peak_rss_mib_max"], r["speedup"], ref,
                       "%.2f×" % r["speedup_vs_serial1"] if "speedup_vs_serial1" in r else "-"))
        f.write("\nTemplate stage computed once (cache entry %s %s during the runs); the %d ways wrote %s files.\n"
                % (os.path.basename(cache), "REBUILT" if rebuilt else "not rewritten", len(rows),
                   "bit-identical" if identical else "DIFFERENT"))
        for r in rows:
            if r["summary"]:
                f.write("\n%s: `%s`\n" % (r["way"], r["summary"]))
    shutil.rmtree(work, ignore_errors=True)
    print(open(os.path.join(args.out, "batch_benchmark%s.md" % args.suffix)).read())
    sys.exit(report(failures))


if __name__ == "__main__":
    main()
