"""LU of K against PARDISO's LDL^T of sym(K) as FGMRES's preconditioner.

Quoted by ``docs/studies/krylov.rst`` ("LDL^T of sym(K) as FGMRES's preconditioner does
not pay on this CPU"). The first tangent of the bench step, EFG with the penalty (as
``make bench`` runs it on PARDISO) and with Nitsche's conditions and the perturbation,
factorised as LU of ``K`` and as PARDISO's LDL^T of ``sym(K) = (K + K^T) / 2``: how far
``K`` is from symmetric (whole and displacement block), their times and flops, one
back-solve of each, and FGMRES on ``K`` preconditioned by the LDL^T (rows scaled as
Newton scales them) to each tolerance: iterations, time and the largest difference from
the LU solution relative to its largest entry. Needs pypardiso.

``python docs/experiments/direct_symmetric.py [nodes ...]`` (default 1e4 1e5; about 6
minutes on 2 cores).
"""

import itertools
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.linalg.pardiso import _Pardiso

from common import count, first_tangent, parsed, parser


def main(argv=None):
    """Factorise and solve; return one row per size, conditions and tolerance
    (``iterations``, ``difference``), with the asymmetry of ``K``."""
    from pyamg.krylov import fgmres

    made = parser(__doc__)
    made.add_argument("sizes", nargs="*", type=count, default=[10_000, 100_000],
                      help="requested node counts")
    made.add_argument("--tolerances", nargs="+", type=float, default=[1e-4, 1e-8, 1e-10],
                      help="FGMRES's relative residuals")
    rows = []
    with parsed(made, argv) as args:
        for nodes, nitsche in itertools.product(args.sizes, (False, True)):
            K, layout = first_tangent(nodes, krylov=nitsche)
            K = sp.csr_matrix(K)
            u = np.flatnonzero(np.asarray(layout.fields) < 2)
            Kuu = K[u][:, u]
            conditions = "Nitsche" if nitsche else "penalty"
            asymmetry = float(spla.norm(K - K.T) / spla.norm(K))
            print(f"{nodes} nodes, {conditions}, {K.shape[0]} unknowns, ||K - K^T|| / ||K||"
                  f" = {asymmetry:.1e} (displacement block "
                  f"{spla.norm(Kuu - Kuu.T) / spla.norm(Kuu):.1e})", flush=True)
            b = np.random.default_rng(0).standard_normal(K.shape[0]) * layout.scales
            solves, solutions = {}, {}
            for name, symmetric in (("LU of K", False), ("LDL^T of sym(K)", True)):
                tic = time.perf_counter()
                solves[name] = _Pardiso(K, layout.groups, symmetric)
                built = time.perf_counter() - tic
                tic = time.perf_counter()
                solutions[name] = solves[name].solve(b)
                print(f"  {name}: factorisation {built:.1f} s, {solves[name].flops:.2e} "
                      f"flops, {solves[name].perturbed_pivots} perturbed pivots; "
                      f"back-solve {time.perf_counter() - tic:.2f} s", flush=True)
            exact, ldlt = solutions["LU of K"], solves["LDL^T of sym(K)"]
            row = 1 / layout.scales
            A = spla.LinearOperator(K.shape, lambda x: row * (K @ x))
            M = spla.LinearOperator(K.shape, lambda r: ldlt.solve(r / row))
            for rtol in args.tolerances:
                residuals, tic = [], time.perf_counter()
                x, _ = fgmres(A, row * b, M=M, tol=rtol, restart=60, maxiter=1,
                              residuals=residuals)
                result = {"nodes": nodes, "conditions": conditions, "asymmetry": asymmetry,
                          "rtol": rtol, "iterations": len(residuals) - 1,
                          "seconds": time.perf_counter() - tic,
                          "difference": float(np.abs(x - exact).max() / np.abs(exact).max())}
                print(f"  FGMRES to {rtol:.0e}: {result['iterations']} iterations, "
                      f"{result['seconds']:.2f} s, difference from LU "
                      f"{result['difference']:.1e}", flush=True)
                rows.append(result)
    return rows


if __name__ == "__main__":
    main()
