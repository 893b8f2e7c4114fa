"""The study toolkit: what every study script in scripts/ shares.

- scenes: `set_args` (a study's edits as `rve`'s own `--set KEY=VALUE`: the one scene
  editor, the command line's; `toml_value` writes a value);
- running: `run_rve` (one `rve run` with its response rows, status and wall time),
  `Runner` (variants run a few times each, with median timings);
- formatting: `pct` (a fraction as a percentage, "0.64 %"), `ms` (seconds as ms);
- plots: `svg_plot` (curves and points, linear or log axes, plain SVG); and a shell
  interface (`main`) for scripts/paper-examples.

Import it as `import studykit` from a script in scripts/ (Python puts the script's own
folder first on the import path). Standard library only.
"""

import csv
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RVE = os.path.join(ROOT, "target", "release", "rve")


# ------------------------------------------------------------------------------- scenes
# One scene editor: `rve`'s own `--set KEY=VALUE` (docs/cli.md), which every study passes
# its edits through, so a scene is edited as the command line edits it and no study writes
# TOML of its own.
def toml_value(v):
    """A Python value as a TOML value: `0.5`, `true`, `"lu"`, `[1, 2]`, `{ to = [...] }`.
    Floats are written with `repr`, which reads back to the same double."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML value for {v!r}")


def set_args(edits):
    """`rve`'s `--set KEY=VALUE` arguments for the dotted keys of `edits`
    ("geometry.seed": 11, "materials.itz.penalty.lambda_p": 1e7, "path.0.increments": 40
    for the first `[[path]]`, "path": [{...}] for a new path). Missing tables are created;
    the scene's validation refuses a misspelt key."""
    return [a for key, value in (edits or {}).items() for a in ("--set", f"{key}={toml_value(value)}")]


def line_path(to, increments):
    """A `[[path]]` list of one straight segment."""
    return [{"to": list(to), "increments": increments}]


# ------------------------------------------------------------------------------ running
class Run:
    """One `rve run`: `rows` (response.csv as floats; the increments before a failure),
    `ok`, `status` ("ok" or the last line of the error), `wall` (seconds)."""

    def __init__(self, rows, ok, status, wall):
        self.rows, self.ok, self.status, self.wall = rows, ok, status, wall


def read_response(out_dir):
    """response.csv of an `rve run --out out_dir` as a list of dicts of floats."""
    path = os.path.join(out_dir, "response.csv")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def run_rve(scene, out_dir, rve=RVE, extra=(), edits=None):
    """Runs `rve run SCENE --out OUT_DIR --quiet` with `edits` set (`set_args`) and reads
    its response."""
    t0 = time.perf_counter()
    p = subprocess.run([rve, "run", scene, "--out", out_dir, "--quiet", *set_args(edits), *extra],
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    lines = [line for line in p.stderr.splitlines() if line.strip()]
    status = "ok" if p.returncode == 0 else (lines[-1] if lines else f"exit {p.returncode}")
    return Run(read_response(out_dir), p.returncode == 0, status, wall)


# --------------------------------------------------------------------------- formatting
def pct(x, digits=2):
    """A fraction as a percentage with `digits` significant digits: 0.0064 -> "0.64 %"."""
    return f"{100 * x:.{digits}g} %"


# ------------------------------------------------------------------- repeated runs
class Runner:
    def __init__(self, rve, tmp, repeats, budget):
        self.rve, self.tmp, self.repeats, self.budget = rve, tmp, repeats, budget
        self.count = 0
        self.wall = 0.0
        # Increments of the first run of every variant, and those the fast path answered.
        self.increments = 0
        self.fast = 0

    def mesh_stats(self, scene, edits=None):
        out = subprocess.run([self.rve, "mesh", scene, *set_args(edits), "--json"],
                             capture_output=True, text=True, check=True).stdout
        return json.loads(out)

    def run(self, name, base, edits):
        """Run a variant REPEATS times; return a dict with the rows and median timings.

        A run that fails (the solver gives up at some increment) is not repeated; its
        response.csv holds the increments before the failure, which are kept (`failed`
        holds the error message)."""
        totals, medians, rows, failed = [], [], None, None
        spent = 0.0
        for r in range(self.repeats):
            if r > 0 and spent > self.budget:
                break  # expensive variant: fewer repeats keep the study within minutes
            out = os.path.join(self.tmp, "%s.%d" % (name, r))
            run = run_rve(base, out, rve=self.rve, edits=edits)
            self.wall += run.wall
            spent += run.wall
            self.count += 1
            rr = run.rows
            shutil.rmtree(out, ignore_errors=True)
            if not run.ok:
                msg = run.status
                m = re.search(r"relative residual ([0-9.eE+-]+)", msg)
                failed = "solver gave up after increment %d (eps_xx = %.4g)%s" % (
                    len(rr), rr[-1]["eps_xx"] if rr else 0.0,
                    ", residual %s" % m.group(1) if m else ": " + msg)
                print("note: %s: %s" % (name, msg), file=sys.stderr)
            secs = [row["seconds"] for row in rr] or [0.0]
            totals.append(sum(secs))
            medians.append(statistics.median(secs))
            if rows is None:
                rows = rr
                self.increments += len(rr)
                self.fast += int(sum(row.get("fast", 0.0) for row in rr))
            elif any(a["sig_xx"] != b["sig_xx"] or a["iterations"] != b["iterations"]
                     for a, b in zip(rows, rr)):
                print("warning: %s is not reproducible across repeats" % name, file=sys.stderr)
            if failed:
                break
        return {
            "name": name, "scene": base, "edits": edits, "rows": rows, "failed": failed,
            "runs": len(totals), "total": statistics.median(totals), "total_min": min(totals),
            "total_max": max(totals), "per_inc": statistics.median(medians),
            "iterations": int(sum(r["iterations"] for r in rows)),
            "max_iterations": int(max([r["iterations"] for r in rows] or [0])),
            "max_substeps": int(max([r["substeps"] for r in rows] or [0])),
        }


def ms(x):
    """Seconds as milliseconds for a table cell: two significant digits below 0.1 ms, one
    decimal below 10 s, none above."""
    if 1e3 * x < 0.1:
        return "%.2g" % (1e3 * x)
    return "%.1f" % (1e3 * x) if x < 10 else "%.0f" % (1e3 * x)


# ------------------------------------------------------------------------------ plots
def svg_plot(path, title, xlabel, ylabel, series, logx=False, logy=False, w=640, h=420,
             legend=160, hlines=(), marks=()):
    """series: list of (label, colour, [(x, y, point_label)], draw_line[, marker radius,
    default 3, 0 for none]); draw_line "dashed" draws it dashed. hlines: (y, label), dotted
    lines across the plot; marks: (x, y, label), open circles with a label. A linear axis
    whose values are all positive starts at 0 when the smallest is below 30 % of the
    largest; the lines x = 0 and y = 0 are drawn when inside the plot."""
    ml, mr, mt, mb = 70, legend, 40, 50
    pw, ph = w - ml - mr, h - mt - mb
    xs = [p[0] for s in series for p in s[2]] + [m[0] for m in marks]
    ys = [p[1] for s in series for p in s[2]] + [m[1] for m in marks] + [y for y, _ in hlines]
    fx = (lambda v: math.log10(v)) if logx else (lambda v: v)
    fy = (lambda v: math.log10(v)) if logy else (lambda v: v)

    def span(vals, f, log):
        lo, hi = min(f(v) for v in vals), max(f(v) for v in vals)
        if log:
            return math.floor(lo), math.ceil(hi) if math.ceil(hi) > math.floor(lo) else math.floor(lo) + 1
        pad = 0.05 * (hi - lo or 1.0)
        return (0.0 if lo >= 0 and lo < 0.3 * hi else lo - pad), hi + pad

    x0, x1 = span(xs, fx, logx)
    y0, y1 = span(ys, fy, logy)
    X = lambda v: ml + (fx(v) - x0) / (x1 - x0) * pw
    Y = lambda v: mt + ph - (fy(v) - y0) / (y1 - y0) * ph
    o = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" '
         'font-family="sans-serif" font-size="12">' % (w, h),
         '<rect width="100%" height="100%" fill="white"/>',
         '<text x="%d" y="22" font-size="14">%s</text>' % (ml, title),
         '<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="#333"/>' % (ml, mt, pw, ph)]

    def ticks(a, b, log):
        if log:
            return [10.0 ** k for k in range(int(a), int(b) + 1)]
        step = 10 ** math.floor(math.log10((b - a) / 5))
        for m in (1, 2, 5, 10):
            if (b - a) / (m * step) <= 6:
                step *= m
                break
        t = math.ceil(a / step) * step
        out = []
        while t <= b + 1e-12:
            out.append(t)
            t += step
        return out

    for t in ticks(x0, x1, logx):
        x = X(t)
        o.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#ddd"/>' % (x, mt, x, mt + ph))
        o.append('<text x="%.1f" y="%d" text-anchor="middle">%s</text>' % (x, mt + ph + 16, "%g" % t))
    for t in ticks(y0, y1, logy):
        y = Y(t)
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#ddd"/>' % (ml, y, ml + pw, y))
        o.append('<text x="%d" y="%.1f" text-anchor="end">%s</text>' % (ml - 6, y + 4, "%g" % t))
    o.append('<text x="%d" y="%d" text-anchor="middle">%s</text>' % (ml + pw / 2, h - 10, xlabel))
    o.append('<text transform="translate(16,%d) rotate(-90)" text-anchor="middle">%s</text>'
             % (mt + ph / 2, ylabel))
    if not logy and y0 < 0 < y1:
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#999"/>' % (ml, Y(0), ml + pw, Y(0)))
    if not logx and x0 < 0 < x1:
        o.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="#999"/>' % (X(0), mt, X(0), mt + ph))
    for y, label in hlines:
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="black" stroke-dasharray="2 3"/>'
                 '<text x="%d" y="%.1f">%s</text>' % (ml, Y(y), ml + pw, Y(y), ml + 4, Y(y) - 4, label))
    for k, (label, colour, pts, line, *radius) in enumerate(series):
        dash = ' stroke-dasharray="6 4"' if line == "dashed" else ""
        if line and len(pts) > 1:
            o.append('<polyline fill="none" stroke="%s" stroke-width="1.5"%s points="%s"/>'
                     % (colour, dash, " ".join("%.1f,%.1f" % (X(p[0]), Y(p[1])) for p in pts)))
        for p in pts:
            if (radius or [3])[0]:
                o.append('<circle cx="%.1f" cy="%.1f" r="%g" fill="%s"/>'
                         % (X(p[0]), Y(p[1]), (radius or [3])[0], colour))
            if p[2]:
                o.append('<text x="%.1f" y="%.1f" font-size="10">%s</text>'
                         % (X(p[0]) + 5, Y(p[1]) - 5, p[2]))
        ly = mt + 14 + 18 * k
        o.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"%s/>'
                 % (ml + pw + 10, ly - 4, ml + pw + 30, ly - 4, colour, dash))
        o.append('<text x="%d" y="%d">%s</text>' % (ml + pw + 34, ly, label))
    for x, y, label in marks:
        o.append('<circle cx="%.1f" cy="%.1f" r="4.5" fill="none" stroke="black"/>'
                 '<text x="%.1f" y="%.1f" font-size="11">%s</text>'
                 % (X(x), Y(y), X(x) + 7, Y(y) - 6, label))
    o.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(o) + "\n")


COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f"]


# ---------------------------------------------------------------------- shell interface
def main(argv):
    """For shell scripts (scripts/paper-examples):

    studykit.py run NAME SCENE WORK [KEY=VALUE ...]   rve run into WORK/NAME with each
                                                      `--set KEY=VALUE`; writes
                                                      WORK/NAME/status ("ok" or the error)
    """
    if len(argv) >= 4 and argv[0] == "run":
        name, scene, work = argv[1:4]
        out = os.path.join(work, name)
        os.makedirs(out, exist_ok=True)
        extra = [a for item in argv[4:] for a in ("--set", item)]
        run = run_rve(scene, out, extra=extra)
        with open(os.path.join(out, "status"), "w") as f:
            f.write(run.status + "\n")
        print(f"{name:<28} {run.wall:6.2f} s  {run.status}", flush=True)
    else:
        raise SystemExit(main.__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
