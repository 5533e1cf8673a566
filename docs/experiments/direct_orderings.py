"""SuperLU's column ordering on the first bench tangent of each method.

Quoted by ``docs/studies/direct.rst``. SuperLU's factorisation of the first tangent of
the bench step (:func:`soilwater.studies.bench.plan.compression`, Cam-clay; EFG as ``make
bench`` runs it on a direct solver, with the penalty) of each method, with scipy's
default column ordering (COLAMD) and with
:data:`soilwater.linalg.direct.SUPERLU_ORDERING`: time and the factor's entries.

``python docs/experiments/direct_orderings.py [nodes ...]`` (default 3e3 1e4; about 3
minutes on 2 cores).
"""

import itertools
import time

import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.linalg.direct import SUPERLU_ORDERING

from common import count, first_tangent, parsed, parser


def main(argv=None):
    """Factorise; return one row per size, method and ordering (``seconds``,
    ``entries`` of L + U)."""
    made = parser(__doc__)
    made.add_argument("sizes", nargs="*", type=count, default=[3_000, 10_000],
                      help="requested node counts")
    made.add_argument("--methods", nargs="+",
                      default=["efg", "fem-th", "fem-q2q1", "fem-p1p1-stab"])
    made.add_argument("--orderings", nargs="+", default=["COLAMD", SUPERLU_ORDERING],
                      choices=["NATURAL", "MMD_ATA", "MMD_AT_PLUS_A", "COLAMD"])
    rows = []
    with parsed(made, argv) as args:
        for nodes, method in itertools.product(args.sizes, args.methods):
            K = sp.csc_matrix(first_tangent(nodes, method=method)[0])
            for ordering in args.orderings:
                tic = time.perf_counter()
                lu = spla.splu(K, permc_spec=ordering)
                row = {"method": method, "nodes": nodes, "unknowns": K.shape[0],
                       "ordering": ordering, "seconds": time.perf_counter() - tic,
                       "entries": lu.L.nnz + lu.U.nnz}
                print(f"{method} {nodes} nodes, {K.shape[0]} unknowns, {ordering}: "
                      f"{row['seconds']:.2f} s, L + U {row['entries']:.3g} entries",
                      flush=True)
                rows.append(row)
    return rows


if __name__ == "__main__":
    main()
