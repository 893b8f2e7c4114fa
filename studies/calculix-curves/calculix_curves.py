#!/usr/bin/env python3
"""Draws calculix_curves.svg: the CalculiX specimens' force against the end displacement,
from the "force-displacement (every increment)" tables of a CalculiX report (docs/calculix.md
by default, a copy of target/calculix/report.md written by
`MESORVE_CCX_FULL=1 MESORVE_CCX_STUDY=1 scripts/test-calculix`). Standard library only; run it
after regenerating docs/calculix.md.

Usage: calculix_curves.py [CALCULIX_MD [OUT_SVG]]
       (defaults docs/calculix.md, target/studies/calculix-curves/calculix_curves.svg)
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from kit.plot import svg_plot  # noqa: E402

RUNS = [  # (table name in calculix.md, legend, colour)
    ("consistent", "strip, implicit (specimen.inp)", "#1f77b4"),
    ("band", "band, ductile ITZ (specimen_band.inp)", "#2ca02c"),
    ("weakened", "weakened strip, IMPL-EX (specimen_weak.inp)", "#d62728"),
    ("notch", "notched strip, IMPL-EX (specimen_notch.inp)", "#9467bd"),
]


def tables(path):
    """{run: [(U, F)]} of the force-displacement tables."""
    out, current = {}, None
    with open(path) as f:
        for line in f:
            m = re.match(r"(\w+): force-displacement \(every increment\)", line)
            if m:
                current = out.setdefault(m.group(1), [])
                continue
            if current is not None:
                cells = [c.strip() for c in line.strip().strip("|").split("|")]
                if len(cells) == 3 and re.match(r"^-?[0-9.]+(e[-+]?\d+)?$", cells[0]):
                    current.append((float(cells[1]), float(cells[2])))
                elif line.startswith("#") or (line.strip() and not line.startswith("|")):
                    current = None
    return out


def main():
    md = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "calculix.md")
    out = sys.argv[2] if len(sys.argv) > 2 else os.path.join(
        ROOT, "target", "studies", "calculix-curves", "calculix_curves.svg")
    found = tables(md)
    series = []
    for name, label, colour in RUNS:
        if not found.get(name):
            sys.exit(f"calculix-curves: no force-displacement table `{name}` in {md}")
        # From the origin; U in µm.
        points = [(0.0, 0.0, "")] + [(1e3 * u, f, "") for u, f in found[name]]
        series.append((label, colour, points, True, 0))
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    svg_plot(out, "CalculiX specimens: tension, unloading, compression",
             "end displacement U (µm)", "force F (N)", series, w=760, h=440, legend=290)
    print(f"{out}: " + ", ".join(f"{n} {len(found[n])} points" for n, _, _ in RUNS))


if __name__ == "__main__":
    main()
