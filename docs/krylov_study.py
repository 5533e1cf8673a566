"""The measured numbers of the Krylov back-end against PARDISO, README "Speed":
python docs/krylov_study.py [nodes ...] (default 1e4 3e4; about 12 minutes on 2 cores).

One step of ``make bench``'s case (:func:`comparisons.bench.compression` with
``krylov=True``: EFG with Nitsche's conditions and the perturbation stabilisation, which
the Krylov back-end needs) on both back-ends, each in its own forked process, stopped
after 400 s. Prints the step time, Newton and FGMRES iterations, solve time and peak
memory.
"""

import sys

from comparisons.bench import compression, in_child, one_step

LIMIT = 400.0


def stabilised(nodes, material="cam-clay", krylov=False):
    """The bench case as the Krylov sizes run it, for both back-ends alike."""
    return compression(nodes, material, krylov=True)


def main(sizes):
    import comparisons.bench

    comparisons.bench.compression = stabilised
    for nodes in sizes:
        for solver in ("pardiso", "krylov"):
            row, status = in_child(one_step, "efg", nodes, "cam-clay", solver,
                                   timeout=LIMIT)
            keys = ("step", "iterations", "linear_iterations", "solve", "peak_mb")
            print(f"{nodes:8d} {solver:8s} {status}",
                  {k: round(row[k], 2) for k in keys} if row else "", flush=True)


if __name__ == "__main__":
    main([int(float(n)) for n in sys.argv[1:]] or [10_000, 30_000])
