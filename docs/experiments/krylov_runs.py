"""Whole runs of the built-in cases on PARDISO and on the Krylov back-end.

Quoted by ``docs/studies/krylov.rst`` ("Essential conditions: either", "Whole runs").
Each run of ``--run`` (default :data:`RUNS`) on each back-end: Newton, FGMRES and
cut-back counts, and the largest difference of p, q and the settlement between the two,
relative to their range, or the failure.

``python docs/experiments/krylov_runs.py`` (about 5 minutes on 2 cores).
"""

from common import RUNS, compare_runs, parsed, parser, run_spec


def main(argv=None):
    """Run each case on each back-end; return one row per run and back-end, and the
    agreement of each pair (:func:`common.compare_runs`)."""
    made = parser(__doc__, overrides=True)
    made.add_argument("--run", action="append", type=run_spec, dest="runs",
                      metavar="CASE:METHOD[:ESSENTIAL[:STABILISATION]]",
                      help="a run (repeatable; default: the five of RUNS)")
    made.add_argument("--solvers", nargs=2, default=["pardiso", "krylov"],
                      choices=["pardiso", "superlu", "krylov"])
    with parsed(made, argv) as args:
        variants = {solver: (solver, None) for solver in args.solvers}
        return compare_runs(args.runs or RUNS, variants, args.overrides)


if __name__ == "__main__":
    main()
