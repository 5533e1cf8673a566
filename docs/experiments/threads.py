"""One Krylov step of the bench case on one thread and on every core.

Quoted by ``docs/studies/speed.rst`` ("Cores"). Per size and thread count
(:func:`soilwater.linalg.threads.using`: EFG's scatter, Cam-clay's return mapping and the
Schwarz sweeps), one Krylov step of the bench case in its own forked process
(:func:`soilwater.studies.bench.runs.one_step`): step, assembly, solve and constitutive
times, Newton and FGMRES iterations.

``python docs/experiments/threads.py 100000`` (the default size; a few minutes on 2
cores).
"""

from soilwater.linalg.threads import CORES, using
from soilwater.studies.bench.runs import in_child, one_step

from common import LIMIT, count, parsed, parser, printed

KEYS = ("step", "assembly", "solve", "constitutive", "iterations", "linear_iterations")


def main(argv=None):
    """Run the steps; return one row per size and thread count (``status``: ``"ok"``
    or why the run did not finish)."""
    made = parser(__doc__)
    made.add_argument("sizes", nargs="*", type=count, default=[100_000],
                      help="requested node counts")
    made.add_argument("--threads", nargs="+", type=count, default=sorted({1, CORES}),
                      help=f"thread counts (default: 1 and every core, {CORES})")
    made.add_argument("--limit", type=float, default=LIMIT, help="seconds per step")
    rows = []
    with parsed(made, argv) as args:
        for nodes in args.sizes:
            for threads in args.threads:
                with using(threads):
                    row, status = in_child(one_step, "efg", nodes, "cam-clay", "krylov",
                                           timeout=args.limit)
                printed(f"{nodes:8d} threads {threads}", row, KEYS, status)
                rows.append({**(row or {}), "threads": threads, "status": status})
    return rows


if __name__ == "__main__":
    main()
