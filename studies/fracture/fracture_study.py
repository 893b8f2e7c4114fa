"""The failing cell (docs/fracture.md): calibration of the paste's crack law against a
normal concrete's tensile strength and fracture energy, the compliance the paste's
interfaces add before cracking, and the cost against the ITZ-only cell.

Usage: python3 studies/fracture/fracture_study.py [--out DIR] [--rve PATH]

Every run is `rve run scenes/concrete_fracture.toml` (uniaxial tension, the lateral
stresses held at zero, to a strain of 2e-2) with `--set` edits:
1. calibration: the paste's fracture energy swept; per value the cell's peak stress f_t,
   its fracture energy G_F (the work of the macro stress to full separation times the
   cell's width, per unit crack length across it), the strain where the stress falls below
   5 % of the peak; the paste G_f that gives the target G_F, interpolated;
2. stiffness: the first increment's D11 against the ITZ-only cell, for initial
   stiffness factors 50, 200 (the default) and 1000 times E_paste / h;
3. cost: wall time (median of 3), state sizes and what each cell carries at 2e-2, with
   paste cracks everywhere, in a band across the crack's path, and with the ITZ alone;
4. mesh: f_t and G_F at mesh sizes 0.84 (the scene's), 0.6 and 0.42 (the interface size
   scaled alike).
Writes fracture_calibration.md and fracture_curves.svg into DIR (target/studies/fracture).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from kit.plot import COLOURS, svg_plot  # noqa: E402
from kit.rve import RVE, ROOT, run_rve, set_args  # noqa: E402

SCENE = os.path.join(ROOT, "scenes", "concrete_fracture.toml")
WIDTH = 10.0  # the scene's cell width, mm
# Targets of a normal concrete with the cell's largest aggregate (docs/fracture.md).
TARGET_FT = 3.2  # MPa: fib Model Code 2010, f_ctm = 0.3 f_ck^(2/3) at f_ck = 35 MPa
TARGET_GF = 67.0  # N/m: Bazant & Becq-Giraudon 2002 at f_c = 43 MPa, d_a = 5 mm, w/c = 0.5
SWEEP = [0.1, 0.15, 0.2, 0.25, 0.3]
ITZ_ONLY = {"effects.paste_cracking": False, "materials.paste_crack": None}


def measures(rows):
    """(peak, strain at peak, G_F in N/m, strain below 5 % of the peak, last stress)."""
    e = [r["eps_xx"] for r in rows]
    s = [r["sig_xx"] for r in rows]
    k = max(range(len(s)), key=lambda i: s[i])
    work = sum(0.5 * (s[i] + s[i - 1]) * (e[i] - e[i - 1]) for i in range(1, len(e)))
    below = next((e[i] for i in range(k, len(s)) if s[i] < 0.05 * s[k]), None)
    return s[k], e[k], 1e3 * work * WIDTH, below, s[-1]


def cell_info(rve, edits):
    """`rve info --json` of the scene with `edits`."""
    out = subprocess.run([rve, "info", SCENE, *set_args(edits), "--json"],
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def run(out, name, rve, edits, repeats=1):
    walls, rows = [], None
    for i in range(repeats):
        r = run_rve(SCENE, os.path.join(out, name), rve=rve, edits=edits)
        if not r.ok:
            sys.exit(f"fracture study: {name}: {r.status}")
        walls.append(r.wall)
        rows = r.rows
    return rows, statistics.median(walls)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "studies", "fracture"))
    ap.add_argument("--rve", default=RVE)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    md = ["# The failing cell: calibration, stiffness, cost", "",
          "Written by `studies/fracture/run` (`fracture_study.py`); `scenes/concrete_fracture.toml`"
          " in uniaxial tension to a strain of 2e-2.", "",
          "## Calibration of the paste's fracture energy", "",
          f"Targets: f_t {TARGET_FT} MPa, G_F {TARGET_GF:.0f} N/m.", "",
          "| paste G_f (N/mm) | cell f_t (MPa) | at strain | cell G_F (N/m) | below 5 % of the peak at | stress at 2e-2 |",
          "|---|---|---|---|---|---|"]
    curves, gfs = [], []
    for i, gf in enumerate(SWEEP):
        rows, _ = run(a.out, f"gf_{gf}", a.rve, {"materials.paste_crack.fracture_energy": gf})
        ft, eft, g, below, last = measures(rows)
        gfs.append((gf, g))
        md.append(f"| {gf} | {ft:.3f} | {eft:.2e} | {g:.1f} | "
                  f"{'%.2e' % below if below else 'not reached'} | {last:.4f} |")
        curves.append((f"paste G_f {gf} N/mm", COLOURS[i % len(COLOURS)],
                       [(r["eps_xx"] * 1e3, r["sig_xx"], "") for r in rows], True, 0))
    pick = next(((g0 + (TARGET_GF - c0) * (g1 - g0) / (c1 - c0)) for (g0, c0), (g1, c1)
                 in zip(gfs, gfs[1:]) if c0 <= TARGET_GF <= c1), None)
    md += ["", f"The paste G_f that gives G_F = {TARGET_GF:.0f} N/m, interpolated: "
           + (f"{pick:.3f} N/mm." if pick else "outside the sweep."), ""]

    md += ["## The paste's interfaces before cracking", "",
           "| initial stiffness (x E_paste / h) | D11 (MPa) | against the ITZ-only cell |", "|---|---|---|"]
    base, _ = run(a.out, "itz_only", a.rve, ITZ_ONLY)
    for factor in (50.0, 200.0, 1000.0):
        stiffness = factor * 25000.0 / 0.84
        rows, _ = run(a.out, f"k_{factor:g}", a.rve,
                      {"materials.paste_crack.stiffness": stiffness, "path.0.increments": 4,
                       "path.0.to": [2e-5, 0.0, 0.0]})
        md.append(f"| {factor:g} | {rows[0]['D11']:.1f} | {rows[0]['D11'] / base[0]['D11'] - 1:+.2%} |")

    md += ["", "## Cost", "",
           "| cell | wall time, median of 3 (s) | stress at 2e-2 (MPa) | G_F (N/m) | unknowns | instance bytes | umat_nstatv |",
           "|---|---|---|---|---|---|---|"]
    walls = {}
    band = {"materials.paste_crack.band": [3.0, 0.0, 8.0, 10.0]}
    for name, edits in (("with paste cracks", {}), ("paste cracks in the band x = 3-8 mm", band),
                        ("ITZ only", ITZ_ONLY)):
        rows, wall = run(a.out, "cost", a.rve, edits, repeats=3)
        walls[name] = wall
        info = cell_info(a.rve, edits)
        _, _, energy, below, _ = measures(rows)
        energy = f"{energy:.1f}" if below else "no failure"
        md.append(f"| {name} | {wall:.2f} | {rows[-1]['sig_xx']:.4f} | {energy} | "
                  f"{info['unknowns']} | {info['instance_bytes']} | {info['umat_nstatv']} |")
        if name == "ITZ only":
            curves.append(("ITZ only", "#888888",
                           [(r["eps_xx"] * 1e3, r["sig_xx"], "") for r in rows if r["sig_xx"] < 8],
                           "dashed", 0))
    md += ["", f"Ratio: {walls['with paste cracks'] / walls['ITZ only']:.2f}."]

    md += ["", "## Mesh", "", "| mesh size (mm) | unknowns | cell f_t (MPa) | cell G_F (N/m) | stress at 2e-2 |",
           "|---|---|---|---|---|"]
    for size in (0.84, 0.6, 0.42):
        edits = {"mesh.size": size, "mesh.interface_size": round(size * 0.48 / 0.84, 6)}
        rows, _ = run(a.out, f"mesh_{size}", a.rve, edits)
        ft, _, g, _, last = measures(rows)
        md.append(f"| {size} | {cell_info(a.rve, edits)['unknowns']} | {ft:.3f} | {g:.1f} | {last:.4f} |")
    with open(os.path.join(a.out, "fracture_calibration.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    svg_plot(os.path.join(a.out, "fracture_curves.svg"),
             "The paper's cell in uniaxial tension", "strain (1e-3)", "stress (MPa)", curves, legend=220)
    print("\n".join(md))


if __name__ == "__main__":
    main()
