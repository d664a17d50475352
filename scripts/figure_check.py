"""Verdicts of the figure scripts (teleop_figures.py, contact_figures.py, ...) and
the reading of the result files they judge.

A figure script measures (runs sflsh, keeps every log and result file in its
work folder) and then judges those files alone, so that `--check WORK_DIR`
re-judges a finished run without simulating (the scripts' tests feed it
crafted folders). Every verdict is computed from the files; a missed target
makes the script exit 1 after printing its table. A missing or malformed
file, column, dataset or log line is one line naming the file and what is
wrong, exit 2, and no table (DESIGN.md §6).
"""
import csv
import math
import re
import sys

EXIT_MISSED = 1
EXIT_BAD_INPUT = 2


class BadResults(Exception):
    """A result file that is missing or malformed; the message names the file and the column/row/line."""


class FigureTable:
    """Rows of `| figure | target | measured | met | scene |`; `ok` None = recorded, no target."""

    def __init__(self):
        self.rows = []
        self.missed = []

    def row(self, figure, target, value, ok, scene):
        if ok is not None:
            ok = bool(ok)
            if not ok:
                self.missed.append(f"{figure.strip(' …')}: {value} (target {target})")
        met = "" if ok is None else "yes" if ok else "**no**"
        self.rows.append(f"| {figure} | {target} | {value} | {met} | `{scene}` |")

    def markdown(self):
        return "\n".join(["| figure | target | measured | met | scene |", "|---|---|---|---|---|"] + self.rows)

    def report_missed(self, script):
        """Prints one stderr line per missed target; returns the exit status (0 or EXIT_MISSED)."""
        for m in self.missed:
            print(f"{script}: target missed: {m}", file=sys.stderr)
        return EXIT_MISSED if self.missed else 0


def run_judged(script, judge):
    """Calls judge() -> (text, FigureTable); prints the text; exits 2 on BadResults, 1 on a missed target."""
    try:
        text, table = judge()
    except BadResults as e:
        print(f"{script}: {e}", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)
    print(text)
    sys.exit(table.report_missed(script))


def read_text(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError as e:
        raise BadResults(f"{path}: cannot read: {e.strerror}") from None


def search(pattern, text, path, what):
    """The first match of `pattern` in `text` (the contents of `path`); BadResults naming `what` if none."""
    m = re.search(pattern, text, re.M)
    if not m:
        raise BadResults(f"{path}: no {what} line")
    return m


def read_csv_columns(path, columns, text_columns=()):
    """Columns of a CSV file as lists of floats (`text_columns` as strings), with one error naming the file
    and the missing column, or the line and column of a value that is not a number."""
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            header = reader.fieldnames or []
            for c in list(columns) + list(text_columns):
                if c not in header:
                    raise BadResults(f"{path}: column '{c}' missing (header: {','.join(header) or 'empty'})")
            out = {c: [] for c in list(columns) + list(text_columns)}
            for n, row in enumerate(reader, start=2):
                for c in columns:
                    v = row.get(c)
                    try:
                        out[c].append(float(v))
                    except (TypeError, ValueError):
                        raise BadResults(f"{path} line {n}: column '{c}': {v!r} is not a number") from None
                for c in text_columns:
                    if row.get(c) is None:
                        raise BadResults(f"{path} line {n}: column '{c}' missing (short row)")
                    out[c].append(row[c])
    except OSError as e:
        raise BadResults(f"{path}: cannot read: {e.strerror}") from None
    if not out or not next(iter(out.values())):
        raise BadResults(f"{path}: no data rows")
    return out


def h5_dataset(path, name):
    """Dataset `name` of HDF5 file `path` as a numpy array; BadResults naming the file and dataset."""
    import h5py
    try:
        with h5py.File(path, "r") as h:
            if name not in h:
                raise BadResults(f"{path}: dataset '{name}' missing")
            return h[name][()]
    except OSError as e:
        raise BadResults(f"{path}: cannot read as HDF5: {e}") from None


def all_finite(values):
    return all(math.isfinite(v) for v in values)
