"""The strength-of-connection threshold of the Krylov back-end's AMG hierarchies.

Quoted by ``docs/studies/krylov.rst`` ("The strength threshold"). Per threshold
``theta`` (the step's :attr:`soilwater.linalg.layout.Layout.strength`, passed to the run
for every discretisation alike, :func:`common.solve`): one Krylov step of the bench case
(EFG) per size, each in its own forked process (step and solve time, Newton and FGMRES
iterations, peak memory), and whole unconfined-compression runs of fem-th and
fem-p1p1-stab on Krylov (time, Newton and FGMRES iterations, cut-backs, or the failure).

``python docs/experiments/krylov_strength.py 0 0.01 0.02`` (the default thresholds, at 3e4
and 1e5 nodes; about 15 minutes on 2 cores).
"""

import argparse

from soilwater.case.loader import load_case
from soilwater.linalg.backends import linear_solver
from soilwater.studies.bench.runs import in_child

from common import LIMIT, bench_step, count, parsed, parser, printed, replaced, whole_run

KEYS = ("step", "solve", "iterations", "linear_iterations", "peak_mb")


def threshold(text):
    """A strength threshold from the command line, in [0, 1)."""
    value = float(text)
    if not 0.0 <= value < 1.0:
        raise argparse.ArgumentTypeError(f"{text!r}: use a threshold in [0, 1)")
    return value


def main(argv=None):
    """Run the steps and the whole runs; return their rows (steps: :func:`bench_step`'s
    with ``theta`` and ``status``; whole runs: :func:`common.whole_run`'s with ``theta``
    and ``method``)."""
    made = parser(__doc__, overrides=True)
    made.add_argument("thetas", nargs="*", type=threshold, default=[0.0, 0.01, 0.02],
                      help="strength thresholds")
    made.add_argument("--sizes", nargs="*", type=count, default=[30_000, 100_000],
                      help="requested node counts of the EFG steps")
    made.add_argument("--whole", nargs="*", default=["fem-th", "fem-p1p1-stab"],
                      help="methods of the whole unconfined-compression runs")
    made.add_argument("--limit", type=float, default=LIMIT, help="seconds per step")
    rows = []
    with parsed(made, argv) as args:
        case = load_case("unconfined-compression", overrides=args.overrides)
        for theta in args.thetas:
            for nodes in args.sizes:
                row, status = in_child(bench_step, "efg", nodes, "krylov",
                                       replaced(strength=theta), timeout=args.limit)
                printed(f"theta {theta} {nodes:8d}", row, KEYS, status, 1)
                rows.append({**(row or {}), "theta": theta, "status": status})
            for method in args.whole:
                with linear_solver("krylov"):
                    row = whole_run(f"theta {theta} unconfined-compression {method}", case,
                                    method, replaced(strength=theta))
                rows.append({**row, "theta": theta, "method": method})
    return rows


if __name__ == "__main__":
    main()
