#!/usr/bin/env python3
"""The CalculiX runner of every study and CI stage, and the readers of ccx's outputs.

Running (ccx dlopens `lib<NAME>.so` for a material `@ABAQUS_<NAME>_UMAT@...`, so the
library is staged as `libRVE.so` in a folder on LD_LIBRARY_PATH):

- `binary()`: the path of ccx 2.20 with run-time user materials (scripts/build-calculix
  builds it once and caches it);
- `stage(folder, lib)`: copies the library (default target/release/librve.so) to
  FOLDER/libRVE.so; a copy, so a rebuild of target/release during a run changes nothing;
- `run(job, folder, ...)`: `ccx JOB` in FOLDER (FOLDER/JOB.inp written by the caller) with
  LD_LIBRARY_PATH (the folder, or `lib_dir`), MESORVE_SCENE_PATH, OMP_NUM_THREADS and any
  extra variables; stdout and stderr to FOLDER/JOB.log; wall, user and system CPU time and
  peak memory (the kernel's rusage of the child, what /usr/bin/time reports) to
  FOLDER/JOB.time (JSON); checks "Job finished" unless told not to. Returns a `Run`.

Reading (JOB: the job's path without extension):

- `dat_blocks(path, kind, nset)`: {time: [[floats per line]]} of the .dat blocks `kind`
  ("force" for "total force", "displacements", "stresses", "internal state variables",
  "global coordinates", ...), of the set `nset` only when given;
- `dat_points(path, kind, nset)`: {time: {(element, point): [floats]}} of element blocks,
  a point's continued lines joined (SDV prints several lines a point);
- `sta(job)`, `cvg(job)`: increments and attempts of JOB.sta, force residuals of JOB.cvg;
- `read_time(job)`: JOB.time as a dict (`wall`, `user`, `sys`, `max_rss_kb`, `cpu_percent`).

Command line, for shell stages:

    ccx.py binary                     prints ccx's path (scripts/build-calculix)
    ccx.py stage FOLDER [--lib PATH]  copies the library to FOLDER/libRVE.so
    ccx.py run JOB [--dir FOLDER] [--ccx PATH] [--lib-dir DIRS] [--scenes PATHS]
               [--threads N] [--env KEY=VALUE]... [--wrap 'CMD ARGS'] [--no-check]
                                      runs ccx; prints "WALL USER" (seconds); exit status 1
                                      (JOB.log's tail on stderr) when the job did not finish,
                                      unless --no-check
    ccx.py dat FILE.dat KIND [NSET]   prints the blocks, one "time value value ..." a line
"""

import argparse
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LIBRARY = os.path.join(ROOT, "target", "release", "librve.so")
# A .dat block's header: "[total ]KIND (columns) for set NAME and time T".
HEADER = re.compile(r"\s*(?:total )?(.+?) \(.*\) for set (\w+) and time\s+(\S+)")


# ------------------------------------------------------------------------------- running
def binary():
    """ccx's path, built once by scripts/build-calculix (it prints it; logs on stderr)."""
    out = subprocess.run([os.path.join(ROOT, "scripts", "build-calculix")], check=True,
                         stdout=subprocess.PIPE, text=True).stdout
    return out.strip()


def stage(folder, lib=LIBRARY):
    """Copies `lib` to FOLDER/libRVE.so (the name ccx dlopens); returns FOLDER."""
    if not os.path.exists(lib):
        sys.exit(f"kit.ccx: {lib} missing: run `cargo build --release` first")
    os.makedirs(folder, exist_ok=True)
    shutil.copy(lib, os.path.join(folder, "libRVE.so"))
    return folder


class Run:
    """One ccx run: `job`, `folder`, `path` (FOLDER/JOB), `finished` ("Job finished" in the
    log), `returncode`, and the times of JOB.time (`wall`, `user`, `sys`, `max_rss_kb`)."""

    def __init__(self, job, folder, finished, returncode, times):
        self.job, self.folder, self.finished, self.returncode = job, folder, finished, returncode
        self.path = os.path.join(folder, job)
        self.times = times
        self.wall, self.user, self.sys = times["wall"], times["user"], times["sys"]
        self.max_rss_kb = times["max_rss_kb"]

    def log(self):
        with open(self.path + ".log", errors="replace") as f:
            return f.read()


def run(job, folder, ccx=None, lib_dir=None, scenes=None, threads=None, env=None,
        check=True, wrap=()):
    """Runs `ccx JOB` in `folder` (see the module's doc). `lib_dir`: LD_LIBRARY_PATH
    (default: the folder, where `stage` put libRVE.so); `scenes`: MESORVE_SCENE_PATH;
    `threads`: OMP_NUM_THREADS (both inherited when None); `env`: more variables; `wrap`:
    a command that runs ccx (gdb's `--args`); `check`: exit with the log's tail when the
    job did not finish."""
    ccx = ccx or binary()
    e = dict(os.environ, LD_LIBRARY_PATH=lib_dir or folder)
    if scenes is not None:
        e["MESORVE_SCENE_PATH"] = scenes
    if threads is not None:
        e["OMP_NUM_THREADS"] = str(threads)
    e.update(env or {})
    start = time.monotonic()
    with open(os.path.join(folder, job + ".log"), "w") as log:
        p = subprocess.Popen([*wrap, ccx, job], cwd=folder, env=e, stdin=subprocess.DEVNULL,
                             stdout=log, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(p.pid, 0)
    wall = time.monotonic() - start
    p.returncode = os.waitstatus_to_exitcode(status)
    cpu = usage.ru_utime + usage.ru_stime
    times = {"wall": wall, "user": usage.ru_utime, "sys": usage.ru_stime,
             "max_rss_kb": usage.ru_maxrss, "cpu_percent": int(100 * cpu / wall) if wall > 0 else 0}
    with open(os.path.join(folder, job + ".time"), "w") as f:
        json.dump(times, f)
    r = Run(job, folder, False, p.returncode, times)
    r.finished = "Job finished" in r.log()
    if check and not r.finished:
        tail = "".join(r.log().splitlines(keepends=True)[-20:])
        sys.exit(f"{tail}kit.ccx: {job} did not finish in {folder}")
    return r


def read_time(job):
    """JOB.time, written by `run`: {wall, user, sys, max_rss_kb, cpu_percent}."""
    with open(job + ".time") as f:
        return json.load(f)


# ------------------------------------------------------------------------------- reading
def dat_headers(path):
    """(line number, kind, set, time) of every block header of a .dat file."""
    out = []
    with open(path) as f:
        for n, line in enumerate(f):
            m = HEADER.match(line) if " for set " in line else None
            if m:
                out.append((n, m.group(1), m.group(2), float(m.group(3))))
    return out


def dat_lines(path, kind, nset=None):
    """Yields (time, tokens) of every non-blank line of the blocks `kind` (of the set
    `nset` only, when given), and (time, None) at each such block's header."""
    wanted, t = False, None
    with open(path) as f:
        for line in f:
            # The substring test first: the regular expression on every line of a
            # member's 100 MB .dat was most of the parsing time.
            m = HEADER.match(line) if " for set " in line else None
            if m:
                wanted = m.group(1) == kind and (nset is None or m.group(2) == nset.upper())
                t = float(m.group(3))
                if wanted:
                    yield t, None
                continue
            if wanted and line.strip():
                yield t, line.split()


def dat_blocks(path, kind, nset=None):
    """{time: [[floats per line]]} of the blocks `kind` ('stresses', 'force', ...), of the
    set `nset` only when given (blocks of several sets at one time are concatenated)."""
    blocks = {}
    for t, tokens in dat_lines(path, kind, nset):
        rows = blocks.setdefault(t, [])
        if tokens is not None:
            rows.append([float(v) for v in tokens])
    return blocks


def dat_points(path, kind, nset=None):
    """{time: {(element, point): [floats]}} of element blocks ("stresses", "internal state
    variables", "global coordinates"): a line that starts with two integers starts a
    point, the lines after it (SDV: several a point) continue its values."""
    out, current = {}, None
    for t, tokens in dat_lines(path, kind, nset):
        points = out.setdefault(t, {})
        if tokens is None:
            current = None
            continue
        if len(tokens) >= 2 and tokens[0].isdigit() and tokens[1].isdigit():
            current = points.setdefault((int(tokens[0]), int(tokens[1])), [])
            tokens = tokens[2:]
        if current is not None:
            current.extend(float(v) for v in tokens)
    return out


def sta(job):
    """[(step, inc, attempt, converged, iterations, increment size)] from JOB.sta."""
    out = []
    with open(job + ".sta") as f:
        for line in f:
            m = re.match(r"\s*(\d+)\s+(\d+)\s+(\d+)(U?)\s+(\d+)\s+\S+\s+\S+\s+(\S+)", line)
            if m:
                out.append((int(m.group(1)), int(m.group(2)), int(m.group(3)),
                            m.group(4) != "U", int(m.group(5)), float(m.group(6))))
    return out


def cvg(job):
    """{(step, inc, attempt): [force residual % per iteration]} from JOB.cvg."""
    out = {}
    with open(job + ".cvg") as f:
        for line in f:
            v = line.split()
            if len(v) == 9 and v[0].isdigit():
                out.setdefault((int(v[0]), int(v[1]), int(v[2])), []).append(float(v[5]))
    return out


# --------------------------------------------------------------------------- command line
def main(argv):
    ap = argparse.ArgumentParser(prog="ccx.py", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("binary")
    s = sub.add_parser("stage")
    s.add_argument("folder")
    s.add_argument("--lib", default=LIBRARY)
    r = sub.add_parser("run")
    r.add_argument("job")
    r.add_argument("--dir", default=".")
    r.add_argument("--ccx")
    r.add_argument("--lib-dir")
    r.add_argument("--scenes")
    r.add_argument("--threads")
    r.add_argument("--env", action="append", default=[], metavar="KEY=VALUE")
    r.add_argument("--wrap", default="", help="a command that runs ccx, e.g. 'gdb -batch --args'")
    r.add_argument("--no-check", action="store_true")
    d = sub.add_parser("dat")
    d.add_argument("file")
    d.add_argument("kind")
    d.add_argument("nset", nargs="?")
    a = ap.parse_args(argv)
    if a.command == "binary":
        print(binary())
    elif a.command == "stage":
        print(stage(os.path.abspath(a.folder), a.lib))
    elif a.command == "run":
        env = dict(item.split("=", 1) for item in a.env)
        res = run(a.job, os.path.abspath(a.dir), a.ccx, a.lib_dir, a.scenes, a.threads, env,
                  not a.no_check, shlex.split(a.wrap))
        print(f"{res.wall:.2f} {res.user:.2f}")
    elif a.command == "dat":
        for t, rows in sorted(dat_blocks(a.file, a.kind, a.nset).items()):
            for row in rows:
                print(f"{t:.9g} " + " ".join(f"{v:.9g}" for v in row))


if __name__ == "__main__":
    main(sys.argv[1:])
