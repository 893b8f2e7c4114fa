"""Checks the files MESORVE_UMAT_VTK wrote in a CalculiX run against the run's .dat.

For each chosen point NOEL.NPT: the point's .pvd lists existing .vtu files; every
increment ccx printed (`*EL PRINT` S, at the increment's end time, 7 digits) has a file at that
time, which parses as VTK XML with the fields of `rve run --vtk`, and whose area-averaged
cell stress [s_xx, s_yy, s_xy] is ccx's S of that point to TOLERANCE of the largest stress
(ccx prints 7 digits); the ITZ damage is not zero at the end. For an implicit scene
(an IMPL-EX increment that reuses its step's factorization gets no file).

Usage: check_umat_vtk.py VTK_DIR JOB.dat NOEL.NPT [NOEL.NPT ...]
(standard library only; prints one line per point, exits 1 on a failure)
"""

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from kit.ccx import dat_points

TOLERANCE = 1e-5


def fail(msg):
    sys.exit(f"check_umat_vtk: FAIL: {msg}")


def dat_stresses(path):
    """{time: {(elem, ip): [sxx, syy, szz, sxy, ...]}} of the .dat's stress blocks."""
    return dat_points(path, "stresses")


def read_vtu(path):
    """Points, cells (node lists) and named cell/point arrays of a .vtu."""
    root = ET.parse(path).getroot()
    arrays = {}
    for a in root.iter("DataArray"):
        values = [float(x) for x in a.text.split()]
        n = int(a.get("NumberOfComponents", "1"))
        arrays[a.get("Name", "Points")] = [values[i:i + n] for i in range(0, len(values), n)]
    conn = [int(v[0]) for v in arrays["connectivity"]]
    offsets = [int(v[0]) for v in arrays["offsets"]]
    cells = [conn[a:b] for a, b in zip([0] + offsets, offsets)]
    return arrays, cells


def measures(path):
    """Area-averaged stress and ITZ-length-weighted damage of one file."""
    arrays, cells = read_vtu(path)
    p = arrays["Points"]
    xs, ys = [q[0] for q in p], [q[1] for q in p]
    volume = (max(xs) - min(xs)) * (max(ys) - min(ys))
    stress, damage, length = [0.0, 0.0, 0.0], 0.0, 0.0
    for c, nodes in enumerate(cells):
        if len(nodes) == 3:
            (ax, ay, _), (bx, by, _), (cx, cy, _) = (p[i] for i in nodes)
            area = 0.5 * abs((bx - ax) * (cy - ay) - (cx - ax) * (by - ay))
            for k in range(3):
                stress[k] += area * arrays["stress"][c][k] / volume
        else:
            (ax, ay, _), (bx, by, _) = p[nodes[0]], p[nodes[1]]
            l = ((bx - ax) ** 2 + (by - ay) ** 2) ** 0.5
            damage += l * arrays["damage"][c][0]
            length += l
    return stress, damage / length


def check_point(vtk, stresses, point):
    noel, npt = (int(v) for v in point.split("."))
    pvd = vtk / f"e{noel}_p{npt}.pvd"
    if not pvd.exists():
        fail(f"{pvd} missing")
    series = {float(d.get("timestep")): vtk / d.get("file")
              for d in ET.parse(pvd).getroot().iter("DataSet")}
    scale = max(abs(v) for b in stresses.values() for s in b.values() for v in s[:4])
    worst, last_damage = 0.0, 0.0
    for t in sorted(stresses):
        match = [f for s, f in series.items() if abs(s - t) <= 1e-6 * max(1.0, abs(t))]
        if len(match) != 1 or not match[0].exists():
            fail(f"{point}: no file at time {t} in {pvd}")
        (sxx, syy, sxy), damage = measures(match[0])
        ccx = stresses[t][(noel, npt)]
        worst = max(worst, max(abs(a - b) for a, b in zip((sxx, syy, sxy), (ccx[0], ccx[1], ccx[3]))) / scale)
        last_damage = damage
    if worst > TOLERANCE:
        fail(f"{point}: file stress differs from ccx's S by {worst:.1e} of the largest stress")
    if last_damage <= 0.0:
        fail(f"{point}: no ITZ damage at the end")
    print(f"check_umat_vtk: {point}: {len(stresses)} increments, {len(series)} files; "
          f"stress to {worst:.1e} of the largest; final ITZ damage {last_damage:.3f}")


def main():
    vtk, dat = Path(sys.argv[1]), sys.argv[2]
    stresses = dat_stresses(dat)
    if not stresses:
        fail(f"no stresses in {dat}")
    for point in sys.argv[3:]:
        check_point(vtk, stresses, point)


if __name__ == "__main__":
    main()
