#!/usr/bin/env python3
"""The member's accuracy against its cost (studies/member-accuracy/run): ccx runs of
calculix_examples/member_beam.py's beam at several increment counts and answer-sharing
tolerances, each scored against a reference run. Standard library only.

  member_accuracy.py table FINE LABEL=JOB[@EXACT] ...

FINE is the reference (the finest increments, no sharing). For every run JOB (a ccx job
path without extension: JOB.inp, JOB.dat, JOB.time from the kit's ccx runner) one row:

- increments, wall time and CPU time (and both against the FINE run's);
- against FINE, along the whole load path (down, back, up), at the run's own increments
  (every run's path is the same piecewise-linear U(t); its increment k of N ends at the
  fraction k / N of it, which FINE's increments include when N divides FINE's count;
  otherwise FINE's F is interpolated linearly in U along the same leg):
  - **L1**: the mean of |F - F_fine| over the run's increments, in units of FINE's largest |F|;
  - **max**: the largest |F - F_fine|, same units;
  - **dissipated work**: W = integral of F dU over the path (trapezoids from the origin)
    less the energy the member gives back on unloading from the last increment. IMPL-EX
    unloads every RVE on its secant through the origin (the paper's eq. 24; checked on the
    member by member_figures.py's `check`: F/U constant within 1 % on the way back), so that
    energy is F_end U_end / 2. The relative difference to FINE's;
- with `@EXACT` (a run at the same increments without sharing): the curve's L1 and max
  against it, and at the deck's stages (`--stage-stress`) the largest difference of a
  point's stress (max over the in-plane components) in units of the largest stress of
  the stage, and how many points are damaged (mirror 4 above member_figures.DAMAGED) in
  one run and not in the other.
"""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from kit.ccx import dat_points, read_time  # noqa: E402
from member_figures import DAMAGED, fail, read_dat, read_inp  # noqa: E402


def stage_stresses(path):
    """{time: {(element, point): (sxx, syy, sxy)}} of the `*EL PRINT` stresses of set EALL."""
    return {t: {k: (v[0], v[1], v[3]) for k, v in points.items()}
            for t, points in dat_points(path, "stresses", "EALL").items() if points}


def load(job):
    curve, stages = read_dat(job + ".dat")
    if not curve:
        fail(f"{job}: no increment in {job}.dat")
    _, _, stage_incs = read_inp(job + ".inp")
    return {"curve": curve, "stages": stages, "stage_incs": stage_incs,
            "stresses": stage_stresses(job + ".dat"), "time": read_time(job)}


def dissipated(curve):
    """integral F dU over the path less F_end U_end / 2 (the secant unloading's energy)."""
    w, u0, f0 = 0.0, 0.0, 0.0
    for _, u, f in curve:
        w += 0.5 * (f + f0) * (u - u0)
        u0, f0 = u, f
    return w - 0.5 * f0 * u0


def legs(curve):
    """The curve split where U turns: [[(U, F), ...] per leg], each leg starting at the
    end of the last (the first at the origin)."""
    out, start, sign = [], (0.0, 0.0), 0
    for _, u, f in curve:
        prev = out[-1][-1] if out else start
        d = (u > prev[0]) - (u < prev[0])
        if not out or (d and sign and d != sign):
            out.append([prev])
        sign = d or sign
        out[-1].append((u, f))
    return out


def on_fine(run, fine):
    """[(F, F_fine)] at the run's increments. When FINE's M increments are a multiple of
    the run's N, increment k of N is FINE's k * M / N; else F_fine is interpolated linearly
    in U along the same leg of FINE's curve (a leg ends where U turns: down, then back
    and up)."""
    n, m = len(run["curve"]), len(fine["curve"])
    if m % n == 0:
        return [(p[2], fine["curve"][(k + 1) * (m // n) - 1][2]) for k, p in enumerate(run["curve"])]
    mine, ref = legs(run["curve"]), legs(fine["curve"])
    if len(mine) != len(ref):
        fail(f"the run has {len(mine)} legs of U, the reference {len(ref)}")
    pairs = []
    for leg, ref_leg in zip(mine, ref):
        for u, f in leg[1:]:
            for (u0, f0), (u1, f1) in zip(ref_leg, ref_leg[1:]):
                if min(u0, u1) - 1e-12 <= u <= max(u0, u1) + 1e-12 and u0 != u1:
                    pairs.append((f, f0 + (f1 - f0) * (u - u0) / (u1 - u0)))
                    break
            else:
                fail(f"U = {u:g} is outside the reference's leg")
    return pairs


def curve_error(pairs, scale):
    d = [abs(a - b) for a, b in pairs]
    return sum(d) / len(d) / scale, max(d) / scale


def stage_errors(run, exact):
    """(largest point stress difference / the stage's largest stress, points damaged in
    one run only) over the stages both runs printed."""
    worst, flips = 0.0, 0
    for t, pts in exact["stresses"].items():
        mine = run["stresses"].get(t)
        if mine is None or mine.keys() != pts.keys():
            fail(f"stage at time {t:g}: the runs printed different points")
        top = max(max(abs(v) for v in s) for s in pts.values())
        worst = max(worst, max(max(abs(a - b) for a, b in zip(mine[k], s)) for k, s in pts.items()) / top)
    for t, pts in exact["stages"].items():
        mine = run["stages"][t]
        flips += sum(1 for k, p in pts.items() if (p[3] > DAMAGED) != (mine[k][3] > DAMAGED))
    return worst, flips


def cost(run):
    tv = run["time"]
    return tv["wall"], tv["user"] + tv["sys"]


def table(fine_job, specs):
    fine = load(fine_job)
    scale = max(abs(p[2]) for p in fine["curve"])
    wf, (fine_wall, fine_cpu) = dissipated(fine["curve"]), cost(fine)
    print(f"Reference: {os.path.basename(fine_job)}, {len(fine['curve'])} increments, largest |F| "
          f"{scale:.2f} N, dissipated work {wf:.4g} N mm, wall {fine_wall:.1f} s, CPU {fine_cpu:.1f} s.\n")
    print("| run | increments | wall time | CPU time | CPU / reference | L1 vs reference | max vs reference "
          "| dissipated work vs reference | L1 vs exact, same increments | max vs exact | largest point "
          "stress difference | points damaged differently |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for spec in specs:
        label, rest = spec.split("=", 1)
        job, _, exact_job = rest.partition("@")
        run = load(job)
        wall, cpu = cost(run)
        l1, mx = curve_error(on_fine(run, fine), scale)
        work = dissipated(run["curve"]) / wf - 1
        same = "| | | | |"
        if exact_job:
            exact = load(exact_job)
            if [p[0] for p in exact["curve"]] != [p[0] for p in run["curve"]]:
                fail(f"{job} and {exact_job} have different increments")
            el1, emx = curve_error([(a[2], b[2]) for a, b in zip(run["curve"], exact["curve"])], scale)
            ds, flips = stage_errors(run, exact)
            same = f"| {100 * el1:.3f} % | {100 * emx:.3f} % | {100 * ds:.2f} % | {flips} |"
        print(f"| {label} | {len(run['curve'])} | {wall:.1f} s | {cpu:.1f} s | {cpu / fine_cpu:.3f} | "
              f"{100 * l1:.3f} % | {100 * mx:.3f} % | {100 * work:+.3f} % {same}")


def main():
    if len(sys.argv) >= 4 and sys.argv[1] == "table":
        table(sys.argv[2], sys.argv[3:])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
