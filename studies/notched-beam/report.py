#!/usr/bin/env python3
"""The notched beam's runs (calculix_examples/notched_beam.py) as a Markdown table and one
load-deflection figure.

  report.py OUT LABEL=JOB ...     (JOB: OUT/JOB.dat; the first run is the reference)

Per run: the peak load of the downward step, the deflection where the load falls below
10 % of it, the load at the step's end, the energy dissipated to there (the work of the
load less a secant unloading's) per unit ligament area, the load back at zero deflection,
and the largest upward load after the reversal. Writes OUT/notched_beam.svg.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "scripts"))
from kit.ccx import dat_blocks  # noqa: E402
from kit.plot import COLOURS, svg_plot  # noqa: E402

LIGAMENT = 30.0  # mm: the beam's 40 mm depth less the 10 mm notch
DOWN, BACK = 200, 100  # the steps' increments (time = increment number)


def curve(job):
    forces = dat_blocks(job + ".dat", "force", "LOAD")
    disp = dat_blocks(job + ".dat", "displacements", "LOAD")
    return [(t, -disp[t][0][2], -forces[t][0][1]) for t in sorted(forces)]


def figures(run):
    down = [p for p in run if p[0] <= DOWN + 1e-9]
    peak = max(p[2] for p in down)
    top = [p[2] for p in down].index(peak)
    below = next((p[1] for p in down[top:] if p[2] < 0.1 * peak), None)
    work, prev = 0.0, (0.0, 0.0)
    for _, u, f in down:
        work += 0.5 * (f + prev[1]) * (u - prev[0])
        prev = (u, f)
    work -= 0.5 * down[-1][1] * down[-1][2]
    back = [p for p in run if DOWN < p[0] <= DOWN + BACK + 1e-9]
    up = [p for p in run if p[0] > DOWN + BACK + 1e-9]
    return {"peak": peak, "below": below, "end": down[-1][2], "energy": 1e3 * work / LIGAMENT,
            "zero": back[-1][2] if back else None, "up": -min(p[2] for p in up) if up else None,
            "increments": len(run)}


def main(out, runs):
    rows = [(label, job, figures(curve(os.path.join(out, job)))) for label, job in runs]
    ref = rows[0][2]
    print("| run | increments | peak load (N) | load < 10 % of it at deflection (mm) | load at "
          "0.2 mm | dissipated (N/m) | over the first run's | load back at 0 (N) | largest "
          "upward load (N) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, _, f in rows:
        below = "never" if f["below"] is None else f"{f['below']:.3f}"
        print(f"| {label} | {f['increments']} | {f['peak']:.2f} | {below} | {f['end']:.2f} | "
              f"{f['energy']:.1f} | {f['energy'] / ref['energy']:.3f} | {f['zero']:.1e} | "
              f"{f['up']:.2f} |")
    series = [(label, COLOURS[k], [(u, f, "") for _, u, f in curve(os.path.join(out, job))],
               True, 0) for k, (label, job, _) in enumerate(rows)]
    svg_plot(os.path.join(out, "notched_beam.svg"),
             "Notched beam, failing cell: down, back, up (CalculiX)",
             "deflection at mid-span, down (mm)", "load, down (N)", series)


if __name__ == "__main__":
    main(sys.argv[1], [tuple(a.split("=", 1)) for a in sys.argv[2:]])
