#!/usr/bin/python3
"""Checks the README against the generated results (scripts/reproduce.sh).

The convention (README "Results"):

* A paragraph or list item (its lines up to a blank line or the next item)
  that links a file under scripts/results/ quotes its figures from the linked
  file(s): every *figure* in it must occur literally in one of them. A table
  row takes the links of its own line and of the paragraph right before the
  table (its caption; blank lines between them allowed, no heading).
* A figure is a number with a decimal point or an exponent (0.175, 7.7e-10),
  or a number followed by %, ×, or a unit (13 %, 2×, 549 avatar-steps/s,
  60 ms; the units are listed in UNITS below). A plain integer before
  anything else (16 avatars, K = 96) is a count or a setting and is not
  checked. Numbers inside `inline code` and link targets are
  settings or names, not figures, and are skipped. "10 %" must occur as
  "10 %" or "10%"; other figures as the number itself, not inside a longer
  number (0.17 does not match 0.175); 10,000 also matches 10000.
* Inside the section "## Results" every paragraph, item or row that holds a
  figure must link a results file (or sit in a table captioned by one): measured figures are
  quoted from generated files only. Elsewhere, lines without a results link
  hold defaults and constants (a 2 mm spacing, the 88-byte datagram), which
  are not checked.
* The README has at most 300 lines, names no work session or issue
  ("session 12", "issue 13", "#13"), and each fenced code block right after a
  marker line `<!-- example: PATH -->` equals the file PATH (the compiled
  example) byte for byte.

Usage: /usr/bin/python3 scripts/check_readme_figures.py [--readme README.md] [--root REPO]
Exit status: 0 when every check holds; 1 otherwise, one line per miss
("README.md:LINE: ..." naming the figure and the file); 2 when the README
cannot be read.
"""

import argparse
import os
import re
import sys

MAX_LINES = 300
RESULTS_PREFIX = "scripts/results/"
UNITS = ("ms", "µs", "us", "s", "min", "h", "mm", "cm", "m", "km", "N", "kN", "J", "MiB", "GiB", "KiB", "MB", "GB",
         "kB", "Hz", "kHz", "fps", "Pa", "kPa", "MPa", "°", "deg", "rad", "kg", "g", "N/m", "N/m³", "m/s", "MB/s",
         "avatar-steps/s", "rows/min")
# A number: 1,234 or 12 or 0.175 or 7.7e-10, not part of a word (K96, hm08, x86) or of a longer number.
NUMBER = re.compile(r"(?<![\w.])(\d{1,3}(?:,\d{3})+|\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)(?![\w.]*\d)")
LINK = re.compile(r"\]\(([^)\s]+)\)")
CODE_SPAN = re.compile(r"`[^`]*`")
LINK_TARGET = re.compile(r"\]\([^)]*\)")
WORK_LABEL = re.compile(r"\b(session|issue)s?\s*#?\s*\d+|(?<![\w&])#\d+\b", re.IGNORECASE)
LIST_ITEM = re.compile(r"^\s*(?:[-*+]|\d+\.)\s")
EXAMPLE_MARKER = re.compile(r"^\s*<!--\s*example:\s*(\S+)\s*-->\s*$")


def results_links(line):
    """Targets of the line's links that lie under scripts/results/ (anchors dropped)."""
    out = []
    for target in LINK.findall(line):
        target = target.split("#", 1)[0]
        if target.startswith("./"):
            target = target[2:]
        if target.startswith(RESULTS_PREFIX):
            out.append(target)
    return out


def figures(line):
    """(text as written, kind) of each figure on the line; kind is 'percent' or 'number'."""
    text = CODE_SPAN.sub(" ", line)
    text = LINK_TARGET.sub("]", text)
    found = []
    for m in NUMBER.finditer(text):
        num = m.group(1)
        rest = text[m.end():]
        after = rest.lstrip(" \u00a0\u202f")
        if after.startswith("%"):
            found.append((num, "percent"))
            continue
        has_point = "." in num or "e" in num.lower()
        times = after.startswith("×")
        unit = False
        if not has_point and not times:
            word = re.match(r"[^\s,;:)\]|]+", after)
            if word and rest[:1] in (" ", "\u00a0", "\u202f"):
                unit = word.group(0).rstrip(".") in UNITS
        if has_point or times or unit:
            found.append((num, "number"))
    return found


def occurs(num, kind, content):
    """Whether the figure occurs literally in the file's content."""
    variants = {num, num.replace(",", "")}
    for v in variants:
        esc = re.escape(v)
        if kind == "percent":
            pattern = r"(?<![\w.])" + esc + r"\s?%"
        else:
            pattern = r"(?<![\w.])" + esc + r"(?![\d])(?!\.\d)"
        if re.search(pattern, content):
            return True
    return False


def check(readme_path, root):
    try:
        with open(readme_path, encoding="utf-8") as f:
            lines = f.read().split("\n")
    except OSError as e:
        print(f"check_readme_figures: {readme_path}: cannot read ({e.strerror})", file=sys.stderr)
        return None
    if lines and lines[-1] == "":
        lines.pop()
    name = os.path.basename(readme_path)
    misses = []
    if len(lines) > MAX_LINES:
        misses.append(f"{name}: {len(lines)} lines (at most {MAX_LINES})")

    cache = {}

    def content_of(target):
        if target not in cache:
            try:
                with open(os.path.join(root, target), encoding="utf-8", errors="replace") as f:
                    cache[target] = f.read()
            except OSError:
                cache[target] = None
        return cache[target]

    in_code = False
    section = ""
    units = []          # paragraphs, list items, table rows, headings: {"lines": [(i, text)], ...}
    unit = None         # the paragraph or list item being read (continuation lines join it)
    pending_example = None  # (line number, path) of a marker waiting for its code block
    example_body = None
    example_start = 0
    for i, line in enumerate(lines, start=1):
        stripped = line.strip()
        if stripped.startswith("```"):
            unit = None
            if not in_code:
                in_code = True
                if pending_example:
                    example_body, example_start = [], i
                continue
            in_code = False
            if example_body is not None:
                marker_line, path = pending_example
                want = content_of(path)
                got = "\n".join(example_body) + "\n"
                if want is None:
                    misses.append(f"{name}:{marker_line}: example {path}: cannot read the file")
                elif got != want:
                    misses.append(f"{name}:{example_start}: the code block differs from {path} "
                                  f"(copy the file into the block)")
                example_body, pending_example = None, None
            continue
        if in_code:
            if example_body is not None:
                example_body.append(line)
            continue
        m = EXAMPLE_MARKER.match(line)
        if m:
            pending_example = (i, m.group(1))
            unit = None
            continue
        if pending_example and stripped:
            misses.append(f"{name}:{pending_example[0]}: example marker for {pending_example[1]} "
                          f"is not followed by a code block")
            pending_example = None
        for w in WORK_LABEL.finditer(line):
            misses.append(f"{name}:{i}: names a work session or issue ('{w.group(0)}'): history belongs in git")
        if not stripped:
            unit = None
            continue
        if stripped.startswith("## "):  # level-2 headings make the sections; "###" stays inside one
            section = stripped[3:].strip().lower()
        if stripped.startswith("#") or stripped.startswith("|"):
            caption = []
            if stripped.startswith("|"):
                prev = units[-1] if units else None
                if prev and prev["kind"] == "row":
                    caption = prev["caption"]
                elif prev and prev["kind"] == "text":
                    caption = [t for _, text in prev["lines"] for t in results_links(text)]
            units.append({"kind": "row" if stripped.startswith("|") else "heading", "lines": [(i, line)],
                          "section": section, "caption": caption})
            unit = None
            continue
        if unit is None or LIST_ITEM.match(line):
            unit = {"kind": "text", "lines": [], "section": section, "caption": []}
            units.append(unit)
        unit["lines"].append((i, line))

    for u in units:
        links = list(dict.fromkeys(u["caption"] + [t for _, text in u["lines"] for t in results_links(text)]))
        contents = []
        for t in links:
            c = content_of(t)
            if c is None:
                misses.append(f"{name}:{u['lines'][0][0]}: links {t}, which does not exist")
            else:
                contents.append(c)
        for i, text in u["lines"]:
            found = figures(text)
            if not found:
                continue
            if not links:
                if u["section"] == "results":
                    misses.append(f"{name}:{i}: figures {', '.join(n for n, _ in found)} in \"Results\" "
                                  f"without a link to the scripts/results/ file they come from")
                continue
            for num, kind in found:
                if contents and not any(occurs(num, kind, c) for c in contents):
                    shown = num + (" %" if kind == "percent" else "")
                    misses.append(f"{name}:{i}: '{shown}' is not in {', '.join(links)}")
    if pending_example:
        misses.append(f"{name}:{pending_example[0]}: example marker for {pending_example[1]} "
                      f"is not followed by a code block")
    return misses


def main():
    root_default = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--readme", default=None, help="README to check (default ROOT/README.md)")
    ap.add_argument("--root", default=root_default, help="folder the README's links are relative to")
    args = ap.parse_args()
    readme = args.readme or os.path.join(args.root, "README.md")
    misses = check(readme, args.root)
    if misses is None:
        return 2
    for m in misses:
        print(m, file=sys.stderr)
    if misses:
        print(f"check_readme_figures: {len(misses)} miss(es)", file=sys.stderr)
        return 1
    print(f"check_readme_figures: {readme}: every quoted figure is in its linked results file")
    return 0


if __name__ == "__main__":
    sys.exit(main())
