#!/usr/bin/env python3
"""Charts of speed against accuracy (docs/SPEED_VS_ACCURACY.md) from the CSV files of `pseudohaptic accuracy`.

    charts.py CSVDIR OUTDIR [--default VARIANT]...   read CSVDIR, write the PNGs into OUTDIR, print the
                                                     Pareto table (Markdown) to stdout
    charts.py --fake-data CSVDIR                     write made-up CSV files (and a FAKE marker) to develop
                                                     and test against; their charts say FAKE DATA while
                                                     the marker is newer than the files (a run of
                                                     `pseudohaptic accuracy` into CSVDIR leaves it older);
                                                     refuses a CSVDIR of measurements

Reads (columns in any order; extra columns are ignored; an empty cell is "not measured"):
  variants.csv      variant,method,ns_per_frame_median,end_err_rms_px required; traversal, storage, sampling,
                    ns_per_frame_p99, ns_per_step, bytes_per_texel, precompute_ms, cd_err_rms, cd_err_max,
                    end_err_max_px, drift_px, default (1 marks the daemon's default) optional
  fig5_traces.csv   target,method,x,cd required; cd_truth optional
  fig2_grid.csv     cos_alpha,delta_beta_deg,cd required
Writes speed_vs_accuracy.png, fig5_traces.png and fig2_cd_surface.png. Python 3 and matplotlib only
(Debian's python3-matplotlib); the Agg backend; the same input gives the same bytes (no timestamps).
"""

import argparse
import csv
import errno
import io
import math
import os
import random
import re
import sys
from pathlib import Path

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.lines import Line2D
except ImportError as e:  # pragma: no cover - depends on the machine
    # (Named as the script run: stability_charts.py imports this one.)
    sys.exit(f"{os.path.basename(sys.argv[0]) or 'charts.py'}: {e}; install Debian's python3-matplotlib "
             f"(scripts/install-deps) and run it with /usr/bin/python3 if another python3 comes first on PATH")

DPI = 110
SAVE_META = {"Software": None}  # no version or date in the PNG: same input, same bytes

VARIANT_REQUIRED = ["variant", "method", "ns_per_frame_median", "end_err_rms_px"]
VARIANT_NUMERIC = ["ns_per_frame_median", "ns_per_frame_p99", "ns_per_step", "bytes_per_texel", "precompute_ms",
                   "cd_err_rms", "cd_err_max", "end_err_rms_px", "end_err_max_px", "drift_px"]
FIG5_REQUIRED = ["target", "method", "x", "cd"]
FIG2_REQUIRED = ["cos_alpha", "delta_beta_deg", "cd"]

METHOD_COLOURS = {"curvature": "#1f77b4", "depth": "#d62728"}
EXTRA_COLOURS = ["#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"]
TRAVERSAL_MARKERS = {"exact": "o", "unit_steps": "s", "frame_midpoint": "^", "direction_lut8": "D",
                     "direction_lut16": "P"}
EXTRA_MARKERS = ["v", "X", "h", "<", ">", "p", "*"]
TRAVERSAL_SHORT = {"exact": "exact", "unit_steps": "unit", "frame_midpoint": "mid", "direction_lut8": "lut8",
                   "direction_lut16": "lut16"}
SAMPLING_SHORT = {"nearest": "nn", "bilinear": "bl"}


class InputError(Exception):
    pass


def warn(message):
    """A warning on stderr, in the scripts' style: `SCRIPT: message`."""
    print(f"{Path(sys.argv[0]).name}: {message}", file=sys.stderr)


def make_outdir(path):
    """Creates the output folder (and its parents); InputError naming it when it cannot be one."""
    if path.exists() and not path.is_dir():
        raise InputError(f"{path}: not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"{e.filename or path}: {e.strerror}") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise InputError(f"{path}: {os.strerror(errno.EACCES)}")


def os_error_text(e, fallback):
    """`PATH: reason` for an OSError raised while writing `fallback` (or a file in it)."""
    return f"{e.filename or fallback}: {e.strerror or e}"


# ---------------------------------------------------------------------------------------------------- input

class Rows(list):
    """The rows of a CSV file, with the file (`path`) and, per numeric column, the lines whose cell was written
    but is not a finite number (`nonfinite`: column -> [(line, text)])."""

    def __init__(self, path):
        super().__init__()
        self.path = path
        self.nonfinite = {}

    def report_nonfinite(self, columns, what):
        """Warns once per column of `columns` that has written non-finite cells: the file, the first line, the
        column, how many, and `what` became of them. Returns whether any was reported."""
        any_reported = False
        for c in columns:
            where = self.nonfinite.get(c)
            if where:
                texts = sorted({t for _, t in where})
                warn(f"{self.path}:{where[0][0]}: column {c}: {len(where)} value(s) not finite "
                     f"({', '.join(texts)}), {what}")
                any_reported = True
        return any_reported


def parse_number(text, path, line, column, required):
    """The cell as a float; NaN for an empty optional cell; InputError for anything else unparsable."""
    s = (text or "").strip()
    if s == "":
        if required:
            raise InputError(f"{path}:{line}: column {column} is empty")
        return math.nan
    try:
        return float(s)
    except ValueError:
        raise InputError(f"{path}:{line}: column {column}: not a number: {s!r}") from None


def read_text(path):
    """The file's text (UTF-8, a byte order mark dropped); InputError naming the file, and the line of a byte
    that is not UTF-8."""
    try:
        data = path.read_bytes()
    except OSError as e:
        raise InputError(f"{path}: {e.strerror or e}") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data[:e.start].count(b"\n") + 1
        column = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise InputError(f"{path}:{line}: not UTF-8 (byte 0x{data[e.start]:02x} at column {column})") from None
    if "\0" in text:
        at = text.index("\0")
        raise InputError(f"{path}:{text.count(chr(10), 0, at) + 1}: a NUL byte (not a text file)")
    return text


def read_table(path, required, numeric_required, numeric_optional=(), command="accuracy"):
    """Rows of a CSV file as dicts (numbers parsed, "_line" the line), a Rows list; InputError naming the file
    when it or a column is missing. `command`: the pseudohaptic command that writes the file, for the message
    when it is missing."""
    if path.exists() and not path.is_file():
        raise InputError(f"{path}: not a file")
    if not path.is_file():
        raise InputError(f"{path}: no such file (written by `pseudohaptic {command} {path.parent}`)")
    reader = csv.reader(io.StringIO(read_text(path), newline=""))
    try:
        header = next(reader, None)
        if header is None:
            raise InputError(f"{path}: empty file, expected a header line")
        header = [h.strip() for h in header]
        missing = [c for c in required if c not in header]
        if missing:
            raise InputError(f"{path}: missing required column(s) {', '.join(missing)} "
                             f"(the header has: {', '.join(header)})")
        rows = Rows(path)
        checked = [(c, header.index(c)) for c in list(numeric_required) + list(numeric_optional) if c in header]
        for line, cells in enumerate(reader, start=2):
            if not cells or all(not c.strip() for c in cells):
                continue
            if len(cells) != len(header):
                raise InputError(f"{path}:{line}: {len(cells)} cells, the header has {len(header)}")
            row = {h: c.strip() for h, c in zip(header, cells)}
            for c in numeric_required:
                row[c] = parse_number(row[c], path, line, c, True)
            for c in numeric_optional:
                if c in row:
                    row[c] = parse_number(row[c], path, line, c, False)
                else:
                    row[c] = math.nan
            for c, i in checked:
                if not math.isfinite(row[c]) and cells[i].strip():
                    rows.nonfinite.setdefault(c, []).append((line, cells[i].strip()))
            row["_line"] = line
            rows.append(row)
    except csv.Error as e:
        raise InputError(f"{path}:{reader.line_num}: not CSV: {e}") from None
    if not rows:
        raise InputError(f"{path}: no data rows")
    return rows, header


def read_variants(csvdir):
    rows, header = read_table(csvdir / "variants.csv", VARIANT_REQUIRED, [],
                              [c for c in VARIANT_NUMERIC])
    seen = set()
    for r in rows:
        if r["variant"] in seen:
            raise InputError(f"{csvdir / 'variants.csv'}: variant {r['variant']!r} appears twice")
        seen.add(r["variant"])
        for c in ("traversal", "storage", "sampling"):
            r.setdefault(c, "")
        r["_default"] = r["default"].lower() in ("1", "true", "yes") if "default" in header else None
    return rows, header


def finite(v):
    return isinstance(v, float) and math.isfinite(v)


# ---------------------------------------------------------------------------------------------------- Pareto

def pareto_front(points):
    """Indices of the non-dominated points (lower x and lower y are better), sorted by x."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best_y = [], math.inf
    for i in order:
        if points[i][1] < best_y:
            front.append(i)
            best_y = points[i][1]
    return front


ERROR_KEYS = ("cd_err_rms", "cd_err_max", "end_err_rms_px", "end_err_max_px", "drift_px")


def same_walk(v):
    """What variants share whose every error is the same to the digits written: they walked the same steps over
    the same values (auto choosing the exact walk on every shape), and their times differ by the noise alone."""
    return tuple(v.get(k) for k in ERROR_KEYS)


def fronts_for(variants, ykey):
    """{"all": list of variant names, <method>: list}, fastest first, of the Pareto fronts in (ns per frame, ykey).
    A variant that is the same walk as one on a front (same_walk) is on it too: a few ns of noise between two runs
    of the same computation decide nothing."""
    ok = [v for v in variants if finite(v["ns_per_frame_median"]) and finite(v[ykey])]
    result = {}
    groups = [("all", ok)] + [(m, [v for v in ok if v["method"] == m]) for m in methods_of(variants)]
    for name, group in groups:
        pts = [(v["ns_per_frame_median"], v[ykey]) for v in group]
        front = {group[i]["variant"] for i in pareto_front(pts)}
        walks = {same_walk(v) for v in group if v["variant"] in front}
        members = [v for v in group if v["variant"] in front or same_walk(v) in walks]
        result[name] = [v["variant"] for v in sorted(members, key=lambda v: (v["ns_per_frame_median"], v[ykey]))]
    return result


COST_KEYS = ("ns_per_frame_median", "bytes_per_texel", "precompute_ms")


def cost_value(v, k):
    """v's value of k for the fronts of all costs: None where it has none (an empty cell, NaN or -inf); +inf is a
    value, the worst one."""
    x = v.get(k)
    if not isinstance(x, float) or math.isnan(x) or x == -math.inf:
        return None
    return x


def cost_front(group, ykey):
    """Names of the variants no other variant of the group dominates on every cost counted as speed
    (time per frame, memory per texel, precompute time) and on ykey at once. Each variant is judged over the
    costs it has, against the variants that have every one of those: a variant that lacks a cost cannot put
    another off the front, and does not change the costs another is judged on. One whose ykey is missing, or
    whose cost or ykey is infinite, is on no front."""
    keys = list(COST_KEYS) + [ykey]
    values = [{k: cost_value(v, k) for k in keys} for v in group]
    front = set()
    for i, v in enumerate(group):
        mine = values[i]
        if mine[ykey] is None:
            continue
        own = [k for k in keys if mine[k] is not None]
        if any(math.isinf(mine[k]) for k in own):
            continue

        def dominates(theirs):
            if any(theirs[k] is None for k in own):
                return False
            return all(theirs[k] <= mine[k] for k in own) and any(theirs[k] < mine[k] for k in own)
        if not any(dominates(values[j]) for j in range(len(group)) if j != i):
            front.add(v["variant"])
    return front


def warn_costs(variants, header, path):
    """Warns which variants lack which cost of the fronts of all costs (and which have an infinite one)."""
    for k in COST_KEYS:
        if k not in header:
            warn(f"{path}: no column {k}: the fronts of all costs leave it out")
            continue
        lacking = [v for v in variants if cost_value(v, k) is None]
        if lacking:
            warn(f"{path}:{lacking[0]['_line']}: column {k}: no value (empty, NaN or -inf) for "
                 f"{', '.join(v['variant'] for v in lacking)}: on the front of all costs each is judged without "
                 f"it, and puts no variant that has it off that front (the table marks with '?' where it might)")
        infinite = [v for v in variants if cost_value(v, k) == math.inf]
        if infinite:
            warn(f"{path}:{infinite[0]['_line']}: column {k}: infinite for "
                 f"{', '.join(v['variant'] for v in infinite)}: on no front of all costs")


def cost_front_doubts(group, ykey, front):
    """{name: [names]}: for each member of the front (cost_front), the variants that lack a cost it has and would
    put it off the front were that cost low enough (they are at least as good on every cost they have)."""
    keys = list(COST_KEYS) + [ykey]
    values = {v["variant"]: {k: cost_value(v, k) for k in keys} for v in group}
    doubts = {}
    for name in front:
        mine = values[name]
        own = [k for k in keys if mine[k] is not None]
        for v in group:
            theirs = values[v["variant"]]
            if v["variant"] == name or theirs[ykey] is None:
                continue
            shared = [k for k in own if theirs[k] is not None]
            if len(shared) < len(own) and all(theirs[k] <= mine[k] for k in shared):
                doubts.setdefault(name, []).append(v["variant"])
    return doubts


def cost_fronts_for(variants, ykey):
    """{<method>: set of names} of the fronts over all costs against ykey, among each method's variants."""
    return {m: cost_front([v for v in variants if v["method"] == m], ykey) for m in methods_of(variants)}


def cost_doubts_for(variants, ykey, fronts):
    """{name: [names]} of cost_front_doubts over every method's front."""
    out = {}
    for m, front in fronts.items():
        out.update(cost_front_doubts([v for v in variants if v["method"] == m], ykey, front))
    return out


def methods_of(rows):
    out = []
    for r in rows:
        if r["method"] not in out:
            out.append(r["method"])
    known = [m for m in METHOD_COLOURS if m in out]
    return known + sorted(m for m in out if m not in METHOD_COLOURS)


def method_colour(method, methods):
    if method in METHOD_COLOURS:
        return METHOD_COLOURS[method]
    extra = [m for m in methods if m not in METHOD_COLOURS]
    return EXTRA_COLOURS[extra.index(method) % len(EXTRA_COLOURS)]


def traversal_marker(traversal, traversals):
    if not traversal:
        return "o"
    if traversal in TRAVERSAL_MARKERS:
        return TRAVERSAL_MARKERS[traversal]
    extra = [t for t in traversals if t and t not in TRAVERSAL_MARKERS]
    return EXTRA_MARKERS[extra.index(traversal) % len(EXTRA_MARKERS)] if traversal in extra else "o"


def short_label(v):
    """A short point label: traversal, storage and sampling abbreviated (the method is the colour)."""
    if v["traversal"] or v["storage"] or v["sampling"]:
        parts = [TRAVERSAL_SHORT.get(v["traversal"], v["traversal"]), v["storage"],
                 SAMPLING_SHORT.get(v["sampling"], v["sampling"])]
        return " ".join(p for p in parts if p)
    name = v["variant"]
    prefix = v["method"] + "/"
    return name[len(prefix):] if name.startswith(prefix) else name


def is_default(v, defaults):
    """Whether v is the daemon's default: named by --default, else marked in an optional `default` column
    (1/true/yes), else the exact traversal with f32 storage and nearest sampling."""
    if defaults:
        return v["variant"] in defaults
    if v["_default"] is not None:
        return v["_default"]
    return v["traversal"] == "exact" and v["storage"] == "f32" and v["sampling"] == "nearest"


# ---------------------------------------------------------------------------------------------------- charts

def fake_watermark(fig, fake):
    if fake:
        fig.text(0.5, 0.5, "FAKE DATA", fontsize=70, color="red", alpha=0.18, rotation=25, ha="center",
                 va="center", zorder=100)


def staircase(front_pts, xlim, ylim):
    """The attainment staircase of a Pareto front (sorted by x): down from the top, right to the edge."""
    xs, ys = [front_pts[0][0]], [ylim[1]]
    for i, (x, y) in enumerate(front_pts):
        if i > 0:
            xs.append(x)
            ys.append(front_pts[i - 1][1])
        xs.append(x)
        ys.append(y)
    xs.append(xlim[1])
    ys.append(front_pts[-1][1])
    return xs, ys


def place_labels(fig, ax, items):
    """Annotates points with labels that do not overlap each other or other markers; items are
    (x, y, text, must, bold). A label that fits nowhere is dropped unless must is set."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    axbox = ax.get_window_extent(renderer)
    obstacles = []
    for x, y, *_ in items:
        px, py = ax.transData.transform((x, y))
        obstacles.append(matplotlib.transforms.Bbox([[px - 4, py - 4], [px + 4, py + 4]]))
    offsets = [(6, 3, "left", "bottom"), (6, -3, "left", "top"), (-6, 3, "right", "bottom"),
               (-6, -3, "right", "top"), (0, 8, "center", "bottom"), (0, -8, "center", "top"),
               (12, 10, "left", "bottom"), (12, -10, "left", "top"), (-12, 10, "right", "bottom"),
               (-12, -10, "right", "top")]
    placed, dropped = [], 0
    order = sorted(range(len(items)), key=lambda i: (not items[i][3], i))
    for i in order:
        x, y, text, must, bold = items[i]
        others = [b for j, b in enumerate(obstacles) if j != i]
        chosen = None
        for dx, dy, ha, va in offsets:
            t = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points", ha=ha, va=va,
                            fontsize=7, fontweight="bold" if bold else "normal", zorder=6)
            bb = t.get_window_extent(renderer).expanded(1.05, 1.1)
            inside = axbox.contains(bb.x0, bb.y0) and axbox.contains(bb.x1, bb.y1)
            if inside and not any(bb.overlaps(o) for o in placed + others):
                chosen = (t, bb)
                break
            t.remove()
        if chosen is None and must:
            dx, dy, ha, va = offsets[0]
            t = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points", ha=ha, va=va,
                            fontsize=7, fontweight="bold" if bold else "normal", zorder=6)
            chosen = (t, t.get_window_extent(renderer))
        if chosen is None:
            dropped += 1
        else:
            placed.append(chosen[1])
    return dropped


def padded(lo, hi, log):
    """Axis limits around [lo, hi] with a margin (in log space on a log axis)."""
    if log:
        a, b = math.log10(lo), math.log10(hi)
        pad = max(0.08 * (b - a), 0.15)
        return 10 ** (a - pad), 10 ** (b + pad)
    pad = max(0.08 * (hi - lo), 0.05 * abs(hi) or 1.0)
    return lo - pad, hi + pad


def speed_panel(fig, ax, side, variants, ykey, ylabel, defaults, xscale):
    """One panel of the speed-accuracy plane: ns per frame against ykey, the Pareto fronts drawn and listed."""
    methods = methods_of(variants)
    traversals = []
    for v in variants:
        if v["traversal"] not in traversals:
            traversals.append(v["traversal"])
    ok = [v for v in variants if finite(v["ns_per_frame_median"]) and finite(v[ykey])]
    skipped = [v["variant"] for v in variants if v not in ok]
    side.axis("off")
    if not ok:
        ax.text(0.5, 0.5, f"no variant has both ns_per_frame_median and {ykey}", transform=ax.transAxes,
                ha="center", va="center")
        ax.set_ylabel(ylabel)
        return None
    xs = [v["ns_per_frame_median"] for v in ok]
    positive = [v[ykey] for v in ok if v[ykey] > 0]
    floor = (min(positive) / 10) if positive else 1e-6
    ys = [v[ykey] if v[ykey] > 0 else floor for v in ok]
    ax.set_xscale(xscale[0])
    ax.set_yscale("log")

    fronts = fronts_for(ok, ykey)
    for v, x, y in zip(ok, xs, ys):
        colour = method_colour(v["method"], methods)
        filled = v["sampling"] != "bilinear"
        ax.scatter([x], [y], s=46, marker=traversal_marker(v["traversal"], traversals),
                   facecolors=colour if filled else "white", edgecolors=colour, linewidths=1.4, zorder=4)
        if v["variant"] in fronts["all"]:
            ax.scatter([x], [y], s=190, marker="o", facecolors="none", edgecolors="black", linewidths=1.0,
                       zorder=3)
        if is_default(v, defaults):
            ax.scatter([x], [y], s=330, marker="*", facecolors="gold", edgecolors="black", linewidths=0.8,
                       zorder=2)

    # Limits fixed before the staircases, which run to the edges; x is the same in every panel.
    xlim = xscale[1]
    ylim = padded(min(ys), max(ys), True)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)

    by_name = {v["variant"]: (x, y) for v, x, y in zip(ok, xs, ys)}
    for name, members in fronts.items():
        if not members:
            continue
        sx, sy = staircase([by_name[m] for m in members], xlim, ylim)
        if name == "all":
            ax.plot(sx, sy, color="black", alpha=0.25, linewidth=5, solid_joinstyle="miter", zorder=1)
        else:
            ax.plot(sx, sy, color=method_colour(name, methods), linestyle="--", linewidth=1.2, zorder=1.5)
    if not positive or len(positive) < len(ok):
        ax.axhline(floor, color="grey", linewidth=0.6, linestyle=":")
        ax.annotate("zero error (drawn here)", (xlim[0], floor), xytext=(3, 2), textcoords="offset points",
                    fontsize=7, color="grey")

    ax.set_ylabel(ylabel)
    ax.grid(True, which="major", alpha=0.35)
    ax.grid(True, which="minor", alpha=0.12)

    # The list of the fronts, beside the panel.
    lines = ["Pareto front, all methods", "(faster → more accurate):"]
    lines += [f"  {m}" for m in fronts["all"]]
    for m in methods:
        if m in fronts and fronts[m]:
            lines += ["", f"front of {m}:"] + [f"  {short_label(next(v for v in ok if v['variant'] == n))}"
                                               for n in fronts[m]]
    if skipped:
        lines += ["", f"not drawn (no value): {len(skipped)}"]
    side.text(0.0, 1.0, "\n".join(lines), transform=side.transAxes, ha="left", va="top", fontsize=7.5,
              family="monospace")
    return skipped, ok, xs, ys, fronts


def legend_handles(variants, defaults):
    methods = methods_of(variants)
    traversals = []
    for v in variants:
        if v["traversal"] and v["traversal"] not in traversals:
            traversals.append(v["traversal"])
    h = [Line2D([], [], linestyle="none", marker="o", markersize=7, color=method_colour(m, methods), label=m)
         for m in methods]
    h += [Line2D([], [], linestyle="none", marker=traversal_marker(t, traversals), markersize=7,
                 markerfacecolor="grey", markeredgecolor="grey", label=t) for t in traversals]
    samplings = {v["sampling"] for v in variants}
    if "bilinear" in samplings:
        h += [Line2D([], [], linestyle="none", marker="o", markersize=7, markerfacecolor="grey",
                     markeredgecolor="grey", label="nearest (filled)"),
              Line2D([], [], linestyle="none", marker="o", markersize=7, markerfacecolor="white",
                     markeredgecolor="grey", label="bilinear (hollow)")]
    h += [Line2D([], [], linestyle="none", marker="o", markersize=12, markerfacecolor="none",
                 markeredgecolor="black", label="on the overall front"),
          Line2D([], [], color="black", alpha=0.25, linewidth=5, label="overall front"),
          Line2D([], [], color="grey", linestyle="--", label="front per method (its colour)")]
    if any(is_default(v, defaults) for v in variants):
        h.append(Line2D([], [], linestyle="none", marker="*", markersize=13, markerfacecolor="gold",
                        markeredgecolor="black", label="daemon default"))
    return h


def chart_speed(variants, outdir, defaults, fake):
    panels = [("end_err_rms_px", "end-position error after a stroke, RMS (px)")]
    if any(finite(v["cd_err_rms"]) for v in variants):
        panels.append(("cd_err_rms", "C/D-ratio error, RMS (relative)"))
    fig = plt.figure(figsize=(12.5, 5.6 * len(panels) + 1.5))
    grid = fig.add_gridspec(len(panels), 2, width_ratios=[3.2, 1], hspace=0.12, wspace=0.03,
                            left=0.07, right=0.99, top=1 - 0.55 / fig.get_figheight(),
                            bottom=1.45 / fig.get_figheight())
    axes, sides = [], []
    for row in range(len(panels)):
        ax = fig.add_subplot(grid[row, 0])
        axes.append(ax)
        sides.append(fig.add_subplot(grid[row, 1]))
    fig.suptitle("Speed against accuracy: one point per engine variant (lower left is better)", fontsize=12)
    label_items = []
    all_x = [v["ns_per_frame_median"] for v in variants if finite(v["ns_per_frame_median"])] or [1.0]
    log_x = min(all_x) > 0 and max(all_x) / min(all_x) > 20
    xscale = ("log" if log_x else "linear", padded(min(all_x), max(all_x), log_x))
    for ax, side, (ykey, ylabel) in zip(axes, sides, panels):
        result = speed_panel(fig, ax, side, variants, ykey, ylabel, defaults, xscale)
        if result is not None:
            _, ok, xs, ys, fronts = result
            on_any = {n for members in fronts.values() for n in members}
            label_items.append((ax, [(x, y, short_label(v) + (" (default)" if is_default(v, defaults) else ""),
                                      v["variant"] in on_any or is_default(v, defaults),
                                      is_default(v, defaults)) for v, x, y in zip(ok, xs, ys)]))
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    axes[-1].set_xlabel("time per frame, median (ns)")
    fig.legend(handles=legend_handles(variants, defaults), loc="lower center", bbox_to_anchor=(0.5, 0.0),
               ncol=5, fontsize=8, frameon=False)
    fake_watermark(fig, fake)
    dropped = 0
    for ax, items in label_items:
        dropped += place_labels(fig, ax, items)
    if dropped:
        axes[0].text(0.01, 0.01, f"{dropped} labels left out where they would overlap; see the table",
                     transform=axes[0].transAxes, fontsize=7, color="grey")
    path = outdir / "speed_vs_accuracy.png"
    fig.savefig(path, dpi=DPI, metadata=SAVE_META)
    plt.close(fig)
    return path


TARGET_RE = re.compile(r"^(bump|hole)-(linear|gaussian|polynomial)-h([0-9.]+)-r([0-9.]+)$")


def target_order(names):
    """The targets in the grid's order: rows shape x profile, columns height x radius (the 24 of the paper);
    names that do not follow the pattern come after, in the order they were read."""
    shapes, profiles = ["bump", "hole"], ["linear", "gaussian", "polynomial"]

    def key(n):
        m = TARGET_RE.match(n)
        if not m:
            return (1, 0, 0, 0, 0)
        return (0, shapes.index(m[1]), profiles.index(m[2]), float(m[3]), float(m[4]))
    return sorted(names, key=lambda n: (key(n), names.index(n)))


HALO_WIDTH, HALO_ALPHA = 3.4, 0.45  # a trace drawn under another it coincides with: wide and pale


def coinciding(series, targets, methods):
    """{method: earlier method} for each method whose measured trace, in some target, is the same as an earlier
    method's at half its points or more: drawn over it in the same way, it would hide it. Such a method is drawn
    wide and pale under the other."""
    out = {}
    for i, m in enumerate(methods):
        for e in methods[:i]:
            if e in out:
                continue
            for t in targets:
                if (t, m) not in series or (t, e) not in series:
                    continue
                theirs = dict(zip(series[(t, e)][0], series[(t, e)][1]))
                mine = [(x, c) for x, c in zip(series[(t, m)][0], series[(t, m)][1]) if finite(x) and finite(c)]
                same = sum(1 for x, c in mine if theirs.get(x) == c)
                if mine and 2 * same >= len(mine):
                    out[m] = e
                    break
            if m in out:
                break
    return out


def chart_fig5(rows, header, outdir, fake):
    has_truth = "cd_truth" in header
    name = getattr(rows, "path", "fig5_traces.csv")
    if isinstance(rows, Rows):
        rows.report_nonfinite(["x", "cd", "cd_truth"], "left out of the chart (a gap in the trace)")
    targets = []
    series = {}
    for r in rows:
        if r["target"] not in targets:
            targets.append(r["target"])
        s = series.setdefault((r["target"], r["method"]), ([], [], []))
        s[0].append(r["x"] if finite(r["x"]) else math.nan)
        s[1].append(r["cd"] if finite(r["cd"]) and finite(r["x"]) else math.nan)
        s[2].append(r["cd_truth"] if has_truth and finite(r["cd_truth"]) and finite(r["x"]) else math.nan)
    targets = target_order(targets)
    methods = methods_of(rows)
    ncols = 4
    nrows = max(1, math.ceil(len(targets) / ncols))
    values = [c for s in series.values() for c in s[1] + s[2] if finite(c) and c > 0]
    if not values:
        raise InputError("fig5_traces.csv: no positive finite C/D value to draw")
    ylo, yhi = min(values), max(values)
    log = yhi / ylo > 8
    if log:
        for column, k in (("cd", 1), ("cd_truth", 2)):
            lines = [r["_line"] for r in rows if finite(r.get(column)) and r[column] <= 0]
            if lines:
                warn(f"{name}:{lines[0]}: column {column}: {len(lines)} "
                     f"value(s) not above 0, left out of the chart (its C/D axis is logarithmic)")
                for s in series.values():
                    s[k][:] = [c if not finite(c) or c > 0 else math.nan for c in s[k]]
    under = coinciding(series, targets, methods)
    drawn, truth_drawn, rim_drawn = set(), False, False
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.4 * ncols, 2.35 * nrows + 1.0), sharex=True, sharey=True,
                             squeeze=False)
    for k, ax in enumerate(axes.flat):
        if k >= len(targets):
            ax.axis("off")
            continue
        t = targets[k]
        m = TARGET_RE.match(t)
        if m:  # the rim of the bump or hole
            for x in (250 - float(m[4]), 250 + float(m[4])):
                ax.axvline(x, color="grey", linewidth=0.6, alpha=0.5)
            rim_drawn = True
        ax.axhline(1.0, color="black", linewidth=0.5, alpha=0.4)
        for method in methods:
            if (t, method) not in series:
                continue
            xs, cds, truths = series[(t, method)]
            colour = method_colour(method, methods)
            if any(finite(c) for c in cds):
                drawn.add(method)
            if method in under:
                ax.plot(xs, cds, color=colour, linewidth=HALO_WIDTH, alpha=HALO_ALPHA, drawstyle="steps-post",
                        zorder=1.9)
            else:
                ax.plot(xs, cds, color=colour, linewidth=1.1, drawstyle="steps-post")
            if any(finite(c) for c in truths):
                ax.plot(xs, truths, color=colour, linewidth=1.0, linestyle=(0, (4, 2.5)), alpha=0.9)
                truth_drawn = True
        ax.set_title(t, fontsize=9)
        ax.tick_params(labelsize=8)
        ax.grid(True, alpha=0.25)
    if log:
        axes[0][0].set_yscale("log")
        ticks = [t for t in (0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100) if ylo * 0.9 <= t <= yhi * 1.1]
        axes[0][0].set_yticks(ticks)
        axes[0][0].set_yticklabels([f"{t:g}" for t in ticks])
        axes[0][0].yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        axes[0][0].set_ylim(ylo / 1.25, yhi * 1.25)
    xs_all = [x for s in series.values() for x, c, ct in zip(*s) if finite(x) and (finite(c) or finite(ct))]
    axes[0][0].set_xlim(min(xs_all), max(xs_all))
    for ax in axes[-1]:
        ax.set_xlabel("x in the target (px)", fontsize=9)
    for row in axes:
        row[0].set_ylabel("C/D ratio" + (" (log)" if log else ""), fontsize=9)
    handles = []
    for m in methods:
        if m not in drawn:
            warn(f"{name}: method {m} has no finite C/D value: not drawn, not in the legend")
        elif m in under:
            handles.append(Line2D([], [], color=method_colour(m, methods), linewidth=HALO_WIDTH, alpha=HALO_ALPHA,
                                  label=f"{m} (measured; wide, under {under[m]} where equal)"))
        else:
            handles.append(Line2D([], [], color=method_colour(m, methods), linewidth=1.5, label=f"{m} (measured)"))
    if truth_drawn:
        handles += [Line2D([], [], color="black", linestyle=(0, (4, 2.5)), label="ground truth (dashed, "
                           "the method's colour)")]
    elif has_truth:
        warn(f"{name}: column cd_truth has no finite value: no ground truth drawn, none in the legend")
    if rim_drawn:
        handles += [Line2D([], [], color="grey", alpha=0.5, label="rim of the bump or hole")]
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), fontsize=9, frameon=False,
               bbox_to_anchor=(0.5, 1 - 0.45 / fig.get_figheight()))
    fig.suptitle("C/D ratio along a horizontal stroke through the centre of each target (the paper's Fig. 5)",
                 fontsize=12, y=1 - 0.12 / fig.get_figheight())
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.75 / fig.get_figheight()), h_pad=0.6, w_pad=0.4)
    fake_watermark(fig, fake)
    path = outdir / "fig5_traces.png"
    fig.savefig(path, dpi=DPI, metadata=SAVE_META)
    plt.close(fig)
    return path


def grid_of(rows):
    """(cos values, delta-beta values, cd[i_db][i_cos]) when the rows fill a regular grid, else None."""
    cs = sorted({r["cos_alpha"] for r in rows})
    ds = sorted({r["delta_beta_deg"] for r in rows})
    if len(cs) < 2 or len(ds) < 2 or len(cs) * len(ds) != len(rows):
        return None
    ci = {c: i for i, c in enumerate(cs)}
    di = {d: i for i, d in enumerate(ds)}
    z = np.full((len(ds), len(cs)), np.nan)
    for r in rows:
        z[di[r["delta_beta_deg"]], ci[r["cos_alpha"]]] = r["cd"]
    if np.isnan(z).any():
        return None
    return np.array(cs), np.array(ds), z


def chart_fig2(rows, outdir, fake):
    if isinstance(rows, Rows):
        rows.report_nonfinite(FIG2_REQUIRED, "those rows are left out of the chart")
    rows = [r for r in rows if finite(r["cos_alpha"]) and finite(r["delta_beta_deg"]) and finite(r["cd"])]
    if len(rows) < 3:
        raise InputError("fig2_grid.csv: fewer than 3 rows with finite values")
    halves = [("cos α ≤ 0: uphill, C/D ≥ 1 (slower)", [r for r in rows if r["cos_alpha"] <= 0], "Reds"),
              ("cos α ≥ 0: downhill, C/D ≤ 1 (faster)", [r for r in rows if r["cos_alpha"] >= 0], "Blues_r")]
    halves = [h for h in halves if len({r["cos_alpha"] for r in h[1]}) >= 2]
    if not halves:
        halves = [("C/D ratio", rows, "viridis")]
    fig, axes = plt.subplots(1, len(halves), figsize=(6.2 * len(halves), 5.4), squeeze=False)
    for ax, (title, part, cmap) in zip(axes[0], halves):
        g = grid_of(part)
        zs = [r["cd"] for r in part]
        levels = np.linspace(min(zs), max(zs), 21) if max(zs) > min(zs) else None
        if g is not None:
            c, d, z = g
            mesh = ax.pcolormesh(c, d, z, cmap=cmap, shading="nearest")
            lines = ax.contour(c, d, z, levels=contour_levels(min(zs), max(zs)), colors="black",
                               linewidths=0.7)
        else:
            cx = [r["cos_alpha"] for r in part]
            dy = [r["delta_beta_deg"] for r in part]
            mesh = ax.tricontourf(cx, dy, zs, levels=levels if levels is not None else 10, cmap=cmap)
            lines = ax.tricontour(cx, dy, zs, levels=contour_levels(min(zs), max(zs)), colors="black",
                                  linewidths=0.7)
        ax.clabel(lines, fontsize=8, fmt="%g")
        bar = fig.colorbar(mesh, ax=ax, fraction=0.07, pad=0.03)
        bar.set_label("C/D ratio")
        ax.set_xlabel("cos(α)")
        ax.set_ylabel("Δβ (degrees)")
        ax.set_title(title, fontsize=10)
    fig.suptitle("Curvature method: C/D ratio as a function of cos(α) and Δβ (the paper's Fig. 2)", fontsize=12)
    fig.tight_layout()
    fake_watermark(fig, fake)
    path = outdir / "fig2_cd_surface.png"
    fig.savefig(path, dpi=DPI, metadata=SAVE_META)
    plt.close(fig)
    return path


def contour_levels(lo, hi):
    """Round C/D values between lo and hi for contour lines (at most about 8)."""
    candidates = [0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.5, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50]
    inside = [c for c in candidates if lo < c < hi]
    while len(inside) > 8:
        inside = inside[::2]
    return inside or [(lo + hi) / 2]


# ---------------------------------------------------------------------------------------------------- table

def fmt_num(v):
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if not finite(v):
        return "-"
    a = abs(v)
    if a == 0:
        return "0"
    if a >= 1000:
        return f"{v:.0f}"
    if a >= 0.01:
        return f"{v:.3g}"
    return f"{v:.2e}"


def markdown_table(variants, header, defaults, fake):
    end = fronts_for(variants, "end_err_rms_px")
    cd = fronts_for(variants, "cd_err_rms")

    def where(name, fronts, what):
        tags = [k for k, members in fronts.items() if name in members]
        if not tags:
            return None
        return f"{what}: " + "+".join("all" if t == "all" else "own method" for t in tags)
    columns = [("ns_per_frame_median", "ns/frame median"), ("ns_per_frame_p99", "ns/frame p99"),
               ("ns_per_step", "ns/step"), ("bytes_per_texel", "bytes/texel"), ("precompute_ms", "precompute ms"),
               ("cd_err_rms", "C/D err RMS"), ("cd_err_max", "C/D err max"), ("end_err_rms_px", "end err RMS px"),
               ("end_err_max_px", "end err max px"), ("drift_px", "drift px")]
    columns = [(k, t) for k, t in columns if k in header]
    out = []
    if fake:
        out.append("**FAKE DATA** (charts.py --fake-data): not measurements.\n")
    end_costs = cost_fronts_for(variants, "end_err_rms_px")
    cd_costs = cost_fronts_for(variants, "cd_err_rms")
    end_doubts = cost_doubts_for(variants, "end_err_rms_px", end_costs)
    cd_doubts = cost_doubts_for(variants, "cd_err_rms", cd_costs)

    def on_cost_fronts(v):
        tags = [what + ("?" if v["variant"] in doubts else "")
                for what, fronts, doubts in (("end", end_costs, end_doubts), ("C/D", cd_costs, cd_doubts))
                if v["variant"] in fronts.get(v["method"], set())]
        lacking = [k for k in COST_KEYS if k in header and cost_value(v, k) is None]
        if tags and lacking:
            return "+".join(tags) + f" (without {', '.join(lacking)})"
        return "+".join(tags) or "no"
    out.append("| variant | on the Pareto front (time) | on the front of all costs | " +
               " | ".join(t for _, t in columns) + " |")
    out.append("|---|---|---|" + "---:|" * len(columns))
    rows = []
    for v in variants:
        tags = [t for t in (where(v["variant"], end, "end"), where(v["variant"], cd, "C/D")) if t]
        if tags or is_default(v, defaults):
            rows.append((v, "; ".join(tags) or "no"))
    methods = methods_of(variants)
    rows.sort(key=lambda r: (methods.index(r[0]["method"]), r[0]["ns_per_frame_median"]))
    for v, tags in rows:
        name = f"`{v['variant']}`" + (" (default)" if is_default(v, defaults) else "")
        out.append(f"| {name} | {tags} | {on_cost_fronts(v)} | " +
                   " | ".join(fmt_num(v[k]) for k, _ in columns) + " |")
    out.append("")
    out.append("\"end\": front of ns/frame against end-position error; \"C/D\": against C/D-ratio error; "
               "\"all\": over every variant; \"own method\": among the variants of its method. \"All costs\": "
               "among the variants of its method, no other is at least as good in time per frame, memory per "
               "texel, precompute time and the error together (and better in one).")
    if any(k in header and cost_value(v, k) is None for v in variants for k in COST_KEYS):
        out.append("A variant that lacks a cost (\"without\") is judged over the costs it has, and puts no variant "
                   "that has that cost off a front of all costs.")
    shown = [v["variant"] for v, _ in rows]
    for what, doubts in (("end", end_doubts), ("C/D", cd_doubts)):
        if any(n in doubts for n in shown):
            out.append(f"\"{what}?\": on that front unless a variant that lacks one of its costs is as good there: " +
                       "; ".join(f"`{n}` (" + ", ".join(f"`{d}`" for d in doubts[n]) + ")" for n in shown
                                 if n in doubts) + ".")
    for v in variants:
        if is_default(v, defaults):
            on_end = v["variant"] in end.get(v["method"], [])
            on_cd = v["variant"] in cd.get(v["method"], [])
            all_end = v["variant"] in end_costs.get(v["method"], set())
            all_cd = v["variant"] in cd_costs.get(v["method"], set())
            out.append(f"Default `{v['variant']}`: on its method's end-error front: {'yes' if on_end else 'NO'}; "
                       f"on its method's C/D-error front: {'yes' if on_cd else 'NO'}; over all costs: "
                       f"end error {'yes' if all_end else 'NO'}{'?' if v['variant'] in end_doubts else ''}, "
                       f"C/D error {'yes' if all_cd else 'NO'}{'?' if v['variant'] in cd_doubts else ''}" +
                       "".join(f" (without {k})" for k in COST_KEYS if k in header and cost_value(v, k) is None) +
                       ".")
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------------- fake data

def fake_profile(kind, u):
    if u >= 1:
        return 0.0
    if kind == "linear":
        return 1 - u
    if kind == "gaussian":
        return math.exp(-u * u / (2 / 9))
    return 1 - u ** 4


def fake_curvature_cd(a1, a2):
    cos_a = (a1 + a2) / 2
    db = math.degrees(math.acos(max(-1, min(1, a1))) - math.acos(max(-1, min(1, a2))))
    kmax = min(max(4 * (1 + db), 1), 30)
    kmin = min(max(1.5 * (1 - db), 1), 5)
    if cos_a > 0:
        return 1 - cos_a * (1 - 1 / kmin)
    if cos_a < 0:
        return 1 - cos_a * (kmax - 1)
    return 1.0


CSV_NAMES = ("variants.csv", "fig5_traces.csv", "fig2_grid.csv")


def is_fake(csvdir, quiet=False):
    """Whether CSVDIR holds --fake-data's files: its FAKE marker, written after them, no older than any of them (a
    run of `pseudohaptic accuracy` into the folder replaces the files and leaves the marker older)."""
    marker = csvdir / "FAKE"
    if not marker.exists():
        return False
    newest = max([(csvdir / n).stat().st_mtime_ns for n in CSV_NAMES if (csvdir / n).exists()], default=0)
    if marker.stat().st_mtime_ns >= newest:
        return True
    if not quiet:
        print(f"charts.py: warning: {marker} is older than the CSV files, which a later run replaced: charted as "
              "measurements", file=sys.stderr)
    return False


def write_fake(csvdir):
    """Made-up CSV files of the contract's shape (deterministic) for developing and testing the charts."""
    rng = random.Random(6)
    measured = [n for n in CSV_NAMES if (csvdir / n).exists()]
    if measured and not is_fake(csvdir, quiet=True):
        raise InputError(f"{csvdir} holds {', '.join(measured)} and no FAKE marker newer than them: measurements, "
                         "which --fake-data would overwrite; give a new or empty folder")
    csvdir.mkdir(parents=True, exist_ok=True)
    cols = ["variant", "method", "traversal", "storage", "sampling"] + VARIANT_NUMERIC
    base = {"exact": 260, "unit_steps": 330, "frame_midpoint": 60, "direction_lut8": 150, "direction_lut16": 165}
    berr = {"exact": 0.02, "unit_steps": 0.05, "frame_midpoint": 3.0, "direction_lut8": 0.8, "direction_lut16": 0.3}
    with (csvdir / "variants.csv").open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(cols)
        for method, storages in (("curvature", ["f32", "n16", "n8"]), ("depth", ["f32", "d16", "d8"])):
            for trav in base:
                for storage in storages:
                    for sampling in ("nearest", "bilinear"):
                        if trav.startswith("direction") and sampling == "bilinear":
                            continue
                        speed = base[trav] * (0.65 if method == "depth" else 1) * (1.4 if sampling == "bilinear"
                                                                                   else 1)
                        speed *= {"f32": 1.0, "n16": 1.05, "n8": 1.03, "d16": 1.04, "d8": 1.02}[storage]
                        err = berr[trav] * {"f32": 1, "n16": 1.3, "n8": 6, "d16": 1.2, "d8": 9}[storage]
                        err *= 0.6 if sampling == "bilinear" else 1
                        err *= rng.uniform(0.85, 1.15)
                        row = [f"{method}/{trav}/{storage}/{sampling}", method, trav, storage, sampling,
                               speed * rng.uniform(0.95, 1.05), speed * 2.3, speed / 6.7,
                               (8 if method == "curvature" else 4) * {"f32": 1, "n16": 0.5, "n8": 0.25,
                                                                      "d16": 0.5, "d8": 0.25}[storage]
                               * (8 if trav == "direction_lut8" else 16 if trav == "direction_lut16" else 1),
                               (30 if trav.startswith("direction") else 1.5) * rng.uniform(0.9, 1.1),
                               err * 0.05, err * 0.4, err, err * 4, err * 12]
                        if trav == "exact" and storage == "f32" and sampling == "nearest" and method == "depth":
                            row[12] = 0.0  # an exact zero, as a real run may give
                        w.writerow([x if isinstance(x, str) else f"{x:.6g}" for x in row])
    names = []
    for shape in ("bump", "hole"):
        for profile in ("linear", "gaussian", "polynomial"):
            for h in (0.25, 1):
                for rad in (100, 200):
                    names.append((shape, profile, h, rad, f"{shape}-{profile}-h{h:g}-r{rad}"))
    with (csvdir / "fig5_traces.csv").open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["target", "method", "x", "cd", "cd_truth"])
        for shape, profile, h, rad, name in names:
            sign = 1 if shape == "bump" else -1

            def height(x):
                return sign * h * 100 * fake_profile(profile, abs(x - 250) / rad)
            for method in ("curvature", "depth"):
                prev_a = None
                for x in range(0, 500):
                    dh = height(x + 1) - height(x)
                    if method == "depth":
                        truth = min(max(1 + 3 * dh, 1 / 1.5), 4)
                    else:
                        a = -dh / math.sqrt(1 + dh * dh)
                        truth = fake_curvature_cd(a if prev_a is None else prev_a, a)
                        prev_a = a
                    cd = truth * (1 + rng.gauss(0, 0.01))
                    w.writerow([name, method, x, f"{cd:.6g}", f"{truth:.6g}"])
    with (csvdir / "fig2_grid.csv").open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["cos_alpha", "delta_beta_deg", "cd"])
        for i in range(81):
            c = -1 + i / 40
            for j in range(81):
                d = -2 + j / 20
                kmax = min(max(4 * (1 + d), 1), 30)
                kmin = min(max(1.5 * (1 - d), 1), 5)
                cd = 1 - c * (1 - 1 / kmin) if c > 0 else 1 - c * (kmax - 1) if c < 0 else 1.0
                w.writerow([f"{c:.6g}", f"{d:.6g}", f"{cd:.6g}"])
    (csvdir / "FAKE").write_text("made by charts.py --fake-data; not measurements\n")  # last: newer than the files


# ---------------------------------------------------------------------------------------------------- main

def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.split("\n")[1:]))
    p.add_argument("csvdir", type=Path, help="folder with variants.csv, fig5_traces.csv and fig2_grid.csv")
    p.add_argument("outdir", type=Path, nargs="?", help="folder to write the PNG files into (created if needed)")
    p.add_argument("--fake-data", action="store_true", help="write made-up CSV files into CSVDIR and exit")
    p.add_argument("--default", action="append", default=[], metavar="VARIANT",
                   help="the daemon's default variant(s), marked with a star (default: the rows whose `default` "
                        "column is 1, or without that column every variant with traversal exact, storage f32 and "
                        "sampling nearest)")
    args = p.parse_args(argv)
    if args.fake_data:
        if args.outdir is not None:
            p.error("--fake-data takes only CSVDIR")
        try:
            write_fake(args.csvdir)
        except InputError as e:
            print(f"charts.py: {e}", file=sys.stderr)
            return 1
        except OSError as e:
            print(f"charts.py: {os_error_text(e, args.csvdir)}", file=sys.stderr)
            return 1
        print(f"charts.py: wrote fake CSV files to {args.csvdir}", file=sys.stderr)
        return 0
    if args.outdir is None:
        p.error("OUTDIR is required")
    try:
        variants, vheader = read_variants(args.csvdir)
        fig5_rows, fig5_header = read_table(args.csvdir / "fig5_traces.csv", FIG5_REQUIRED, ["x", "cd"],
                                            ["cd_truth"])
        fig2_rows, _ = read_table(args.csvdir / "fig2_grid.csv", FIG2_REQUIRED,
                                  ["cos_alpha", "delta_beta_deg", "cd"])
        unknown = [d for d in args.default if d not in {v["variant"] for v in variants}]
        if unknown:
            raise InputError(f"--default {', '.join(unknown)}: no such variant in variants.csv")
        fake = is_fake(args.csvdir)
        make_outdir(args.outdir)
        variants.report_nonfinite([c for c in VARIANT_NUMERIC if c not in COST_KEYS],
                                  "shown as inf or - in the table; not drawn, and on no front, where it is the error")
        warn_costs(variants, vheader, variants.path)
        written = [chart_speed(variants, args.outdir, args.default, fake),
                   chart_fig5(fig5_rows, fig5_header, args.outdir, fake),
                   chart_fig2(fig2_rows, args.outdir, fake)]
    except InputError as e:
        print(f"charts.py: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"charts.py: {os_error_text(e, args.outdir)}", file=sys.stderr)
        return 1
    no_value = [v["variant"] for v in variants if not finite(v["ns_per_frame_median"]) or
                not finite(v["end_err_rms_px"])]
    if no_value:
        print(f"charts.py: not drawn (no ns_per_frame_median or end_err_rms_px): {', '.join(no_value)}",
              file=sys.stderr)
    print(markdown_table(variants, vheader, args.default, fake))
    for path in written:
        print(f"charts.py: wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
