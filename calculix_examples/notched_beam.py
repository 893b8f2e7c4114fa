#!/usr/bin/env python3
"""Writes the CalculiX deck of the notched beam of the failing cell on stdout: three-point
bending to failure and reversed, at an element size H, to check that the member's failure
does not follow its mesh (docs/fracture.md).

  notched_beam.py [--size H] [--down N] [--back N] [--up N] [--no-regularization]

A plane-strain beam 160 mm long and 40 mm deep of CPE4 elements of H x H mm (H divides
10), with a notch 10 mm wide and 10 mm deep at the middle of its lower edge (the elements
there left out). Every integration point is the failing cell integrated by IMPL-EX
(concrete_fracture_implex.toml, STATEV mode), given its element's length H as PROPS(7)
(0 with --no-regularization). Supports at the bottom corners (left: ux = uy = 0; right:
uy = 0), holding down as well as up. The top node at mid-span (node set LOAD) is moved
in y: down to -DOWN_MAX in N increments (default 200), back to 0 in N (100), up to
+UP_MAX in N (100), each increment of the same size within its step and DTIME = 1
(*STATIC, DIRECT).
"""
import argparse

LENGTH, DEPTH = 160.0, 40.0
NOTCH = (75.0, 85.0, 0.0, 10.0)  # x0, x1, y0, y1
DOWN_MAX, UP_MAX = 0.4, 0.1
MATERIAL = "@ABAQUS_RVE_UMAT@CONCRETE_FRACTURE_IMPLEX"
# STATEV mode: `rve info calculix_examples/concrete_fracture_implex.toml`'s umat_nstatv
# (3733) and the five inspection mirrors (docs/guide.md, *DEPVAR).
DEPVAR = 3738


def grid(h):
    nx, ny = round(LENGTH / h), round(DEPTH / h)
    elements = []
    x0, x1, y0, y1 = NOTCH
    for j in range(ny):
        for i in range(nx):
            cx, cy = (i + 0.5) * h, (j + 0.5) * h
            if not (x0 < cx < x1 and y0 < cy < y1):
                n = j * (nx + 1) + i + 1
                elements.append((n, n + 1, n + nx + 2, n + nx + 1))
    used = sorted({n for e in elements for n in e})
    coords = {n: ((n - 1) % (nx + 1) * h, (n - 1) // (nx + 1) * h) for n in used}
    return coords, elements


def node_at(coords, x, y):
    return next(n for n, c in coords.items() if abs(c[0] - x) < 1e-9 and abs(c[1] - y) < 1e-9)


def step(u, n):
    return ["*STEP, INC=100000", "*STATIC, DIRECT", f"{1.0:g}, {float(n):g}", "*BOUNDARY",
            f"LOAD, 2, 2, {u:g}", "*NODE PRINT, NSET=LOAD, TOTALS=ONLY", "RF",
            "*NODE PRINT, NSET=LOAD", "U", "*END STEP"]


def deck(a):
    coords, elements = grid(a.size)
    length = 0.0 if a.no_regularization else a.size
    left, right = node_at(coords, 0.0, 0.0), node_at(coords, LENGTH, 0.0)
    load = node_at(coords, LENGTH / 2, DEPTH)
    out = [
        f"** notched_beam.py --size {a.size:g} --down {a.down} --back {a.back} --up {a.up}"
        + (" --no-regularization" if a.no_regularization else ""),
        f"** A plane-strain beam {LENGTH:g} x {DEPTH:g} mm, notched 10 x 10 mm at mid-span,",
        f"** of {len(elements)} CPE4 elements of {a.size:g} mm; PROPS(7) = {length:g}.",
        "*HEADING",
        "mesorve failing cell at every integration point: notched beam, IMPL-EX",
        "*NODE, NSET=NALL",
    ]
    out += [f"{n}, {x:g}, {y:g}" for n, (x, y) in coords.items()]
    out += ["*ELEMENT, TYPE=CPE4, ELSET=EALL"]
    out += [f"{k + 1}, " + ", ".join(map(str, e)) for k, e in enumerate(elements)]
    out += ["*NSET, NSET=LOAD", str(load),
            f"*MATERIAL, NAME={MATERIAL}", "*USER MATERIAL, CONSTANTS=7",
            f"0., 0., 0., 0., 0., 0., {length:g}", "*DEPVAR", str(DEPVAR),
            f"*SOLID SECTION, ELSET=EALL, MATERIAL={MATERIAL}", "1.",
            "*BOUNDARY", f"{left}, 1, 2, 0.", f"{right}, 2, 2, 0."]
    out += step(-DOWN_MAX, a.down) + step(0.0, a.back) + step(UP_MAX, a.up)
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--size", type=float, default=10.0)
    p.add_argument("--down", type=int, default=200)
    p.add_argument("--back", type=int, default=100)
    p.add_argument("--up", type=int, default=100)
    p.add_argument("--no-regularization", action="store_true")
    print(deck(p.parse_args()), end="")
