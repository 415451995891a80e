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
import math
import sys
from collections import OrderedDict


def worst_by_group(path):
    """{(method, traversal, sampling): {"other": px, "d8": px}} in the file's order."""
    groups = OrderedDict()
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            key = (row["method"], row["traversal"], row["sampling"])
            kind = "d8" if row["storage"] == "d8" else "other"
            worst = groups.setdefault(key, {})
            worst[kind] = max(worst.get(kind, 0.0), float(row["end_err_max_px"]))
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
