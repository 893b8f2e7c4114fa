#!/usr/bin/env python3
"""Make the Gmsh test meshes in tests/data/gmsh/, using the real Gmsh (Python API).

How to run (from the repository root):

    pip install gmsh                       # tested with gmsh 4.15.2 from PyPI
    python3 scripts/make_gmsh_meshes.py    # (re)writes the fixture files below

If `import gmsh` fails on missing shared libraries (headless machines), install them,
e.g. `apt-get install libglu1-mesa libxcursor1 libxinerama1 libxft2`.

Default mode writes, into tests/data/gmsh/:

  two_circles_v22.msh  a 10 x 10 square with two circular aggregates, MSH 2.2 ASCII
  two_circles_v41.msh  the SAME mesh (same node and element tags), MSH 4.1 ASCII
  quads_v41.msh        a recombined (quadrangle) mesh of a square, MSH 4.1 ASCII
  binary_v41.msh       a tiny mesh of a square, MSH 4.1 binary
  clockwise_v22.msh    a tiny mesh of a square whose triangles are all clockwise: built-in
                       kernel, Plane Surface on a clockwise Curve Loop (normal along -z)

The two-circle mesh has the physical surface groups "matrix" (tag 1) and "aggregate"
(tag 2), and also a physical curve group "boundary" (the square's sides) and a physical
point group "corner", so the files carry line (type 1) and point (type 15) elements that
the importer must skip.

Re-save mode proves that real Gmsh reads the files written by our Rust writer
(`rve::mesh::gmsh::write_msh22` / `write_msh41`):

    cargo test --test gmsh_import          # writes target/tmp/gmsh_import/ours_v22.msh
                                           # and target/tmp/gmsh_import/ours_v41.msh
    python3 scripts/make_gmsh_meshes.py --resave target/tmp/gmsh_import/ours_v41.msh \\
        tests/data/gmsh/rewritten_by_gmsh_v22.msh
    python3 scripts/make_gmsh_meshes.py --resave target/tmp/gmsh_import/ours_v22.msh \\
        tests/data/gmsh/rewritten_by_gmsh_v41.msh

`--resave IN OUT` opens IN with Gmsh and writes OUT in the other MSH version
(2.2 -> 4.1, 4.1 -> 2.2); `--version 2.2|4.1` forces the output version.
"""

import argparse
import pathlib
import sys

import gmsh

DATA_DIR = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "gmsh"

# Geometry of the fixture: cell size and the two inclusions (centre x, centre y, radius).
# tests/gmsh_import.rs repeats these numbers: keep them in sync.
CELL = 10.0
CIRCLES = [(3.0, 3.2, 1.8), (6.8, 6.5, 2.2)]
MESH_SIZE = 1.0


def start():
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 1)
    gmsh.option.setNumber("General.Verbosity", 2)  # errors and warnings only


def write(path, version, binary=False):
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", 1 if binary else 0)
    gmsh.write(str(path))
    print(f"wrote {path} ({path.stat().st_size} bytes)")


def two_circles():
    """Square with two disks, fragmented so the mesh is conforming along the circles."""
    gmsh.model.add("two_circles")
    occ = gmsh.model.occ
    square = occ.addRectangle(0.0, 0.0, 0.0, CELL, CELL)
    disks = [occ.addDisk(x, y, 0.0, r, r) for (x, y, r) in CIRCLES]
    _, children = occ.fragment([(2, square)], [(2, d) for d in disks])
    occ.synchronize()

    # children[0]: what became of the square (the matrix with holes, plus the disks it
    # overlaps); children[1:]: what became of each disk.
    aggregate = sorted({tag for child in children[1:] for (dim, tag) in child if dim == 2})
    matrix = sorted({tag for (dim, tag) in children[0] if dim == 2} - set(aggregate))
    assert len(aggregate) == len(CIRCLES) and len(matrix) == 1, (matrix, aggregate)
    gmsh.model.addPhysicalGroup(2, matrix, 1, name="matrix")
    gmsh.model.addPhysicalGroup(2, aggregate, 2, name="aggregate")

    # Lower-dimensional groups, only so the files contain line and point elements.
    def on_cell_border(dim, tag):
        x, y, _ = occ.getCenterOfMass(dim, tag)
        return min(abs(x), abs(y), abs(x - CELL), abs(y - CELL)) < 1e-9

    curves = gmsh.model.getBoundary([(2, t) for t in matrix], combined=False, oriented=False)
    sides = sorted({tag for (_, tag) in curves if on_cell_border(1, tag)})
    assert len(sides) == 4, sides
    gmsh.model.addPhysicalGroup(1, sides, 3, name="boundary")
    origin = [t for (_, t) in gmsh.model.getEntitiesInBoundingBox(-1e-6, -1e-6, -1e-6, 1e-6, 1e-6, 1e-6, 0)]
    assert len(origin) == 1, origin
    gmsh.model.addPhysicalGroup(0, origin, 4, name="corner")

    gmsh.option.setNumber("Mesh.MeshSizeMin", MESH_SIZE)
    gmsh.option.setNumber("Mesh.MeshSizeMax", MESH_SIZE)
    gmsh.model.mesh.generate(2)
    write(DATA_DIR / "two_circles_v22.msh", 2.2)
    write(DATA_DIR / "two_circles_v41.msh", 4.1)

    triangles = gmsh.model.mesh.getElementsByType(2)[0]
    print(f"{len(triangles)} triangles")
    gmsh.model.remove()


def square_mesh(name, size, recombine):
    gmsh.model.add(name)
    surface = gmsh.model.occ.addRectangle(0.0, 0.0, 0.0, CELL, CELL)
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [surface], 1, name="matrix")
    gmsh.option.setNumber("Mesh.MeshSizeMin", size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.RecombineAll", 1 if recombine else 0)
    gmsh.model.mesh.generate(2)
    gmsh.option.setNumber("Mesh.RecombineAll", 0)


def quads():
    square_mesh("quads", 2.5, recombine=True)
    write(DATA_DIR / "quads_v41.msh", 4.1)
    gmsh.model.remove()


def binary():
    square_mesh("binary", 5.0, recombine=False)
    write(DATA_DIR / "binary_v41.msh", 4.1, binary=True)
    gmsh.model.remove()


def clockwise():
    geo = gmsh.model.geo
    gmsh.model.add("clockwise")
    corners = [geo.addPoint(x, y, 0.0, 5.0) for (x, y) in [(0, 0), (0, CELL), (CELL, CELL), (CELL, 0)]]
    sides = [geo.addLine(corners[k], corners[(k + 1) % 4]) for k in range(4)]
    surface = geo.addPlaneSurface([geo.addCurveLoop(sides)])
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, [surface], 1, name="matrix")
    gmsh.model.mesh.generate(2)
    write(DATA_DIR / "clockwise_v22.msh", 2.2)
    gmsh.model.remove()


def msh_version(path):
    """The version number on the line after `$MeshFormat`."""
    with open(path, "rb") as f:
        lines = f.read(200).split(b"\n")
    if len(lines) < 2 or lines[0].strip() != b"$MeshFormat":
        sys.exit(f"{path}: not an MSH file (no $MeshFormat on the first line)")
    return float(lines[1].split()[0])


def resave(src, dst, version):
    if version is None:
        version = 4.1 if msh_version(src) < 4.0 else 2.2
    gmsh.open(str(src))
    write(pathlib.Path(dst), version)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resave", nargs=2, metavar=("IN", "OUT"),
                        help="open IN with Gmsh and save it as OUT in the other MSH version")
    parser.add_argument("--version", type=float, choices=[2.2, 4.1],
                        help="output version for --resave (default: the other one)")
    args = parser.parse_args()

    start()
    try:
        if args.resave:
            resave(args.resave[0], args.resave[1], args.version)
        else:
            DATA_DIR.mkdir(parents=True, exist_ok=True)
            two_circles()
            quads()
            binary()
            clockwise()
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main()
