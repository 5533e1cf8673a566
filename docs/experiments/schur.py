"""Which block of the Krylov preconditioner limits it: displacement and pressure solves.

Quoted by ``docs/studies/krylov.rst`` ("The right Schur complement and smoother for
MLS") and by :mod:`soilwater.linalg.krylov`. On the first tangent of the bench step as the
Krylov sizes run it, the displacement-pressure rows scaled and ordered as
:class:`soilwater.linalg.krylov.Krylov` does, FGMRES (restart 60) to 1e-8 on a random
right-hand side, preconditioned block triangular with the displacement block solved by
one AMG V-cycle (pyamg's default Gauss-Seidel smoother or the back-end's Schwarz) or
exactly (SuperLU), and the pressure block by the fixed-stress ``D - s M_p/M`` with the
lumped or the consistent mass, the SIMPLE ``D - C diag(A)^-1 B``, or (up to
``--true-up-to`` pressures) the true Schur complement ``D - C A^-1 B``, each exactly or
through AMG.

``python docs/experiments/schur.py [nodes ...]`` (default 3e3 1e4; about 5 minutes on 2
cores).
"""

import time

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.linalg.krylov import RESTART, Krylov
from soilwater.linalg.krylov_amg import amg, rigid_modes

from common import count, first_tangent, parsed, parser, scaled_tangent


def _exact(M):
    return spla.splu(sp.csc_matrix(M)).solve


def _scaled(sign, cycle):
    """The solve of ``S`` from the V-cycle ``cycle`` of ``sign S``."""
    return lambda r: sign * cycle(r)


def blocks(nodes, true_up_to):
    """The scaled tangent, its displacement count, and the displacement and pressure
    solves by name."""
    K, layout = first_tangent(nodes, krylov=True)
    precondition = Krylov(K, layout)
    nu, n_p = precondition.sizes
    order, row = precondition.order[:nu + n_p], precondition.row[:nu + n_p]
    scaled = scaled_tangent(K, precondition, nu + n_p)
    A, B = scaled[:nu, :nu], scaled[:nu, nu:]
    C, D = scaled[nu:, :nu], scaled[nu:, nu:]
    s = -precondition.sign_p
    mass = sp.csr_matrix(sp.diags(row[nu:]) @ layout.mass_matrix()[order[nu:]][:, order[nu:]]
                         / layout.modulus)
    lumped = sp.diags(np.asarray(mass.sum(axis=1)).ravel())
    consistent = sp.csr_matrix(D - s * mass)
    modes = rigid_modes(layout.locations[order[:nu]], layout.fields[order[:nu]])
    displacements = {"AMG, Gauss-Seidel": amg(A, "gauss_seidel", layout.strength, modes, 2),
                     "AMG, Schwarz": precondition.amg_u,
                     "exact": _exact(A)}
    pressures = {"fixed-stress lumped, exact": _exact(D - s * lumped),
                 "SIMPLE, exact": _exact(D - C @ sp.diags(1 / A.diagonal()) @ B),
                 "fixed-stress, AMG Gauss-Seidel": _scaled(-s, amg(
                     -s * consistent, "gauss_seidel", layout.strength)),
                 "fixed-stress, AMG Schwarz": _scaled(-s, amg(
                     -s * consistent, "schwarz", layout.strength)),
                 "fixed-stress, exact": _exact(consistent)}
    if n_p <= true_up_to:
        true = scipy.linalg.lu_factor(D.toarray() - C @ _exact(A)(B.toarray()))
        pressures["true Schur, exact"] = lambda r: scipy.linalg.lu_solve(true, r)
    return scaled, nu, displacements, pressures


def main(argv=None):
    """Solve with each pair of block solves; return one row per size and pair
    (``iterations``, ``seconds``)."""
    from pyamg.krylov import fgmres

    made = parser(__doc__)
    made.add_argument("sizes", nargs="*", type=count, default=[3_000, 10_000],
                      help="requested node counts")
    made.add_argument("--true-up-to", type=count, default=4000,
                      help="most pressures for the dense true Schur complement")
    rows = []
    with parsed(made, argv) as args:
        for nodes in args.sizes:
            scaled, nu, displacements, pressures = blocks(nodes, args.true_up_to)
            B = scaled[:nu, nu:]
            b = np.random.default_rng(0).standard_normal(scaled.shape[0])
            print(f"{nodes} nodes: {nu} displacements, {scaled.shape[0] - nu} pressures",
                  flush=True)
            for a_name, solve_A in displacements.items():
                for p_name, solve_S in pressures.items():
                    def apply(r, solve_A=solve_A, solve_S=solve_S):
                        y_p = solve_S(r[nu:])
                        return np.concatenate([solve_A(r[:nu] - B @ y_p), y_p])

                    residuals, tic = [], time.perf_counter()
                    fgmres(scaled, b, M=spla.LinearOperator(scaled.shape, apply, dtype=float),
                           tol=1e-8, restart=RESTART, maxiter=10, residuals=residuals)
                    row = {"nodes": nodes, "displacement": a_name, "pressure": p_name,
                           "iterations": len(residuals) - 1,
                           "seconds": time.perf_counter() - tic}
                    print(f"  A {a_name:17s} S {p_name:30s}: {row['iterations']:4d} "
                          f"iterations, {row['seconds']:5.1f} s", flush=True)
                    rows.append(row)
    return rows


if __name__ == "__main__":
    main()
