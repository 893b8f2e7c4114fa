#!/usr/bin/env python3
"""Reads the runs of the STATEV checks (scripts/test-calculix; decks from statev_decks.py,
UMAT calls logged by umat_log.c) and prints one line of figures per check; exits non-zero
when a check fails.

  statev_check.py restart LABEL FULL PART2 same|differ
      Step 2 of the uninterrupted run FULL against the continuation PART2 (JOB.dat, and
      JOB.calls, umat_log.c's log of the UMAT calls): the total reaction force of the
      loaded face at every increment of step 2 as ccx prints it (e13.6, 7 digits), and
      the UMAT calls of step 2 bit for bit (strain, stress, STATEV hash). `same`: the
      forces must agree to 1e-12 of the largest and the calls be identical; `differ`: the
      forces must differ by more than 1e-3 of the largest (the check has teeth).
  statev_check.py lost PART2
      A continuation without the contact pair (ccx 2.20 keeps no state variables in its
      restart file then): fails unless every UMAT call of PART2's first increment had
      STATEV all zero, ccx stopped (no "Job finished" in PART2.log) and the UMAT's refusal
      (a lost state, naming the contact pair) is in PART2.log: loud, never answered.
  statev_check.py modelchange KEEP_STATEV KEEP_TABLE RESET_STATEV RESET_TABLE
      The *MODEL CHANGE deck in STATEV mode and table mode, as ccx runs it (KEEP_*) and with
      umat_log.c's MESORVE_UMAT_RESET zeroing the re-added column's STATEV in step 3's
      first increment (RESET_*; RESET_STATEV under a scene with [statev] zero_at_strain =
      "virgin"). Fails unless: ccx handed each re-added point in STATEV mode the STATEV it
      had after its last call before the removal (not zeros; ccx passes that state's own
      strain as STRAN, a step later in TIME); the STATEV run stopped with the UMAT's
      refusal, the state of another increment (KEEP_STATEV.log), and the table run
      finished; with the reset, every re-added point
      in STATEV mode answers bit for bit as a fresh point at the same strain (umat_log.c's
      twin) and in table mode none does (the table ignores STATEV).
  statev_check.py strain-match JOB...
      Over every UMAT call of the jobs with a non-zero STATEV handed over, except the calls
      of the re-added column in step 3 (*MODEL CHANGE), the largest |STRAN - the strain the
      STATEV was committed at| (umat_log.c's MATCH): fails above STRAN_AGREEMENT, a
      thousandth of the UMAT's tolerance at these strains (1e-9 of 1e-4).
  statev_check.py depvar RVE DECK...
      Fails unless every *DEPVAR of the decks' mesorve materials (`@ABAQUS_RVE_UMAT@SCENE`,
      SCENE.toml beside the deck) is at least the scene's umat_nstatv (`RVE info SCENE
      --json`) + 5: STATEV mode with the inspection mirrors.
  statev_check.py homogeneous DAT CSV
      The homogeneous specimen run in STATEV mode against `rve run` (as calculix_report.py
      homogeneous, which holds table mode to 1e-6): prints the largest difference, fails
      above 1e-4 of the largest stress.
"""
import csv
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
from kit.ccx import dat_blocks  # noqa: E402

COLUMN = (6, 18, 30)  # statev_decks.py's COLUMN
SAME = 1e-12
DIFFER = 1e-3
# |STRAN - committed strain| a CalculiX analysis must stay below: the UMAT refuses above
# 1e-9 of the strain (plus 1e-12), here ~1e-13; this is a thousandth of that.
STRAN_AGREEMENT = 1e-16
MIRRORS = 5
# The homogeneous specimen in STATEV mode differs from `rve run` by 2.1e-5 of the largest
# stress at the RVE's snap (increment 21; docs/calculix.md); table mode is held to 1e-6.
HOMOGENEOUS_STATEV = 1e-4


def calls(job):
    """[(kstep, kinc, time, noel, npt, entry, strain, stress, hash, twin, line, match)] in
    file order; `line` without the MATCH column (a property of the handed STATEV, compared
    apart), `match` its value or None."""
    out = []
    with open(job + ".calls") as f:
        for line in f:
            p = line.split()
            if len(p) < 10 or not p[0].isdigit():
                continue
            n = (len(p) - 10) // 2
            out.append((int(p[0]), int(p[1]), float(p[2]), int(p[4]), int(p[5]), p[6],
                        [float.fromhex(v) for v in p[7:7 + n]],
                        [float.fromhex(v) for v in p[7 + n:7 + 2 * n]], p[-3], p[-2],
                        " ".join(p[:-1]), None if p[-1] == "-" else float(p[-1])))
    return out


def forces(job):
    """{time: total y reaction of TOP}."""
    return {t: v[0][1] for t, v in dat_blocks(job + ".dat", "force", "TOP").items()}


def restart(label, full, part2, expect):
    f_full, f_part = forces(full), forces(part2)
    times = sorted(f_part)
    if not times or any(t not in f_full for t in times):
        sys.exit(f"restart {label}: {part2}.dat's times {times} are not all in {full}.dat")
    scale = max(abs(f_full[t]) for t in times)
    worst = max(abs(f_full[t] - f_part[t]) for t in times) / scale
    printed = sum(f_full[t] == f_part[t] for t in times)
    step2 = sorted(c[10] for c in calls(full) if c[0] == 2)
    split = sorted(c[10] for c in calls(part2))
    differ = sum(a != b for a, b in zip(step2, split)) + abs(len(step2) - len(split))
    first = [c for c in calls(part2) if c[1] == 1]
    zero = sum(c[5] == "zero" for c in first)
    print(f"restart, {label}: step 2's {len(times)} forces: max |dF| = {worst:.2e} of the "
          f"largest ({scale:.4g} N), {printed} of {len(times)} printed alike; UMAT calls "
          f"of step 2: {len(split)}, {differ} not bit-identical to the uninterrupted run's; "
          f"STATEV zero at {zero} of the {len(first)} calls of its first increment")
    if expect == "same" and (worst > SAME or differ):
        sys.exit(f"restart {label}: the continuation differs from the uninterrupted run")
    if expect == "differ" and worst <= DIFFER:
        sys.exit(f"restart {label}: the continuation agrees with the uninterrupted run to "
                 f"{worst:.1e}: the check has no teeth")


def stopped_with(job, needle):
    """Whether ccx did not finish JOB and its log holds the UMAT's message with `needle`."""
    with open(job + ".log", errors="replace") as f:
        log = f.read()
    return "Job finished" not in log and any(
        l.startswith("mesorve UMAT: ") and needle in l for l in log.splitlines())


def lost(part2):
    first = [c for c in calls(part2) if c[1] == 1]
    zero = sum(c[5] == "zero" for c in first)
    loud = stopped_with(part2, "did not carry this point's state")
    print(f"restart, STATEV mode without the contact pair: ccx 2.20 kept no state variables "
          f"in its restart file (zeros at {zero} of the {len(first)} calls of the "
          f"continuation's first increment); the UMAT refused them (a lost state, the "
          f"message names the contact pair) and ccx stopped: {'yes' if loud else 'NO'}")
    if not first or zero != len(first):
        sys.exit("statev_check: ccx carried STATEV through a restart without a contact pair: "
                 "update docs/calculix.md and statev_decks.py (--pair may be unneeded)")
    if not loud:
        sys.exit("statev_check: the continuation from lost states was not refused loudly")


def force_at_end(job):
    f = forces(job)
    return f[max(f)]


def first_after_readding(cs):
    """({point: its last call before the removal}, {point: its first call after re-adding})
    of the column's points."""
    last_before, first_after = {}, {}
    for c in cs:
        key = (c[3], c[4])
        if c[3] not in COLUMN:
            continue
        if c[0] < 3:
            last_before[key] = c
        elif key not in first_after:
            first_after[key] = c
    return last_before, first_after


def modelchange(keep_statev, keep_table, reset_statev, reset_table):
    cs = calls(keep_statev)
    last_before, first_after = first_after_readding(cs)
    handed = sum(first_after[k][5] == last_before[k][8] and first_after[k][5] != "zero"
                 for k in first_after)
    zero = sum(c[5] == "zero" for c in first_after.values())
    jumps = [c[11] for c in first_after.values() if c[11] is not None]
    removed = sum(c[0] == 2 and c[3] in COLUMN for c in cs)
    loud = stopped_with(keep_statev, "the state of another increment")
    twins = {}
    for label, job in (("statev", reset_statev), ("table", reset_table)):
        reset = [c for c in calls(job) if c[5] == "reset"]
        twins[label] = (sum(c[9] == "same" for c in reset), len(reset))
    f = {job: force_at_end(job) for job in (keep_table, reset_statev, reset_table)}
    f1 = forces(keep_statev)
    at = min(f1, key=lambda t: abs(t - 0.5))  # step 1 at U = 4e-3 mm: the virgin strip
    print(f"model change: the column's {len(first_after)} points got no call while removed "
          f"({removed} calls in step 2); at their first call after re-adding ccx handed "
          f"{handed} of them the STATEV of their last call before the removal, {zero} zeros, "
          f"with STRAN at most {max(jumps, default=0):.1e} from the strain that STATEV was "
          f"committed at (the jump is all in DSTRAN) but a step later in TIME; STATEV mode "
          f"refused them as the state of another increment and ccx stopped: "
          f"{'yes' if loud else 'NO'} (table mode answers from its table, as before). "
          f"With STATEV zeroed at the re-adding (MESORVE_UMAT_RESET, a scene with "
          f"zero_at_strain = \"virgin\"): {twins['statev'][0]} of {twins['statev'][1]} calls "
          f"in STATEV mode answer bit for bit as a fresh point, {twins['table'][0]} of "
          f"{twins['table'][1]} in table mode. F at U = 4e-3 mm: step 1 (virgin strip) "
          f"{f1[at]:.2f} N; step 3 in table mode {f[keep_table]:.2f} N, column reset "
          f"{f[reset_statev]:.2f} N (table mode {f[reset_table]:.2f})")
    ok = (first_after and handed == len(first_after) and removed == 0 and loud
          and len(jumps) == len(first_after)
          and twins["statev"][1] > 0 and twins["statev"][0] == twins["statev"][1]
          and twins["table"][1] > 0 and twins["table"][0] == 0)
    if not ok:
        sys.exit("model change: a check failed (see the line above)")


def strain_match(jobs):
    worst, where, counted = 0.0, None, 0
    for job in jobs:
        for c in calls(job):
            readded = c[0] == 3 and c[3] in COLUMN and "mc_" in os.path.basename(job)
            if c[11] is None or readded:
                continue
            counted += 1
            if c[11] > worst:
                worst, where = c[11], (os.path.basename(job), c[0], c[1], c[3], c[4])
    print(f"STRAN against the strain the handed STATEV was committed at, over {counted} UMAT "
          f"calls of {len(jobs)} analyses (restart parts, cut-backs after refusals, the "
          f"re-added column's calls left out): largest difference {worst:.1e} "
          f"(at {where}); the UMAT's tolerance is 1e-9 of the strain plus 1e-12")
    if counted == 0 or worst > STRAN_AGREEMENT:
        sys.exit(f"strain-match: STRAN differs from the committed strain by {worst:.1e}")


def depvar(rve, decks):
    needed, bad = {}, []
    for deck in decks:
        with open(deck) as f:
            lines = [l.strip() for l in f]
        material = None
        for k, line in enumerate(lines):
            m = re.match(r"\*MATERIAL,\s*NAME=@ABAQUS_RVE_UMAT@([^@\s]+)", line, re.I)
            if m:
                material = m.group(1).lower()
            elif line.upper().startswith("*MATERIAL"):
                material = None
            elif line.upper().startswith("*DEPVAR") and material:
                scene = os.path.join(os.path.dirname(deck), material + ".toml")
                if scene not in needed:
                    info = subprocess.run([rve, "info", scene, "--json"], check=True,
                                          capture_output=True, text=True).stdout
                    needed[scene] = json.loads(info)["umat_nstatv"] + MIRRORS
                n = int(lines[k + 1].split(",")[0])
                if n < needed[scene]:
                    bad.append(f"{deck}: *DEPVAR {n} < {needed[scene]} ({material})")
    print("*DEPVAR of the shipped decks: " + ", ".join(
        f"{os.path.basename(s)} needs {n}" for s, n in sorted(needed.items())))
    if bad:
        sys.exit("statev_check: decks in table mode: " + "; ".join(bad))


def homogeneous(dat, csv_path):
    stresses = dat_blocks(dat, "stresses")
    with open(csv_path) as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    times = sorted(stresses)
    if len(times) != len(rows):
        sys.exit(f"homogeneous: ccx printed {len(times)} increments, rve run has {len(rows)}")
    keys = ("sig_xx", "sig_yy", "s_zz", "sig_xy")
    scale = max(abs(r[k]) for r in rows for k in keys)
    worst, where = 0.0, None
    for k, (t, r) in enumerate(zip(times, rows)):
        for ip in stresses[t]:
            d = max(abs(g - r[c]) for g, c in zip(ip[2:6], keys)) / scale
            if d > worst:
                worst, where = d, k + 1
    print(f"STATEV mode: largest difference {worst:.1e} of the largest stress, increment "
          f"{where}; tolerance {HOMOGENEOUS_STATEV:.0e}")
    if worst > HOMOGENEOUS_STATEV:
        sys.exit(1)


if __name__ == "__main__":
    args = sys.argv[1:]
    if args[:1] == ["restart"] and len(args) == 5 and args[4] in ("same", "differ"):
        restart(*args[1:])
    elif args[:1] == ["lost"] and len(args) == 2:
        lost(args[1])
    elif args[:1] == ["strain-match"] and len(args) >= 2:
        strain_match(args[1:])
    elif args[:1] == ["modelchange"] and len(args) == 5:
        modelchange(*args[1:])
    elif args[:1] == ["depvar"] and len(args) >= 3:
        depvar(args[1], args[2:])
    elif args[:1] == ["homogeneous"] and len(args) == 3:
        homogeneous(*args[1:])
    else:
        sys.exit(__doc__)
