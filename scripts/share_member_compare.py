"""Compares two ccx runs of the member (scripts/share-member): exact and with answer
sharing. Prints the wall times, the load-deflection L1 difference (the mean over the
increments of |F_shared - F_exact|, over the largest |F_exact|) and the largest, the
largest per-point stress difference at the printed stages over the largest stress, and
per stage the in-plane points damaged (mirror 4 above 0.01) in one run and not the
other, with the largest damage difference. Usage: share_member_compare.py EXACT SHARED
(the job paths without .dat)."""
import re
import sys
from pathlib import Path

import member_study

STRESS = re.compile(r"\s*stresses \(.*\) for set EALL and time\s+(\S+)")


def stresses(path):
    out, t = {}, None
    for line in open(path):
        m = STRESS.match(line)
        if m:
            t = float(m.group(1))
            out[t] = {}
            continue
        if member_study.HEADER.match(line):
            t = None
            continue
        tok = line.split()
        if t is not None and len(tok) == 8:
            out[t][(int(tok[0]), int(tok[1]))] = [float(v) for v in tok[2:]]
    return out


def wall(job):
    text = (Path(job).parent / "time.txt").read_text()
    clock = re.search(r"Elapsed \(wall clock\) time.*: (\S+)", text).group(1)
    return member_study.seconds(clock)


def shared_counts(job):
    log = (Path(job).parent / "time.txt").read_text()
    pairs = [(int(a), int(b)) for a, b in re.findall(r"(\d+) calls solved, (\d+) shared", log)]
    return sum(a for a, _ in pairs), sum(b for _, b in pairs), len(pairs)


def main(exact, shared):
    ce, se = member_study.read_dat(exact + ".dat")
    cs, ss = member_study.read_dat(shared + ".dat")
    if [p[0] for p in ce] != [p[0] for p in cs]:
        sys.exit("the runs have different increments")
    fmax = max(abs(p[2]) for p in ce)
    diffs = [abs(p[2] - q[2]) for p, q in zip(ce, cs)]
    print(f"increments {len(ce)}; wall time exact {wall(exact):.1f} s, shared {wall(shared):.1f} s "
          f"({wall(shared) / wall(exact):.3f})")
    solved, nshared, incs = shared_counts(shared)
    print(f"UMAT calls (increments logged: {incs}): solved {solved}, shared {nshared}")
    print(f"load-deflection L1 {sum(diffs) / len(diffs) / fmax:.2e}, largest {max(diffs) / fmax:.2e} "
          f"of the largest force {fmax:.3f} N")
    sa, sb = stresses(exact + ".dat"), stresses(shared + ".dat")
    smax = max(abs(v) for t in sa for p in sa[t].values() for v in p)
    sdiff = max(abs(a - b) for t in sa for k in sa[t] for a, b in zip(sa[t][k], sb[t][k]))
    print(f"largest per-point stress difference {sdiff / smax:.2e} of the largest stress "
          f"{smax:.3f} MPa ({len(sa)} stages)")
    for t in sorted(se):
        de = {k: v[3] for k, v in se[t].items()}
        ds = {k: v[3] for k, v in ss[t].items()}
        one = {k for k, v in de.items() if v > 0.01}
        two = {k for k, v in ds.items() if v > 0.01}
        worst = max(abs(de[k] - ds[k]) for k in de)
        print(f"stage at time {t}: damaged {len(one)} exact, {len(two)} shared, in one only "
              f"{len(one ^ two)}; largest damage difference {worst:.2e}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
