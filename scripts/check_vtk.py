"""Reads back a VTK series written by `rve run --vtk DIR` with meshio and checks it
against the run's response.csv and against the point displacements:

- one .vtu per CSV row, listed in order by series.pvd;
- the area average of the per-triangle stresses equals the CSV's homogenized stress;
- the per-triangle strains equal the gradient of the point displacements;
- the per-ITZ normal and shear openings equal the jump of the point displacements at
  mid-length, in the element's local axes;
- ITZ-only arrays are NaN on triangles (branch -1), the ITZ values are admissible.

Usage: check_vtk.py OUT_DIR VTK_DIR   (prints one line per check, exits 1 on a failure)
"""

import csv
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np

TOL = 1e-12


def fail(msg):
    print(f"check_vtk: FAIL: {msg}")
    sys.exit(1)


def main():
    out, vtk = Path(sys.argv[1]), Path(sys.argv[2])
    with open(out / "response.csv") as f:
        rows = list(csv.DictReader(f))
    pvd = ET.parse(vtk / "series.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    if len(files) != len(rows):
        fail(f"{len(files)} data sets in series.pvd, {len(rows)} CSV rows")
    worst = {"stress": 0.0, "strain": 0.0, "opening": 0.0}
    branches = set()
    for row, name in zip(rows, files):
        m = meshio.read(vtk / name)
        tri = m.cells_dict["triangle"]
        quad = m.cells_dict.get("quad", np.zeros((0, 4), dtype=int))
        # meshio keeps the cell blocks in file order: triangles, then quads.
        if [c.type for c in m.cells] != ["triangle", "quad"][: len(m.cells)]:
            fail(f"{name}: cell blocks {[c.type for c in m.cells]}")
        cd = {k: v for k, v in m.cell_data.items()}
        p = m.points[:, :2]
        u = m.point_data["displacement"][:, :2]

        # Area average of the stresses against the CSV's homogenized stress.
        a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
        area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                            - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]))
        xs, ys = p[:, 0], p[:, 1]
        cell_area = (xs.max() - xs.min()) * (ys.max() - ys.min())
        stress = cd["stress"][0]
        avg = (area[:, None] * stress).sum(axis=0) / cell_area
        hom = np.array([float(row[k]) for k in ("sig_xx", "sig_yy", "sig_xy")])
        err = np.abs(avg - hom).max() / np.abs(stress).max()
        worst["stress"] = max(worst["stress"], err)
        if err > TOL:
            fail(f"{name}: area-averaged stress {avg} vs CSV {hom} (rel. {err:.2e})")

        # Strains from the gradient of the linear displacement on each triangle.
        strain = cd["strain"][0]
        det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
        ua, ub, uc = u[tri[:, 0]], u[tri[:, 1]], u[tri[:, 2]]
        # grad u = [du_b, du_c] [dx_b, dx_c]^-1
        dxb, dxc = b - a, c - a
        dub, duc = ub - ua, uc - ua
        inv = np.stack([np.stack([dxc[:, 1], -dxc[:, 0]], 1),
                        np.stack([-dxb[:, 1], dxb[:, 0]], 1)], 1) / det[:, None, None]
        # rows of inv: d/dx and d/dy weights for (du_b, du_c)
        dudx = dub * inv[:, 0, 0, None] + duc * inv[:, 1, 0, None]
        dudy = dub * inv[:, 0, 1, None] + duc * inv[:, 1, 1, None]
        grad = np.stack([dudx[:, 0], dudy[:, 1], dudy[:, 0] + dudx[:, 1]], 1)
        err = np.abs(grad - strain).max() / max(np.abs(strain).max(), 1e-300)
        worst["strain"] = max(worst["strain"], err)
        if err > TOL:
            fail(f"{name}: strain vs displacement gradient, rel. {err:.2e}")

        # ITZ openings from the point displacements (quad nodes a0 a1 b1 b0).
        if len(quad):
            a0, a1, b1, b0 = (quad[:, k] for k in range(4))
            s = p[a1] - p[a0]
            s /= np.hypot(s[:, 0], s[:, 1])[:, None]
            n = np.stack([s[:, 1], -s[:, 0]], 1)
            jump = 0.5 * ((u[b0] - u[a0]) + (u[b1] - u[a1]))
            ds, dn = (jump * s).sum(1), (jump * n).sum(1)
            scale = np.abs(u).max()
            err = max(np.abs(ds - cd["shear_opening"][1].reshape(-1)).max(),
                      np.abs(dn - cd["normal_opening"][1].reshape(-1)).max()) / scale
            worst["opening"] = max(worst["opening"], err)
            if err > TOL:
                fail(f"{name}: ITZ openings vs displacement jumps, rel. {err:.2e}")
            br = cd["branch"][1].reshape(-1)
            if not set(br.tolist()) <= {0, 1, 2}:
                fail(f"{name}: ITZ branch values {set(br.tolist())}")
            branches |= set(br.tolist())
            dmg = cd["damage"][1].reshape(-1)
            mor = cd["max_opening_ratio"][1].reshape(-1)
            if not ((dmg >= 0) & (dmg < 1) & (mor >= 0)).all():
                fail(f"{name}: damage outside [0, 1) or negative delta_max/delta_c")
            if not (np.isnan(cd["damage"][0]).all() and (cd["branch"][0] == -1).all()):
                fail(f"{name}: ITZ arrays not NaN / -1 on triangles")
    print(f"check_vtk: {len(files)} files; max rel. error: area-averaged stress vs CSV "
          f"{worst['stress']:.1e}, strain vs displacement gradient {worst['strain']:.1e}, "
          f"ITZ openings vs jumps {worst['opening']:.1e}; ITZ branches seen "
          f"{sorted(int(b) for b in branches)} (0 loading, 1 unloading, 2 contact)")


if __name__ == "__main__":
    main()
