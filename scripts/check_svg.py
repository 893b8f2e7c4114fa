"""Checks the pictures of `rve run --svg DIR` against the VTK series of the same run:
every step_NNNN.svg and response.svg is well-formed XML; a step picture draws one ITZ
polygon per interface element of the mesh and one contact dot per element with a closed
point (the `closed_points` array of step_NNNN.vtu); response.svg draws the three stress
curves with one point per CSV row, and one contact bar per row with contact points.

Usage: check_svg.py OUT_DIR SVG_DIR VTK_DIR
"""

import csv
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio

NS = "{http://www.w3.org/2000/svg}"


def fail(msg):
    print(f"check_svg: FAIL: {msg}")
    sys.exit(1)


def count(root, tag, cls):
    return sum(1 for e in root.iter(NS + tag) if e.get("class") == cls)


def main():
    out, svg, vtk = (Path(a) for a in sys.argv[1:4])
    with open(out / "response.csv") as f:
        rows = list(csv.DictReader(f))
    frames = sorted(svg.glob("step_*.svg"))
    if not frames:
        fail(f"no step_*.svg in {svg}")
    for frame in frames:
        root = ET.parse(frame).getroot()  # raises on malformed XML
        m = meshio.read(vtk / (frame.stem + ".vtu"))
        closed = m.cell_data["closed_points"][1].reshape(-1)
        n_itz, n_closed = len(closed), int((closed > 0).sum())
        if count(root, "polygon", "itz") != n_itz:
            fail(f"{frame.name}: {count(root, 'polygon', 'itz')} ITZ polygons, mesh has {n_itz}")
        if count(root, "circle", "closed") != n_closed:
            fail(f"{frame.name}: {count(root, 'circle', 'closed')} contact dots, {n_closed} expected")
        if "displacements x " not in "".join(root.itertext()):
            fail(f"{frame.name}: no amplification stated")
        print(f"check_svg: {frame.name}: {n_itz} ITZ elements, {n_closed} with contact")
    root = ET.parse(svg / "response.svg").getroot()
    curves = [e for e in root.iter(NS + "polyline") if e.get("class") == "curve"]
    if len(curves) != 3 or any(len(c.get("points").split()) != len(rows) for c in curves):
        fail("response.svg: expected 3 curves of one point per CSV row")
    bars = sum(1 for r in rows if int(r["contact_points"]) > 0)
    if count(root, "rect", "contact") != bars:
        fail(f"response.svg: {count(root, 'rect', 'contact')} contact bars, {bars} expected")
    print(f"check_svg: response.svg: 3 curves of {len(rows)} points, {bars} contact increments")


if __name__ == "__main__":
    main()
