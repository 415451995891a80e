#!/usr/bin/env python3
"""The chart and table scripts of tools/ on malformed input: each ends with `SCRIPT: message` and a status
(never a traceback), warns of what it leaves out, and never changes a verdict quietly.

    tests/charts_inputs_check.py      (run by ctest with the python3 that has matplotlib)

Builds small CSV files in a temporary folder (a good set like the one `pseudohaptic accuracy|stability|study`
writes, then one flaw at a time), runs tools/charts.py, stability_charts.py, study_charts.py, study_paired.py
and error_bounds.py on them with this interpreter, and checks each status, that stderr has no traceback, and
the message's key text. Exits 1, naming each failed check, when one fails.
"""

import concurrent.futures
import csv
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

TOOLS = Path(__file__).resolve().parent.parent / "tools"
PYTHON = sys.executable

# ------------------------------------------------------------------------------------------------ good data

VARIANT_COLUMNS = ["variant", "method", "traversal", "storage", "sampling", "ns_per_frame_median",
                   "ns_per_frame_p99", "ns_per_step", "bytes_per_texel", "precompute_ms", "cd_err_rms", "cd_err_max",
                   "end_err_rms_px", "end_err_max_px", "drift_px"]
# (variant, ns per frame, bytes per texel, precompute ms, C/D error, end error). Over all costs: A is on the
# front only by its precompute time (H is faster at the same errors, but precomputes longer), so a front that
# leaves precompute_ms out takes A off it; B is dominated by A and dominates no one.
VARIANTS = [
    ("curvature/exact/f32/nearest", 100, 8, 5, 0.01, 0.1),  # A
    ("curvature/unit_steps/f32/nearest", 150, 8, 5, 0.02, 0.3),  # B
    ("curvature/frame_midpoint/f32/nearest", 60, 8, 5, 0.05, 1.0),  # C
    ("curvature/exact/n16/nearest", 105, 4, 2, 0.012, 0.12),  # D
    ("curvature/exact/f32/bilinear", 200, 8, 5, 0.03, 0.5),  # E
    ("curvature/auto2/f32/nearest", 99, 8, 20, 0.01, 0.1),  # H
    ("depth/exact/f32/nearest", 70, 4, 1, 0.03, 0.3),
    ("depth/exact/d8/nearest", 72, 1, 0.5, 0.3, 5.0),
]
B = "curvature/unit_steps/f32/nearest"
H = "curvature/auto2/f32/nearest"


def write_csv(path, header, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)


def num(v):
    return v if isinstance(v, str) else f"{v:.6g}"


def accuracy_set(d, traces_same=True):
    rows = []
    for name, ns, texel, pre, cd, end in VARIANTS:
        method, traversal, storage, sampling = name.split("/")
        rows.append([name, method, traversal, storage, sampling] +
                    [num(v) for v in (ns, ns * 1.3, ns / 4, texel, pre, cd, cd * 10, end, end * 3, end * 2)])
    write_csv(d / "variants.csv", VARIANT_COLUMNS, rows)
    trace_rows = []
    for method in ("curvature", "depth", "hybrid"):
        for i in range(100):
            x = i * 5 + 0.5
            inside = 50 <= x < 450
            cd = (2.0 if x < 250 else 0.7) if inside else 1.0
            if method == "depth":
                cd = (2.5 if x < 250 else 0.6) if inside else 1.0
            trace_rows.append(["bump-linear-h1-r200", method, num(x), num(cd), num(cd)])
    write_csv(d / "fig5_traces.csv", ["target", "method", "x", "cd", "cd_truth"], trace_rows)
    grid = []
    for i in range(5):
        c = -1 + i / 2
        for j in range(5):
            db = -2 + j
            kmax = min(max(4 * (1 + db), 1), 30)
            kmin = min(max(1.5 * (1 - db), 1), 5)
            cd = 1 - c * (1 - 1 / kmin) if c > 0 else 1 - c * (kmax - 1) if c < 0 else 1.0
            grid.append([num(c), num(db), num(cd)])
    write_csv(d / "fig2_grid.csv", ["cos_alpha", "delta_beta_deg", "cd"], grid)


STABILITY_COLUMNS = ["mode", "family", "severity", "method", "variant", "traversal", "sampling", "cd_err_rms",
                     "jitter_rms", "jitter_truth_rms", "travel_err_pct", "travel_sens_pct", "iso_pct", "rate_px",
                     "contrast", "contrast_truth", "faults", "strokes"]


def stability_set(d):
    write_csv(d / "modes.csv", ["mode", "family", "severity", "has_features", "description"],
              [["jump", "C-1 step", "height (px)", "1", "a height jump"],
               ["cone", "C0 kink", "slope (deg)", "1", "a cone"]])
    rows = []
    for mi, (mode, family) in enumerate((("jump", "C-1 step"), ("cone", "C0 kink"))):
        for severity in (1, 8):
            for k, method in enumerate(("curvature", "depth", "hybrid")):
                for variant, sampling in (("exact", "nearest"), ("exact+bilinear", "bilinear")):
                    base = (1 + k) * (1 + mi) * severity * (1.5 if sampling == "bilinear" else 1)
                    rows.append([mode, family, severity, method, variant, "exact", sampling] +
                                [num(base * f) for f in (0.01, 0.02, 0.015, 0.5, 0.01, 0.3, 1e-13, 2.0, 1.5)] +
                                ["0", "10"])
    write_csv(d / "stability.csv", STABILITY_COLUMNS, rows)


SUMMARY_COLUMNS = ["technique", "grouping", "group", "participants", "trials", "error_pct", "error_lo", "error_hi",
                   "time_s", "time_lo", "time_hi", "decided_pct", "paper_error_pct", "paper_time_s"]
TRIAL_COLUMNS = ["participant", "technique", "block", "order", "scored", "target", "shape", "profile", "height",
                 "radius", "answer", "correct", "decided", "time_s", "strokes", "frames", "evidence"]


def study_set(d):
    summary = []
    for k, (technique, paper_err, paper_time) in enumerate((("curvature:sign+1", "3.47", "4.88"),
                                                             ("depth", "7.47", "6.03"))):
        summary.append([technique, "overall", "all", "2", "48", num(5.0 + k), num(2.0 + k), num(8.0 + k),
                        num(4.0 + k / 2), num(3.5 + k / 2), num(4.5 + k / 2), "90", paper_err, paper_time])
        for g in ("h1-r100", "h1-r200", "h0.25-r100", "h0.25-r200"):
            summary.append([technique, "height_radius", g, "2", "12", num(6.0 + k), num(1.0 + k), num(11.0 + k),
                            num(4.0 + k / 2), num(3.0 + k / 2), num(5.0 + k / 2), "90", "", ""])
    write_csv(d / "summary.csv", SUMMARY_COLUMNS, summary)
    trials = []
    order = 0
    for participant in ("0", "1"):
        for k, technique in enumerate(("curvature:sign+1", "depth")):
            for profile in ("linear", "gaussian", "polynomial"):
                for radius in ("100", "200"):
                    for height in ("1", "0.25"):
                        for shape in ("bump", "hole"):
                            correct = "0" if (order % 7 == 3) else "1"
                            trials.append([participant, technique, "0", str(order), "1",
                                           f"{shape}-{profile}-h{height}-r{radius}", shape, profile, height, radius,
                                           shape, correct, "1", f"{3.0 + k + (order % 5) * 0.3:.3f}", "3", "200",
                                           "1.0"])
                            order += 1
    write_csv(d / "trials.csv", TRIAL_COLUMNS, trials)


# ------------------------------------------------------------------------------------------------ flaws

def edit_cell(path, column, value, row=1):
    """Sets `column` of data row `row` (1 = the first; "all" = every one) to `value`."""
    with path.open(newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    i = rows[0].index(column)
    for k, r in enumerate(rows[1:], 1):
        if row == "all" or k == row:
            r[i] = value
    write_csv(path, rows[0], rows[1:])


def edit_where(path, match, column, value):
    """Sets `column` to `value` in the data rows whose cells include every (column, value) of `match`."""
    with path.open(newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    h = rows[0]
    for r in rows[1:]:
        if all(r[h.index(c)] == v for c, v in match.items()):
            r[h.index(column)] = value
    write_csv(path, h, rows[1:])


def drop_column(path, column):
    with path.open(newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    i = rows[0].index(column)
    write_csv(path, [c for k, c in enumerate(rows[0]) if k != i], [[c for k, c in enumerate(r) if k != i]
                                                                   for r in rows[1:]])


def keep_rows(path, keep):
    with path.open(newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    h = rows[0]
    write_csv(path, h, [r for r in rows[1:] if keep(dict(zip(h, r)))])


def header_only(path):
    with path.open(encoding="utf-8") as f:
        first = f.readline()
    path.write_text(first, encoding="utf-8")


def add_bom(path):
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())


def latin1_on_line_3(path):
    lines = path.read_bytes().split(b"\n")
    lines[2] = lines[2].replace(b",", b"\xe9,", 1)
    path.write_bytes(b"\n".join(lines))


# ------------------------------------------------------------------------------------------------ cases

class Case:
    def __init__(self, name, script, args, rc, err=(), out=(), no_err=(), check=None, files=(), no_files=(),
                 no_out=()):
        self.name, self.script, self.args, self.rc = name, script, args, rc
        self.err, self.out, self.no_err, self.check = list(err), list(out), list(no_err), check
        self.no_out = list(no_out)
        self.files, self.no_files = list(files), list(no_files)


def table_verdicts(markdown):
    """{variant: its "on the front of all costs" cell} of charts.py's table."""
    out = {}
    for line in markdown.splitlines():
        if line.startswith("| `"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            out[cells[0].split("`")[1]] = cells[2]
    return out


def build(root):
    """The cases, their folders made under root."""
    cases = []
    good_acc, good_stab, good_study = root / "acc", root / "stab", root / "study"
    accuracy_set(good_acc)
    stability_set(good_stab)
    study_set(good_study)

    def variant(name, base, *edits):
        d = root / name
        shutil.copytree(base, d)
        for e in edits:
            e(d)
        return d

    out = root / "out"

    def charts(name, d, rc, **kw):
        cases.append(Case(name, "charts.py", [d, out / name], rc, **kw))

    def stability(name, d, rc, extra=(), **kw):
        cases.append(Case(name, "stability_charts.py", [d, out / name] + list(extra), rc, **kw))

    def study(name, d, rc, **kw):
        cases.append(Case(name, "study_charts.py", [d, out / name], rc, **kw))

    def paired(name, d, rc, **kw):
        cases.append(Case(name, "study_paired.py", [d], rc, **kw))

    def bounds(name, d, rc, **kw):
        cases.append(Case(name, "error_bounds.py", [d / "variants.csv", d / "variants.csv"], rc, **kw))

    # The good sets: status 0 and no warning (the baseline of item 1's verdicts).
    charts("good accuracy", good_acc, 0, no_err=["not finite", "no value", "warning"])
    stability("good stability", good_stab, 0, no_err=["not finite", "no value", "not drawn"],
              files=["stability_cd_err_rms.png"])
    study("good study", good_study, 0, no_err=["not finite", "not drawn"])
    paired("good paired", good_study, 0, out=["| curvature:sign+1 \u2212 depth, all targets |"])
    bounds("good bounds", good_acc, 0, out=["| curvature | exact | nearest |"])

    # 1. A blank (or infinite) cost in one variant: the others keep their verdicts; an infinite cost is no help.
    def same_verdicts_but_b(result, baseline):
        mine, theirs = table_verdicts(result.stdout), table_verdicts(baseline.stdout)
        changed = [f"{n}: {theirs[n]!r} -> {mine.get(n)!r}" for n in theirs if n != B and mine.get(n) != theirs[n]]
        if not theirs or theirs.get("curvature/exact/f32/nearest") != "end+C/D":
            return f"the good set's table is not as this check expects: {theirs}"
        return "other variants' verdicts changed: " + "; ".join(changed) if changed else None
    charts("1 blank precompute_ms", variant("c_blank_pre", good_acc,
                                            lambda d: edit_where(d / "variants.csv", {"variant": B},
                                                                 "precompute_ms", "")), 0,
           err=["column precompute_ms: no value", B], check=("baseline", same_verdicts_but_b))
    charts("1 nan bytes_per_texel", variant("c_nan_bytes", good_acc,
                                            lambda d: edit_where(d / "variants.csv", {"variant": B},
                                                                 "bytes_per_texel", "nan")), 0,
           err=["column bytes_per_texel: no value", B], check=("baseline", same_verdicts_but_b))

    def h_not_on_front(result, _):
        verdict = table_verdicts(result.stdout).get(H)
        return None if verdict == "no" else f"{H} with an infinite precompute_ms: {verdict!r}, expected 'no'"
    charts("1 inf precompute_ms", variant("c_inf_pre", good_acc,
                                          lambda d: edit_where(d / "variants.csv", {"variant": H},
                                                               "precompute_ms", "inf")), 0,
           err=["column precompute_ms: infinite for", H], out=["| inf |"], check=("baseline", h_not_on_front))

    # 3. Legend entries only for what is drawn.
    charts("3 no ground truth", variant("c_truth_nan", good_acc,
                                        lambda d: edit_cell(d / "fig5_traces.csv", "cd_truth", "", "all")), 0,
           err=["column cd_truth has no finite value", "none in the legend"])
    stability("3 no exact-input jitter", variant("s_jtruth", good_stab,
                                                 lambda d: edit_cell(d / "stability.csv", "jitter_truth_rms", "",
                                                                     "all")), 0,
              err=["stability_jitter_rms.png", "exact input's line is not drawn, not in the legend"])
    study("3 technique without values", variant("t_nan_tech", good_study,
                                                lambda d: edit_where(d / "summary.csv", {"technique": "depth"},
                                                                     "error_pct", "nan")), 0,
          err=["technique depth has no error rate: not drawn, not in the legend", "summary.csv:7: column error_pct"])

    # 4. Non-finite values left out are named (file:line, column, how many); stability's tables show inf.
    charts("4 fig2 inf", variant("c_f2_inf", good_acc, lambda d: edit_cell(d / "fig2_grid.csv", "cd", "inf", 4)), 0,
           err=["fig2_grid.csv:5: column cd: 1 value(s) not finite (inf)"])
    charts("4 fig5 nan x and inf cd", variant("c_f5", good_acc,
                                              lambda d: edit_cell(d / "fig5_traces.csv", "x", "nan", 3),
                                              lambda d: edit_cell(d / "fig5_traces.csv", "cd", "inf", 7),
                                              lambda d: edit_cell(d / "fig5_traces.csv", "cd", "inf", 9)), 0,
           err=["fig5_traces.csv:4: column x: 1 value(s) not finite (nan)",
                "fig5_traces.csv:8: column cd: 2 value(s) not finite (inf)"])
    stability("4 inf cd_err_rms", variant("s_inf", good_stab,
                                          lambda d: edit_where(d / "stability.csv",
                                                               {"mode": "jump", "severity": "8",
                                                                "method": "hybrid", "variant": "exact"},
                                                               "cd_err_rms", "inf")), 0,
              err=["stability.csv:", "column cd_err_rms: 1 value(s) not finite (inf)"],
              out=["| jump | hybrid | inf |", "(inf against curvature's",
                   "| hybrid | jump | cd_err_rms | 1, 8 | inf at 8"])

    # 5. error_bounds.py: NaN, inf, an empty cell, a missing column, an empty or header-only file.
    bounds("5 nan", variant("e_nan", good_acc, lambda d: edit_cell(d / "variants.csv", "end_err_max_px", "nan", 2)),
           1, err=["variants.csv:3: column end_err_max_px: not finite: nan"])
    bounds("5 inf", variant("e_inf", good_acc, lambda d: edit_cell(d / "variants.csv", "end_err_max_px", "inf")),
           1, err=["variants.csv:2: column end_err_max_px: not finite: inf"])
    bounds("5 empty cell", variant("e_cell", good_acc, lambda d: edit_cell(d / "variants.csv", "end_err_max_px", "")),
           1, err=["variants.csv:2: column end_err_max_px: empty"])
    bounds("5 missing column", variant("e_col", good_acc, lambda d: drop_column(d / "variants.csv", "storage")),
           1, err=["missing column(s) storage"])
    bounds("5 empty file", variant("e_empty", good_acc, lambda d: (d / "variants.csv").write_text("")),
           1, err=["variants.csv: empty file"])
    bounds("5 header only", variant("e_header", good_acc, lambda d: header_only(d / "variants.csv")),
           1, err=["variants.csv: no data rows"])

    # 6. A missing or value-less metric column: its chart is left out with a warning, the tables still come.
    stability("6 no cd_err_rms column", variant("s_drop_cd", good_stab,
                                                lambda d: drop_column(d / "stability.csv", "cd_err_rms")), 0,
              err=["no column cd_err_rms: stability_cd_err_rms.png is not drawn"], out=["| mode | method |"],
              files=["stability_jitter_rms.png"], no_files=["stability_cd_err_rms.png"])
    stability("6 all-NaN iso_pct", variant("s_nan_iso", good_stab,
                                           lambda d: edit_cell(d / "stability.csv", "iso_pct", "nan", "all")), 0,
              err=["column iso_pct has no value: stability_iso_pct.png is not drawn"], out=["| mode | method |"],
              no_files=["stability_iso_pct.png"])

    # 7. study_charts.py: no `overall` rows; an infinite error rate.
    study("7 no overall", variant("t_nooverall", good_study,
                                  lambda d: keep_rows(d / "summary.csv", lambda r: r["grouping"] != "overall")), 1,
          err=["summary.csv: no row of grouping `overall`"])
    study("7 inf error_pct", variant("t_inf", good_study, lambda d: edit_cell(d / "summary.csv", "error_pct", "inf")),
          1, err=["summary.csv:2: column error_pct: infinite"])

    # 8. An output folder that is a file, or under a file; --bounds-cpp into a missing folder.
    afile = root / "afile"
    afile.write_text("not a folder\n")
    for script, d in (("charts.py", good_acc), ("stability_charts.py", good_stab), ("study_charts.py", good_study)):
        cases.append(Case(f"8 {script} OUTDIR a file", script, [d, afile], 1, err=[f"{script}: {afile}: not a folder"]))
        cases.append(Case(f"8 {script} OUTDIR under a file", script, [d, afile / "sub"], 1,
                          err=[f"{script}: {afile / 'sub'}: Not a directory"]))
        if os.geteuid() != 0:  # root writes anywhere
            locked = root / f"locked-{script}"
            locked.mkdir()
            locked.chmod(0o555)
            cases.append(Case(f"8 {script} OUTDIR unwritable", script, [d, locked], 1,
                              err=[f"{script}: {locked}", "ermission denied"]))
    stability("8 --bounds-cpp into a missing folder", good_stab, 1,
              extra=["--bounds-cpp", root / "no-such-folder" / "bounds.inc"], err=["no folder", "no-such-folder"])

    # 9. A byte order mark is read; a byte that is not UTF-8 is named by file and line.
    charts("9 BOM", variant("c_bom", good_acc, lambda d: add_bom(d / "variants.csv")), 0,
           out=["| `curvature/exact/f32/nearest`"])
    charts("9 not UTF-8", variant("c_latin1", good_acc, lambda d: latin1_on_line_3(d / "variants.csv")), 1,
           err=["variants.csv:3: not UTF-8"])
    stability("9 BOM", variant("s_bom", good_stab, lambda d: add_bom(d / "modes.csv"),
                               lambda d: add_bom(d / "stability.csv")), 0, out=["| jump |"])
    stability("9 not UTF-8", variant("s_latin1", good_stab, lambda d: latin1_on_line_3(d / "stability.csv")), 1,
              err=["stability.csv:3: not UTF-8"])
    study("9 BOM", variant("t_bom", good_study, lambda d: add_bom(d / "summary.csv"),
                           lambda d: add_bom(d / "trials.csv")), 0)
    study("9 not UTF-8", variant("t_latin1", good_study, lambda d: latin1_on_line_3(d / "trials.csv")), 1,
          err=["trials.csv:3: not UTF-8"])
    paired("9 BOM", variant("p_bom", good_study, lambda d: add_bom(d / "trials.csv")), 0,
           out=["| curvature:sign+1 \u2212 depth, all targets |"])
    paired("9 not UTF-8", variant("p_latin1", good_study, lambda d: latin1_on_line_3(d / "trials.csv")), 1,
           err=["trials.csv:3: not UTF-8"])
    bounds("9 BOM", variant("e_bom", good_acc, lambda d: add_bom(d / "variants.csv")), 0,
           out=["| curvature | exact | nearest |"])
    bounds("9 not UTF-8", variant("e_latin1", good_acc, lambda d: latin1_on_line_3(d / "variants.csv")), 1,
           err=["variants.csv:3: not UTF-8"])

    # 10. --variants naming no variant of the run; study_paired.py with nothing to compare or a bad `correct`.
    stability("10 unknown --variants", good_stab, 1, extra=["--variants", "exact,nope"],
              err=["--variants exact,nope", "nope", "it has: exact, exact+bilinear"])
    paired("10 header only", variant("p_header", good_study, lambda d: header_only(d / "trials.csv")), 1,
           err=["trials.csv: no data rows"])
    paired("10 one technique", variant("p_one", good_study,
                                       lambda d: keep_rows(d / "trials.csv", lambda r: r["technique"] == "depth")), 1,
           err=["one technique only (depth): nothing to compare"])
    paired("10 no scored trials", variant("p_unscored", good_study,
                                          lambda d: edit_cell(d / "trials.csv", "scored", "0", "all")), 1,
           err=["no scored trials: nothing to compare"])
    paired("10 correct 2", variant("p_correct", good_study, lambda d: edit_cell(d / "trials.csv", "correct", "2", 4)),
           1, err=["trials.csv:5: correct: not 0 or 1: '2'"])
    # 11. A run of other techniques than the paper's two (`study --technique none --technique hybrid`): its charts but
    # the paper's Fig. 4, which shows those two, and a warning that says so.
    def other_techniques(d):
        for name in ("summary.csv", "trials.csv"):
            for old, new in (("curvature:sign+1", "none"), ("depth", "hybrid")):
                edit_where(d / name, {"technique": old}, "technique", new)

    (out / "11 not the paper's techniques").mkdir(parents=True)  # an earlier run's chart there: removed
    (out / "11 not the paper's techniques" / "study_times.png").write_bytes(b"an earlier run's")
    study("11 not the paper's techniques", variant("t_others", good_study, other_techniques), 0,
          err=["study_times.png: not drawn", "no scored trial with a time of the paper's techniques"],
          files=["study_errors.png", "study_techniques.png"], no_files=["study_times.png"])

    # 12. The FAKE marker of --fake-data: it marks the charts while it is newer than the CSV files; a later run that
    # replaced them leaves it older, and they are measurements again; --fake-data never overwrites measurements.
    def marked(d, age_s):
        (d / "FAKE").write_text("made by charts.py --fake-data; not measurements\n")
        newest = max((d / n).stat().st_mtime_ns for n in ("variants.csv", "fig5_traces.csv", "fig2_grid.csv"))
        at = newest + age_s * 1_000_000_000  # in ns: a float of seconds loses the last digits, and the order with it
        os.utime(d / "FAKE", ns=(at, at))

    charts("12 FAKE marker", variant("fake", good_acc, lambda d: marked(d, 0)), 0, out=["**FAKE DATA**"])
    charts("12 stale FAKE marker", variant("fake_stale", good_acc, lambda d: marked(d, -60)), 0,
           err=["FAKE is older than the CSV files", "charted as measurements"], no_out=["FAKE DATA"])
    cases.append(Case("12 fake data over measurements", "charts.py", ["--fake-data", variant("fake_over", good_acc)],
                      1, err=["holds variants.csv, fig5_traces.csv, fig2_grid.csv and no FAKE marker"]))
    cases.append(Case("12 fake data over measurements after fake data", "charts.py",
                      ["--fake-data", variant("fake_over_stale", good_acc, lambda d: marked(d, -60))], 1,
                      err=["no FAKE marker newer than them"]))
    return cases


def run(case):
    command = [PYTHON, str(TOOLS / case.script)] + [str(a) for a in case.args]
    try:
        return subprocess.run(command, capture_output=True, text=True, timeout=100,
                              env=dict(os.environ, PYTHONDONTWRITEBYTECODE="1"))  # nothing left in tools/
    except subprocess.TimeoutExpired as e:
        return subprocess.CompletedProcess(command, 124, e.stdout or "", f"timed out after {e.timeout} s")


def judge(case, result, results):
    """What is wrong with the case's result (empty when nothing)."""
    problems = []
    if result.returncode != case.rc:
        problems.append(f"status {result.returncode}, expected {case.rc}")
    if "Traceback" in result.stderr:
        problems.append("a traceback on stderr")
    problems += [f"stderr lacks {t!r}" for t in case.err if t not in result.stderr]
    problems += [f"stdout lacks {t!r}" for t in case.out if t not in result.stdout]
    problems += [f"stderr has {t!r}" for t in case.no_err if t in result.stderr]
    problems += [f"stdout has {t!r}" for t in case.no_out if t in result.stdout]
    if case.rc != 0 and case.script == "stability_charts.py" and result.stdout:
        problems.append("tables printed although it failed")
    outdir = Path(case.args[1]) if len(case.args) > 1 and case.script != "error_bounds.py" else None
    problems += [f"{f} not written" for f in case.files if outdir is None or not (outdir / f).is_file()]
    problems += [f"{f} written" for f in case.no_files if outdir is not None and (outdir / f).exists()]
    if case.check:
        what, check = case.check
        baseline = results.get(("charts.py", "good accuracy"))
        said = check(result, baseline) if baseline is not None else "the good set did not run"
        if said:
            problems.append(said)
    if problems and (result.stderr or result.stdout):
        problems.append("stderr: " + result.stderr.strip()[-1500:])
    return problems


def check_coinciding():
    """Item 2 (fig5): a trace the same as an earlier method's is drawn under it, wide and pale."""
    sys.path.insert(0, str(TOOLS))
    sys.dont_write_bytecode = True
    import charts  # noqa: E402  (matplotlib: this interpreter has it)
    xs = [float(i) for i in range(10)]
    series = {("t", "curvature"): (xs, [1.0] * 10, []), ("t", "depth"): (xs, [2.0] * 10, []),
              ("t", "hybrid"): (xs, [1.0] * 8 + [3.0, 3.0], [])}
    got = charts.coinciding(series, ["t"], ["curvature", "depth", "hybrid"])
    return [] if got == {"hybrid": "curvature"} else [f"charts.coinciding: {got}, expected {{'hybrid': 'curvature'}}"]


def main():
    failed = []
    with tempfile.TemporaryDirectory(prefix="charts-inputs-") as tmp:
        root = Path(tmp)
        cases = build(root)
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(2, min(8, os.cpu_count() or 2))) as pool:
            futures = {(c.script, c.name): pool.submit(run, c) for c in cases}
            results = {key: f.result() for key, f in futures.items()}
        for case in cases:
            problems = judge(case, results[(case.script, case.name)], results)
            if problems:
                failed.append(f"{case.name} ({case.script}): " + "\n    ".join(problems))
        for dirpath, dirnames, _ in os.walk(root):  # the unwritable folders, so that they can be removed
            for d in dirnames:
                os.chmod(os.path.join(dirpath, d), 0o755)
    try:
        failed += check_coinciding()
    except Exception as e:  # noqa: BLE001  (a failure to report, not to end on)
        failed.append(f"charts.coinciding: {type(e).__name__}: {e}")
    if failed:
        print(f"charts_inputs_check: {len(failed)} of {len(cases) + 1} checks failed:", file=sys.stderr)
        for f in failed:
            print("  " + f, file=sys.stderr)
        return 1
    print(f"charts_inputs_check: {len(cases) + 1} checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
