"""Whether two `rve` binaries give the same response.csv for every shipped scene.

Usage: python3 scripts/same_responses.py RVE_BEFORE RVE_NOW [WORK]

Runs `rve run SCENE` with each binary for every scene in scenes/ and scenes/paper/ and
compares the two response.csv files cell by cell as text (so bit for bit as printed),
without the `seconds` column. A run that writes no response.csv (a scene that only hosts
read, with no path) compares by its last error line. Prints one line per scene and exits
1 when any differs. The check behind "behaviour stays bit-identical" after a refactor:
build the earlier commit in a worktree (`git worktree add ../before COMMIT`, `cargo build
--release --bin rve` there) and pass both binaries.
"""

import csv
import glob
import os
import sys
import tempfile

from kit.rve import ROOT, run_rve


def response(rve, scene, out):
    """(exit code, rows without `seconds`, as text) of `rve run SCENE --out OUT`."""
    os.makedirs(out, exist_ok=True)
    p = run_rve(scene, out, rve, cwd=ROOT)
    path = os.path.join(out, "response.csv")
    if not os.path.exists(path):
        lines = p.stderr.strip().splitlines()
        return p.returncode, [lines[-1] if lines else ""]
    with open(path) as f:
        rows = list(csv.reader(f))
    keep = [i for i, name in enumerate(rows[0]) if name != "seconds"]
    return p.returncode, [[row[i] for i in keep] for row in rows]


def main(before, now, work):
    scenes = sorted(glob.glob(os.path.join(ROOT, "scenes", "*.toml"))
                    + glob.glob(os.path.join(ROOT, "scenes", "paper", "*.toml")))
    differ = 0
    for scene in scenes:
        name = os.path.relpath(scene, ROOT)
        slug = name.replace("/", "_")
        a = response(before, scene, os.path.join(work, "before", slug))
        b = response(now, scene, os.path.join(work, "now", slug))
        differ += a != b
        print(f"{name:45} {len(b[1]) - 1:4} increments  {'same' if a == b else 'DIFFERENT'}"
              f" (exit {b[0]})", flush=True)
    print(f"{len(scenes) - differ} of {len(scenes)} scenes give the same response.csv")
    return 1 if differ else 0


if __name__ == "__main__":
    if len(sys.argv) not in (3, 4):
        raise SystemExit(__doc__)
    work = sys.argv[3] if len(sys.argv) == 4 else tempfile.mkdtemp(prefix="same-responses-")
    sys.exit(main(sys.argv[1], sys.argv[2], work))
