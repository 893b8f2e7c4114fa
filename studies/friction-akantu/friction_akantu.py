#!/usr/bin/env python3
"""Coulomb friction on a closed crack: Akantu 5.0.7's MaterialCohesiveLinearFriction
against the closed form of our law (and against `examples/friction_path` when given).

One cohesive element (two unit quadrangles sharing the edge y = 1, the intrinsic
`_cohesive_2d_4` inserted on it), every DOF prescribed: the bottom quad fixed, the top
quad moved rigidly by the jump [delta_s, delta_n], so the tractions are the law evaluated
on the prescribed jump, the history committed once per `solveStep('static')`.

Path: open to 2 delta_c (fully damaged), back to 0, closed to delta_n < 0, then a shear
cycle delta_s 0 -> +a -> -a -> 0 at that delta_n, a = 5 mu |t_n| / k.

Each Akantu run is a subprocess (`--case ...`), so a crash is reported, not fatal.

    friction_akantu.py --out DIR [--ours]        (the runner studies/friction-akantu/run)

Python 3 with numpy and akantu (the study's venv); `kit` from scripts/ for provenance.
"""

import argparse
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))

# Units: N, mm (MPa for tractions, N/mm^3 for stiffnesses per unit area).
MU = 0.6          # friction coefficient (Akantu `mu`)
K_STICK = 1e4     # stick stiffness k (Akantu `penalty_for_friction`)
K_P = 2e4         # contact penalty k_p (Akantu `penalty`)
DN = -1e-3        # normal jump of the closed phase: t_n = k_p DN = -20
SIGMA_C = 3.0     # Akantu `sigma_c` (only the damage phase uses it)
DELTA_C = 0.05    # Akantu `delta_c`
TAU = MU * K_P * abs(DN)          # mu |t_n| = 12
A = 5.0 * TAU / K_STICK           # cycle amplitude, 5 stick limits = 6e-3

MESH = """$MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
6
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 1 2 0
6 0 2 0
$EndNodes
$Elements
2
1 3 2 1 1 1 2 3 4
2 3 2 2 2 4 3 5 6
$EndElements
"""

MATERIAL = """material elastic [
  name = bulk
  rho = 1
  E = 1e4
  nu = 0
]
material cohesive_linear_friction [
  name = interface
  sigma_c = {sigma_c}
  beta = 0
  delta_c = {delta_c}
  penalty = {kp}
  mu = {mu}
  penalty_for_friction = {k}
  contact_after_breaking = {cab}
]
"""


# --------------------------------------------------------------------------- paths
def cycle(n):
    """delta_s of the shear cycle 0 -> a -> -a -> 0, n steps per quarter (4n + 1 points)."""
    up = [A * i / n for i in range(n + 1)]
    across = [A - 2.0 * A * i / (2 * n) for i in range(1, 2 * n + 1)]
    back = [-A + A * i / n for i in range(1, n + 1)]
    return up + across + back


def full_path(n, shift):
    """[(delta_s, delta_n, phase)]: damage, closure, cycle; delta_s shifted by `shift`."""
    pre = [(shift, d, "damage") for d in (0.5 * DELTA_C, DELTA_C, 2.0 * DELTA_C)]
    pre += [(shift, 0.0, "closure"), (shift, 0.5 * DN, "closure"), (shift, DN, "closure")]
    return pre + [(s + shift, DN, "cycle") for s in cycle(n)]


# --------------------------------------------------------------------------- laws
def closed_form(path, mu=MU, k=K_STICK, kp=K_P):
    """Our law (crates/core/src/interface/friction.rs) on a fully damaged point:
    [(t_s, t_n, slip)] along [(delta_s, delta_n, ...)]."""
    s, out = 0.0, []
    for ds, dn, *_ in path:
        if dn >= 0.0:                      # open: no traction, the slip follows
            s = ds
            out.append((0.0, 0.0, s))
            continue
        tn = kp * dn
        limit = mu * abs(tn)
        trial = k * (ds - s)
        if abs(trial) <= limit:
            ts = trial                     # stick
        else:
            ts = math.copysign(limit, trial)
            s = ds - ts / k                # slip
        out.append((ts, tn, s))
    return out


def akantu_as_read(path, contact=True, mu=MU, k=K_STICK, kp=K_P):
    """A transcription of MaterialCohesiveLinearFriction<2>::computeTraction (fully
    damaged, contact_after_breaking): a scalar slip on the NORM g = |delta_s| of the
    tangential jump, the direction from delta_s / |delta_s|, and the update
    s = g - |tau| / k (the absolute value), not s = g - tau / k. Without
    `contact_after_breaking` a fully damaged point has neither contact nor friction."""
    s, out = 0.0, []
    for ds, dn, *_ in path:
        if not contact or not dn / DELTA_C < -1e-10:   # no `penetration`: s kept
            out.append((0.0, 0.0, s))
            continue
        g = abs(ds)
        tau = min(k * abs(g - s), mu * kp * abs(dn))
        if g - s < 0.0:
            tau = -tau
        direction = ds / g if g > 0.0 else float("nan")   # 0/0 in Akantu
        s = g - abs(tau) / k
        out.append((tau * direction, kp * dn, s))
    return out


# --------------------------------------------------------------------------- akantu case
def run_case(args):
    """In a subprocess: drive Akantu along the path, write CSV (and the tangent JSON)."""
    import numpy as np
    import akantu as aka

    os.makedirs(args.workdir, exist_ok=True)
    os.chdir(args.workdir)
    with open("mesh.msh", "w") as f:
        f.write(MESH)
    with open("material.dat", "w") as f:
        f.write(MATERIAL.format(sigma_c=SIGMA_C, delta_c=DELTA_C, kp=K_P, mu=MU,
                                k=K_STICK, cab="true" if args.contact else "false"))
    aka.parseInput("material.dat")
    mesh = aka.Mesh(2)
    mesh.read("mesh.msh")
    model = aka.SolidMechanicsModelCohesive(mesh)
    model.initFull(_analysis_method=aka._static, _is_extrinsic=False)
    T, G = aka._cohesive_2d_4, aka._not_ghost
    mat = model.getMaterial("interface")
    # 5.0.7: "delta max" has no history although computeTraction reads its previous
    # value (segfault in ElementTypeMapArray::operator() otherwise).
    if args.history_fix:
        dmax = mat.getInternalReal("delta max")
        if not dmax.hasHistory():
            dmax.initializeHistory()

    cohesive = mesh.getConnectivity(T)
    assert len(cohesive) == 1, cohesive
    bottom_pair, top_pair = list(cohesive[0][:2]), list(cohesive[0][2:])
    quads = mesh.getConnectivity(aka._quadrangle_4)
    nodes = mesh.getNodes()
    top_quad = max(range(len(quads)), key=lambda e: nodes[quads[e], 1].mean())
    top = sorted(set(int(i) for i in quads[top_quad]))
    assert set(top_pair) <= set(top), (top, top_pair)

    model.getBlockedDOFs()[:] = True
    u = model.getDisplacement()
    solver = model.getNonLinearSolver("static")
    solver.set("max_iterations", 10)
    solver.set("threshold", 1e-12)

    def internal(name):
        return mat.getInternalReal(name)(T, G)

    rows, tangents = [], {}
    path = full_path(args.n, args.shift)
    for i, (ds, dn, phase) in enumerate(path):
        u[:] = 0.0
        u[top, 0] = ds
        u[top, 1] = dn
        model.solveStep("static")
        # Akantu's jump is u(bottom) - u(top) with normal -y: its traction vector is
        # minus ours in x, y (check: contact_tractions = (0, -k_p delta_n)).
        t = -(internal("tractions") + internal("contact_tractions"))
        opening = internal("opening") + internal("contact_opening")
        rows.append(dict(
            step=i, phase=phase, delta_s=ds, delta_n=dn,
            t_s=float(t[:, 0].mean()), t_n=float(t[:, 1].mean()),
            t_s_spread=float(np.ptp(t[:, 0])) if np.all(np.isfinite(t)) else float("nan"),
            jump_s=float(-opening[:, 0].mean()), jump_n=float(-opening[:, 1].mean()),
            damage=float(internal("damage").mean()),
            residual_sliding=float(internal("residual_sliding").mean())))
        if args.tangent_at and phase == "cycle":
            j = i - len(path) + len(cycle(args.n))   # index in the cycle
            if j in args.tangent_at:
                model.assembleStiffnessMatrix()
                K = aka.AkantuSparseMatrix(
                    model.getDOFManager().getMatrix("K")).toarray()

                def block(a, b):
                    return K[2 * a:2 * a + 2, 2 * b:2 * b + 2]
                # Only the cohesive element couples its two sides: with linear shapes
                # on a unit edge, K(b0, t0) = -D/3 and K(b0, t1) = -D/6, D = dt/djump.
                d_pair = -3.0 * block(bottom_pair[0], top_pair[0])
                d_cross = -6.0 * block(bottom_pair[0], top_pair[1])
                tangents[str(j)] = dict(
                    delta_s=ds, D=d_pair.tolist(),
                    D_cross_check=float(np.abs(d_pair - d_cross).max()),
                    unrelated_block=float(np.abs(block(0, top_pair[0])).max()))
    with open(args.csv, "w") as f:
        keys = list(rows[0])
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join(str(r[k]) for k in keys) + "\n")
    if tangents:
        with open(args.csv.replace(".csv", "_tangent.json"), "w") as f:
            json.dump(tangents, f, indent=1)


# --------------------------------------------------------------------------- comparison
def read_csv(file):
    with open(file) as f:
        keys = f.readline().strip().split(",")
        rows = []
        for line in f:
            values = line.strip().split(",")
            rows.append({k: (v if k == "phase" else float(v)) for k, v in zip(keys, values)})
    return rows


OURS = "cargo run --release --quiet --example friction_path --"


def ours_example(path, command=OURS):
    """`cargo run --release --example friction_path -- mu k kp` on the path: [(t_s, t_n,
    slip)], or None with the reason."""
    text = "".join("%.17g %.17g\n" % (ds, dn) for ds, dn, _ in path)
    run = subprocess.run(command.split() + [repr(MU), repr(K_STICK), repr(K_P)],
                         cwd=ROOT, input=text, capture_output=True, text=True)
    if run.returncode != 0:
        return None, "exit %d: %s" % (run.returncode, run.stderr.strip()[-300:])
    out = []
    for line in run.stdout.splitlines():
        try:
            values = [float(v) for v in line.split(",")]
        except ValueError:
            continue                           # a header
        if len(values) >= 5:
            out.append((values[2], values[3], values[4]))
    if len(out) != len(path):
        return None, "%d rows for %d input lines" % (len(out), len(path))
    return out, ""


def loop_dissipation(ds, ts, k=K_STICK):
    """Work of t_s over the cycle (trapezoid) minus the elastic energy left at its end."""
    work = sum(0.5 * (ts[i] + ts[i - 1]) * (ds[i] - ds[i - 1]) for i in range(1, len(ds)))
    return work - ts[-1] ** 2 / (2.0 * k)


def exact_dissipation():
    """0 -> a: slides a - tau/k; a -> -a: 2a - 2 tau/k; -a -> 0: a - 2 tau/k (a >= 2 tau/k)."""
    return TAU * (4.0 * A - 5.0 * TAU / K_STICK)


def quarter_errors(akantu, ref, n):
    """max |t_s - ref| / tau on 0 -> a, a -> -a, -a -> 0 (NaN rows skipped) and overall."""
    spans = [(0, n + 1), (n + 1, 3 * n + 1), (3 * n + 1, 4 * n + 1)]
    errs = []
    for lo, hi in spans:
        e = [abs(akantu[i] - ref[i]) / TAU for i in range(lo, hi) if math.isfinite(akantu[i])]
        errs.append(max(e) if e else float("nan"))
    return errs


def fmt(x, spec=".2e"):
    return "n/a" if x is None or not math.isfinite(x) else format(x, spec)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=os.path.join(ROOT, "target/studies/friction-akantu"))
    p.add_argument("--ours", action="store_true", help="also run examples/friction_path")
    p.add_argument("--ours-cmd", default=OURS, help="the command of --ours (before MU K KP)")
    p.add_argument("--case", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--n", type=int, default=10, help=argparse.SUPPRESS)
    p.add_argument("--shift", type=float, default=0.0, help=argparse.SUPPRESS)
    p.add_argument("--contact", type=int, default=1, help=argparse.SUPPRESS)
    p.add_argument("--history-fix", type=int, default=1, help=argparse.SUPPRESS)
    p.add_argument("--tangent-at", type=lambda s: [int(v) for v in s.split(",") if v],
                   default=[], help=argparse.SUPPRESS)
    p.add_argument("--csv", help=argparse.SUPPRESS)
    p.add_argument("--workdir", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.case:
        run_case(args)
        return

    from kit import provenance  # noqa: E402
    record = provenance.start(["studies/friction-akantu"])
    import akantu
    args.out = os.path.abspath(args.out)
    os.makedirs(args.out, exist_ok=True)
    shift = 1e-9 * A
    # name, steps per quarter, shift, contact_after_breaking, history fix, tangent probes
    cases = [
        ("n10", 10, shift, 1, 1, "1,4"),
        ("n50", 50, shift, 1, 1, ""),
        ("n250", 250, shift, 1, 1, ""),
        ("n10-unshifted", 10, 0.0, 1, 1, ""),
        ("n10-no-contact-after-breaking", 10, shift, 0, 1, ""),
        ("n10-no-history-fix", 10, shift, 1, 0, ""),
    ]
    results, runs = [], 0
    for name, n, sh, contact, fix, probes in cases:
        csv = os.path.join(args.out, "akantu_%s.csv" % name)
        if os.path.exists(csv):
            os.remove(csv)
        cmd = [sys.executable, os.path.abspath(__file__), "--case", "--n", str(n),
               "--shift", repr(sh), "--contact", str(contact), "--history-fix", str(fix),
               "--tangent-at", probes, "--csv", csv,
               "--workdir", os.path.join(args.out, "work", name)]
        run = subprocess.run(cmd, capture_output=True, text=True)
        runs += 1
        path = full_path(n, sh)
        res = dict(name=name, n=n, shift=sh, rc=run.returncode,
                   stderr=run.stderr.strip()[-400:])
        results.append(res)
        if run.returncode != 0 or not os.path.exists(csv):
            print("%s: exit %d %s" % (name, run.returncode, res["stderr"]), file=sys.stderr)
            continue
        rows = read_csv(csv)
        cyc = [r for r in rows if r["phase"] == "cycle"]
        first = len(rows) - len(cyc)
        ds = [r["delta_s"] for r in cyc]
        ts = [r["t_s"] for r in cyc]
        ref = closed_form(path)
        ref_ts = [t for t, _, _ in ref[first:]]
        read = akantu_as_read(path, contact=bool(contact))
        res.update(
            nan=sum(1 for t in ts if not math.isfinite(t)),
            quarters=quarter_errors(ts, ref_ts, n),
            tn_err=max((abs(r["t_n"] - K_P * r["delta_n"]) / abs(K_P * DN) for r in cyc
                        if math.isfinite(r["t_n"])), default=float("nan")),
            reversal=[(ds[i], ts[i], ref_ts[i]) for i in range(n, min(2 * n + 1, len(ds)))],
            jump_err=max(max(abs(r["jump_s"] - r["delta_s"]), abs(r["jump_n"] - r["delta_n"]))
                         for r in cyc),
            damage=cyc[0]["damage"],
            diss=loop_dissipation(ds, ts), diss_ref=loop_dissipation(ds, ref_ts),
            as_read=max((abs(a - b[0]) / TAU for a, b in zip(ts, read[first:])
                         if math.isfinite(a)), default=float("nan")),
            as_read_nan=[i for i, (a, b) in enumerate(zip(ts, read[first:]))
                         if math.isfinite(a) != math.isfinite(b[0])])
        if args.ours:
            ours, why = ours_example(path, args.ours_cmd)
            if ours is None:
                res["ours"] = why
            else:
                o_ts = [t for t, _, _ in ours[first:]]
                res["ours"] = dict(
                    vs_closed=max(abs(a - b) / TAU for a, b in zip(o_ts, ref_ts)),
                    vs_akantu=quarter_errors(ts, o_ts, n),
                    diss=loop_dissipation(ds, o_ts))
        tangent = csv.replace(".csv", "_tangent.json")
        if os.path.exists(tangent):
            with open(tangent) as f:
                res["tangent"] = json.load(f)
        print("%s: done" % name, file=sys.stderr)

    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    page = report(results, record, runs, akantu.getVersion(), args.ours)
    with open(os.path.join(args.out, "friction_akantu.md"), "w") as f:
        f.write(page)
    print(page)


def report(results, record, runs, version, ours):
    from kit import provenance  # noqa: E402
    L = ["# Coulomb friction on a closed crack: Akantu %s against our law" % version, "",
         provenance.sentence(record, runs, "Akantu runs (one subprocess each)"), "",
         "mu = %g, k = %g, k_p = %g, delta_n = %g (t_n = %g, mu|t_n| = %g), a = %g "
         "(5 stick limits); sigma_c = %g, delta_c = %g, opened to 2 delta_c first."
         % (MU, K_STICK, K_P, DN, K_P * DN, TAU, A, SIGMA_C, DELTA_C), "",
         "Errors are max |t_s - t_s,ref| / (mu |t_n|) against the closed form, per part of "
         "the cycle; the dissipation is the loop work minus the elastic energy left at "
         "its end, exact %.6g." % exact_dissipation(), "",
         "| run | steps/quarter | delta_s shift | NaN steps | 0 -> a | a -> -a | -a -> 0 "
         "| t_n error | dissipation Akantu | closed form (trapezoid) | source transcription |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        if "quarters" not in r:
            L.append("| %s | %d | %s | crashed: exit %d | | | | | | | |"
                     % (r["name"], r["n"], fmt(r["shift"], ".0e"), r["rc"]))
            continue
        q = r["quarters"]
        L.append("| %s | %d | %s | %d | %s | %s | %s | %s | %s | %s | %s |" % (
            r["name"], r["n"], fmt(r["shift"], ".0e") if r["shift"] else "0", r["nan"],
            fmt(q[0]), fmt(q[1]), fmt(q[2]), fmt(r["tn_err"]), fmt(r["diss"], ".5g"),
            fmt(r["diss_ref"], ".5g"), fmt(r["as_read"])))
    L += ["", "Source transcription: max |t_s(Akantu) - t_s(akantu_as_read)| / (mu|t_n|), "
          "the Python transcription of Akantu's update in `friction_akantu.py`.", ""]
    for r in results:
        if "tangent" in r:
            L.append("Tangent D = dt/d[delta_s, delta_n] from Akantu's assembled K (%s):" % r["name"])
            for j, t in sorted(r["tangent"].items(), key=lambda kv: int(kv[0])):
                D = t["D"]
                L.append("- cycle step %s (delta_s = %.3g): [[%.6g, %.6g], [%.6g, %.6g]] "
                         "(pair/cross blocks agree to %.1e)" % (
                             j, t["delta_s"], D[0][0], D[0][1], D[1][0], D[1][1],
                             t["D_cross_check"]))
            L.append("- ours (friction.rs, consistent tangent): stick [[%g, 0], [0, %g]], "
                     "slip forward [[0, %g], [0, %g]]" % (K_STICK, K_P, -MU * K_P, K_P))
    for r in results:
        if r.get("reversal"):
            L += ["", "The first reversal (a -> -a, its first %d steps) of %s:" % (
                len(r["reversal"]) - 1, r["name"]), "",
                "| delta_s | t_s Akantu | t_s closed form |", "|---|---|---|"]
            L += ["| %.4g | %.6g | %.6g |" % row for row in r["reversal"]]
            break
    if ours:
        L += ["", "Our example `friction_path`:"]
        for r in results:
            if "ours" in r:
                o = r["ours"]
                if isinstance(o, str):
                    L.append("- %s: not compared (%s)" % (r["name"], o))
                else:
                    L.append("- %s: against the closed form %s; Akantu against it per part %s; "
                             "dissipation %s" % (r["name"], fmt(o["vs_closed"]),
                                                 ", ".join(fmt(v) for v in o["vs_akantu"]),
                                                 fmt(o["diss"], ".5g")))
    else:
        L += ["", "Our example `friction_path` was not run (absent or not built): the "
              "reference is the closed form only."]
    for r in results:
        if r["rc"] != 0:
            L += ["", "%s exited with %d; its stderr ends with:" % (r["name"], r["rc"]), "",
                  "```", r["stderr"] or "(nothing)", "```"]
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    main()
