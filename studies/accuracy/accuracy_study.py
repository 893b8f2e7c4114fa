#!/usr/bin/env python3
"""Accuracy-cost study of mesorve's scene knobs.

Runs `rve run` on variants of scenes/paper_rve.toml and scenes/paper_rve_fine.toml
(written to a temporary directory), and writes accuracy.md plus SVG plots into --out
(default target/studies/accuracy; studies/accuracy/run --docs copies them into docs/).
Standard library only. Called by studies/accuracy/run; see that script for usage.

Every number in the report comes from the runs made here: times are the `seconds` column
of response.csv (the wall time of each update, excluding meshing and model setup); each
variant is run REPEATS times and the median over repeats is reported, because the
machine may be shared. Stresses are checked to be identical across repeats.
"""

import argparse
import os
import re
import shutil
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from kit import ms, provenance  # noqa: E402
from kit.plot import COLOURS, svg_plot  # noqa: E402
from kit.rve import Runner  # noqa: E402

COARSE = os.path.join(ROOT, "scenes", "paper_rve.toml")
FINE = os.path.join(ROOT, "scenes", "paper_rve_fine.toml")
EPS_END = 2.2e-4  # the section 5.2.1 path, eps = [2.2e-4, 0, 0]


# ---------------------------------------------------------------- measures

def peak(rows):
    i = max(range(len(rows)), key=lambda k: rows[k]["sig_xx"])
    return i, rows[i]["sig_xx"], rows[i]["eps_xx"]


def at_strain(rows, eps):
    for r in rows:
        if abs(r["eps_xx"] - eps) <= 1e-9 * EPS_END:
            return r
    raise KeyError(eps)


def percent_cell(x, digits=2):
    """A number already in percent (100 * a relative error) as a table cell: `digits`
    decimals, "%.1e" below 10^-digits, "0 (ref.)" for the reference itself, "—" for none.
    (kit.pct takes a fraction instead.)"""
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


# ---------------------------------------------------------------- studies

def mesh_study(R, md):
    # (size, interface_size): the two shipped scenes' values and others at the same ratio.
    sizes = [(1.2, 0.69), (0.84, 0.48), (0.6, 0.34), (0.42, 0.24), (0.3, 0.17),
             (0.21, 0.127), (0.15, 0.09)]
    REF = 5  # index of the fine scene's mesh, the reference
    vs = []
    for s, si in sizes:
        v = R.run("mesh_%g" % s, FINE, {"mesh.size": s, "mesh.interface_size": si})
        st = R.mesh_stats(FINE, {"mesh.size": s, "mesh.interface_size": si})
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
            percent_cell(100 * e if v is not ref else 0), percent_cell(100 * ed if v is not ref else 0),
            spv, jp + 1, percent_cell(100 * v["peakerr"] if v is not ref else 0)))
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
        g = R.run("quad_g3_" + mesh, base, {"mesh.interface_quadrature": "gauss3"})
        l = R.run("quad_l2_" + mesh, base, {"mesh.interface_quadrature": "lobatto2"})
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
                percent_cell(100 * (spv - sp) / sp) if v is l else "0 (ref.)",
                percent_cell(100 * pre) if v is l else "0 (ref.)", percent_cell(100 * dd, 3) if v is l else "0 (ref.)",
                percent_cell(100 * allm) if v is l else "0 (ref.)"))
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
        vs = [R.run("tol_%g_%s" % (t, mesh), base, {"solver.tolerance": t}) for t in tols]
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
                percent_cell(100 * es, 4) if v is not ref else "0 (ref.)",
                percent_cell(100 * et, 4) if v is not ref else "0 (ref.)",
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
        vs = [R.run("inc_%d_%s" % (n, mesh), base, {"path.0.increments": n}) for n in ns]
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
                percent_cell(100 * pre) if v is not ref else "0 (ref.)",
                "0 (ref.)" if v is eref else ("failed" if end is None else percent_cell(100 * end)),
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
        vs = {k: R.run("bc_%s_%s" % (k, mesh), base, {"boundary.kind": k}) for k in kinds}
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
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "studies", "accuracy"))
    ap.add_argument("--repeats", type=int, default=3,
                    help="runs per variant (the median time is reported)")
    ap.add_argument("--budget", type=float, default=3.0,
                    help="no further repeats of a variant once its runs took this many seconds")
    ap.add_argument("--readings", default=os.path.join(ROOT, "docs", "accuracy_readings.md"),
                    help="hand-written readings of the tables, inserted under each table "
                         "(sections start with '## (a)' ... '## (e)')")
    a = ap.parse_args()
    t_start = time.perf_counter()
    record = provenance.start()  # the commit the binary was just built from
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
    write_page(a, R, sections, provenance.finish(record, R.count))


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
    """accuracy.md: the header, then each study's table and its hand-written reading;
    `record` is the run's provenance (`provenance.finish`)."""

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
           provenance.sentence(record),
           "",
           "Generated by `studies/accuracy/run`; do not edit by hand — the "
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
