#!/usr/bin/env python3
"""Writes the CalculiX deck of the notched strip (calculix_examples/specimen_notch.inp is
`notch_strip.py` with the defaults) on stdout.

  notch_strip.py [--size H] [--increment DT] [--direct] [--tension-only]

A plane-strain strip 80 mm wide and 50 mm high of CPE4 elements of H x H mm (H divides
10; default 10, the RVE's size), with a notch 10 x 10 mm cut out of each side edge
between y = 20 and 30 (the elements there left out), every integration point the paper's
RVE integrated by IMPL-EX (concrete_implex.toml). Displacement control of the top face in
y: step 1 tension to U = UMAX, step 2 unloading to U = 0, step 3 compression to -UMAX;
bottom face uy = 0, its left node ux = 0, sides free. Step 1's increments are DT of the
step (default 0.05), steps 2 and 3's 0.1; ccx's automatic incrementation (never above
them) unless --direct (fixed increments). --tension-only writes step 1 alone.
"""
import argparse

WIDTH, HEIGHT = 80.0, 50.0
NOTCHES = ((0.0, 10.0, 20.0, 30.0), (70.0, 80.0, 20.0, 30.0))  # x0, x1, y0, y1
UMAX = 0.020
MATERIAL = "@ABAQUS_RVE_UMAT@CONCRETE_IMPLEX"
# STATEV mode: `rve info calculix_examples/concrete_implex.toml`'s umat_nstatv (790) and
# the three inspection mirrors (docs/calculix.md, "State in STATEV").
DEPVAR = 793


def grid(h):
    nx, ny = round(WIDTH / h), round(HEIGHT / h)
    elements = []
    for j in range(ny):
        for i in range(nx):
            cx, cy = (i + 0.5) * h, (j + 0.5) * h
            if not any(x0 < cx < x1 and y0 < cy < y1 for x0, x1, y0, y1 in NOTCHES):
                n = j * (nx + 1) + i + 1
                elements.append((n, n + 1, n + nx + 2, n + nx + 1))
    used = sorted({n for e in elements for n in e})
    coords = {n: ((n - 1) % (nx + 1) * h, (n - 1) // (nx + 1) * h) for n in used}
    return coords, elements


def id_lines(ids):
    ids = list(ids)
    return [", ".join(map(str, ids[k:k + 16])) for k in range(0, len(ids), 16)]


def node_set(name, coords, y):
    return [f"*NSET, NSET={name}"] + id_lines(n for n, (_, ny) in coords.items() if ny == y)


def mesh(h):
    coords, elements = grid(h)
    out = ["*NODE, NSET=NALL"]
    out += [f"{n}, {x:g}, {y:g}" for n, (x, y) in coords.items()]
    out += ["*ELEMENT, TYPE=CPE4, ELSET=EALL"]
    out += [f"{k + 1}, " + ", ".join(map(str, e)) for k, e in enumerate(elements)]
    sets = (("BOTTOM", 0.0), ("LIGLOW", NOTCHES[0][2]), ("LIGTOP", NOTCHES[0][3]), ("TOP", HEIGHT))
    for name, y in sets:
        out += node_set(name, coords, y)
    return out, len(elements)


def step(u, dt, direct):
    static = "*STATIC, DIRECT" if direct else "*STATIC"
    out = ["*STEP, INC=1000", static, f"{dt:g}, 1., 1e-4, {dt:g}", "*BOUNDARY",
           f"TOP, 2, 2, {u:g}", "*NODE PRINT, NSET=TOP, TOTALS=ONLY", "RF"]
    for nset in ("TOP", "LIGLOW", "LIGTOP"):
        out += [f"*NODE PRINT, NSET={nset}", "U"]
    return out + ["*END STEP"]


def header(a, n):
    return [
        f"** specimen_notch{'' if a.size == 10 else '_h' + format(a.size, 'g')}.inp -- written by "
        f"calculix_examples/notch_strip.py --size {a.size:g} --increment {a.increment:g}"
        + (" --direct" if a.direct else "") + (" --tension-only" if a.tension_only else "") + ".",
        "** A plane-strain strip 80 mm wide, 50 mm high, with a notch 10 x 10 mm cut out of each",
        f"** side between y = 20 and 30: {n} CPE4 elements of {a.size:g} x {a.size:g} mm "
        f"({8 * n} RVEs),",
        "** the paper's ITZ law integrated by IMPL-EX (concrete_implex.toml). Top face's uy = U:",
        f"** tension to U = {UMAX:g} mm (through the peak: the ligament between the notches",
        f"** debonds), unloading to U = 0, compression to U = -{UMAX:g} mm; bottom uy = 0,",
        "** its left node ux = 0, sides free. The node sets LIGLOW and LIGTOP (y = 20 and 30)",
        "** bound the notches' row. Run as specimen.inp (scripts/test-calculix does).",
        "*HEADING",
        "mesorve RVE at every integration point: notched plane-strain strip, IMPL-EX",
    ]


def deck(a):
    lines, n = mesh(a.size)
    lines = header(a, n) + lines + [
        f"*MATERIAL, NAME={MATERIAL}", "*USER MATERIAL, CONSTANTS=6", "0., 0., 0., 0., 0., 0.",
        "*DEPVAR", str(DEPVAR), f"*SOLID SECTION, ELSET=EALL, MATERIAL={MATERIAL}", "1.",
        "*BOUNDARY", "BOTTOM, 2, 2, 0.", "1, 1, 1, 0."]
    lines += step(UMAX, a.increment, a.direct)
    if not a.tension_only:
        lines += step(0.0, 0.1, a.direct) + step(-UMAX, 0.1, a.direct)
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--size", type=float, default=10.0)
    p.add_argument("--increment", type=float, default=0.05)
    p.add_argument("--direct", action="store_true")
    p.add_argument("--tension-only", action="store_true")
    print(deck(p.parse_args()), end="")
