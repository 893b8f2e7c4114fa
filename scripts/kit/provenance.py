#!/usr/bin/env python3
"""Where and when a study ran, in the words every generated study page uses.

A study calls `start()` before its runs (after the release build, so the commit is the
one the binary was built from), keeps the record it returns, and writes `sentence(record,
runs)` on its page:

    Generated on commit `0123456789ab` (2026-11-27 UTC); AMD EPYC, 2 CPUs, Linux 6.1.0:
    219 `rve run` invocations, 180 s in all; load average (1 min) 0.4 at the start and
    1.9 at the end.

The commit is followed by ", with uncommitted changes in ..." when the work tree differs
from it (in the given paths, by default anywhere). A study driven by a shell script
records its start in a file first:

    python3 scripts/kit/provenance.py FILE.json

and its report reads it back with `load(FILE.json)`. Standard library only.
"""

import json
import os
import platform
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MAX_NAMED = 6  # uncommitted files named on the page; the rest are counted


def git(*args):
    """git's output, unstripped (`status --porcelain` starts its lines with a blank)."""
    return subprocess.run(["git", "-C", ROOT] + list(args), capture_output=True,
                          text=True).stdout


def uncommitted(paths=()):
    """The files of the work tree (below `paths`, if given) that differ from HEAD."""
    status = git("status", "--porcelain", "--", *paths)
    return [line[3:] for line in status.splitlines() if line.strip()]


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            names = re.findall(r"(?m)^model name\s*:\s*(.*)$", f.read())
    except OSError:
        names = []
    return names[0].strip() if names else platform.processor() or "unknown CPU"


def machine():
    """`CPU model, N CPUs, kernel`."""
    return "%s, %d CPUs, %s %s" % (cpu_model(), os.cpu_count() or 0, platform.system(),
                                   platform.release())


def changes(files):
    if not files:
        return ""
    named = ", ".join("`%s`" % f for f in files[:MAX_NAMED])
    more = len(files) - MAX_NAMED
    return ", with uncommitted changes in %s%s" % (
        named, " and %d more file%s" % (more, "s" * (more > 1)) if more > 0 else "")


def start(paths=()):
    """The record of a study's start: commit, work tree, date (UTC), machine, load."""
    return {
        "commit": git("rev-parse", "--short=12", "HEAD").strip() or "unknown",
        "uncommitted": uncommitted(paths),
        "date": time.strftime("%Y-%m-%d", time.gmtime()),
        "machine": machine(),
        "load_start": os.getloadavg()[0],
        "started": time.time(),
    }


def where(record):
    """`commit `...` (date UTC)[, with uncommitted changes in ...]; machine`."""
    return "commit `%s` (%s UTC)%s; %s" % (record["commit"], record["date"],
                                          changes(record["uncommitted"]), record["machine"])


def finish(record, runs):
    """The record with the number of runs, the seconds since the start and the load now."""
    done = dict(record)
    done.update(runs=runs, seconds=time.time() - record["started"],
                load_end=os.getloadavg()[0])
    return done


def sentence(record, runs=None, what="`rve run` invocations"):
    """The provenance sentence of a page; `record` from `start()` (then finished here with
    `runs`) or from `finish()`."""
    if "seconds" not in record:
        record = finish(record, runs)
    return ("Generated on %s: %d %s, %.0f s in all; load average (1 min) %.1f at the start "
            "and %.1f at the end." % (where(record), record["runs"], what, record["seconds"],
                                      record["load_start"], record["load_end"]))


def save(record, file):
    with open(file, "w") as f:
        json.dump(record, f)


def load(file):
    with open(file) as f:
        return json.load(f)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: provenance.py FILE.json   (records the start of a study)")
    save(start(), sys.argv[1])
