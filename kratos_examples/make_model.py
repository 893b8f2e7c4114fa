#!/usr/bin/env python3
"""Writes a Kratos GeoMechanics model whose material is the mesorve RVE through Kratos's
`SmallStrainUMAT2DPlaneStrainLaw` (`umat_` of librve.so): DIR/model.mdpa,
DIR/MaterialParameters.json and DIR/ProjectParameters.json.

The model: a 1 x 1 square of NX x NX `UPwSmallStrainElement2D4N` (water pressure fixed at
0 everywhere, undrained effects ignored: a plain small-strain solid), loaded in
displacement from time 0 to 1 in STEPS equal steps (Kratos does not grow them; it halves
one whose Newton iterations fail, NaN in the stress among the reasons):
- `homogeneous`: every node's u_x = EPS * x * t and u_y = 0: the strain [EPS t, 0, 0] at
  every point, the RVE's own path;
  with --free-interior only the boundary nodes are moved: the interior ones are found by
  Newton (the homogeneous state is still the equilibrium);
- `uniaxial`: u_x = 0 on the left edge, u_x = EPS * t on the right, u_y = 0 at the
  bottom-left node only, on a mesh whose interior nodes are moved by up to DISTORT of an
  element's size: a uniaxial stress state that Newton must find (the predictor is not
  homogeneous).

Usage: make_model.py DIR CASE LIBRVE NSTATV [--eps 3e-4] [--steps 15] [--nx 2]
       [--distort 0.25] [--max-iterations 10] [--free-interior]
NSTATV: the STATE_VARIABLES given to every point (zeros): `rve info SCENE --json`'s
umat_nstatv plus up to 5 mirrors. The scene is MESORVE_UMAT_SCENE's, set by the caller.
"""
import argparse
import json
import os


def nodes_of(nx, distort):
    """Node ids and coordinates, row by row from the bottom; interior nodes moved by a
    fixed pattern of up to `distort` of the element size (deterministic)."""
    h = 1.0 / nx
    coords = {}
    for j in range(nx + 1):
        for i in range(nx + 1):
            x, y = i * h, j * h
            if 0 < i < nx and 0 < j < nx:
                x += distort * h * (0.9 if (i + j) % 2 else -0.7)
                y += distort * h * (-0.6 if i % 2 else 0.8)
            coords[j * (nx + 1) + i + 1] = (x, y)
    return coords


def elements_of(nx):
    elems = {}
    for j in range(nx):
        for i in range(nx):
            n1 = j * (nx + 1) + i + 1
            elems[j * nx + i + 1] = (n1, n1 + 1, n1 + nx + 2, n1 + nx + 1)
    return elems


def part(name, nodes, elements=(), tables=()):
    lines = [f"Begin SubModelPart {name}", "  Begin SubModelPartTables"]
    lines += [f"    {t}" for t in tables]
    lines += ["  End SubModelPartTables", "  Begin SubModelPartNodes"]
    lines += [f"    {n}" for n in sorted(nodes)]
    lines += ["  End SubModelPartNodes", "  Begin SubModelPartElements"]
    lines += [f"    {e}" for e in sorted(elements)]
    lines += ["  End SubModelPartElements", "End SubModelPart", ""]
    return lines


def mdpa(case, nx, eps, distort, free_interior=False):
    """The mdpa text and the constrained parts: (name, fixed x, fixed y, table of x)."""
    coords = nodes_of(nx, 0.0 if case == "homogeneous" else distort)
    elems = elements_of(nx)
    lines = ["Begin Properties 1", "End Properties", ""]
    parts, constraints = [], []
    if case == "homogeneous":
        # One table per column of nodes: u_x = EPS * x * t (x exact: the mesh is regular).
        for i in range(nx + 1):
            x = i / nx
            lines += [f"Begin Table {i + 1} TIME DISPLACEMENT_X", "  0.0 0.0",
                      f"  1.0 {eps * x!r}", "End Table", ""]
            col = [n for n, (cx, cy) in coords.items() if abs(cx - x) < 1e-12
                   and not (free_interior and 0 < cx < 1 and 0 < cy < 1)]
            parts += part(f"column_{i}", col, tables=[i + 1])
            constraints.append((f"column_{i}", True, True, i + 1))
    else:
        lines += ["Begin Table 1 TIME DISPLACEMENT_X", "  0.0 0.0", f"  1.0 {eps!r}",
                  "End Table", ""]
        left = [n for n, (x, _) in coords.items() if x == 0.0]
        right = [n for n, (x, _) in coords.items() if x == 1.0]
        parts += part("left", left) + part("right", right, tables=[1]) + part("corner", [1])
        constraints += [("left", True, False, 0), ("right", True, False, 1),
                        ("corner", False, True, 0)]
    lines += ["Begin Nodes"]
    lines += [f"  {n} {x!r} {y!r} 0.0" for n, (x, y) in coords.items()]
    lines += ["End Nodes", "", "Begin Elements UPwSmallStrainElement2D4N"]
    lines += [f"  {e} 1 {' '.join(map(str, ns))}" for e, ns in elems.items()]
    lines += ["End Elements", ""]
    lines += part("soil", coords, elems)
    lines += parts
    return "\n".join(lines), constraints


def materials(librve, nstatv):
    variables = {
        "IGNORE_UNDRAINED": True,
        "DENSITY_SOLID": 0.0, "DENSITY_WATER": 0.0, "POROSITY": 0.0,
        "BULK_MODULUS_SOLID": 1.0e12, "BULK_MODULUS_FLUID": 1.0e9,
        "PERMEABILITY_XX": 1.0e-30, "PERMEABILITY_YY": 1.0e-30, "PERMEABILITY_XY": 0.0,
        "DYNAMIC_VISCOSITY": 1.0e-3, "BIOT_COEFFICIENT": 1.0,
        "RETENTION_LAW": "SaturatedLaw", "SATURATED_SATURATION": 1.0,
        "RESIDUAL_SATURATION": 0.0, "MINIMUM_RELATIVE_PERMEABILITY": 1.0e-4,
        "THICKNESS": 1.0,
        "UDSM_NAME": librve, "UDSM_NUMBER": 1, "IS_FORTRAN_UDSM": True,
        "UMAT_PARAMETERS": [0.0],
        "STATE_VARIABLES": [0.0] * nstatv,
    }
    law = {"name": "SmallStrainUMAT2DPlaneStrainLaw"}
    return {"properties": [{"model_part_name": "PorousDomain.soil", "properties_id": 1,
                            "Material": {"constitutive_law": law, "Variables": variables},
                            "Tables": {}}]}


def constraint(name, fix_x, fix_y, table):
    return {"python_module": "apply_vector_constraint_table_process",
            "kratos_module": "KratosMultiphysics.GeoMechanicsApplication",
            "process_name": "ApplyVectorConstraintTableProcess",
            "Parameters": {"model_part_name": f"PorousDomain.{name}",
                           "variable_name": "DISPLACEMENT",
                           "active": [fix_x, fix_y, False], "is_fixed": [fix_x, fix_y, False],
                           "value": [0.0, 0.0, 0.0], "table": [table, 0, 0]}}


def project(steps, max_iterations, constraints):
    pressure = {"python_module": "apply_scalar_constraint_table_process",
                "kratos_module": "KratosMultiphysics.GeoMechanicsApplication",
                "process_name": "ApplyScalarConstraintTableProcess",
                "Parameters": {"model_part_name": "PorousDomain.soil",
                               "variable_name": "WATER_PRESSURE", "is_fixed": True,
                               "value": 0.0, "table": 0, "fluid_pressure_type": "Uniform"}}
    solver = {
        "solver_type": "U_Pw", "model_part_name": "PorousDomain", "domain_size": 2,
        "model_import_settings": {"input_type": "mdpa", "input_filename": "model"},
        "material_import_settings": {"materials_filename": "MaterialParameters.json"},
        "time_stepping": {"time_step": 1.0 / steps, "max_delta_time_factor": 1.0},
        "buffer_size": 2, "echo_level": 0, "clear_storage": False,
        "compute_reactions": True, "move_mesh_flag": False,
        "reform_dofs_at_each_step": False,
        "block_builder": True, "solution_type": "quasi_static", "scheme_type": "Backward_Euler",
        "strategy_type": "newton_raphson",
        "convergence_criterion": "residual_criterion",
        "residual_relative_tolerance": 1.0e-8, "residual_absolute_tolerance": 1.0e-12,
        "min_iterations": 0, "max_iterations": max_iterations, "number_cycles": 8,
        "reduction_factor": 0.5, "increase_factor": 1.0,
        "rotation_dofs": False,
        "linear_solver_settings": {"solver_type": "LinearSolversApplication.sparse_lu"},
        "problem_domain_sub_model_part_list": ["soil"],
        "processes_sub_model_part_list": ["soil"] + [c[0] for c in constraints],
        "body_domain_sub_model_part_list": ["soil"],
    }
    return {
        "problem_data": {"problem_name": "mesorve", "start_time": 0.0, "end_time": 1.0,
                         "echo_level": 0, "parallel_type": "OpenMP",
                         "number_of_threads": int(os.environ.get("OMP_NUM_THREADS", "1"))},
        "solver_settings": solver,
        "processes": {"constraints_process_list": [constraint(*c) for c in constraints]
                      + [pressure], "loads_process_list": []},
        "output_processes": {},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("case", choices=["homogeneous", "uniaxial"])
    ap.add_argument("librve")
    ap.add_argument("nstatv", type=int)
    ap.add_argument("--eps", type=float, default=3e-4)
    ap.add_argument("--steps", type=int, default=15)
    ap.add_argument("--nx", type=int, default=2)
    ap.add_argument("--distort", type=float, default=0.25)
    ap.add_argument("--max-iterations", type=int, default=10)
    ap.add_argument("--free-interior", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    text, constraints = mdpa(a.case, a.nx, a.eps, a.distort, a.free_interior)
    with open(os.path.join(a.dir, "model.mdpa"), "w") as f:
        f.write(text)
    with open(os.path.join(a.dir, "MaterialParameters.json"), "w") as f:
        json.dump(materials(os.path.abspath(a.librve), a.nstatv), f, indent=2)
    with open(os.path.join(a.dir, "ProjectParameters.json"), "w") as f:
        json.dump(project(a.steps, a.max_iterations, constraints), f, indent=2)


if __name__ == "__main__":
    main()
