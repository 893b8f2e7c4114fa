#!/usr/bin/env python3
"""Accuracy-cost study of mesorve's scene knobs.

Runs `rve run` on variants of scenes/paper_rve.toml and scenes/paper_rve_fine.toml
(written to a temporary directory), and writes docs/accuracy.md plus SVG plots.
Standard library only. Called by scripts/accuracy-study; see that script for usage.

Every number in the report comes from the runs made here: times are the `seconds` column
of response.csv (the wall time of each update, excluding meshing and model setup); each
variant is run REPEATS times and the median over repeats is reported, because the
machine may be shared. Stresses are checked to be identical across repeats.
"""

import argparse
import csv
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import study_provenance

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COARSE = os.path.join(ROOT, "scenes", "paper_rve.toml")
FINE = os.path.join(ROOT, "scenes", "paper_rve_fine.toml")
EPS_END = 2.2e-4  # the section 5.2.1 path, eps = [2.2e-4, 0, 0]


# ---------------------------------------------------------------- scene editing

def set_key(text, section, key, value):
    """Set `key = value` inside `[section]` (or the first `[[section]]`) of a TOML text.

    Replaces the key's line if present, else inserts it right after the header. Only the
    flat `key = value` lines the shipped scenes use are handled."""
    lines = text.split("\n")
    start = None
    for i, line in enumerate(lines):
        s = line.strip()
        if s in ("[%s]" % section, "[[%s]]" % section):
            start = i
            break
    if start is None:
        lines += ["", "[%s]" % section, "%s = %s" % (key, value)]
        return "\n".join(lines)
    end = len(lines)
    for j in range(start + 1, len(lines)):
        if lines[j].strip().startswith("["):
            end = j
            break
    pat = re.compile(r"^\s*%s\s*=" % re.escape(key))
    for j in range(start + 1, end):
        if pat.match(lines[j]):
            lines[j] = "%s = %s" % (key, value)
            return "\n".join(lines)
    lines.insert(start + 1, "%s = %s" % (key, value))
    return "\n".join(lines)


def absolutize_files(text, scene_dir):
    """Scene files name meshes relative to the scene's directory (`geometry.file`); a copy
    written elsewhere must name them absolutely."""
    def repl(m):
        path = m.group(2)
        if not os.path.isabs(path):
            path = os.path.normpath(os.path.join(scene_dir, path))
        return '%sfile = "%s"' % (m.group(1), path)
    return re.sub(r'^(\s*)file\s*=\s*"([^"]*)"', repl, text, flags=re.M)


def toml_value(v):
    if isinstance(v, str):
        return '"%s"' % v
    if isinstance(v, float):
        return repr(v)
    return str(v)


def make_scene(base, edits, path):
    with open(base) as f:
        text = f.read()
    text = absolutize_files(text, os.path.dirname(base))
    for (section, key), value in edits.items():
        text = set_key(text, section, key, toml_value(value))
    with open(path, "w") as f:
        f.write(text)
    return path


# ---------------------------------------------------------------- running

class Runner:
    def __init__(self, rve, tmp, repeats, budget):
        self.rve, self.tmp, self.repeats, self.budget = rve, tmp, repeats, budget
        self.count = 0
        self.wall = 0.0
        # Increments of the first run of every variant, and those the fast path answered.
        self.increments = 0
        self.fast = 0

    def mesh_stats(self, scene):
        out = subprocess.run([self.rve, "mesh", scene, "--json"], capture_output=True,
                             text=True, check=True).stdout
        return json.loads(out)

    def run(self, name, base, edits):
        """Run a variant REPEATS times; return a dict with the rows and median timings.

        A run that fails (the solver gives up at some increment) is not repeated; its
        response.csv holds the increments before the failure, which are kept (`failed`
        holds the error message)."""
        scene = make_scene(base, edits, os.path.join(self.tmp, name + ".toml"))
        totals, medians, rows, failed = [], [], None, None
        spent = 0.0
        for r in range(self.repeats):
            if r > 0 and spent > self.budget:
                break  # expensive variant: fewer repeats keep the study within minutes
            out = os.path.join(self.tmp, "%s.%d" % (name, r))
            t0 = time.perf_counter()
            p = subprocess.run([self.rve, "run", scene, "--out", out, "--quiet"],
                               capture_output=True, text=True)
            self.wall += time.perf_counter() - t0
            spent += time.perf_counter() - t0
            self.count += 1
            rr = []
            if os.path.exists(os.path.join(out, "response.csv")):
                with open(os.path.join(out, "response.csv")) as f:
                    rr = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
            shutil.rmtree(out, ignore_errors=True)
            if p.returncode != 0:
                msg = (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]
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
            "name": name, "scene": scene, "rows": rows, "failed": failed,
            "runs": len(totals), "total": statistics.median(totals), "total_min": min(totals),
            "total_max": max(totals), "per_inc": statistics.median(medians),
            "iterations": int(sum(r["iterations"] for r in rows)),
            "max_iterations": int(max([r["iterations"] for r in rows] or [0])),
            "max_substeps": int(max([r["substeps"] for r in rows] or [0])),
        }


# ---------------------------------------------------------------- measures

def peak(rows):
    i = max(range(len(rows)), key=lambda k: rows[k]["sig_xx"])
    return i, rows[i]["sig_xx"], rows[i]["eps_xx"]


def at_strain(rows, eps):
    for r in rows:
        if abs(r["eps_xx"] - eps) <= 1e-9 * EPS_END:
            return r
    raise KeyError(eps)


def ms(x):
    if 1e3 * x < 0.1:
        return "%.2g" % (1e3 * x)
    return "%.1f" % (1e3 * x) if x < 10 else "%.0f" % (1e3 * x)


def pct(x, digits=2):
    if x is None:
        return "—"
    if x == 0:
        return "0 (ref.)"
    if abs(x) < 10 ** (-digits):
        return "%.1e" % x
    return "%.*f" % (digits, x)


def time_cells(v):
    if v["failed"]:
        return "%s (1 run, %d increments done)" % (ms(v["total"]), len(v["rows"]))
    if v["runs"] == 1:
        return "%s (1 run)" % ms(v["total"])
    return "%s (%s–%s, %d runs)" % (ms(v["total"]), ms(v["total_min"]), ms(v["total_max"]), v["runs"])


def notes(vs, md):
    """List the failed runs under a table."""
    for v in vs:
        if v["failed"]:
            md.append("- `%s`: %s. Its row uses the increments done." % (v["name"], v["failed"]))


# ---------------------------------------------------------------- SVG

def svg_plot(path, title, xlabel, ylabel, series, logx=False, logy=False, w=640, h=420,
             legend=160):
    """series: list of (label, colour, [(x, y, point_label)], draw_line[, marker radius,
    default 3, 0 for none])."""
    ml, mr, mt, mb = 70, legend, 40, 50
    pw, ph = w - ml - mr, h - mt - mb
    xs = [p[0] for s in series for p in s[2]]
    ys = [p[1] for s in series for p in s[2]]
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
    for k, (label, colour, pts, line, *radius) in enumerate(series):
        if line and len(pts) > 1:
            o.append('<polyline fill="none" stroke="%s" stroke-width="1.5" points="%s"/>'
                     % (colour, " ".join("%.1f,%.1f" % (X(p[0]), Y(p[1])) for p in pts)))
        for p in pts:
            if (radius or [3])[0]:
                o.append('<circle cx="%.1f" cy="%.1f" r="%g" fill="%s"/>'
                         % (X(p[0]), Y(p[1]), (radius or [3])[0], colour))
            if p[2]:
                o.append('<text x="%.1f" y="%.1f" font-size="10">%s</text>'
                         % (X(p[0]) + 5, Y(p[1]) - 5, p[2]))
        ly = mt + 14 + 18 * k
        o.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"/>'
                 % (ml + pw + 10, ly - 4, ml + pw + 30, ly - 4, colour))
        o.append('<text x="%d" y="%d">%s</text>' % (ml + pw + 34, ly, label))
    o.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(o) + "\n")


COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f"]


# ---------------------------------------------------------------- studies

def mesh_study(R, md):
    # (size, interface_size): the two shipped scenes' values and others at the same ratio.
    sizes = [(1.2, 0.69), (0.84, 0.48), (0.6, 0.34), (0.42, 0.24), (0.3, 0.17),
             (0.21, 0.127), (0.15, 0.09)]
    REF = 5  # index of the fine scene's mesh, the reference
    vs = []
    for s, si in sizes:
        v = R.run("mesh_%g" % s, FINE, {("mesh", "size"): s, ("mesh", "interface_size"): si})
        st = R.mesh_stats(make_scene(FINE, {("mesh", "size"): s, ("mesh", "interface_size"): si},
                                     os.path.join(R.tmp, "m.toml")))
        v.update(size=s, isize=si, tri=st["triangles"], itz=st["interface_elements"])
        vs.append(v)
    ref = vs[REF]
    ip, sp, ep = peak(ref["rows"])
    d11 = ref["rows"][0]["D11"]
    md.append("## (a) Mesh density\n")
    md.append("Path: section 5.2.1, eps = [2.2e-4, 0, 0] in 20 increments, periodic BC, "
              "tolerance 1e-6, gauss3; `mesh.size` / `mesh.interface_size` varied on the "
              "paper's microstructure (seed 7; 0.84/0.48 is `paper_rve.toml`, 0.21/0.127 is "
              "`paper_rve_fine.toml`, the others keep the same ratio). Reference: the fine "
              "scene (0.21). The 0.15 row is finer than the reference and shows how far the "
              "reference itself is from convergence. Pre-peak error: max |sig_xx − ref| over "
              "increments 1..%d (before the reference's peak at increment %d, eps_xx = %.3g), "
              "divided by the reference peak %.3f N/mm². D11 error: initial tangent "
              "(increment 1) vs the reference's %.0f N/mm².\n" % (ip, ip + 1, ep, sp, d11))
    md.append("| mesh.size / interface_size | triangles / ITZ | total time ms (min–max) | "
              "median ms / increment | Newton iterations | pre-peak error % | "
              "D11 error % | peak sig_xx (increment) | peak error % |")
    md.append("|---|---|---|---|---|---|---|---|---|")
    for v in vs:
        rows = v["rows"]
        if len(rows) < ip:
            md.append("| %g / %g | | failed before the peak (below) | | | | | | |" % (v["size"], v["isize"]))
            continue
        e = max(abs(rows[k]["sig_xx"] - ref["rows"][k]["sig_xx"]) for k in range(ip)) / sp
        ed = abs(rows[0]["D11"] - d11) / d11
        jp, spv, _ = peak(rows)
        v.update(err=e, d11err=ed, peakerr=abs(spv - sp) / sp)
        md.append("| %g / %g%s | %d / %d | %s | %s | %d | %s | %s | %.3f (%d) | %s |" % (
            v["size"], v["isize"], " (ref.)" if v is ref else "", v["tri"], v["itz"],
            time_cells(v), ms(v["per_inc"]), v["iterations"],
            pct(100 * e if v is not ref else 0), pct(100 * ed if v is not ref else 0),
            spv, jp + 1, pct(100 * v["peakerr"] if v is not ref else 0)))
    notes(vs, md)
    return vs, ref


def quadrature_study(R, md):
    md.append("## (b) Interface quadrature\n")
    md.append("Same path and settings; `mesh.interface_quadrature` on the coarse "
              "(`paper_rve.toml`) and fine (`paper_rve_fine.toml`) meshes. Reference: gauss3 "
              "(the paper's). Stress error: max over all 20 increments of |sig_xx − ref| / "
              "reference peak.\n")
    md.append("| mesh | quadrature | total time ms (min–max) | median ms / increment | "
              "Newton iterations | peak sig_xx (increment) | peak diff % | "
              "pre-peak max diff % | D11 diff % | max diff, all increments % |")
    md.append("|---|---|---|---|---|---|---|---|---|---|")
    out = {}
    for mesh, base in (("coarse", COARSE), ("fine", FINE)):
        g = R.run("quad_g3_" + mesh, base, {("mesh", "interface_quadrature"): "gauss3"})
        l = R.run("quad_l2_" + mesh, base, {("mesh", "interface_quadrature"): "lobatto2"})
        ip, sp, _ = peak(g["rows"])
        for v in (g, l):
            r = v["rows"]
            if len(r) < ip:
                md.append("| %s | %s | failed before the peak (below) | | | | | | | |" % (mesh, v["name"]))
                continue
            jp, spv, _ = peak(r)
            pre = max(abs(r[k]["sig_xx"] - g["rows"][k]["sig_xx"]) for k in range(ip)) / sp
            allm = max(abs(a["sig_xx"] - b["sig_xx"]) for a, b in zip(r, g["rows"])) / sp
            dd = abs(r[0]["D11"] - g["rows"][0]["D11"]) / g["rows"][0]["D11"]
            v.update(peakdiff=(spv - sp) / sp, prediff=pre, alldiff=allm)
            md.append("| %s | %s | %s | %s | %d | %.3f (%d) | %s | %s | %s | %s |" % (
                mesh, "gauss3 (ref.)" if v is g else "lobatto2", time_cells(v),
                ms(v["per_inc"]), v["iterations"], spv, jp + 1,
                pct(100 * (spv - sp) / sp) if v is l else "0 (ref.)",
                pct(100 * pre) if v is l else "0 (ref.)", pct(100 * dd, 3) if v is l else "0 (ref.)",
                pct(100 * allm) if v is l else "0 (ref.)"))
        out[mesh] = (g, l)
        notes((g, l), md)
    return out


def tolerance_study(R, md):
    tols = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
    md.append("## (c) Newton tolerance\n")
    md.append("Same path; `solver.tolerance` from 1e-4 to 1e-10 on both meshes (1e-6 is the "
              "shipped setting). Reference: 1e-10 (where it gives up past the peak, its "
              "increments before are used). Pre-peak stress error: max |sig_xx − ref| / "
              "reference peak over the increments before the peak of the shipped 1e-6 run; tangent "
              "error: max over the same increments of max_ij |D_ij − D_ref,ij| / "
              "max_ij |D_ref,ij|. Past the peak the RVE has several equilibria within one "
              "increment, so instead of an error the table gives sig_xx at the last two "
              "increments: a different value there is a different branch, not a less "
              "accurate one.\n")
    md.append("| mesh | tolerance | total time ms (min–max) | median ms / increment | "
              "Newton iterations | max iterations / increment (max substeps) | "
              "pre-peak stress error % | pre-peak tangent error % | sig_xx at increments 19, 20 |")
    md.append("|---|---|---|---|---|---|---|---|---|")
    out = {}
    keys = ["D%d%d" % (i, j) for i in (1, 2, 3) for j in (1, 2, 3)]
    for mesh, base in (("coarse", COARSE), ("fine", FINE)):
        vs = [R.run("tol_%g_%s" % (t, mesh), base, {("solver", "tolerance"): t}) for t in tols]
        for t, v in zip(tols, vs):
            v["tol"] = t
        ref = vs[-1]
        ip = peak(vs[2]["rows"])[0]  # before the peak of the shipped setting (1e-6)
        sp = max(r["sig_xx"] for r in ref["rows"])
        for t, v in zip(tols, vs):
            if len(v["rows"]) < ip or len(ref["rows"]) < ip:
                md.append("| %s | %g | failed before the peak (below) | | | | | | |" % (mesh, t))
                continue
            pr = list(zip(v["rows"][:ip], ref["rows"][:ip]))
            es = max(abs(a["sig_xx"] - b["sig_xx"]) for a, b in pr) / sp
            et = max(max(abs(a[k] - b[k]) for k in keys) / max(abs(b[k]) for k in keys)
                     for a, b in pr)
            v.update(err=es, terr=et)
            md.append("| %s | %g%s | %s | %s | %d | %d (%d) | %s | %s | %s |" % (
                mesh, t, " (ref.)" if v is ref else "", time_cells(v), ms(v["per_inc"]),
                v["iterations"], v["max_iterations"], v["max_substeps"],
                pct(100 * es, 4) if v is not ref else "0 (ref.)",
                pct(100 * et, 4) if v is not ref else "0 (ref.)",
                ", ".join("%.3f" % r["sig_xx"] for r in v["rows"][18:20]) + (" †" if v["failed"] else "")))
        out[mesh] = vs
        notes(vs, md)
    return out


def increments_study(R, md):
    ns = [5, 10, 20, 40, 80, 160]
    md.append("## (d) Number of increments\n")
    md.append("Same path cut into n equal increments (`[[path]] increments`). Reference: "
              "n = 160 (pre-peak and peak; where it gives up near the peak, its increments "
              "before are used, and its peak is the largest stress it reached), and the "
              "largest n that completes the path for the end point. The strain points common to all runs are those of n = 5 "
              "(eps_xx = 4.4e-5, 8.8e-5, 1.32e-4, 1.76e-4, 2.2e-4); the first four lie before "
              "the peak, the last one after it. Pre-peak error: max |sig_xx − ref| / "
              "reference peak over the first four; end error: the same at eps_xx = 2.2e-4. "
              "Peak captured: the largest sig_xx the run reports, and its signed difference from the reference's (a coarse path steps over the "
              "limit point); the increment that crosses the peak is the one with the most "
              "Newton iterations.\n")
    md.append("| mesh | increments | total time ms (min–max) | median ms / increment | "
              "Newton iterations | max iterations (at eps_xx) | max substeps | "
              "pre-peak error % | end-point error % | peak captured sig_xx (eps_xx) | peak error % |")
    md.append("|---|---|---|---|---|---|---|---|---|---|---|")
    common = [EPS_END * k / 5 for k in range(1, 6)]
    out = {}
    for mesh, base in (("coarse", COARSE), ("fine", FINE)):
        vs = [R.run("inc_%d_%s" % (n, mesh), base, {("path", "increments"): n}) for n in ns]
        ref = vs[-1]
        ip, sp, ep = peak(ref["rows"])
        done = [v for v in vs if not v["failed"]]
        eref = done[-1] if done else None
        for n, v in zip(ns, vs):
            v["n"] = n
            r = v["rows"]
            try:
                pre = max(abs(at_strain(r, e)["sig_xx"] - at_strain(ref["rows"], e)["sig_xx"])
                          for e in common[:4]) / sp
            except KeyError:
                md.append("| %s | %d | failed before the peak (below) | | | | | | | | |" % (mesh, n))
                continue
            end = (abs(at_strain(r, common[4])["sig_xx"] - at_strain(eref["rows"], common[4])["sig_xx"]) / sp
                   if not v["failed"] and eref is not None else None)
            jp, spv, epv = peak(r)
            km = max(range(len(r)), key=lambda k: r[k]["iterations"])
            v.update(err=pre, enderr=end, peakerr=(spv - sp) / sp)
            md.append("| %s | %d%s | %s | %s | %d | %d (%.3g) | %d | %s | %s | %.3f (%.3g) | %s |" % (
                mesh, n, (" (ref.)" if v is ref else "") + (" †" if v["failed"] else ""), time_cells(v), ms(v["per_inc"]),
                v["iterations"], r[km]["iterations"], r[km]["eps_xx"], v["max_substeps"],
                pct(100 * pre) if v is not ref else "0 (ref.)",
                "0 (ref.)" if v is eref else ("failed" if end is None else pct(100 * end)),
                spv, epv, "%+.2f" % (100 * v["peakerr"]) if v is not ref else "0 (ref.)"))
        out[mesh] = vs
        notes(vs, md)
    return out


def boundary_study(R, md):
    kinds = ["taylor", "linear", "periodic", "minimal"]
    md.append("## (e) Boundary condition\n")
    md.append("Same path; `boundary.kind` on both meshes. There is no converged reference "
              "here: the four conditions are different models, bounds in the order "
              "taylor ≥ linear ≥ periodic ≥ minimal for the stiffness. Differences are "
              "given relative to periodic (the shipped scenes').\n")
    md.append("| mesh | boundary | total time ms (min–max) | median ms / increment | "
              "Newton iterations | D11 initial | D11 vs periodic % | peak sig_xx (eps_xx) | "
              "peak vs periodic % | sig_xx at 2.2e-4 |")
    md.append("|---|---|---|---|---|---|---|---|---|---|")
    out = {}
    for mesh, base in (("coarse", COARSE), ("fine", FINE)):
        vs = {k: R.run("bc_%s_%s" % (k, mesh), base, {("boundary", "kind"): k}) for k in kinds}
        per = vs["periodic"]
        for k in kinds:
            v = vs[k]
            r = v["rows"]
            if not r or not per["rows"]:
                md.append("| %s | %s | failed at once (below) | | | | | | | |" % (mesh, k))
                continue
            jp, spv, epv = peak(r)
            d = r[0]["D11"]
            dp = per["rows"][0]["D11"]
            sp = peak(per["rows"])[1]
            md.append("| %s | %s | %s | %s | %d | %.0f | %+.2f | %.3f (%.3g) | %+.2f | %.3f |" % (
                mesh, k, time_cells(v), ms(v["per_inc"]), v["iterations"], d,
                100 * (d - dp) / dp, spv, epv, 100 * (spv - sp) / sp, r[-1]["sig_xx"]))
        out[mesh] = vs
        notes(vs.values(), md)
    return out


# ---------------------------------------------------------------- main

def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rve", default=os.path.join(ROOT, "target", "release", "rve"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs"))
    ap.add_argument("--repeats", type=int, default=3,
                    help="runs per variant (the median time is reported)")
    ap.add_argument("--budget", type=float, default=3.0,
                    help="no further repeats of a variant once its runs took this many seconds")
    ap.add_argument("--readings", default=os.path.join(ROOT, "docs", "accuracy_readings.md"),
                    help="hand-written readings of the tables, inserted under each table "
                         "(sections start with '## (a)' ... '## (e)')")
    a = ap.parse_args()
    t_start = time.perf_counter()
    record = study_provenance.start()  # the commit the binary was just built from
    tmp = tempfile.mkdtemp(prefix="rve-accuracy-")
    R = Runner(a.rve, tmp, a.repeats, a.budget)
    sections = []
    try:
        for study in (mesh_study, quadrature_study, tolerance_study, increments_study,
                      boundary_study):
            md = []
            res = study(R, md)
            sections.append((md, res))
            print("done: %s (%d runs so far, %.0f s)" % (study.__name__, R.count,
                                                         time.perf_counter() - t_start),
                  file=sys.stderr)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(a.out, exist_ok=True)
    plots(a.out, sections)
    write_page(a, R, sections, study_provenance.finish(record, R.count))


def plots(out, sections):
    """The error-against-time plot of (a) and (d), and the mesh densities' curves."""
    mesh_vs, mesh_ref = sections[0][1]
    inc = sections[3][1]
    series = [("mesh.size (20 inc.)", COLOURS[0],
               [(v["total"], 100 * v["err"], "%d tri" % v["tri"]) for v in mesh_vs
                if "err" in v and v is not mesh_ref and v["err"] > 0], True)]
    for k, mesh in enumerate(("coarse", "fine")):
        series.append(("increments, %s" % mesh, COLOURS[1 + k],
                       [(v["total"], 100 * v["err"], "n=%d" % v["n"]) for v in inc[mesh][:-1]
                        if "err" in v and v["err"] > 0], True))
    svg_plot(os.path.join(out, "accuracy_error_vs_time.svg"),
             "Pre-peak sig_xx error vs time of the path (section 5.2.1 path)",
             "total time of the path, s (median over runs)",
             "pre-peak error, % of peak", series, logx=True, logy=True)
    curves = []
    for k, v in enumerate(mesh_vs):
        curves.append(("%d triangles" % v["tri"], COLOURS[k % len(COLOURS)],
                       [(1e4 * r["eps_xx"], r["sig_xx"], "") for r in v["rows"]], True))
    svg_plot(os.path.join(out, "accuracy_mesh_curves.svg"),
             "sig_xx vs eps_xx for each mesh density (20 increments)",
             "eps_xx x 1e4", "sig_xx, N/mm²", curves)


def write_page(a, R, sections, record):
    """docs/accuracy.md: the header, then each study's table and its hand-written reading;
    `record` is the run's provenance (`study_provenance.finish`)."""

    readings = {}
    if os.path.exists(a.readings):
        cur = None
        for line in open(a.readings):
            m = re.match(r"^## \((\w)\)", line)
            if m:
                cur = m.group(1)
                readings[cur] = []
            elif cur:
                readings[cur].append(line.rstrip("\n"))
    doc = ["# Accuracy and cost of the scene knobs\n",
           study_provenance.sentence(record),
           "",
           "Generated by `scripts/accuracy-study`; do not edit by hand — the "
           "readings under each table are hand-written in `docs/accuracy_readings.md` from "
           "the committed run (they quote stresses and iteration counts, which are "
           "deterministic; times move from run to run). Every number in the tables "
           "below is from the run named above (%.0f s of it inside `rve run`, including "
           "meshing and setup)." % R.wall,
           "",
           "Times are the `seconds` column of `response.csv` (wall time of each update, "
           "excluding meshing and model setup). Each variant ran up to %d times (fewer when "
           "its runs had taken %g s; a run that fails is not repeated); the tables give "
           "the median total of the path with the min–max over the runs, and the median "
           "over runs of the median time per increment. The machine these runs were made on is shared with other "
           "work, so differences in time below ~20 %% (and the absolute times) are not "
           "significant; stresses and iteration counts are deterministic (checked identical "
           "across repeats)." % (a.repeats, a.budget),
           "",
           "The fast path (`solver.fast_path`, `docs/fast_path.md`: an update that keeps every "
           "ITZ point on its linear branch, answered without Newton) answered %d of the %d "
           "increments of these runs (first run of each variant): the paths here load "
           "monotonically through the peak, so the times are those of full solves. Its share "
           "on cyclic paths is in `docs/robustness.md`." % (R.fast, R.increments),
           "",
           "IMPL-EX integration of the ITZ law (`solver.integration = \"implex\"`) against "
           "the implicit scheme, error against time on the §5.2.1 and §5.2.2 paths and ten "
           "hard cases: [implex_accuracy.md](implex_accuracy.md), the study's second part.",
           "",
           "![error vs time](accuracy_error_vs_time.svg)",
           "",
           "![mesh curves](accuracy_mesh_curves.svg)",
           ""]
    for (md, _), key in zip(sections, "abcde"):
        doc += md
        doc.append("")
        if key in readings:
            doc += readings[key]
        doc.append("")
    with open(os.path.join(a.out, "accuracy.md"), "w") as f:
        f.write(re.sub(r"\n{3,}", "\n\n", "\n".join(doc)).rstrip() + "\n")
    print("wrote %s (%.0f s)" % (os.path.join(a.out, "accuracy.md"), record["seconds"]),
          file=sys.stderr)


if __name__ == "__main__":
    main()
