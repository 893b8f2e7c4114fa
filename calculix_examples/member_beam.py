#!/usr/bin/env python3
"""Writes the CalculiX deck of the plain-concrete beam in reversed three-point bending on
stdout (calculix_examples/member_beam_h10.inp and member_beam_h5.inp are this script with
`--size 10` and `--size 5`, the other options at their defaults).

  member_beam.py [--size H] [--down N] [--back N] [--up N] [--umax U] [--stages K,K,K|none]
                 [--stage-stress]

A plane-strain beam 400 mm long and 100 mm deep (thickness 1 mm, ccx's default) of CPE4
elements of H x H mm (H divides 100; default 10, the RVE's size: 400 elements, 3200 RVE
points; 5: 1600 elements, 12800 points: ccx runs a CPE4 as a C3D8 one element thick, with
8 integration points, two layers of 4 with the same strain), every point the paper's RVE
integrated by IMPL-EX (concrete_implex.toml, STATEV mode: *DEPVAR = its umat_nstatv 790
+ 5 mirrors). Supports at the bottom corners (left: ux = uy = 0; right: uy = 0), both
holding down as well as up. The load: the top node at mid-span (node set LOAD) moved in
y, down to -UMAX in N increments, back to 0 in N, up to +UMAX in N (defaults 24, 12, 24,
UMAX = 0.12 mm): increment k of the whole path (1, 2, ..., down + back + up) ends at its
own prescribed displacement, at time k. ccx's automatic incrementation, never above those
steps. Every increment has the same time increment (DTIME = 1, each step's time period is
its number of increments): IMPL-EX extrapolates the RVE's history by the ratio of the
increment's DTIME to the last one's (crates/core/src/solver/implex.rs), so a step whose increments
had another DTIME would extrapolate further or less at its first increment.

Stages: the increments K (default: down / 3, down, and the last) at which ccx prints every
point's state variables (*EL PRINT SDV, with the points' coordinates, COORD) to the
.dat: the beam before the peak, at the largest load of the downward branch and after the
reversal (scripts/member_figures.py colours the member by the damage mirror). Each stage
increment is a step of its own (ccx prints a step's every increment); the other steps
print the stresses of the two bottom elements at mid-span (element set EMID), which also
cancels the previous step's SDV request. Splitting the path into steps changes nothing
else: the prescribed displacement is ramped linearly within each step from where the last
one ended, and every increment has the same displacement and time increment.
`--stages none` prints no stage (ccx prints a stage's 795 values per point serially: on the
5 mm beam about 6 s a stage, docs/structure.md). `--stage-stress` prints every point's stresses at the stages too (*EL PRINT S: the per-point
comparison of studies/member-accuracy/member_accuracy.py).
"""
import argparse

LENGTH, DEPTH = 400.0, 100.0
MATERIAL = "@ABAQUS_RVE_UMAT@CONCRETE_IMPLEX"
# STATEV mode: `rve info calculix_examples/concrete_implex.toml`'s umat_nstatv (790) and
# the five inspection mirrors (docs/guide.md, *DEPVAR); damage is SDV 794, the largest
# opening SDV 795.
DEPVAR = 795


def grid(h):
    """(nx, ny, {node: (x, y)}, [element nodes, counterclockwise])."""
    nx, ny = round(LENGTH / h), round(DEPTH / h)
    if abs(nx * h - LENGTH) > 1e-9 or abs(ny * h - DEPTH) > 1e-9 or nx % 2:
        raise SystemExit(f"member_beam.py: the element size {h:g} must divide {DEPTH:g} mm")
    coords = {j * (nx + 1) + i + 1: (i * h, j * h) for j in range(ny + 1) for i in range(nx + 1)}
    elements = []
    for j in range(ny):
        for i in range(nx):
            n = j * (nx + 1) + i + 1
            elements.append((n, n + 1, n + nx + 2, n + nx + 1))
    return nx, ny, coords, elements


def mesh(h):
    nx, ny, coords, elements = grid(h)
    out = ["*NODE, NSET=NALL"]
    out += [f"{n}, {x:g}, {y:g}" for n, (x, y) in coords.items()]
    out += ["*ELEMENT, TYPE=CPE4, ELSET=EALL"]
    out += [f"{k + 1}, " + ", ".join(map(str, e)) for k, e in enumerate(elements)]
    out += ["*NSET, NSET=LOAD", str(ny * (nx + 1) + nx // 2 + 1),
            "*NSET, NSET=SUPL", "1", "*NSET, NSET=SUPR", str(nx + 1),
            "*ELSET, ELSET=EMID", f"{nx // 2}, {nx // 2 + 1}"]
    return out, len(elements)


def path(a):
    """[(u at the end of increment k)] for k = 1 .. down + back + up."""
    u = [-a.umax * k / a.down for k in range(1, a.down + 1)]
    u += [-a.umax * (1 - k / a.back) for k in range(1, a.back + 1)]
    return u + [a.umax * k / a.up for k in range(1, a.up + 1)]


def steps(a):
    """[(u at the step's end, increments, stage)]: the path cut so that every stage
    increment is a step of one increment, and at every turn of the load."""
    ends = {a.down, a.down + a.back, len(path(a))} | set(a.stages)
    ends |= {k - 1 for k in a.stages if k > 1}
    u, out, last = path(a), [], 0
    for k in sorted(ends):
        out.append((u[k - 1], k - last, k in a.stages))
        last = k
    return out


def step(u, n, stage, stress):
    out = ["*STEP, INC=1000", "*STATIC", f"1., {n}., 1e-4, 1.",
           "*BOUNDARY", f"LOAD, 2, 2, {u + 0.0!r}",
           "*NODE PRINT, NSET=LOAD, TOTALS=ONLY", "RF", "*NODE PRINT, NSET=LOAD", "U"]
    stage_print = "SDV, COORD, S" if stress else "SDV, COORD"
    out += ["*EL PRINT, ELSET=EALL", stage_print] if stage else ["*EL PRINT, ELSET=EMID", "S"]
    return out + ["*END STEP"]


def header(a, n):
    size = f"{a.size:g}"
    return [
        f"** member_beam_h{size}.inp -- written by calculix_examples/member_beam.py --size {size}"
        f" --down {a.down} --back {a.back} --up {a.up} --umax {a.umax:g}"
        f" --stages {','.join(map(str, a.stages))}{' --stage-stress' if a.stage_stress else ''}.",
        f"** A plain-concrete beam 400 x 100 mm in plane strain, {n} CPE4 elements of {size} x {size} mm",
        f"** ({8 * n} RVE points: ccx's CPE4 has 8, two layers of 4), the paper's ITZ law integrated",
        "** by IMPL-EX (concrete_implex.toml, STATEV mode). Reversed three-point bending: supports",
        f"** at the bottom corners, the top node at mid-span (LOAD) moved down to -{a.umax:g} mm in {a.down}",
        f"** increments, back to 0 in {a.back}, up to +{a.umax:g} mm in {a.up}, DTIME = 1 throughout. Every point's",
        "** state variables printed at the stage increments (steps of one increment). Run with",
        "** LD_LIBRARY_PATH holding libRVE.so (librve.so) and MESORVE_SCENE_PATH=calculix_examples:",
        "** calculix_examples/member.md.",
        "*HEADING",
        "mesorve RVE at every integration point: concrete beam in reversed three-point bending",
    ]


def deck(a):
    lines, n = mesh(a.size)
    lines = header(a, n) + lines + [
        f"*MATERIAL, NAME={MATERIAL}", "*USER MATERIAL, CONSTANTS=6", "0., 0., 0., 0., 0., 0.",
        "*DEPVAR", str(DEPVAR), f"*SOLID SECTION, ELSET=EALL, MATERIAL={MATERIAL}", "1.",
        "*BOUNDARY", "SUPL, 1, 2, 0.", "SUPR, 2, 2, 0."]
    for u, k, stage in steps(a):
        lines += step(u, k, stage, a.stage_stress)
    return "\n".join(lines) + "\n"


def arguments(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--size", type=float, default=10.0)
    p.add_argument("--down", type=int, default=24)
    p.add_argument("--back", type=int, default=12)
    p.add_argument("--up", type=int, default=24)
    p.add_argument("--umax", type=float, default=0.12)
    p.add_argument("--stages", default=None,
                   type=lambda s: [] if s == "none" else [int(k) for k in s.split(",")])
    p.add_argument("--stage-stress", action="store_true")
    a = p.parse_args(argv)
    total = a.down + a.back + a.up
    if a.stages is None:
        a.stages = [max(1, a.down // 3), a.down, total]
    if min(a.down, a.back, a.up) < 1 or not all(1 <= k <= total for k in a.stages):
        p.error(f"increments must be positive and stages within 1 .. {total}")
    return a


if __name__ == "__main__":
    print(deck(arguments()), end="")
