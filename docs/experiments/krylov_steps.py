"""One bench step on PARDISO and on the Krylov back-end: step time, iterations, memory.

Quoted by ``docs/studies/krylov.rst`` ("Speed and memory"). One step of ``make bench``'s
case (:func:`soilwater.studies.bench.plan.compression`, Cam-clay) as the Krylov sizes run
it (EFG with Nitsche's conditions and the perturbation stabilisation, which the Krylov
back-end needs) on each back-end, each in its own forked process
(:func:`soilwater.studies.bench.runs.in_child`) stopped after ``--limit`` seconds. Prints
the step time, Newton and FGMRES iterations, solve time and peak memory.

``python docs/experiments/krylov_steps.py [nodes ...]`` (default 1e4 3e4; about 12
minutes on 2 cores).
"""

from soilwater.studies.bench.runs import in_child, one_step

from common import LIMIT, count, parsed, parser, printed

KEYS = ("step", "iterations", "linear_iterations", "solve", "peak_mb")


def main(argv=None):
    """Run the steps; return one row per size and back-end (``status``: ``"ok"`` or why
    the run did not finish)."""
    made = parser(__doc__)
    made.add_argument("sizes", nargs="*", type=count, default=[10_000, 30_000],
                      help="requested node counts")
    made.add_argument("--solvers", nargs="+", default=["pardiso", "krylov"],
                      choices=["pardiso", "superlu", "krylov"])
    made.add_argument("--method", default="efg", help="efg or an FEM pair")
    made.add_argument("--limit", type=float, default=LIMIT, help="seconds per step")
    rows = []
    with parsed(made, argv) as args:
        for nodes in args.sizes:
            for solver in args.solvers:
                row, status = in_child(one_step, args.method, nodes, "cam-clay", solver,
                                       True, timeout=args.limit)
                printed(f"{nodes:8d} {solver:8s}", row, KEYS, status)
                rows.append({**(row or {}), "requested": nodes, "solver": solver,
                             "status": status})
    return rows


if __name__ == "__main__":
    main()
