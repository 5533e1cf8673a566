"""The Schwarz subdomains' overlap against its cost.

Quoted by ``docs/studies/krylov.rst`` ("The Schwarz overlap"). On the first tangent of the
bench step as the Krylov sizes run it, per share
(:data:`soilwater.linalg.krylov_schwarz.OVERLAP`: an unknown joins an aggregate's
subdomain when at least this share of its neighbours is in it; above 1 none joins): the
preconditioner's build time and kept Schwarz inverses [MB], and FGMRES on a random
right-hand side to 1e-8: iterations and time. The share is no argument of the library:
it is set for each build only (:func:`common.scoped`).

``python docs/experiments/krylov_overlap.py --nodes 30000 --overlaps 0.25 0.5 1.01`` (the
defaults; a few minutes on 2 cores).
"""

import time

import numpy as np

import soilwater.linalg.krylov_schwarz
from soilwater.linalg.krylov import Krylov
from soilwater.linalg.krylov_schwarz import Schwarz

from common import count, first_tangent, parsed, parser, scoped


def kept_inverses(precondition):
    """Bytes of the Schwarz inverses the preconditioner's two V-cycles keep."""
    total = 0
    for cycle in (precondition.amg_u, precondition.amg_p):
        levels = cycle.args[0]                  # the V-cycle's pyamg levels
        smoother = getattr(getattr(levels[0], "presmoother", None), "__self__", None)
        total += smoother.inverses.nbytes if isinstance(smoother, Schwarz) else 0
    return total


def main(argv=None):
    """Build and solve per overlap; return one row each (``build`` and ``solve`` [s],
    ``inverses_mb``, ``iterations``)."""
    made = parser(__doc__)
    made.add_argument("--nodes", type=count, default=30_000, help="requested node count")
    made.add_argument("--overlaps", nargs="+", type=float, default=[0.25, 0.5, 1.01],
                      help="share of its neighbours that makes an unknown join an "
                      "aggregate's subdomain (above 1: none joins)")
    rows = []
    with parsed(made, argv) as args:
        K, layout = first_tangent(args.nodes, krylov=True)
        b = np.random.default_rng(0).standard_normal(K.shape[0])
        for share in args.overlaps:
            tic = time.perf_counter()
            with scoped(soilwater.linalg.krylov_schwarz, "OVERLAP", share):
                precondition = Krylov(K, layout)
            built = time.perf_counter() - tic
            precondition.solve(b, rtol=1e-8)
            row = {"overlap": share, "build": built,
                   "inverses_mb": kept_inverses(precondition) / 1e6,
                   "iterations": precondition.iterations,
                   "solve": time.perf_counter() - tic - built}
            print(f"{args.nodes} nodes, overlap {share}: build {built:.1f} s, inverses "
                  f"{row['inverses_mb']:.0f} MB, FGMRES {row['iterations']} iterations, "
                  f"{row['solve']:.1f} s", flush=True)
            rows.append(row)
    return rows


if __name__ == "__main__":
    main()
