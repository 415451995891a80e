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
    """(rows, modes, the metrics that have a value): refuses a severity that is not a finite number; warns of
    written values that are not finite numbers, and of a metric column that is missing or has no value (its
    chart is left out)."""
    path = csvdir / "stability.csv"
    rows, header = charts.read_table(path, STABILITY_REQUIRED, ["severity"],
                                     [c for c in NUMERIC if c != "severity"], command="stability")
    bad = rows.nonfinite.get("severity")
    if bad:
        raise InputError(f"{path}:{bad[0][0]}: column severity: not a finite number: {bad[0][1]!r}")
    modes, _ = charts.read_table(csvdir / "modes.csv", ["mode", "family", "severity"], [], command="stability")
    order = [m["mode"] for m in modes]
    unknown = sorted({r["mode"] for r in rows} - set(order))
    if unknown:
        raise InputError(f"{path}: modes not in modes.csv: {', '.join(unknown)}")
    rows.report_nonfinite([m[0] for m in METRICS], "drawn as a triangle at the top of its panel where infinite, "
                          "left out where NaN; the tables show them")
    rows.report_nonfinite([c for c in NUMERIC if c not in [m[0] for m in METRICS] and c != "severity"],
                          "left out (the tables show them)")
    metrics = []
    for metric in METRICS:
        column = metric[0]
        if column not in header:
            charts.warn(f"{path}: no column {column}: stability_{column}.png is not drawn"
                        + ("; its tables' cells show –" if column in BOUNDED else ""))
        elif not any(not math.isnan(r[column]) for r in rows):
            charts.warn(f"{path}: column {column} has no value: stability_{column}.png is not drawn"
                        + ("; its tables' cells show –" if column in BOUNDED else ""))
        else:
            metrics.append(metric)
    return rows, modes, metrics


def severities_of(rows, mode):
    """The mode's severities in the order the run lists them (mildest first)."""
    out = []
    for r in rows:
        if r["mode"] == mode and r["severity"] not in out:
            out.append(r["severity"])
    return out


def panel(ax, mode, rows, methods, variants, metric):
    """Draws one mode's panel; returns what it drew: {(method, variant)}, whether an exact input's line, and
    whether an infinite value (a triangle at the top)."""
    column, _, log, floor, truth_column = metric
    sev = severities_of(rows, mode["mode"])
    drawn, truth_drawn, inf_drawn = set(), False, False
    for method in methods:
        colour = charts.method_colour(method, methods)
        for variant in variants:
            sel = [r for r in rows if r["mode"] == mode["mode"] and r["method"] == method and r["variant"] == variant]
            pts = [(r["severity"], max(r[column], floor) if log else r[column]) for r in sel if finite(r[column])]
            infinite = [r["severity"] for r in sel if r[column] == math.inf]
            if infinite:
                ax.plot(infinite, [1.0] * len(infinite), linestyle="none", marker="^", markersize=6, color=colour,
                        transform=ax.get_xaxis_transform(), clip_on=False, zorder=5)
                drawn.add((method, variant))
                inf_drawn = True
            if not pts:
                continue
            ax.plot([p[0] for p in pts], [p[1] for p in pts], VARIANT_STYLES.get(variant, "-"), color=colour,
                    marker="o", markersize=3, linewidth=1.4)
            drawn.add((method, variant))
            if truth_column and variant == variants[0]:
                tp = [(r["severity"], r[truth_column]) for r in sel if finite(r[truth_column])]
                if tp:
                    ax.plot([p[0] for p in tp], [max(p[1], floor) if log else p[1] for p in tp], ":",
                            color=colour, linewidth=0.9, alpha=0.8)
                    truth_drawn = True
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
    return drawn, truth_drawn, inf_drawn


def chart_metric(rows, modes, methods, variants, metric, outdir):
    if metric[0] == "contrast":
        modes = [m for m in modes if m.get("has_features", "1") == "1"]
    cols = 4
    nrows = math.ceil((len(modes) + 1) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(4.0 * cols, 3.0 * nrows), squeeze=False)
    flat = [a for row in axes for a in row]
    drawn, truth_drawn, inf_drawn = set(), False, False
    for ax, mode in zip(flat, modes):
        d, t, i = panel(ax, mode, rows, methods, variants, metric)
        drawn |= d
        truth_drawn |= t
        inf_drawn |= i
    legend_ax = flat[len(modes)]
    for ax in flat[len(modes):]:
        ax.axis("off")
    name = f"stability_{metric[0]}.png"
    shown_methods = [m for m in methods if any((m, v) in drawn for v in variants)]
    shown_variants = [v for v in variants if any((m, v) in drawn for m in methods)]
    for what, left in (("method", [m for m in methods if m not in shown_methods]),
                       ("variant", [v for v in variants if v not in shown_variants])):
        if left:
            charts.warn(f"{name}: no value of {metric[0]} for {what}(s) {', '.join(left)}: not drawn, not in "
                        f"the legend")
    handles = [plt.Line2D([], [], color=charts.method_colour(m, methods), linewidth=2, label=m)
               for m in shown_methods]
    handles += [plt.Line2D([], [], color="0.3", linestyle=VARIANT_STYLES.get(v, "-"), label=f"engine: {v}")
                for v in shown_variants]
    if metric[4] and truth_drawn:
        handles.append(plt.Line2D([], [], color="0.3", linestyle=":", linewidth=0.9, label="the exact input"))
    elif metric[4] and drawn:
        charts.warn(f"{name}: no value of {metric[4]} for the variant {variants[0]}: the exact input's line is "
                    f"not drawn, not in the legend")
    if inf_drawn:
        handles.append(plt.Line2D([], [], color="0.3", linestyle="none", marker="^", markersize=6,
                                  label="infinite (at the top)"))
    legend_ax.legend(handles=handles, loc="center", fontsize=9, frameon=False)
    fig.suptitle(metric[1], fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    path = outdir / f"stability_{metric[0]}.png"
    fig.savefig(path, dpi=charts.DPI, metadata=charts.SAVE_META)
    plt.close(fig)
    return path


def fmt(v, digits=2):
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
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
            contrast = (f" · {fmt(r['contrast'])} ({fmt(r['contrast_truth'])})" if not math.isnan(r["contrast"])
                        else "")
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
                    if mine is None or None in theirs or math.isnan(mine[metric]):
                        continue
                    values = [r[metric] for r in theirs if not math.isnan(r[metric])]
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
                    if mine is None or None in theirs or math.isnan(mine[metric]):
                        continue
                    values = [(r[metric], p) for r, p in zip(theirs, parents) if not math.isnan(r[metric])]
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
    """v rounded up to two significant digits, at least FLOOR (an infinite v stays infinite)."""
    if v == math.inf:
        return v
    if not finite(v) or v <= FLOOR:
        return FLOOR
    scale = 10 ** (math.floor(math.log10(v)) - 1)
    return math.ceil(v / scale - 1e-9) * scale


def bounds_of(rows, modes, methods, variant):
    """[(mode, method, [bound per BOUNDED metric])]: each metric's worst value over the mode's severities plus a
    quarter, rounded up; None where the metric has no value there (an infinite value gives an infinite bound)."""
    out = []
    for mode in modes:
        for method in methods:
            sel = [r for r in rows if r["mode"] == mode["mode"] and r["method"] == method and r["variant"] == variant]
            if sel:
                values = [[r[c] for r in sel if not math.isnan(r[c])] for c in BOUNDED]
                out.append((mode["mode"], method, [round_up(1.25 * max(v)) if v else None for v in values]))
    return out


def bounds_table(bounds, variant):
    lines = [f"Bounds (variant `{variant}`): per mode and method, each metric's worst value over the severities "
             f"x 1.25, rounded up (at least {FLOOR:g}).", "",
             "| mode | method | " + " | ".join(BOUNDED) + " |", "|---|---|" + "---:|" * len(BOUNDED)]
    for mode, method, values in bounds:
        lines.append(f"| {mode} | {method} | " + " | ".join("–" if v is None else f"{v:.2g}" for v in values) + " |")
    return "\n".join(lines)


def bounds_cpp(bounds):
    """The same as the initialiser list tests/test_tool_stability.cpp holds; InputError where a bound is missing
    or infinite (no test can hold it)."""
    for mode, method, values in bounds:
        for c, v in zip(BOUNDED, values):
            if v is None or not math.isfinite(v):
                raise InputError(f"--bounds-cpp: the bound of {c} for {mode}, {method} is "
                                 f"{'missing' if v is None else 'infinite'}; nothing written")
    return "\n".join(f'{{"{mode}", "{method}", {{' + ", ".join(f"{v:.2g}" for v in values) + "}},"
                     for mode, method, values in bounds)


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.split("\n")[1:]))
    p.add_argument("csvdir", type=Path, help="folder with stability.csv and modes.csv")
    p.add_argument("outdir", type=Path, help="folder to write the PNG files into (created if needed)")
    p.add_argument("--variants",
                   help=f"engine variants to draw, comma-separated (default: {','.join(DEFAULT_VARIANTS)})")
    p.add_argument("--bounds-cpp", type=Path, metavar="FILE",
                   help="also write the bounds as the C++ initialiser list of tests/test_tool_stability.cpp")
    args = p.parse_args(argv)
    try:
        rows, modes, metrics = read_inputs(args.csvdir)
        methods = charts.methods_of(rows)
        present = []
        for r in rows:
            if r["variant"] not in present:
                present.append(r["variant"])
        if args.variants is None:
            variants = [v for v in DEFAULT_VARIANTS if v in present]
            if not variants:
                raise InputError(f"{args.csvdir / 'stability.csv'}: none of the default variants "
                                 f"({', '.join(DEFAULT_VARIANTS)}); it has: {', '.join(present)} (see --variants)")
        else:
            variants = [v.strip() for v in args.variants.split(",") if v.strip()]
            unknown = [v for v in variants if v not in present]
            if unknown or not variants:
                raise InputError(f"--variants {args.variants}: no such variant in stability.csv: "
                                 f"{', '.join(unknown) or '(none named)'}; it has: {', '.join(present)}")
        # Everything is computed, and every output folder checked, before anything is written or printed.
        tables = [summary_table(rows, modes, methods, variants[0]),
                  worse_than_every_other(rows, modes, methods, variants[0])]
        parents = against_better_parent(rows, modes, methods, variants[0])
        if parents:
            tables.append(parents)
        bounds = bounds_of(rows, modes, methods, variants[0])
        tables.append(bounds_table(bounds, variants[0]))
        cpp = bounds_cpp(bounds) + "\n" if args.bounds_cpp else None
        if args.bounds_cpp:
            folder = args.bounds_cpp.parent
            if args.bounds_cpp.is_dir():
                raise InputError(f"{args.bounds_cpp}: a folder (--bounds-cpp names a file)")
            if not folder.is_dir():
                raise InputError(f"{args.bounds_cpp}: no folder {folder} (--bounds-cpp)")
        charts.make_outdir(args.outdir)
        written = [chart_metric(rows, modes, methods, variants, m, args.outdir) for m in metrics]
        if args.bounds_cpp:
            try:
                args.bounds_cpp.write_text(cpp)
            except OSError as e:
                raise InputError(charts.os_error_text(e, args.bounds_cpp)) from None
    except InputError as e:
        print(f"stability_charts.py: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"stability_charts.py: {charts.os_error_text(e, args.outdir)}", file=sys.stderr)
        return 1
    print("\n\n".join(tables))
    for path in written:
        print(f"stability_charts.py: wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
