#!/usr/bin/env python3
"""Charts of the failure-mode suite (docs/STABILITY.md) from the CSV files of `pseudohaptic stability`.

    stability_charts.py CSVDIR OUTDIR [--variants V,...]   read CSVDIR, write one PNG per metric into OUTDIR
                                                           (one panel per failure mode, the metric against
                                                           the severity, one line per method and variant),
                                                           print the summary table, where each method is worse
                                                           than every other, the hybrid against the better of
                                                           its parents, and the tests' bounds (Markdown) to
                                                           stdout

Reads stability.csv (mode, severity, method, variant and the metric columns) and modes.csv (mode, family,
severity, has_features, description). Writes stability_<metric>.png for each metric. The exact input's own
jitter and contrast are drawn thin and dotted in the method's colour. Python 3 and matplotlib only; the same
input gives the same bytes. Uses the input and colour machinery of tools/charts.py.
"""

import argparse
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import charts  # noqa: E402  (the accuracy charts' machinery: CSV reading, colours, PNG settings)
from charts import plt, InputError, finite  # noqa: E402

STABILITY_REQUIRED = ["mode", "severity", "method", "variant"]
METRICS = [
    # column, title, log scale, floor for the log scale, the exact input's column
    ("cd_err_rms", "C/D error against the exact input (relative, RMS)", True, 1e-4, None),
    ("jitter_rms", "jitter: RMS change of ln C/D per px", True, 1e-3, "jitter_truth_rms"),
    ("travel_err_pct", "motor travel error against the exact input (%, RMS)", True, 1e-3, None),
    ("travel_sens_pct", "motor travel change for a 0.01 px start offset (%, RMS)", True, 1e-4, None),
    ("iso_pct", "isotropy: travel error at 30/45 deg minus at 0 deg (%, largest)", True, 1e-3, None),
    ("rate_px", "125 Hz against 1000 Hz: distance between the cursors (px)", True, 1e-14, None),
    ("contrast", "contrast at the step or kink (peak C/D within 3 px / surroundings)", True, 1.0, "contrast_truth"),
]
NUMERIC = ["severity"] + [m[0] for m in METRICS] + ["jitter_truth_rms", "contrast_truth", "faults"]
VARIANT_STYLES = {"exact": "-", "exact+bilinear": "--", "unit_steps": ":", "direction_lut16": "-."}
DEFAULT_VARIANTS = ["exact", "exact+bilinear"]
# Severity axes better read on a log scale.
LOG_X = {"grating-a0.5", "grating-a4", "fbm", "thin", "quantised"}


def read_inputs(csvdir):
    rows, _ = charts.read_table(csvdir / "stability.csv", STABILITY_REQUIRED, ["severity"],
                                [c for c in NUMERIC if c != "severity"], command="stability")
    modes, _ = charts.read_table(csvdir / "modes.csv", ["mode", "family", "severity"], [], command="stability")
    order = [m["mode"] for m in modes]
    unknown = sorted({r["mode"] for r in rows} - set(order))
    if unknown:
        raise InputError(f"{csvdir / 'stability.csv'}: modes not in modes.csv: {', '.join(unknown)}")
    return rows, modes


def severities_of(rows, mode):
    """The mode's severities in the order the run lists them (mildest first)."""
    out = []
    for r in rows:
        if r["mode"] == mode and r["severity"] not in out:
            out.append(r["severity"])
    return out


def panel(ax, mode, rows, methods, variants, metric):
    column, _, log, floor, truth_column = metric
    sev = severities_of(rows, mode["mode"])
    drawn = False
    for method in methods:
        colour = charts.method_colour(method, methods)
        for variant in variants:
            pts = [(r["severity"], r[column]) for r in rows
                   if r["mode"] == mode["mode"] and r["method"] == method and r["variant"] == variant]
            pts = [(x, max(y, floor) if log else y) for x, y in pts if finite(y)]
            if not pts:
                continue
            ax.plot([p[0] for p in pts], [p[1] for p in pts], VARIANT_STYLES.get(variant, "-"), color=colour,
                    marker="o", markersize=3, linewidth=1.4)
            drawn = True
            if truth_column and variant == variants[0]:
                tp = [(r["severity"], r[truth_column]) for r in rows if r["mode"] == mode["mode"] and
                      r["method"] == method and r["variant"] == variant and finite(r[truth_column])]
                if tp:
                    ax.plot([p[0] for p in tp], [max(p[1], floor) if log else p[1] for p in tp], ":",
                            color=colour, linewidth=0.9, alpha=0.8)
    ax.set_title(f"{mode['mode']} ({mode['family']})", fontsize=9)
    ax.set_xlabel(mode["severity"], fontsize=8)
    ax.tick_params(labelsize=7)
    if log:
        ax.set_yscale("log")
    if mode["mode"] in LOG_X and all(s > 0 for s in sev):
        ax.set_xscale("log", base=2)
    elif mode["mode"] == "normal-noise":
        ax.set_xscale("symlog", linthresh=0.005)
        ax.set_xlim(left=0)
    if len(sev) > 1 and sev[0] > sev[-1]:
        ax.invert_xaxis()
    ax.grid(True, alpha=0.3, which="both", linewidth=0.5)
    if not drawn:
        ax.text(0.5, 0.5, "no feature" if metric[0] == "contrast" else "no data", transform=ax.transAxes,
                ha="center", va="center", fontsize=8, color="0.5")


def chart_metric(rows, modes, methods, variants, metric, outdir):
    if metric[0] == "contrast":
        modes = [m for m in modes if m.get("has_features", "1") == "1"]
    cols = 4
    nrows = math.ceil((len(modes) + 1) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.0 * cols, 3.0 * nrows), squeeze=False)
    flat = [a for row in axes for a in row]
    for ax, mode in zip(flat, modes):
        panel(ax, mode, rows, methods, variants, metric)
    legend_ax = flat[len(modes)]
    for ax in flat[len(modes):]:
        ax.axis("off")
    handles = [plt.Line2D([], [], color=charts.method_colour(m, methods), linewidth=2, label=m) for m in methods]
    handles += [plt.Line2D([], [], color="0.3", linestyle=VARIANT_STYLES.get(v, "-"), label=f"engine: {v}")
                for v in variants]
    if metric[4]:
        handles.append(plt.Line2D([], [], color="0.3", linestyle=":", linewidth=0.9, label="the exact input"))
    legend_ax.legend(handles=handles, loc="center", fontsize=9, frameon=False)
    fig.suptitle(metric[1], fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    path = outdir / f"stability_{metric[0]}.png"
    fig.savefig(path, dpi=charts.DPI, metadata=charts.SAVE_META)
    plt.close(fig)
    return path


def fmt(v, digits=2):
    if not finite(v):
        return "–"
    if v == 0:
        return "0"
    if abs(v) >= 100 or abs(v) < 0.01:
        return f"{v:.1e}"
    return f"{v:.{digits}g}" if abs(v) < 1 else f"{v:.{digits + 1}g}"


def summary_table(rows, modes, methods, variant):
    """At each mode's harshest severity, per method: C/D error, jitter (exact input's), travel sensitivity,
    isotropy, contrast (exact input's)."""
    lines = [f"Engine variant `{variant}`; each mode at its harshest severity. Cells: C/D error · jitter "
             f"(exact input) · travel sensitivity % · isotropy % · contrast (exact input).", "",
             "| mode | harshest | " + " | ".join(methods) + " |",
             "|---|---|" + "---|" * len(methods)]
    for mode in modes:
        sev = severities_of(rows, mode["mode"])
        if not sev:
            continue
        worst = sev[-1]
        cells = []
        for method in methods:
            r = next((r for r in rows if r["mode"] == mode["mode"] and r["method"] == method and
                      r["variant"] == variant and r["severity"] == worst), None)
            if r is None:
                cells.append("–")
                continue
            contrast = (f" · {fmt(r['contrast'])} ({fmt(r['contrast_truth'])})" if finite(r["contrast"]) else "")
            cells.append(f"{fmt(r['cd_err_rms'])} · {fmt(r['jitter_rms'])} ({fmt(r['jitter_truth_rms'])}) · "
                         f"{fmt(r['travel_sens_pct'])} · {fmt(r['iso_pct'])}{contrast}")
        lines.append(f"| {mode['mode']} | {fmt(worst, 3)} | " + " | ".join(cells) + " |")
    faults = sum(r["faults"] for r in rows if finite(r["faults"]))
    lines += ["", f"Faults (NaN, C/D out of bounds, strokes that never ended) over all rows: {faults:.0f}."]
    return "\n".join(lines)


BOUNDED = ["cd_err_rms", "jitter_rms", "travel_err_pct", "travel_sens_pct", "iso_pct"]
# A method is worse than another on a metric where its value exceeds the other's by more than a tenth and by more
# than this (values below it are rounding).
WORSE_MARGIN = 1e-3


def worse_than_every_other(rows, modes, methods, variant):
    """Where a method is worse than every other method of the run (lower is better on each BOUNDED metric), per
    method, mode and metric: the severities, and the values at the one where the gap to the worst of the others is
    largest. Each method is measured against its own exact input, so this compares what the maps and the walk do
    to each; a method built from others (the hybrid from curvature and depth) should never be here."""
    if len(methods) < 2:
        return "Where a method is worse than every other: one method only."
    lines = [f"Where a method is worse than every other (variant `{variant}`; by more than a tenth and more than "
             f"{WORSE_MARGIN:g}): the severities, and at the one with the largest gap the method's value (the others', "
             "in the order of the other columns).", "",
             "| method | mode | metric | severities | value (the others') |", "|---|---|---|---|---|"]
    at = {(r["mode"], r["severity"], r["method"]): r for r in rows if r["variant"] == variant}
    for method in methods:
        others = [m for m in methods if m != method]
        for mode in modes:
            for metric in BOUNDED:
                found = []
                for sev in severities_of(rows, mode["mode"]):
                    mine = at.get((mode["mode"], sev, method))
                    theirs = [at.get((mode["mode"], sev, m)) for m in others]
                    if mine is None or None in theirs or not finite(mine[metric]):
                        continue
                    values = [r[metric] for r in theirs if finite(r[metric])]
                    if not values:
                        continue
                    worst = max(values)
                    if mine[metric] > 1.1 * worst + WORSE_MARGIN:
                        found.append((mine[metric] / max(worst, WORSE_MARGIN), sev, mine[metric], values))
                if found:
                    _, sev, value, values = max(found)
                    sevs = ", ".join(fmt(f[1], 3) for f in sorted(found, key=lambda f: f[1]))
                    theirs = ", ".join(fmt(v) for v in values)
                    lines.append(f"| {method} | {mode['mode']} | {metric} | {sevs} | {fmt(value)} at {fmt(sev, 3)} "
                                 f"({theirs}) |")
    return "\n".join(lines)
# Methods built from others, and what they are built from, for docs/STABILITY.md's "The hybrid against the better of
# its parents" (its aim: at least as good as the better parent on every failure mode).
COMPOSITES = {"hybrid": ("curvature", "depth")}
METRIC_NAMES = {"cd_err_rms": "C/D error", "jitter_rms": "jitter", "travel_err_pct": "travel error",
                "travel_sens_pct": "travel sensitivity", "iso_pct": "isotropy"}


def against_better_parent(rows, modes, methods, variant):
    """Per failure mode, how a method built from others (COMPOSITES) compares with the better of them on each BOUNDED
    metric, severity by severity: as good (within a tenth, or 0.001), better than both (by more), or behind the
    better one, with the largest gap's severity and values. Lower is better on every one of these metrics."""
    lines = []
    at = {(r["mode"], r["severity"], r["method"]): r for r in rows if r["variant"] == variant}
    for method, parents in COMPOSITES.items():
        if method not in methods or any(p not in methods for p in parents):
            continue
        lines += [f"`{method}` against the better of {' and '.join(parents)} (variant `{variant}`), severity by "
                  "severity: where it is behind the better one by more than a tenth (and 0.001), the metric, its "
                  "severities and, at the one with the largest gap, its value against the better parent's; where it "
                  "is better than both by as much, the metrics.", "",
                  "| mode | behind the better parent | better than both on |", "|---|---|---|"]
        for mode in modes:
            behind, ahead = [], []
            for metric in BOUNDED:
                gaps, better = [], False
                for sev in severities_of(rows, mode["mode"]):
                    mine = at.get((mode["mode"], sev, method))
                    theirs = [at.get((mode["mode"], sev, p)) for p in parents]
                    if mine is None or None in theirs or not finite(mine[metric]):
                        continue
                    values = [(r[metric], p) for r, p in zip(theirs, parents) if finite(r[metric])]
                    if not values:
                        continue
                    best, who = min(values)
                    if mine[metric] > 1.1 * best + WORSE_MARGIN:
                        gaps.append((mine[metric] / max(best, WORSE_MARGIN), sev, mine[metric], best, who))
                    elif mine[metric] * 1.1 + WORSE_MARGIN < best:
                        better = True
                if gaps:
                    _, sev, value, best, who = max(gaps)
                    sevs = ", ".join(fmt(g[1], 3) for g in sorted(gaps, key=lambda g: g[1]))
                    behind.append(f"{METRIC_NAMES[metric]} at {sevs} ({fmt(value)} against {who}'s {fmt(best)} at "
                                  f"{fmt(sev, 3)})")
                elif better:
                    ahead.append(METRIC_NAMES[metric])
            lines.append(f"| {mode['mode']} | {'; '.join(behind) or '–'} | {', '.join(ahead) or '–'} |")
    return "\n".join(lines)


FLOOR = 1e-3  # no bound below this: values under it are rounding, and may differ between builds


def round_up(v):
    """v rounded up to two significant digits, at least FLOOR."""
    if not finite(v) or v <= FLOOR:
        return FLOOR
    scale = 10 ** (math.floor(math.log10(v)) - 1)
    return math.ceil(v / scale - 1e-9) * scale


def bounds_of(rows, modes, methods, variant):
    """[(mode, method, [bound per BOUNDED metric])]: each metric's worst value over the mode's severities plus a
    quarter, rounded up."""
    out = []
    for mode in modes:
        for method in methods:
            sel = [r for r in rows if r["mode"] == mode["mode"] and r["method"] == method and r["variant"] == variant]
            if sel:
                out.append((mode["mode"], method,
                            [round_up(1.25 * max(r[c] for r in sel if finite(r[c]))) for c in BOUNDED]))
    return out


def bounds_table(bounds, variant):
    lines = [f"Bounds (variant `{variant}`): per mode and method, each metric's worst value over the severities "
             f"x 1.25, rounded up (at least {FLOOR:g}).", "",
             "| mode | method | " + " | ".join(BOUNDED) + " |", "|---|---|" + "---:|" * len(BOUNDED)]
    for mode, method, values in bounds:
        lines.append(f"| {mode} | {method} | " + " | ".join(f"{v:.2g}" for v in values) + " |")
    return "\n".join(lines)


def bounds_cpp(bounds):
    """The same as the initialiser list tests/test_tool_stability.cpp holds."""
    return "\n".join(f'{{"{mode}", "{method}", {{' + ", ".join(f"{v:.2g}" for v in values) + "}},"
                     for mode, method, values in bounds)


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.split("\n")[1:]))
    p.add_argument("csvdir", type=Path, help="folder with stability.csv and modes.csv")
    p.add_argument("outdir", type=Path, help="folder to write the PNG files into (created if needed)")
    p.add_argument("--variants", default=",".join(DEFAULT_VARIANTS),
                   help=f"engine variants to draw, comma-separated (default: {','.join(DEFAULT_VARIANTS)})")
    p.add_argument("--bounds-cpp", type=Path, metavar="FILE",
                   help="also write the bounds as the C++ initialiser list of tests/test_tool_stability.cpp")
    args = p.parse_args(argv)
    try:
        rows, modes = read_inputs(args.csvdir)
        methods = charts.methods_of(rows)
        present = {r["variant"] for r in rows}
        variants = [v for v in args.variants.split(",") if v in present]
        if not variants:
            raise InputError(f"--variants {args.variants}: none of them in stability.csv")
        args.outdir.mkdir(parents=True, exist_ok=True)
        written = [chart_metric(rows, modes, methods, variants, m, args.outdir) for m in METRICS]
    except InputError as e:
        print(f"stability_charts.py: {e}", file=sys.stderr)
        return 1
    print(summary_table(rows, modes, methods, variants[0]))
    print()
    print(worse_than_every_other(rows, modes, methods, variants[0]))
    parents = against_better_parent(rows, modes, methods, variants[0])
    if parents:
        print()
        print(parents)
    bounds = bounds_of(rows, modes, methods, variants[0])
    print()
    print(bounds_table(bounds, variants[0]))
    if args.bounds_cpp:
        args.bounds_cpp.write_text(bounds_cpp(bounds) + "\n")
    for path in written:
        print(f"stability_charts.py: wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
