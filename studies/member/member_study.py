#!/usr/bin/env python3
"""The member study's tables (studies/member/run), from its timed ccx runs of
calculix_examples/member_beam_h*.inp. Standard library only.

  member_study.py table LABEL=JOB:THREADS ...
      The Markdown table of wall time, peak memory, the RVE's share of the CPU time,
      increments and ccx iterations of timed runs: JOB.time is the kit's timing of the run
      (scripts/kit/ccx.py), JOB.times.csv calculix_examples/umat_timing.c's (the calling
      thread's CPU time of every UMAT call); the RVE share is their sum over ccx's CPU
      time (user + system, all threads).

  member_study.py compare JOB JOB
      The largest difference between two runs' forces, over the largest force (the same
      deck on 1 and 2 threads).

  member_study.py provenance START.json RUNS
      The provenance sentence (scripts/kit/provenance.py) of a study started with
      `provenance.py START.json`: commit, machine, load at the start and now.
"""
import csv
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
from kit import provenance  # noqa: E402
from kit.ccx import read_time, sta  # noqa: E402
from member_figures import fail, read_dat  # noqa: E402


def table(specs):
    print("| run | threads | RVE points | increments (cut back) | ccx iterations | wall time | "
          "CPU the run got | peak memory | CPU time | RVE CPU time | RVE share | RVE per point and increment |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for spec in specs:
        label, rest = spec.split("=", 1)
        job, threads = rest.rsplit(":", 1)
        tv = read_time(job)
        cpu = tv["user"] + tv["sys"]
        wall = tv["wall"]
        rve, points = 0.0, set()
        with open(job + ".times.csv") as f:
            for row in csv.reader(f):
                rve += float(row[6])
                points.add((row[4], row[5]))
        rows = sta(job)
        done = sum(1 for r in rows if r[3])
        print(f"| {label} | {threads} | {len(points)} | {done} ({len(rows) - done}) | "
              f"{sum(r[4] for r in rows)} | {wall:.1f} s | {tv['cpu_percent']}% | "
              f"{tv['max_rss_kb'] / 1024:.0f} MiB | "
              f"{cpu:.1f} s | {rve:.1f} s | {100 * rve / cpu:.0f} % | "
              f"{1e3 * rve / (len(points) * done):.2f} ms |")


def compare(a, b):
    ca, cb = read_dat(a + ".dat")[0], read_dat(b + ".dat")[0]
    if [p[0] for p in ca] != [p[0] for p in cb]:
        fail(f"{a} and {b} have different increments")
    fmax = max(abs(p[2]) for p in ca)
    worst = max(abs(p[2] - q[2]) for p, q in zip(ca, cb))
    print(f"largest force difference {worst:.2e} N, {worst / fmax:.1e} of the largest force "
          f"({fmax:.2f} N), over {len(ca)} increments")


def main():
    if len(sys.argv) >= 3 and sys.argv[1] == "table":
        table(sys.argv[2:])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 4 and sys.argv[1] == "provenance":
        print(provenance.sentence(provenance.load(sys.argv[2]), int(sys.argv[3]), "ccx runs"))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
