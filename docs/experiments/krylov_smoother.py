"""The Krylov back-end's finest-level AMG smoother per discretisation.

Quoted by ``docs/studies/krylov.rst`` ("The smoother per discretisation"). One Krylov step
of the bench case per size, method and smoother (the step's
:attr:`soilwater.linalg.layout.Layout.smoother`, passed to the run,
:func:`common.solve`), each in its own forked process: step and solve time, Newton and
FGMRES iterations. Then whole unconfined-compression runs of fem-th and fem-q2q1 (on the
case's grid without centres) on Krylov with each smoother: time, Newton and FGMRES
iterations, cut-backs.

``python docs/experiments/krylov_smoother.py [nodes ...]`` (default 1e4 3e4; about 10
minutes on 2 cores).
"""

from soilwater.case.loader import load_case
from soilwater.linalg.backends import linear_solver
from soilwater.studies.bench.runs import in_child

from common import LIMIT, bench_step, count, parsed, parser, printed, replaced, whole_run

SMOOTHERS = ("gauss_seidel", "schwarz")
KEYS = ("step", "solve", "iterations", "linear_iterations")
#: The whole runs: method, the case overrides its elements need.
WHOLE = {"fem-th": [], "fem-q2q1": ["discretisation.layout=grid"]}


def main(argv=None):
    """Run the steps and the whole runs; return their rows (steps: :func:`bench_step`'s
    with ``smoother`` and ``status``; whole runs: :func:`common.whole_run`'s with
    ``method`` and ``smoother``)."""
    made = parser(__doc__, overrides=True)
    made.add_argument("sizes", nargs="*", type=count, default=[10_000, 30_000],
                      help="requested node counts of the steps")
    made.add_argument("--methods", nargs="+",
                      default=["efg", "fem-p1p1-stab", "fem-q2q1", "fem-th"],
                      help="methods of the steps")
    made.add_argument("--whole", nargs="*", default=list(WHOLE), choices=list(WHOLE),
                      help="methods of the whole unconfined-compression runs")
    made.add_argument("--limit", type=float, default=LIMIT, help="seconds per step")
    rows = []
    with parsed(made, argv) as args:
        for nodes in args.sizes:
            for method in args.methods:
                for smoother in SMOOTHERS:
                    row, status = in_child(bench_step, method, nodes, "krylov",
                                           replaced(smoother=smoother), timeout=args.limit)
                    printed(f"{nodes:8d} {method:14s} {smoother:12s}", row, KEYS, status, 1)
                    rows.append({**(row or {}), "method": method, "smoother": smoother,
                                 "status": status})
        for method in args.whole:
            case = load_case("unconfined-compression", WHOLE[method],
                             overrides=args.overrides)
            for smoother in SMOOTHERS:
                with linear_solver("krylov"):
                    row = whole_run(f"unconfined-compression {method} {smoother}", case,
                                    method, replaced(smoother=smoother))
                rows.append({**row, "method": method, "smoother": smoother})
    return rows


if __name__ == "__main__":
    main()
