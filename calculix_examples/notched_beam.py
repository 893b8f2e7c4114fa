#!/usr/bin/env python3
"""Writes the CalculiX deck of the notched beam of the failing cell on stdout: three-point
bending to failure and reversed, at an element size H, to check that the member's failure
does not follow its mesh (docs/fracture.md).

  notched_beam.py [--size H] [--down N] [--back N] [--up N] [--no-regularization]

A plane-strain beam 160 mm long and 40 mm deep of CPE8R elements of H x H mm (H divides
10; quadratic, so that four elements through the depth bend without the locking of
CPE4's; ccx runs a CPE8R as a C3D20R, 8 integration points like a CPE4), with a notch 20
mm wide and 10 mm deep at the middle of its lower edge (the elements there left out: a
notch of whole elements at both sizes).
Every integration point is the failing cell integrated by IMPL-EX
(concrete_fracture_implex.toml, STATEV mode), given its element's length H as PROPS(7)
(0 with --no-regularization). Load and supports act through plates 10 mm wide: the
bottom nodes within 10 mm of each end hold uy = 0 (down as well as up; the left corner
also ux = 0), and the top nodes within 5 mm of mid-span (node set LOAD) are moved
together in y: down to -DOWN_MAX in N increments (default 200), back to 0 in N (100), up
to +UP_MAX in N (100), each increment of the same size within its step and DTIME = 1
(*STATIC, DIRECT).
"""
import argparse

LENGTH, DEPTH = 160.0, 40.0
NOTCH = (70.0, 90.0, 0.0, 10.0)  # x0, x1, y0, y1: whole elements of 10 and of 5 mm
# Steel plates 10 mm wide under the load and on the supports (their nodes moved alike): a
# load or support at one node is a 2D point force, whose stresses grow without bound as
# the mesh is refined and would crush the cells beside it first.
PLATE = 10.0
DOWN_MAX, UP_MAX = 0.2, 0.1
MATERIAL = "@ABAQUS_RVE_UMAT@CONCRETE_FRACTURE_IMPLEX"
# STATEV mode: `rve info calculix_examples/concrete_fracture_implex.toml`'s umat_nstatv
# (3733) and the five inspection mirrors (docs/guide.md, *DEPVAR).
DEPVAR = 3738


def grid(h):
    """Nodes on a grid of h/2 (corners and midsides of the CPE8R elements) and the
    elements' eight nodes (corners counterclockwise, then midsides)."""
    nx, ny = round(LENGTH / h), round(DEPTH / h)
    row = 2 * nx + 1
    node = lambda i2, j2: j2 * row + i2 + 1  # noqa: E731
    elements = []
    x0, x1, y0, y1 = NOTCH
    for j in range(ny):
        for i in range(nx):
            cx, cy = (i + 0.5) * h, (j + 0.5) * h
            if not (x0 < cx < x1 and y0 < cy < y1):
                a, b = 2 * i, 2 * j
                elements.append((node(a, b), node(a + 2, b), node(a + 2, b + 2), node(a, b + 2),
                                 node(a + 1, b), node(a + 2, b + 1), node(a + 1, b + 2),
                                 node(a, b + 1)))
    used = sorted({n for e in elements for n in e})
    coords = {n: ((n - 1) % row * h / 2, (n - 1) // row * h / 2) for n in used}
    return coords, elements


def nodes_between(coords, x0, x1, y):
    return [n for n, (x, ny) in coords.items()
            if x0 - 1e-9 <= x <= x1 + 1e-9 and abs(ny - y) < 1e-9]


def id_lines(ids):
    ids = list(ids)
    return [", ".join(map(str, ids[k:k + 16])) for k in range(0, len(ids), 16)]


def step(u, n):
    return ["*STEP, INC=100000", "*STATIC, DIRECT", f"{1.0:g}, {float(n):g}", "*BOUNDARY",
            f"LOAD, 2, 2, {u:g}", "*NODE PRINT, NSET=LOAD, TOTALS=ONLY", "RF",
            "*NODE PRINT, NSET=LOAD", "U", "*END STEP"]


def deck(a):
    coords, elements = grid(a.size)
    length = 0.0 if a.no_regularization else a.size
    left = nodes_between(coords, 0.0, PLATE, 0.0)
    right = nodes_between(coords, LENGTH - PLATE, LENGTH, 0.0)
    load = nodes_between(coords, (LENGTH - PLATE) / 2, (LENGTH + PLATE) / 2, DEPTH)
    out = [
        f"** notched_beam.py --size {a.size:g} --down {a.down} --back {a.back} --up {a.up}"
        + (" --no-regularization" if a.no_regularization else ""),
        f"** A plane-strain beam {LENGTH:g} x {DEPTH:g} mm, notched 20 x 10 mm at mid-span,",
        f"** of {len(elements)} CPE8R elements of {a.size:g} mm; PROPS(7) = {length:g}.",
        "*HEADING",
        "mesorve failing cell at every integration point: notched beam, IMPL-EX",
        "*NODE, NSET=NALL",
    ]
    out += [f"{n}, {x:g}, {y:g}" for n, (x, y) in coords.items()]
    out += ["*ELEMENT, TYPE=CPE8R, ELSET=EALL"]
    out += [f"{k + 1}, " + ", ".join(map(str, e)) for k, e in enumerate(elements)]
    for name, nodes in (("LOAD", load), ("LEFT", left), ("RIGHT", right)):
        out += [f"*NSET, NSET={name}"] + id_lines(nodes)
    out += [
            f"*MATERIAL, NAME={MATERIAL}", "*USER MATERIAL, CONSTANTS=7",
            f"0., 0., 0., 0., 0., 0., {length:g}", "*DEPVAR", str(DEPVAR),
            f"*SOLID SECTION, ELSET=EALL, MATERIAL={MATERIAL}", "1.",
            "*BOUNDARY", f"{left[0]}, 1, 1, 0.", "LEFT, 2, 2, 0.", "RIGHT, 2, 2, 0."]
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
