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
import io
import math
import signal
import sys
from collections import defaultdict

# Two-sided 95 % quantile of Student's t, as core/lab/study_stats.cpp computes it for summary.csv (exact to df 5,
# then the Cornish-Fisher expansion around the normal quantile, within 0.06 % from df 6): the two tools' intervals
# agree. (A table read at the nearest df below was 1 % wide at df 61-119 and 0.6 % narrow past 120.)
T95_SMALL = [12.7062, 4.3027, 3.1824, 2.7764, 2.5706]


def t95(df):
    df = max(df, 1)
    if df <= 5:
        return T95_SMALL[df - 1]
    z, n = 1.959964, float(df)
    return (z + (z ** 3 + z) / (4 * n) + (5 * z ** 5 + 16 * z ** 3 + 3 * z) / (96 * n * n)
            + (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / (384 * n ** 3))


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
    return {p: (100.0 * sum(r["correct"] == "0" for r in ts) / len(ts), sum(r["time_s"] for r in ts) / len(ts))
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


REQUIRED = ["participant", "technique", "scored", "correct", "time_s", "shape", "height", "radius"]


def fail(message):
    sys.exit(f"study_paired.py: {message}")


def read_text(path):
    """The file's text (UTF-8, a byte order mark dropped); exits naming the file, and the line of a byte that is
    not UTF-8."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        fail(f"{e.filename}: {e.strerror}")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data[:e.start].count(b"\n") + 1
        column = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        fail(f"{path}:{line}: not UTF-8 (byte 0x{data[e.start]:02x} at column {column})")


def read_trials(path):
    """The rows of trials.csv, time_s as a float; exits naming the file (and line) where it is not what
    `pseudohaptic study` writes."""
    try:
        reader = csv.DictReader(io.StringIO(read_text(path), newline=""))
        if reader.fieldnames is None:
            fail(f"{path}: empty file, expected a header line (written by `pseudohaptic study`)")
        missing = [c for c in REQUIRED if c not in reader.fieldnames]
        if missing:
            fail(f"{path}: missing column(s) {', '.join(missing)} (written by `pseudohaptic study`)")
        rows = []
        for row in reader:
            if any(row[c] is None for c in REQUIRED):
                fail(f"{path}:{reader.line_num}: fewer cells than the header has")
            try:
                row["time_s"] = float(row["time_s"])
            except ValueError:
                fail(f"{path}:{reader.line_num}: time_s: not a number: {row['time_s']!r}")
            if not math.isfinite(row["time_s"]):
                fail(f"{path}:{reader.line_num}: time_s: not finite: {row['time_s']}")
            for c in ("correct", "scored"):
                if row[c] not in ("0", "1"):
                    fail(f"{path}:{reader.line_num}: {c}: not 0 or 1: {row[c]!r}")
            rows.append(row)
    except csv.Error as e:
        fail(f"{path}:{reader.line_num}: not a CSV file: {e}")
    if not rows:
        fail(f"{path}: no data rows")
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("outdir", help="what `pseudohaptic study OUTDIR` wrote")
    args = parser.parse_args()
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `| head`: end quietly, as the C++ tool does
    path = f"{args.outdir}/trials.csv"
    rows = read_trials(path)
    techniques = []
    for row in rows:
        if row["technique"] not in techniques:
            techniques.append(row["technique"])
    if len(techniques) < 2:
        fail(f"{path}: one technique only ({techniques[0]}): nothing to compare")
    if not any(row["scored"] == "1" for row in rows):
        fail(f"{path}: no scored trials: nothing to compare")
    lines = []
    for a, b, label, keep in COMPARISONS:
        if a not in techniques or b not in techniques:
            continue
        pa, pb = per_participant(rows, a, keep), per_participant(rows, b, keep)
        both = sorted(set(pa) & set(pb))
        if not both:  # no participant has scored trials of both here (a run of few targets)
            continue
        errors = mean_ci([pa[p][0] - pb[p][0] for p in both])
        times = mean_ci([pa[p][1] - pb[p][1] for p in both])
        lines.append(f"| {a} \u2212 {b}, {label} | {signed(errors[0], 2)} \u00b1 {errors[1]:.2f} | "
                     f"{signed(times[0], 2)} \u00b1 {times[1]:.2f} |")
    if not lines:
        fail(f"{path}: no comparison docs/STUDY.md discusses has scored trials of both its techniques from one "
             f"participant (the run has: {', '.join(techniques)})")
    print("| paired difference | error, percentage points | decision time, s |")
    print("|---|---|---|")
    for line in lines:
        print(line)


if __name__ == "__main__":
    main()
