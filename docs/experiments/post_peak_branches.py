"""Unconfined compression past its peak on a refined grid: which branch each solver takes.

Quoted by ``docs/studies/krylov.rst`` ("Past the peak the homogeneous solution is
unstable, and the solver picks the branch"). The case is the built-in unconfined
compression on the 825-node grid of :data:`GRID` (EFG, Nitsche's conditions, the
perturbation stabilisation: what the Krylov back-end runs). Its exact solution is
homogeneous, and MLS with a linear basis reproduces a homogeneous field on any layout, so
the spread of q and p_w over the nodes measures how far a run has left that solution.

Each ``--path`` (default :data:`PATHS`): EFG with PARDISO's modified Newton (the
default), full Newton on PARDISO (the current tangent factorised at every iteration:
:data:`soilwater.linalg.layout.CONTRACTION` 0, no argument of the library, set for that
run only, :func:`common.scoped`; in double precision, as a single factor's refinement
asked for no contraction would redo it in double at its first solve) and the Krylov
back-end; then fem-th and fem-p1p1-stab on the same nodes (PARDISO's modified Newton).
Prints time, Newton and FGMRES iterations, cut-backs and the largest q, and every
``--every`` seconds of the case the spread (largest minus smallest) of q and of p_w over
the nodes relative to their mean magnitude (of a run that fails, up to its last level).

``python docs/experiments/post_peak_branches.py`` (about 18 minutes on 2 cores).
"""

import argparse
import time
from contextlib import nullcontext

import numpy as np

import soilwater.linalg.layout
from soilwater.case.loader import load_case
from soilwater.errors import ConvergenceError
from soilwater.linalg.backends import linear_solver

from common import parsed, parser, replaced, scoped, solve

#: Grid k = 8 of the case's 3 x 4 m quarter: 25 x 33 nodes, spacing 0.125 m.
GRID = ["discretisation.nx=25", "discretisation.ny=33", "discretisation.layout=grid",
        'efg.essential="nitsche"', 'efg.stabilisation="perturbation"']
#: The paths of ``--path``: method, linear solver, Newton (``modified``, ``full``: no
#: contraction test, or ``newton``: the Krylov back-end's own).
PATHS = (("efg", "pardiso", "modified"), ("efg", "pardiso", "full"),
         ("efg", "krylov", "newton"), ("fem-th", "pardiso", "modified"),
         ("fem-p1p1-stab", "pardiso", "modified"))
NEWTON = {"modified": "modified Newton", "full": "full Newton", "newton": "Newton"}


def case(overrides=()):
    """The study's case (:data:`GRID`), with more ``overrides``."""
    return load_case("unconfined-compression", GRID, overrides=overrides)


def path(text):
    """``method:solver:newton`` from the command line."""
    parts = tuple(text.split(":"))
    if len(parts) != 3 or parts[2] not in NEWTON:
        raise argparse.ArgumentTypeError(f"{text!r}: use method:solver:newton, newton "
                                         "one of modified, full, newton")
    return parts


def branch(study, method, solver, newton, every):
    """One run of ``study`` (a case); its row (``failed``: the error, or None) with the
    spreads of q and p_w (``spreads``: time, q, p_w) at every ``every`` seconds."""
    label = f"{method} on {solver}, {NEWTON[newton]}"
    snapshots, tic = [], time.perf_counter()
    row = {"path": (method, solver, newton), "failed": None}
    full = (scoped(soilwater.linalg.layout, "CONTRACTION", 0.0) if newton == "full"
            else nullcontext())
    with linear_solver(solver), full:
        try:
            result = solve(study, method, snapshots=snapshots,
                           layout=replaced(single=False) if newton == "full" else None)
            s = result.summary
            row.update(newton=s["newton_iterations"], fgmres=s["linear_iterations"],
                       cutbacks=s["cutbacks"], largest_q=float(result.history.q.max()))
            print(f"{label}: {time.perf_counter() - tic:.0f} s, Newton {row['newton']}, "
                  f"FGMRES {row['fgmres']}, cut-backs {row['cutbacks']}, largest q "
                  f"{row['largest_q']:.6f} kPa", flush=True)
        except ConvergenceError as err:
            row["failed"] = str(err)
            print(f"{label}: failed after {time.perf_counter() - tic:.0f} s: {err}",
                  flush=True)
    row["spreads"] = []
    for snap in snapshots:
        if snap.time > 0 and abs(snap.time / every - round(snap.time / every)) < 1e-9:
            q, p = snap.point_data["q"], snap.point_data["p_w"]
            spread = (snap.time, np.ptp(q) / np.abs(q).mean(), np.ptp(p) / np.abs(p).mean())
            row["spreads"].append(spread)
            print(f"  t = {snap.time:4.1f} s: spread of q {spread[1]:.1e}, of p_w "
                  f"{spread[2]:.1e}", flush=True)
    return row


def main(argv=None):
    """Run each path; return their rows (:func:`branch`)."""
    made = parser(__doc__, overrides=True)
    made.add_argument("--path", action="append", type=path, dest="paths",
                      metavar="METHOD:SOLVER:NEWTON", help="a run (repeatable; default: "
                      "the five of PATHS)")
    made.add_argument("--every", type=float, default=2.0,
                      help="seconds of the case between the spreads printed")
    with parsed(made, argv) as args:
        study = case(args.overrides)
        return [branch(study, *spec, args.every) for spec in args.paths or PATHS]


if __name__ == "__main__":
    main()
