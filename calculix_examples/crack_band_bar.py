#!/usr/bin/env python3
"""Writes the CalculiX deck of the crack-band bar on stdout: one crack through a bar at two
element sizes, to check that the failing cell regularized by the element's length
dissipates the same energy whatever the mesh (docs/fracture.md).

  crack_band_bar.py [--size H] [--increments N] [--no-regularization]

A plane-strain bar 10 mm wide (x) and 40 mm long (y) of CPE4 elements of H x H mm (H
divides 10), every integration point the failing cell integrated by IMPL-EX
(concrete_fracture_implex.toml). The row of elements just above y = 20 is weaker (its
ITZ strength 5 % lower, PROPS(1), material tag @WEAK), so the crack forms there, in one
row of height H. Each material gives its elements' length H as PROPS(7), or 0 with
--no-regularization. Displacement control of the top face in y to U = UMAX in N fixed
increments (*STATIC, DIRECT); bottom face uy = 0, its left node ux = 0, sides free.
"""
import argparse

WIDTH, LENGTH = 10.0, 40.0
WEAK_ROW_BOTTOM = 20.0
UMAX = 0.25
MATERIAL = "@ABAQUS_RVE_UMAT@CONCRETE_FRACTURE_IMPLEX"
# The ITZ's sigma_c of concrete_fracture_implex.toml, 5 % lower in the weak row.
WEAK_SIGMA_C = 0.95 * 2.5
# STATEV mode: `rve info calculix_examples/concrete_fracture_implex.toml`'s umat_nstatv
# (3733) and the five inspection mirrors (docs/guide.md, *DEPVAR).
DEPVAR = 3738


def grid(h):
    nx, ny = round(WIDTH / h), round(LENGTH / h)
    coords = {j * (nx + 1) + i + 1: (i * h, j * h) for j in range(ny + 1) for i in range(nx + 1)}
    sound, weak = [], []
    for j in range(ny):
        for i in range(nx):
            n = j * (nx + 1) + i + 1
            element = (n, n + 1, n + nx + 2, n + nx + 1)
            (weak if abs(j * h - WEAK_ROW_BOTTOM) < 1e-9 else sound).append(element)
    return coords, sound, weak


def id_lines(ids):
    ids = list(ids)
    return [", ".join(map(str, ids[k:k + 16])) for k in range(0, len(ids), 16)]


def deck(a):
    coords, sound, weak = grid(a.size)
    length = 0.0 if a.no_regularization else a.size
    out = [
        f"** crack_band_bar.py --size {a.size:g} --increments {a.increments}"
        + (" --no-regularization" if a.no_regularization else ""),
        f"** A plane-strain bar {WIDTH:g} x {LENGTH:g} mm of {len(sound) + len(weak)} CPE4 "
        f"elements of {a.size:g} mm, the row above y = {WEAK_ROW_BOTTOM:g} weaker;",
        f"** PROPS(7) = {length:g} (the element's length; 0: not regularized).",
        "*HEADING",
        "mesorve failing cell at every integration point: crack-band bar, IMPL-EX",
        "*NODE, NSET=NALL",
    ]
    out += [f"{n}, {x:g}, {y:g}" for n, (x, y) in coords.items()]
    for name, elements, first in (("SOUND", sound, 1), ("WEAK", weak, len(sound) + 1)):
        out += [f"*ELEMENT, TYPE=CPE4, ELSET={name}"]
        out += [f"{first + k}, " + ", ".join(map(str, e)) for k, e in enumerate(elements)]
    for name, y in (("BOTTOM", 0.0), ("TOP", LENGTH)):
        out += [f"*NSET, NSET={name}"] + id_lines(n for n, (_, ny) in coords.items() if ny == y)
    for name, sigma_c in (("SOUND", 0.0), ("WEAK", WEAK_SIGMA_C)):
        material = MATERIAL + ("@WEAK" if name == "WEAK" else "")
        out += [f"*MATERIAL, NAME={material}", "*USER MATERIAL, CONSTANTS=7",
                f"{sigma_c:g}, 0., 0., 0., 0., 0., {length:g}", "*DEPVAR", str(DEPVAR),
                f"*SOLID SECTION, ELSET={name}, MATERIAL={material}", "1."]
    dt = 1.0 / a.increments
    out += ["*BOUNDARY", "BOTTOM, 2, 2, 0.", "1, 1, 1, 0.",
            "*STEP, INC=100000", "*STATIC, DIRECT", f"{dt:g}, 1.", "*BOUNDARY",
            f"TOP, 2, 2, {UMAX:g}", "*NODE PRINT, NSET=TOP, TOTALS=ONLY", "RF",
            "*NODE PRINT, NSET=TOP", "U", "*END STEP"]
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--size", type=float, default=10.0)
    p.add_argument("--increments", type=int, default=250)
    p.add_argument("--no-regularization", action="store_true")
    print(deck(p.parse_args()), end="")
