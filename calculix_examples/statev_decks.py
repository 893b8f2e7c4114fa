#!/usr/bin/env python3
"""Writes the CalculiX decks of the STATEV checks (scripts/test-calculix, docs/calculix.md,
"State in STATEV: restart and *MODEL CHANGE") on stdout, from specimen_weak.inp (the
weakened strip, 36 CPE4 elements, IMPL-EX; read from this directory).

  statev_decks.py restart --depvar N [--pair] --part full|1|2 [--scene NAME]
  statev_decks.py modelchange --depvar N [--scene NAME]

Every *DEPVAR becomes N: `rve info`'s umat_nstatv (789 for concrete_implex.toml) keeps the
RVE state in STATEV, a smaller N (3) the library's table.

restart: specimen_weak.inp's steps 1 and 2 (tension through the weak element's debonding
to U = 8e-3 mm in 20 increments, unloading to U = 0 in 10). `--part full` is both steps;
`--part 1` step 1 with *RESTART, WRITE, FREQUENCY=1 (ccx writes JOB.rout at its end);
`--part 2` is `*RESTART, READ, STEP=1` and step 2 (ccx reads JOB.rin: copy part 1's .rout
there). `--pair` adds, before the steps, two fixed elastic blocks far from the strip with
a node-to-surface contact pair between them that never closes: ccx 2.20 writes and reads
the state variables in its restart file only when the model has a contact pair of type
NODE TO SURFACE or SURFACE TO SURFACE (restartwrite.f and restartread.f test
`mortar.eq.0` / `mortar.eq.1`; without a contact pair calinput.f sets mortar = -2), so
without the pair a restart hands the UMAT zeros.

modelchange: step 1 as above; step 2 removes the column of elements 6, 18, 30 (x = 50 to
60 mm, the weakened element 18 in its middle; *MODEL CHANGE, TYPE=ELEMENT, REMOVE) and
unloads to U = 0; step 3 adds it back (ADD=WITHSTRAIN: ccx's default, strain-free
addition, needs NLGEOM) and loads to U = 4e-3 mm in 5 increments.

`--scene NAME` makes the materials use NAME.toml instead of concrete_implex.toml (the
check's host that zeroes the re-added elements' STATEV needs a scene that says so,
`[statev] zero_at_strain = "virgin"`).
"""
import argparse
import os

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = "specimen_weak.inp"
COLUMN = (6, 18, 30)

PAIR = """** Two elastic blocks far from the strip, every node fixed, and a node-to-surface contact
** pair between them that never closes: with a contact pair ccx 2.20 keeps the state
** variables in its restart file (statev_decks.py's docstring).
*NODE, NSET=BLOCKN
901, 200., 0.
902, 210., 0.
903, 210., 10.
904, 200., 10.
905, 220., 0.
906, 230., 0.
907, 230., 10.
908, 220., 10.
*ELEMENT, TYPE=CPE4, ELSET=BLOCKS
901, 901, 902, 903, 904
902, 905, 906, 907, 908
*NSET, NSET=BLOCKGAP
902, 903
*MATERIAL, NAME=BLOCK
*ELASTIC
25000., 0.2
*SOLID SECTION, ELSET=BLOCKS, MATERIAL=BLOCK
1.
*BOUNDARY
BLOCKN, 1, 2, 0.
*SURFACE, NAME=BLOCKSLAVE, TYPE=NODE
BLOCKGAP
*SURFACE, NAME=BLOCKMASTER
902, S4
*SURFACE INTERACTION, NAME=NEVER
*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR
1e3, 1e-20, 1e-3
*CONTACT PAIR, INTERACTION=NEVER, TYPE=NODE TO SURFACE
BLOCKSLAVE, BLOCKMASTER""".split("\n")


def source(depvar):
    """specimen_weak.inp without its header comment, *DEPVAR set: (model lines, [steps])."""
    with open(os.path.join(HERE, SOURCE)) as f:
        lines = f.read().split("\n")
    while lines and lines[0].startswith("**"):
        lines.pop(0)
    out = []
    for k, line in enumerate(lines):
        out.append(str(depvar) if k > 0 and lines[k - 1].startswith("*DEPVAR") else line)
    starts = [k for k, l in enumerate(out) if l.startswith("*STEP")]
    ends = [k for k, l in enumerate(out) if l.startswith("*END STEP")]
    return out[:starts[0]], [out[s:e + 1] for s, e in zip(starts, ends)]


def with_cards(step, cards, target=None, increment=None):
    """A step with `cards` after its *STEP line, the TOP displacement `target` and the
    *STATIC increment `increment` when given."""
    out = [step[0]] + cards
    static = False
    for line in step[1:]:
        if target is not None and line.startswith("TOP, 2, 2,"):
            line = f"TOP, 2, 2, {target}"
        if static and increment is not None:
            line = f"{increment}, 1., 1e-4, {increment}"
        static = line.startswith("*STATIC")
        out.append(line)
    return out


def header(a):
    what = (f"restart --depvar {a.depvar}" + (" --pair" if a.pair else "") + f" --part {a.part}"
            if a.deck == "restart" else f"modelchange --depvar {a.depvar}")
    if a.scene:
        what += f" --scene {a.scene}"
    return [f"** Written by calculix_examples/statev_decks.py {what}",
            f"** from {SOURCE} (the weakened strip, IMPL-EX); see the script's docstring."]


def restart(a):
    model, steps = source(a.depvar)
    if a.pair:
        model = model + PAIR
    if a.part == "full":
        return header(a) + model + steps[0] + steps[1]
    if a.part == "1":
        return header(a) + model + with_cards(steps[0], ["*RESTART, WRITE, FREQUENCY=1"])
    return header(a) + ["*RESTART, READ, STEP=1"] + steps[1]


def modelchange(a):
    model, steps = source(a.depvar)
    model = model + ["*ELSET, ELSET=COLUMN", ", ".join(map(str, COLUMN))]
    change = "*MODEL CHANGE, TYPE=ELEMENT, "
    return (header(a) + model + steps[0]
            + with_cards(steps[1], [change + "REMOVE", "COLUMN"])
            + with_cards(steps[2], [change + "ADD=WITHSTRAIN", "COLUMN"], "0.004", "0.2"))


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("deck", choices=("restart", "modelchange"))
    p.add_argument("--depvar", type=int, required=True)
    p.add_argument("--pair", action="store_true")
    p.add_argument("--part", choices=("full", "1", "2"), default="full")
    p.add_argument("--scene", help="the scene of the materials instead of CONCRETE_IMPLEX")
    args = p.parse_args()
    lines = restart(args) if args.deck == "restart" else modelchange(args)
    if args.scene:
        lines = [l.replace("@ABAQUS_RVE_UMAT@CONCRETE_IMPLEX", "@ABAQUS_RVE_UMAT@" + args.scene)
                 for l in lines]
    print("\n".join(lines))
