#!/usr/bin/env python3
"""Charts of the simulated user study (docs/STUDY.md) from the CSV files of `pseudohaptic study`.

    study_charts.py CSVDIR OUTDIR     read CSVDIR/trials.csv and CSVDIR/summary.csv, write the PNGs into OUTDIR

Writes study_errors.png (error rate per height x radius and technique, 95 % CIs over participants, the paper's
overall rates marked), study_times.png (per-participant mean decision times per profile, radius and height for
the paper's two techniques, as boxplots like the paper's Fig. 4; not drawn, with a warning, for a run without
them) and study_techniques.png (every technique's overall error against its time). Reuses tools/charts.py's reader and style; the same input gives the same bytes.
"""

import argparse
import math
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from charts import (DPI, EXTRA_COLOURS, METHOD_COLOURS, SAVE_META, InputError, make_outdir, os_error_text,  # noqa: E402
                    plt, read_table, warn)

SUMMARY_REQUIRED = ["technique", "grouping", "group", "error_pct", "error_lo", "error_hi", "time_s", "time_lo",
                    "time_hi"]
SUMMARY_NUMERIC = ["error_pct", "error_lo", "error_hi", "time_s", "time_lo", "time_hi"]
SUMMARY_OPTIONAL = ["paper_error_pct", "paper_time_s"]
TRIALS_REQUIRED = ["participant", "technique", "scored", "profile", "height", "radius", "time_s"]
PAPER_TECHNIQUES = ["curvature:sign+1", "depth"]  # the paper's two, as `pseudohaptic study` names them
CHANCE = "none"  # the flat control: at chance, and off the scale of the others
HEIGHT_RADIUS = ["h1-r100", "h1-r200", "h0.25-r100", "h0.25-r200"]


def colour_of(technique, techniques):
    base = technique.split(":")[0].split("+")[0]
    if technique in PAPER_TECHNIQUES and base in METHOD_COLOURS:
        return METHOD_COLOURS[base]
    others = [t for t in techniques if t not in PAPER_TECHNIQUES]
    return EXTRA_COLOURS[others.index(technique) % len(EXTRA_COLOURS)] if technique in others else "#333333"


def finite(v):
    return isinstance(v, float) and math.isfinite(v)


def techniques_of(summary):
    out = []
    for r in summary:
        if r["technique"] not in out:
            out.append(r["technique"])
    return out


def check_summary(summary):
    """Refuses what no chart can show: an infinite value, no `overall` row at all. Warns of NaN values (left
    out) and of a 95 % interval that does not hold its value."""
    path = getattr(summary, "path", "summary.csv")
    for r in summary:
        for c in SUMMARY_NUMERIC + SUMMARY_OPTIONAL:
            v = r.get(c, math.nan)
            if isinstance(v, float) and math.isinf(v):
                raise InputError(f"{path}:{r['_line']}: column {c}: infinite")
        for value, lo, hi in (("error_pct", "error_lo", "error_hi"), ("time_s", "time_lo", "time_hi")):
            if r[lo] > r[value] + 1e-9 or r[hi] < r[value] - 1e-9:
                warn(f"{path}:{r['_line']}: {value} {r[value]:g} is outside its interval [{r[lo]:g}, {r[hi]:g}] "
                     f"({lo}, {hi}): its error bar stops at the value on that side")
    overall = [r for r in summary if r["grouping"] == "overall"]
    if not overall:
        raise InputError(f"{path}: no row of grouping `overall` (the techniques' overall error and time)")
    if not any(finite(r["error_pct"]) and finite(r["time_s"]) for r in overall):
        raise InputError(f"{path}: no row of grouping `overall` has a finite error_pct and time_s")
    if hasattr(summary, "report_nonfinite"):
        summary.report_nonfinite(SUMMARY_NUMERIC, "not drawn")


def interval(value, bound):
    """The length of an error bar from value to bound; NaN (no bar) where either is NaN."""
    d = value - bound
    return math.nan if math.isnan(d) else max(0.0, d)


def chart_errors(summary, outdir):
    every = techniques_of(summary)
    techniques = [t for t in every if t != CHANCE]
    rows = {(r["technique"], r["group"]): r for r in summary if r["grouping"] in ("overall", "height_radius")}
    groups = ["all"] + [g for g in HEIGHT_RADIUS if any((t, g) in rows for t in techniques)]
    fig, ax = plt.subplots(figsize=(9.5, 4.6))
    width = 0.8 / max(1, len(techniques))
    paper_labelled = False
    for i, t in enumerate(techniques):
        xs, ys, lo, hi = [], [], [], []
        for gi, g in enumerate(groups):
            r = rows.get((t, g))
            if r is None or not finite(r["error_pct"]):
                continue
            xs.append(gi + (i - (len(techniques) - 1) / 2) * width)
            ys.append(r["error_pct"])
            lo.append(interval(r["error_pct"], r["error_lo"]))
            hi.append(interval(r["error_hi"], r["error_pct"]))
        if not xs:
            warn(f"study_errors.png: technique {t} has no error rate: not drawn, not in the legend")
            continue
        ax.bar(xs, ys, width * 0.92, color=colour_of(t, every), label=t, yerr=[lo, hi], capsize=2,
               error_kw={"elinewidth": 0.8})
        paper = rows.get((t, "all"), {}).get("paper_error_pct", math.nan)
        overall = rows.get((t, "all"), {}).get("error_pct", math.nan)
        if t in PAPER_TECHNIQUES and finite(paper) and finite(overall):
            ax.plot([xs[0]], [paper], marker="D", color="black", markersize=6, zorder=5,
                    label=None if paper_labelled else "paper (overall)")
            paper_labelled = True
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels(["overall"] + [g.replace("h", "height ").replace("-r", ", radius ") for g in groups[1:]])
    ax.set_ylabel("misclassified targets (%)")
    ax.set_ylim(bottom=0)
    ax.set_title("Simulated error rate per height and radius (95 % CI over participants; 'none' is at chance)",
                 fontsize=10)
    ax.legend(fontsize=8, ncol=2)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    path = outdir / "study_errors.png"
    fig.savefig(path, dpi=DPI, metadata=SAVE_META)
    plt.close(fig)
    return path


def chart_times(trials, summary, outdir):
    techniques = [t for t in PAPER_TECHNIQUES if any(r["technique"] == t for r in trials)]
    if not techniques:
        raise InputError("trials.csv has neither of the paper's techniques (" + ", ".join(PAPER_TECHNIQUES) + ")")
    cells = []
    for profile in ("linear", "gaussian", "polynomial"):
        for radius in ("100", "200"):
            for height in ("1", "0.25"):
                cells.append((profile, radius, height))
    # Per participant, the mean time of its scored trials in each cell: what the paper's boxplots show.
    sums = defaultdict(lambda: [0.0, 0])
    for r in trials:
        if r["scored"] != "1" or r["technique"] not in techniques or not finite(r["time_s"]):
            continue
        a = sums[(r["technique"], (r["profile"], r["radius"], r["height"]), r["participant"])]
        a[0] += r["time_s"]
        a[1] += 1
    scored = {t for t, _, _ in sums}
    for t in techniques:
        if t not in scored:
            warn(f"study_times.png: technique {t} has no scored trial with a time: not drawn, not in the legend")
    techniques = [t for t in techniques if t in scored]
    if not techniques:
        raise InputError("trials.csv has no scored trial with a time of the paper's techniques ("
                         + ", ".join(PAPER_TECHNIQUES) + ")")
    fig, ax = plt.subplots(figsize=(11, 4.8))
    width = 0.8 / len(techniques)
    for i, t in enumerate(techniques):
        data, pos = [], []
        for ci, c in enumerate(cells):
            vals = [s / n for (tt, cc, _), (s, n) in sorted(sums.items()) if tt == t and cc == c and n > 0]
            data.append(vals)
            pos.append(ci + (i - (len(techniques) - 1) / 2) * width)
        box = ax.boxplot(data, positions=pos, widths=width * 0.85, patch_artist=True, showfliers=True,
                         flierprops={"markersize": 3})
        for patch in box["boxes"]:
            patch.set_facecolor(colour_of(t, techniques))
            patch.set_alpha(0.6)
        ax.plot([], [], color=colour_of(t, techniques), linewidth=6, alpha=0.6, label=t)
    paper = {r["technique"]: r.get("paper_time_s", math.nan) for r in summary
             if r["grouping"] == "height_radius" and r["group"] == "h0.25-r200"}
    paper_labelled = False
    for i, t in enumerate(techniques):
        p = paper.get(t, math.nan)
        if finite(p):
            xs = [ci + (i - (len(techniques) - 1) / 2) * width for ci, c in enumerate(cells)
                  if c[1] == "200" and c[2] == "0.25"]
            ax.plot(xs, [p] * len(xs), linestyle="none", marker="D", color="black", markersize=5,
                    label=None if paper_labelled else "paper, height 0.25 radius 200 (mean over profiles)")
            paper_labelled = True
    ax.set_xticks(range(len(cells)))
    ax.set_xticklabels([f"{p[:4]}\nr{r} h{h}" for p, r, h in cells], fontsize=8)
    ax.set_ylabel("mean decision time per participant (s)")
    ax.set_ylim(0, 10.5)
    ax.set_title("Simulated decision times by profile, radius and height (like the paper's Fig. 4)", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    path = outdir / "study_times.png"
    fig.savefig(path, dpi=DPI, metadata=SAVE_META)
    plt.close(fig)
    return path


def chart_techniques(summary, outdir):
    techniques = techniques_of(summary)
    overall = {r["technique"]: r for r in summary if r["grouping"] == "overall"}
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    marked = set()
    for t in techniques:
        r = overall.get(t)
        if r is None or not finite(r["time_s"]) or not finite(r["error_pct"]):
            warn(f"study_techniques.png: technique {t} has no overall "
                 f"{'row' if r is None else 'error and time'}: not drawn, not in the legend")
            continue
        ax.errorbar([r["time_s"]], [r["error_pct"]],
                    xerr=[[interval(r["time_s"], r["time_lo"])], [interval(r["time_hi"], r["time_s"])]],
                    yerr=[[interval(r["error_pct"], r["error_lo"])], [interval(r["error_hi"], r["error_pct"])]],
                    marker="o", color=colour_of(t, techniques), label=t, capsize=3)
        method = t.split(":")[0]
        if method not in marked and finite(r.get("paper_error_pct", math.nan)) and finite(
                r.get("paper_time_s", math.nan)):
            marked.add(method)
            ax.plot([r["paper_time_s"]], [r["paper_error_pct"]], marker="D", color=colour_of(t, techniques),
                    markeredgecolor="black", markersize=8, linestyle="none", label=f"paper: {method}")
    ax.set_xlabel("mean decision time (s)")
    ax.set_ylabel("misclassified targets (%)")
    ax.set_ylim(bottom=0)
    ax.set_title("Every technique: error against decision time (95 % CI over participants)", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path = outdir / "study_techniques.png"
    fig.savefig(path, dpi=DPI, metadata=SAVE_META)
    plt.close(fig)
    return path


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.split("\n")[1:]))
    p.add_argument("csvdir", type=Path, help="folder with trials.csv and summary.csv")
    p.add_argument("outdir", type=Path, help="folder to write the PNG files into (created if needed)")
    args = p.parse_args(argv)
    try:
        summary, _ = read_table(args.csvdir / "summary.csv", SUMMARY_REQUIRED, SUMMARY_NUMERIC, SUMMARY_OPTIONAL,
                                command="study")
        trials, _ = read_table(args.csvdir / "trials.csv", TRIALS_REQUIRED, ["time_s"], command="study")
        check_summary(summary)
        infinite = [t for t in trials if math.isinf(t["time_s"])]
        if infinite:
            raise InputError(f"{trials.path}:{infinite[0]['_line']}: column time_s: infinite")
        trials.report_nonfinite(["time_s"], "left out of study_times.png")
        # study_times.png is the paper's Fig. 4, of its two techniques: a run of others (`--technique`) has the
        # other two charts only.
        times = any(r["technique"] in PAPER_TECHNIQUES and r["scored"] == "1" and finite(r["time_s"]) for r in trials)
        if not times:
            warn(f"study_times.png: not drawn: {trials.path} has no scored trial with a time of the paper's "
                 "techniques (" + ", ".join(PAPER_TECHNIQUES) + "), which it shows")
        make_outdir(args.outdir)
        written = [chart_errors(summary, args.outdir)]
        if times:
            written.append(chart_times(trials, summary, args.outdir))
        else:  # an earlier run's would read as this one's
            (args.outdir / "study_times.png").unlink(missing_ok=True)
        written.append(chart_techniques(summary, args.outdir))
    except InputError as e:
        print(f"study_charts.py: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"study_charts.py: {os_error_text(e, args.outdir)}", file=sys.stderr)
        return 1
    for path in written:
        print(f"study_charts.py: wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
