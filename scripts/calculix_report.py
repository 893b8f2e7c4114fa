#!/usr/bin/env python3
"""Reads CalculiX outputs of scripts/test-calculix and checks and reports them.

  calculix_report.py homogeneous JOB.dat RESPONSE.csv
      The homogeneous specimen (every node prescribed, one strain state) against `rve run`
      on the same strain path: every increment's stress (sxx, syy, szz, sxy at every
      integration point) must agree to TOLERANCE times the largest stress of the path.
      ccx prints 7 significant digits, so the printed values differ from exact ones by
      up to 5e-7 of themselves. Prints a table; exit status 1 on disagreement.

  calculix_report.py specimen LABEL=JOB ... > report.md
      Increments, attempts (cut-backs), ccx's Newton iterations per converged increment,
      the residual history of the hardest increment, and the force-displacement curve of
      each run, as Markdown.

  calculix_report.py friction JOB MU
      calculix_examples/friction_shear.inp (a closed crack under a held normal force,
      sheared through an elastic element): every increment of steps 3 and 4 must keep
      sigma_xx of element 1 at its first value and |sigma_xy| <= MU |sigma_xx|, and each
      step must end sliding, |sigma_xy| = MU |sigma_xx|, all to FRICTION_TOLERANCE (ccx
      prints 7 digits). Prints one Markdown line: ccx's iterations per step, the largest,
      the increments above ccx's minimum of 2.

  calculix_report.py iterations STEP LABEL=JOB ...
      ccx's Newton iterations of every increment of step STEP, one column per run, and
      the force residuals of each run's increment with the most iterations, as Markdown.

  calculix_report.py cycle JOB
      A tension (time <= 1), unloading (to time 2) and compression (to time 3) cycle under
      displacement control (specimen_weak.inp, specimen_notch.inp): one Markdown line of
      figures. Exit status 1 unless the run reached time 3, the force falls after its
      peak by at least DROP within the tension, the force at U = 0 after the unloading is
      below ZERO_FORCE times the peak force, and the compression's secant slope (F/U from
      U = 0 to the end) exceeds the unloading's (from its start to U = 0).

  calculix_report.py curves LABEL=JOB ...
      The tension (time <= 1) of several runs of one specimen (step sizes, meshes): peak,
      lowest force after it, the dissipated energy, and the force at every displacement
      of the first run (the others' increments must include them), as Markdown.

  calculix_report.py ligament LABEL=JOB ...
      The notched strip's mean strains eps_yy at its first peak and at the lowest force
      after it: the ligament's middle half (between LIGLOW and LIGTOP, 20 <= x <= 60) and
      the parts below and above the notches at the same x, as Markdown.

  calculix_report.py rvetime LABEL=JOB ...
      The RVE time of runs made with the timing UMAT (calculix_examples/umat_timing.c,
      JOB.times.csv): calls, RVE seconds in all and per converged increment, as Markdown;
      and the same up to the last converged time of the shortest run.

  calculix_report.py hostits LABEL=JOB ...
      ccx's Newton iterations per converged increment (median, max), increments and
      attempts cut back of each run, as Markdown.

  calculix_report.py factorizations LABEL=JOB:COUNT ...
      COUNT numeric factorizations (counted under gdb) per RVE per converged increment,
      the RVEs being the points of the timing UMAT's JOB.times.csv, as Markdown.

  calculix_report.py band JOB
      The localization of specimen_band.inp: the force's peak in the tension (time <= 2)
      and its lowest value after it, and the mean strains of the band (between the node
      sets BANDLOW and BANDTOP) and of the two sound rows there. Exit status 1 unless the
      force falls after its peak by at least DROP while U grows, the band stretches and
      the sound rows contract (unload).

  calculix_report.py control JOB PLAIN SMALLEST
      The tension (step 1) of a cycle deck under solver.step_tolerance with
      solver.smallest_step = SMALLEST, against the same deck's plain run PLAIN: one line of
      figures. Exit status 1 unless the step finished, the UMAT asked for a cut at least
      once (PNEWDT), every attempt ccx cut was redone smaller (the UMAT never hands it a
      PNEWDT of 1 or more, which ccx would redo at the same size), ccx grew the increment
      again after a cut (its own rule), no increment but the step's last is below
      SMALLEST, and the peak force is at least 5 % below the plain run's (which lands the
      crack late: +11.6 % against 16x its increments, docs/step_control.md).

  calculix_report.py snap REFERENCE.csv LABEL=JOB:EXPECT ...
      specimen_snap.inp's runs (one element pulled in one step through the RVE's
      snap-back) against `rve run` of the same path in 100 increments (REFERENCE.csv, its
      force 10 sig_xx, at the run's last time on the reference's grid): the force at the
      end, increments, cut-backs, whether the UMAT printed its step-check line and what
      ccx did with its PNEWDT, as Markdown. EXPECT: `+`-separated checks of the run:
      `flagged` (the step-check line is in JOB.log), `stopped` (ccx stopped the DIRECT
      step: "solution seems to diverge"), `cut` (ccx cut an attempt "through pnewdt", to
      SNAP_RATIO of its size), `close` (it finished within SNAP_TOLERANCE of the
      reference's end), `-` none. Exit status 1 when a check fails, with the reasons.
  calculix_report.py crackband COARSE FINE UNREGULARIZED
      calculix_examples/crack_band_bar.py's runs, each LABEL=JOB:H (H the element size,
      mm): the coarse and fine meshes regularized (PROPS(7) = H) and the fine one without.
      One Markdown row each: peak force, where the force falls below 10 % of it, the
      force at the end, the dissipated energy per unit crack length (N/m; the bar is
      WIDTH mm wide), and that energy over the coarse run's. Exit status 1 unless every
      run finished and fell below 10 % of its peak, the regularized runs' energies are
      within OBJECTIVITY_ENERGY and their peaks within OBJECTIVITY_PEAK of each other, and
      the unregularized run's energy is below UNREGULARIZED_AT_MOST of the coarse one's
      (without the regularization the crack's energy follows the element's size).
"""
import sys

from kit.ccx import cvg, dat_blocks, dat_points, sta

TOLERANCE = 1e-6
DROP = 0.01
# With IMPL-EX every RVE is linear through the origin within a host increment (secant
# unloading, penalty contact), so at U = 0 the host's exact solution is u = 0, F = 0; ccx's
# second iteration solves the increment's linear system with its exact tangent, leaving
# round-off (about 1e-16 of the peak force in these runs). 1e-9 leaves room for the
# conditioning of the host and RVE systems and stays far below the residual force that
# ccx's convergence criterion tolerates (0.5 % of the average force): an unloading that
# does not end at the origin fails.
ZERO_FORCE = 1e-9
# The RVE's lower branch after the snap-back, on the path of specimen_snap.inp: `rve run` in
# 16 to 400 increments ends at 3.2043 to 3.2138 N/mm^2 (0.30 % apart: which ITZ points crack
# depends a little on the path), ccx in STATEV mode 0.04 % from `rve run` (100 DIRECT
# increments, before the step check's PNEWDT reached ccx, which now stops them); the upper
# branch that a too large increment lands on is 32-33 % above. 1 % is three times the
# first spread and a thirtieth of the jump: a run within it has taken the snap.
SNAP_TOLERANCE = 0.01
# The step ratio the step check asks for (PNEWDT), by which ccx cuts an automatic increment.
SNAP_RATIO = 0.5
PNEWDT_CUT = "increment size decrease requested by a material user routine (through pnewdt)"

# crack_band_bar.py's width (mm): the crack's length per unit thickness.
WIDTH = 10.0
# The mesh-objectivity targets for two host meshes (h and h/2) with the
# regularization: dissipated energy within 10 %, peak load within 5 %.
OBJECTIVITY_ENERGY = 0.10
OBJECTIVITY_PEAK = 0.05
# Without it the fine mesh's crack row dissipates about half (the mesh ratio) plus what
# does not localize; a run above 80 % of the coarse one's shows no mesh dependence.
UNREGULARIZED_AT_MOST = 0.80


def homogeneous(dat, csv):
    stresses = dat_blocks(dat, "stresses")
    with open(csv) as f:
        header = f.readline().strip().split(",")
        rows = [dict(zip(header, map(float, l.split(",")))) for l in f if l.strip()]
    times = sorted(stresses)
    if len(times) != len(rows):
        sys.exit(f"homogeneous: ccx printed {len(times)} increments, rve run has {len(rows)}")
    scale = max(abs(r[k]) for r in rows for k in ("sig_xx", "sig_yy", "s_zz", "sig_xy"))
    worst, where = 0.0, None
    print("| increment | eps_xx | rve run sig_xx | ccx sxx | rve run s_zz | ccx szz | max diff / max stress |")
    print("|---|---|---|---|---|---|---|")
    for k, (t, r) in enumerate(zip(times, rows)):
        want = [r["sig_xx"], r["sig_yy"], r["s_zz"], r["sig_xy"]]
        diff = 0.0
        for ip in stresses[t]:
            got = ip[2:6]
            diff = max(diff, max(abs(g - w) for g, w in zip(got, want)) / scale)
        if diff > worst:
            worst, where = diff, k + 1
        if k % 5 == 4 or r["limit_points"] > 0 or k == len(rows) - 1:
            ip = stresses[t][0]
            print(f"| {k + 1} | {r['eps_xx']:.3e} | {want[0]:.6e} | {ip[2]:.6e} | "
                  f"{want[2]:.6e} | {ip[4]:.6e} | {diff:.1e} |")
    print(f"\nlargest difference: {worst:.1e} of the largest stress ({scale:.3f}), "
          f"increment {where}; tolerance {TOLERANCE:.0e}")
    if worst > TOLERANCE:
        sys.exit(1)


def curve(job):
    """[(time, U, F)]: the loaded face's displacement and total reaction per increment."""
    forces = dat_blocks(job + ".dat", "force", "TOP")
    disp = dat_blocks(job + ".dat", "displacements", "TOP")
    return [(t, disp[t][0][2] if disp.get(t) else float("nan"), forces[t][0][1])
            for t in sorted(forces)]


def specimen(runs):
    print("| run | finished | increments | attempts cut back | ccx iterations | "
          "iterations per increment (median / max) | wall time |")
    print("|---|---|---|---|---|---|---|")
    for label, job, seconds, finished in runs:
        rows = sta(job)
        conv = [r for r in rows if r[3]]
        cut = [r for r in rows if not r[3]]
        its = sorted(r[4] for r in conv)
        median = its[len(its) // 2] if its else 0
        print(f"| {label} | {finished} | {len(conv)} | {len(cut)} | "
              f"{sum(r[4] for r in rows)} | {median} / {max(its, default=0)} | {seconds} s |")
    for label, job, _, _ in runs:
        rows = sta(job)
        res = cvg(job)
        conv = [r for r in rows if r[3]]
        if not conv:
            continue
        hard = max(conv, key=lambda r: r[4])
        seq = res.get((hard[0], hard[1], hard[2]), [])
        print(f"\n{label}: the converged increment with the most iterations (step {hard[0]}, "
              f"increment {hard[1]}, attempt {hard[2]}): force residuals (%) "
              + ", ".join(f"{v:.2e}" for v in seq))
    for label, job, _, _ in runs:
        print(f"\n{label}: force-displacement (every increment)\n")
        print("| time | U (mm) | F (N) |")
        print("|---|---|---|")
        for t, u, f in curve(job):
            print(f"| {t:.4f} | {u:.5e} | {f:.4e} |")


def band_strains(job):
    """{time: (band's mean eps_yy, sound rows' mean eps_yy)} of specimen_band.inp."""
    low = dat_blocks(job + ".dat", "displacements", "BANDLOW")
    top = dat_blocks(job + ".dat", "displacements", "BANDTOP")
    out = {}
    for t, u, _ in curve(job):
        a = sum(r[2] for r in low[t]) / len(low[t])
        b = sum(r[2] for r in top[t]) / len(top[t])
        # The band (between BANDLOW and BANDTOP) is 10 mm high, the two sound rows 20 mm.
        out[t] = ((b - a) / 10.0, (a + u - b) / 20.0)
    return out


def band(job):
    c = [p for p in curve(job) if p[0] <= 2.0 + 1e-9]
    strains = band_strains(job)
    peak = max(range(len(c)), key=lambda k: c[k][2])
    if peak == len(c) - 1:
        sys.exit(f"band: the force rises to the end of the tension ({c[peak][2]:.4e} N)")
    low = min(range(peak, len(c)), key=lambda k: c[k][2])
    (tp, up, fp), (tl, ul, fl) = c[peak], c[low]
    (bp, rp), (bl, rl) = strains[tp], strains[tl]
    print(f"peak {fp:.2f} N at U = {up:.4e} mm; after it down to {fl:.2f} N "
          f"({100 * (1 - fl / fp):.1f} %) at U = {ul:.4e} mm, then {c[-1][2]:.2f} N at "
          f"U = {c[-1][1]:.4e} mm. Between the two: the band's mean strain "
          f"{bp:.4e} -> {bl:.4e}, the sound rows' {rp:.4e} -> {rl:.4e}.")
    ok = fl < (1 - DROP) * fp and ul > up and bl > bp and rl < rp
    if not ok:
        sys.exit(f"band: no localization (a force drop of at least {DROP:.0%} after the peak "
                 "with the band stretching and the sound rows unloading)")


def phases(c):
    """The tension (time <= 1), unloading (1 < time <= 2) and compression (time > 2) of a
    curve [(time, U, F)], each starting from the previous phase's last point."""
    eps = 1e-9
    tension = [p for p in c if p[0] <= 1 + eps]
    unloading = [tension[-1]] + [p for p in c if 1 + eps < p[0] <= 2 + eps]
    compression = [unloading[-1]] + [p for p in c if p[0] > 2 + eps]
    return tension, unloading, compression


def secant(points):
    """(F_last - F_first) / (U_last - U_first)."""
    (_, u0, f0), (_, u1, f1) = points[0], points[-1]
    return (f1 - f0) / (u1 - u0)


def first_peak(points):
    """The index of the first local maximum of the force (the last point if it rises to
    the end)."""
    k = 0
    while k + 1 < len(points) and points[k + 1][2] >= points[k][2]:
        k += 1
    return k


def cycle_figures(job):
    c = curve(job)
    tension, unloading, compression = phases(c)
    peak = first_peak(tension)
    low = min(tension[peak:], key=lambda p: p[2])
    return {"peak": tension[peak], "low": low,
            "zero": unloading[-1], "unload": secant(unloading),
            "compress": secant(compression)}


def cycle(job):
    end = curve(job)[-1][0]
    if abs(end - 3.0) > 1e-9:
        sys.exit(f"cycle {job}: ends at time {end:g}, not at the end of the compression (3)")
    f = cycle_figures(job)
    (_, up, fp), (_, ul, fl), (_, u0, f0) = f["peak"], f["low"], f["zero"]
    print(f"peak {fp:.2f} N at U = {up:.4e} mm, down to {fl:.2f} N "
          f"({100 * (1 - fl / fp):.1f} %) at U = {ul:.4e} mm; at U = {u0:.1e} mm after the "
          f"unloading F = {f0:.2e} N ({abs(f0) / fp:.0e} of the peak); secant slopes: "
          f"unloading {f['unload']:.4e} N/mm, compression {f['compress']:.4e} N/mm "
          f"(ratio {f['compress'] / f['unload']:.2f})")
    checks = [
        (fl < (1 - DROP) * fp, f"the force does not fall by {DROP:.0%} after its peak"),
        (abs(f0) <= ZERO_FORCE * fp, f"|F| at U = 0 exceeds {ZERO_FORCE:.0e} of the peak"),
        (f["compress"] > f["unload"], "the compression is not stiffer than the unloading"),
    ]
    failed = [why for ok, why in checks if not ok]
    if failed:
        sys.exit(f"cycle {job}: " + "; ".join(failed))


def dissipated(tension):
    """Work of the force along the tension less the energy a secant unloading to the
    origin gives back (N mm)."""
    work = sum(0.5 * (f0 + f1) * (u1 - u0)
               for (_, u0, f0), (_, u1, f1) in zip([(0, 0.0, 0.0)] + tension, tension))
    return work - 0.5 * tension[-1][1] * tension[-1][2]


def curves(runs):
    tensions = [(label, phases(curve(job))[0]) for label, job in runs]
    print("| run | increments | first peak F (N) | U at peak (mm) | lowest after it (N) | "
          "fall | dissipated (N mm) |")
    print("|---|---|---|---|---|---|---|")
    for label, t in tensions:
        peak = t[first_peak(t)]
        low = min(t[first_peak(t):], key=lambda p: p[2])
        print(f"| {label} | {len(t)} | {peak[2]:.2f} | {peak[1]:.4e} | {low[2]:.2f} | "
              f"{100 * (1 - low[2] / peak[2]):.1f} % | {dissipated(t):.4e} |")
    print("\n| U (mm) | " + " | ".join(label for label, _ in tensions) + " |")
    print("|---|" + "---|" * len(tensions))
    for _, u, _ in tensions[0][1]:
        forces = [next((f"{p[2]:.2f}" for p in t if abs(p[1] - u) < 1e-9), "") for _, t in tensions]
        print(f"| {u:.4e} | " + " | ".join(forces) + " |")


def middle(rows):
    """The mean uy (column 2) of the middle half of a node set's rows (x order)."""
    n = len(rows)
    part = rows[n // 4:n - n // 4]
    return sum(r[2] for r in part) / len(part)


def ligament(runs):
    print("| run | point | U (mm) | F (N) | ligament | below | above |")
    print("|---|---|---|---|---|---|---|")
    for label, job in runs:
        low = dat_blocks(job + ".dat", "displacements", "LIGLOW")
        top = dat_blocks(job + ".dat", "displacements", "LIGTOP")
        tension = phases(curve(job))[0]
        k = first_peak(tension)
        points = [("peak", tension[k]), ("lowest after", min(tension[k:], key=lambda p: p[2]))]
        for name, (t, u, f) in points:
            a, b = middle(low[t]), middle(top[t])
            print(f"| {label} | {name} | {u:.4e} | {f:.2f} | {(b - a) / 10:.3e} | "
                  f"{a / 20:.3e} | {(u - b) / 20:.3e} |")

def umat_times(job):
    """{(kstep, kinc, start time): [calls, seconds]} of the timing UMAT's JOB.times.csv
    (every attempt of an increment under its key)."""
    out = {}
    with open(job + ".times.csv") as f:
        for line in f:
            v = line.split(",")
            key = (int(v[0]), int(v[1]), round(float(v[2]), 9))
            entry = out.setdefault(key, [0, 0.0])
            entry[0] += 1
            entry[1] += float(v[6])
    return out


def rvetime_row(label, job, until=None):
    """Prints the RVE time of the converged increments up to time `until` (default: all
    of them, with every call of the run); returns the time of the last converged one."""
    times = umat_times(job)
    c = [p for p in curve(job) if until is None or p[0] <= until + 1e-9]
    keys = [k for k in times if until is None or k[2] < until - 1e-9]
    calls = sum(times[k][0] for k in keys)
    seconds = sum(times[k][1] for k in keys)
    print(f"| {label} | {len(c)} (to U = {c[-1][1]:.4e} mm) | {calls} | {seconds:.2f} | "
          f"{1e3 * seconds / len(c):.1f} | {1e6 * seconds / calls:.0f} |")
    return c[-1][0]


def rvetime(runs):
    head = ("| run | converged increments | UMAT calls | RVE time (s) | RVE time per "
            "converged increment (ms) | per call (µs) |\n|---|---|---|---|---|---|")
    print(head)
    until = min(rvetime_row(label, job) for label, job in runs)
    print(f"\nUp to time {until:g} (the shortest run's last converged increment):\n")
    print(head)
    for label, job in runs:
        rvetime_row(label, job, until)

def hostits(runs):
    print("| run | converged increments | attempts cut back | ccx iterations per increment "
          "(median / max) | finished |")
    print("|---|---|---|---|---|")
    for label, job in runs:
        rows = sta(job)
        its = sorted(r[4] for r in rows if r[3])
        with open(job + ".log") as f:
            finished = "yes" if "Job finished" in f.read() else "no"
        print(f"| {label} | {len(its)} | {sum(not r[3] for r in rows)} | "
              f"{its[len(its) // 2]} / {its[-1]} | {finished} |")


def factorizations(runs):
    print("| run | RVEs | converged increments | attempts cut back | factorizations | "
          "per RVE per converged increment |")
    print("|---|---|---|---|---|---|")
    for label, arg in runs:
        job, count = arg.rsplit(":", 1)
        with open(job + ".times.csv") as f:
            points = len({tuple(line.split(",")[4:6]) for line in f})
        rows = sta(job)
        n = sum(r[3] for r in rows)
        print(f"| {label} | {points} | {n} | {sum(not r[3] for r in rows)} | {count} | "
              f"{int(count) / (points * n):.4f} |")

def converged(job, step):
    """The `sta` rows of the converged increments of step `step`."""
    return [r for r in sta(job) if r[0] == step and r[3]]


def iterations(step, runs):
    rows_of = [converged(job, step) for _, job in runs]
    cols = [[r[4] for r in rows] for rows in rows_of]
    print("| increment | " + " | ".join(label for label, _ in runs) + " |")
    print("|---|" + "---|" * len(runs))
    for k in range(max(len(c) for c in cols)):
        print(f"| {k + 1} | " + " | ".join(str(c[k]) if k < len(c) else "" for c in cols) + " |")
    print("| total | " + " | ".join(str(sum(c)) for c in cols) + " |")
    for (label, job), rows in zip(runs, rows_of):
        hard = max(rows, key=lambda r: r[4])
        seq = cvg(job).get((hard[0], hard[1], hard[2]), [])
        print(f"\n{label}, step {step}, increment {hard[1]} (the most iterations): force "
              "residuals (%) " + ", ".join(f"{v:.1e}" for v in seq))


def pnewdt_cuts(job):
    """The ratios (reattempted size / cut size) of the cut-backs in JOB.sta."""
    rows = sta(job)
    return [b[5] / a[5] for a, b in zip(rows, rows[1:]) if not a[3]]


def snap_run(job):
    """The figures of one specimen_snap.inp run (see `snap`)."""
    with open(job + ".log") as f:
        log = f.read()
    forces = dat_blocks(job + ".dat", "force", "RIGHT")
    rows = sta(job)
    end = max(forces) if forces else 0.0
    return {"finished": "Job finished" in log,
            "stopped": "solution seems to diverge" in log,
            "flagged": "depends on the size of this increment" in log,
            "pnewdt": log.count(PNEWDT_CUT), "ratios": pnewdt_cuts(job),
            "increments": sum(r[3] for r in rows), "cut": sum(not r[3] for r in rows),
            "time": end, "force": forces[end][0][0] if forces else float("nan")}


def snap_failures(label, r, gap):
    """The failed checks of a run (`snap`); gap: its end force against the reference's."""
    ratios = ", ".join(f"{q:.4g}" for q in r["ratios"]) or "none"
    checks = {"flagged": (r["flagged"], "the UMAT printed no step-check line"),
              "stopped": (r["stopped"], "ccx did not stop the DIRECT step"),
              "cut": (r["pnewdt"] > 0 and r["ratios"] and
                      all(abs(q - SNAP_RATIO) < 1e-9 for q in r["ratios"]),
                      f"ccx cut {r['pnewdt']} attempts through PNEWDT, by {ratios} "
                      f"(expected {SNAP_RATIO})"),
              "close": (r["finished"] and abs(gap) <= SNAP_TOLERANCE,
                        f"finished {r['finished']}, force {gap:+.2%} of the reference "
                        f"(tolerance {SNAP_TOLERANCE:.0%})")}
    return [f"{label}: {checks[e][1]}" for e in r["expect"] if not checks[e][0]]


def snap_reference(path):
    """{time: force} of `rve run` in 100 increments (its step k at time k / 100)."""
    with open(path) as f:
        header = f.readline().strip().split(",")
        rows = [l.split(",") for l in f if l.strip()]
    k, sxx = header.index("step"), header.index("sig_xx")
    return {round(int(r[k]) / len(rows), 9): 10 * float(r[sxx]) for r in rows}


def snap_reaction(r):
    """What ccx did with the UMAT's PNEWDT in run r, for the table."""
    if r["stopped"]:
        return "stopped the step"
    if r["pnewdt"]:
        return "cut " + ", ".join(f"by {q:g}" for q in r["ratios"])
    return "nothing"


def snap(reference_csv, runs):
    reference = snap_reference(reference_csv)
    final = reference[1.0]
    print(f"Reference: `rve run`, 100 increments: {final:.4f} N at the end.\n")
    print("| run | finished | increments | failed attempts | end time | force (N) | "
          "against `rve run` at that time | step-check line | ccx on PNEWDT |")
    print("|---|---|---|---|---|---|---|---|---|")
    failures = []
    for arg in runs:
        label, rest = arg.split("=", 1)
        job, expect = rest.rsplit(":", 1)
        r = snap_run(job)
        r["expect"] = [] if expect == "-" else expect.split("+")
        status = "yes" if r["finished"] else ("stopped" if r["stopped"] else "no")
        at = reference.get(round(r["time"], 9))
        gap = f"{r['force'] / at - 1:+.2%}" if at else "-"
        print(f"| {label} | {status} | {r['increments']} | {r['cut']} | {r['time']:.4f} | "
              f"{r['force']:.4f} | {gap} | {'yes' if r['flagged'] else 'no'} | "
              f"{snap_reaction(r)} |")
        failures += snap_failures(label, r, r["force"] / final - 1)
    if failures:
        sys.exit("\n".join(f"calculix_report.py snap: {m}" for m in failures))



def control_failures(attempts, smallest):
    """What the step-1 attempts [(inc, converged, size)] of a controlled run break."""
    failures, grew, cut_seen = [], False, False
    for (inc, ok, size), (_, _, after) in zip(attempts, attempts[1:]):
        if not ok and after >= size:
            failures.append(f"increment {inc} was cut but redone at {after:g} >= {size:g}")
        grew = grew or (cut_seen and ok and after > size * (1 + 1e-9))
        cut_seen = cut_seen or not ok
    if not grew:
        failures.append("ccx never grew the increment after a cut")
    below = [s for _, ok, s in attempts[:-1] if s < smallest * (1 - 1e-6)]
    if below:
        failures.append(f"{len(below)} increments below smallest_step {smallest:g}: {below[:3]}")
    return failures


def control(job, plain, smallest):
    attempts = [(inc, ok, size) for step, inc, _, ok, _, size in sta(job) if step == 1]
    tension, plain_tension = phases(curve(job))[0], phases(curve(plain))[0]
    with open(job + ".log") as f:
        cuts = f.read().count(PNEWDT_CUT)
    peak, plain_peak = max(p[2] for p in tension), max(p[2] for p in plain_tension)
    failures = control_failures(attempts, smallest)
    if tension[-1][0] < 1 - 1e-9:
        failures.append(f"the tension stopped at time {tension[-1][0]:g}")
    if cuts < 1:
        failures.append("no PNEWDT cut")
    if peak > 0.95 * plain_peak:
        failures.append(f"peak {peak:.2f} N is not 5 % below the plain run's {plain_peak:.2f} N")
    print(f"{len(tension)} increments ({cuts} attempts cut on PNEWDT), smallest "
          f"{min(s for _, ok, s in attempts if ok):g} (floor {smallest:g}); peak {peak:.2f} N "
          f"against the plain run's {plain_peak:.2f} N ({100 * (peak / plain_peak - 1):+.1f} %)")
    if failures:
        sys.exit("calculix_report.py control: " + "; ".join(failures))

FRICTION_TOLERANCE = 2e-6


def friction(job, mu):
    points = dat_points(job + ".dat", "stresses")
    times = sorted(t for t in points if t > 2.0)
    first = points[times[0]][(1, 1)][0]
    failures = []
    for t in times:
        for (element, point), s in points[t].items():
            sxx, sxy = s[0], s[3]
            if element != 1:
                continue
            if abs(sxx - first) > FRICTION_TOLERANCE * abs(first):
                failures.append(f"t {t}: sigma_xx {sxx} moved from {first}")
            if abs(sxy) > mu * abs(sxx) * (1 + FRICTION_TOLERANCE):
                failures.append(f"t {t}: |sigma_xy| {sxy} above mu |sigma_xx|")
            if t in (3.0, 4.0) and abs(abs(sxy) - mu * abs(sxx)) > FRICTION_TOLERANCE * abs(sxx):
                failures.append(f"t {t}: not sliding, sigma_xy {sxy}, sigma_xx {sxx}")
    rows = [r for r in sta(job) if r[0] in (3, 4) and r[3]]
    if len({r[0] for r in rows}) != 2 or not times or max(times) < 4.0 - 1e-9:
        failures.append("steps 3 and 4 did not finish")
    if failures:
        sys.exit("calculix_report.py friction: " + "; ".join(failures[:5]))
    per_step = {k: sum(r[4] for r in rows if r[0] == k) for k in (3, 4)}
    counts = {k: sum(1 for r in rows if r[0] == k) for k in (3, 4)}
    above = [f"{r[0]}.{r[1]}: {r[4]}" for r in rows if r[4] > 2]
    print(f"sliding at mu |sigma_xx| = {mu * abs(first):.6g} MPa; ccx iterations: step 3 "
          f"{per_step[3]} in {counts[3]} increments, step 4 {per_step[4]} in {counts[4]}, "
          f"at most {max(r[4] for r in rows)}; above 2: {', '.join(above) or 'none'}")


def crackband(runs):
    rows, failed = [], []
    for arg in runs:
        label, spec = arg.split("=", 1)
        job, h = spec.rsplit(":", 1)
        run = curve(job)
        points = [(u, f) for _, u, f in run]
        finished = abs(run[-1][0] - 1.0) < 1e-9
        peak = max(f for _, f in points)
        top = [f for _, f in points].index(peak)
        below = next((u for u, f in points[top:] if f < 0.1 * peak), None)
        energy = 1e3 * dissipated([(0, u, f) for u, f in points]) / WIDTH
        rows.append((label, float(h), peak, below, points[-1], energy, finished))
    coarse = rows[0]
    print("| run | h (mm) | peak F (N) | F < 10 % of it at U (mm) | F at U = "
          f"{coarse[4][0]:g} mm | dissipated (N/m) | over the coarse run's |")
    print("|---|---|---|---|---|---|---|")
    for label, h, peak, below, (u, f), energy, finished in rows:
        print(f"| {label} | {h:g} | {peak:.2f} | {below if below is None else f'{below:.4f}'} | "
              f"{f:.3f} ({100 * f / peak:.1f} %) | {energy:.1f} | {energy / coarse[5]:.3f} |")
        if not finished:
            failed.append(f"{label} did not finish its step")
        if below is None:
            failed.append(f"{label} never fell below 10 % of its peak")
    fine, unregularized = rows[1], rows[2]
    if abs(fine[5] / coarse[5] - 1) > OBJECTIVITY_ENERGY:
        failed.append(f"regularized energies {coarse[5]:.1f} and {fine[5]:.1f} N/m")
    if abs(fine[2] / coarse[2] - 1) > OBJECTIVITY_PEAK:
        failed.append(f"regularized peaks {coarse[2]:.2f} and {fine[2]:.2f} N")
    if unregularized[5] > UNREGULARIZED_AT_MOST * coarse[5]:
        failed.append(f"unregularized {unregularized[5]:.1f} N/m against {coarse[5]:.1f}")
    if failed:
        sys.exit("crackband: " + "; ".join(failed))


if __name__ == "__main__":
    if sys.argv[1] == "homogeneous":
        homogeneous(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "specimen":
        runs = []
        for arg in sys.argv[2:]:
            label, job, seconds, finished = arg.split("=", 1)[1:] and (
                arg.split("=")[0], *arg.split("=", 1)[1].split(","))
            runs.append((label, job, seconds, finished))
        specimen(runs)
    elif sys.argv[1] == "iterations":
        iterations(int(sys.argv[2]), [tuple(a.split("=", 1)) for a in sys.argv[3:]])
    elif sys.argv[1] == "cycle":
        cycle(sys.argv[2])
    elif sys.argv[1] in ("curves", "ligament", "rvetime", "hostits", "factorizations"):
        runs = [tuple(a.split("=", 1)) for a in sys.argv[2:]]
        {"curves": curves, "ligament": ligament, "rvetime": rvetime, "hostits": hostits,
         "factorizations": factorizations}[sys.argv[1]](runs)
    elif sys.argv[1] == "control":
        control(sys.argv[2], sys.argv[3], float(sys.argv[4]))
    elif sys.argv[1] == "band":
        band(sys.argv[2])
    elif sys.argv[1] == "snap":
        snap(sys.argv[2], sys.argv[3:])
    elif sys.argv[1] == "friction":
        friction(sys.argv[2], float(sys.argv[3]))
    elif sys.argv[1] == "crackband":
        crackband(sys.argv[2:])
    else:
        sys.exit(__doc__)
