#!/usr/bin/env python3
"""The "Error bounds" table of docs/SPEED_VS_ACCURACY.md, from two runs of `pseudohaptic accuracy`.

Every variant's worst end-position error against the ground truth (end_err_max_px), per method, traversal and
sampling: the maximum over the storages other than 8-bit depth maps, and apart over 8-bit depth maps; for the
full stroke set and for the --small one. The --small columns are the bounds tests/test_tool_accuracy.cpp checks:
the worst case plus a quarter, rounded up to a whole px.

usage: error_bounds.py FULL/variants.csv SMALL/variants.csv   (prints Markdown)
"""
import argparse
import csv
import io
import math
import sys
from collections import OrderedDict


REQUIRED = ["method", "traversal", "storage", "sampling", "end_err_max_px"]


class InputError(Exception):
    pass


def read_text(path):
    """The file's text (UTF-8, a byte order mark dropped); InputError naming the line of a byte that is not."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data[:e.start].count(b"\n") + 1
        column = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise InputError(f"{path}:{line}: not UTF-8 (byte 0x{data[e.start]:02x} at column {column})") from None


def worst_by_group(path):
    """{(method, traversal, sampling): {"other": px, "d8": px}} in the file's order; InputError naming the file
    (and line) where it is not what `pseudohaptic accuracy` writes: no header or no row, a missing column, a
    short row, an end_err_max_px that is not a finite number."""
    groups = OrderedDict()
    reader = csv.DictReader(io.StringIO(read_text(path), newline=""))
    try:
        if reader.fieldnames is None:
            raise InputError(f"{path}: empty file, expected a header line (written by `pseudohaptic accuracy`)")
        missing = [c for c in REQUIRED if c not in reader.fieldnames]
        if missing:
            raise InputError(f"{path}: missing column(s) {', '.join(missing)} (the header has: "
                             f"{', '.join(reader.fieldnames)})")
        for row in reader:
            if any(row[c] is None for c in REQUIRED):
                raise InputError(f"{path}:{reader.line_num}: fewer cells than the header has")
            text = row["end_err_max_px"].strip()
            try:
                px = float(text)
            except ValueError:
                raise InputError(f"{path}:{reader.line_num}: column end_err_max_px: "
                                 f"{'empty' if not text else 'not a number: ' + repr(text)}") from None
            if not math.isfinite(px):
                raise InputError(f"{path}:{reader.line_num}: column end_err_max_px: not finite: {text}")
            key = (row["method"], row["traversal"], row["sampling"])
            kind = "d8" if row["storage"] == "d8" else "other"
            worst = groups.setdefault(key, {})
            worst[kind] = max(worst.get(kind, 0.0), px)
    except csv.Error as e:
        raise InputError(f"{path}:{reader.line_num}: not CSV: {e}") from None
    if not groups:
        raise InputError(f"{path}: no data rows")
    return groups


def bound(px):
    return math.ceil(px * 1.25)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("full", help="FULL/variants.csv: the full accuracy run's")
    parser.add_argument("small", help="SMALL/variants.csv: the --small run's")
    args = parser.parse_args(argv)
    try:
        full, small = (worst_by_group(p) for p in (args.full, args.small))
    except OSError as e:
        print(f"error_bounds.py: {e.filename}: {e.strerror}", file=sys.stderr)
        return 1
    except InputError as e:
        print(f"error_bounds.py: {e}", file=sys.stderr)
        return 1
    print("| method | traversal | sampling | full set, other storage | full set, 8-bit depth "
          "| `--small`, other storage (tested) | `--small`, 8-bit depth (tested) |")
    print("|---|---|---|---:|---:|---:|---:|")
    for key, worst in full.items():
        s = small.get(key, {})
        cells = [f"{worst['other']:.1f}" if "other" in worst else "-", f"{worst['d8']:.1f}" if "d8" in worst else "-",
                 str(bound(s["other"])) if "other" in s else "-", str(bound(s["d8"])) if "d8" in s else "-"]
        print(f"| {' | '.join(key)} | {' | '.join(cells)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
