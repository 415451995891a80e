#!/usr/bin/env python3
"""Paired differences between the techniques of a simulated study (docs/STUDY.md).

    tools/study_paired.py OUTDIR      (OUTDIR: what `pseudohaptic study OUTDIR` wrote)

Every participant meets every technique with the same hands and noise, so a difference between two
techniques is taken per participant first: error rate (percentage points) and mean decision time over
the scored trials, then the mean over participants with a 95 % interval (Student's t). Prints a Markdown
table of the comparisons docs/STUDY.md discusses; a comparison whose techniques the run lacks is left out.
"""

import argparse
import csv
import math
import sys
from collections import defaultdict

# Two-sided 95 % quantiles of Student's t for small samples; the normal quantile beyond.
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228,
       11: 2.201, 15: 2.131, 20: 2.086, 30: 2.042, 60: 2.000, 120: 1.980}


def t95(df):
    known = [k for k in sorted(T95) if k <= df]
    return T95[known[-1]] if df <= 120 else 1.960


def everything(_row):
    return True


def cell(height, radius):
    return lambda row: row["height"] == height and row["radius"] == radius


def shape(name):
    return lambda row: row["shape"] == name


COMPARISONS = [
    ("curvature:sign+1", "depth", "all targets", everything),
    ("curvature:sign-1", "depth", "all targets", everything),
    ("curvature:sign+1", "depth", "height 0.25, radius 200", cell("0.25", "200")),
    ("curvature:sign+1", "depth", "height 0.25, radius 100", cell("0.25", "100")),
    ("curvature:sign+1", "depth", "height 1, radius 200", cell("1", "200")),
    ("curvature:sign-1", "curvature:sign+1", "all targets", everything),
    ("curvature:sign-1", "curvature:sign+1", "bumps", shape("bump")),
    ("curvature:sign-1", "curvature:sign+1", "holes", shape("hole")),
    ("hybrid", "curvature:sign+1", "all targets", everything),
    ("hybrid", "depth", "all targets", everything),
    ("curvature+wells", "curvature:sign+1", "all targets", everything),
    ("curvature+materials", "depth", "all targets", everything),
]


def per_participant(rows, technique, keep):
    """participant -> (error %, mean time s) over the scored trials `keep` takes."""
    trials = defaultdict(list)
    for row in rows:
        if row["technique"] == technique and row["scored"] == "1" and keep(row):
            trials[row["participant"]].append(row)
    return {p: (100.0 * sum(r["correct"] == "0" for r in ts) / len(ts), sum(float(r["time_s"]) for r in ts) / len(ts))
            for p, ts in trials.items()}


def mean_ci(values):
    n = len(values)
    mean = sum(values) / n
    if n < 2:
        return mean, float("nan")
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    return mean, t95(n - 1) * sd / math.sqrt(n)


def signed(value, digits):
    text = f"{value:+.{digits}f}"
    return text.replace("-", "\u2212")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir", help="what `pseudohaptic study OUTDIR` wrote")
    args = parser.parse_args()
    try:
        with open(f"{args.outdir}/trials.csv", newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"study_paired.py: {e.filename}: {e.strerror}")
    techniques = {row["technique"] for row in rows}
    print("| paired difference | error, percentage points | decision time, s |")
    print("|---|---|---|")
    for a, b, label, keep in COMPARISONS:
        if a not in techniques or b not in techniques:
            continue
        pa, pb = per_participant(rows, a, keep), per_participant(rows, b, keep)
        both = sorted(set(pa) & set(pb))
        errors = mean_ci([pa[p][0] - pb[p][0] for p in both])
        times = mean_ci([pa[p][1] - pb[p][1] for p in both])
        print(f"| {a} \u2212 {b}, {label} | {signed(errors[0], 2)} \u00b1 {errors[1]:.2f} | "
              f"{signed(times[0], 2)} \u00b1 {times[1]:.2f} |")


if __name__ == "__main__":
    main()
