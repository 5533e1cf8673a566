"""The AMG block solves of the Krylov preconditioner: one V-cycle of smoothed aggregation.

:class:`soilwater.linalg.krylov.Krylov` inverts its displacement block and its
fixed-stress Schur complement approximately, each by one V-cycle of pyamg's
smoothed-aggregation hierarchy from a zero guess (:func:`amg`, :func:`amg_schur`).
The V-cycles smooth by symmetric Gauss-Seidel on node blocks (pyamg's default), except
where the discretisation asks for Schwarz (``Layout.smoother``): then the finest level is
smoothed by multiplicative Schwarz on overlapping aggregates
(:mod:`soilwater.linalg.krylov_schwarz`): the first coarsening's aggregates, each grown by
every unknown with at least ``OVERLAP`` of its matrix neighbours in it, solved exactly in
turn (their inverses kept), forward before the coarse correction and backward after it
(the cycle stays symmetric at half the cost of symmetric sweeps on both sides), in an
order whose independent subdomains are solved side by side on every core. Gauss-Seidel
smooths a wide MLS stencil poorly (77 FGMRES iterations against 19 at 10^4 nodes, the
Schur complement solved exactly), and P1 and Q2 elements well enough that Schwarz's
dearer sweeps do not pay (``python docs/experiments/krylov_smoother.py``).
The AMG setup runs under a fixed random seed (:func:`_seeded`), so a preconditioner, and a
run's iteration counts, repeat.
"""

from contextlib import contextmanager
from functools import partial

import numpy as np
import scipy.sparse as sp

from soilwater.linalg.krylov_schwarz import Schwarz, subdomains

#: Smallest coarse grid of the AMG hierarchies (solved by a pseudo-inverse).
MAX_COARSE = 500
#: The smoother of every level Schwarz does not smooth: symmetric Gauss-Seidel on the
#: matrix's blocks (nodes; pyamg's default).
GAUSS_SEIDEL = ("block_gauss_seidel", {"sweep": "symmetric"})


def rigid_modes(locations, fields):
    """The 2-D rigid-body modes (translations, rotation) on displacement unknowns."""
    xy = locations - locations.mean(axis=0)
    modes = np.zeros((len(xy), 3))
    modes[fields == 0, 0] = 1.0
    modes[fields == 1, 1] = 1.0
    modes[:, 2] = np.where(fields == 0, -xy[:, 1], xy[:, 0])
    return modes


def amg(A, smoother, strength, modes=None, blocksize=1):
    """One V-cycle of smoothed-aggregation AMG on ``A`` (near-null ``modes``; unknowns in
    node blocks of ``blocksize``; couplings of at least ``strength``, pyamg's symmetric
    measure), its finest level smoothed by
    :class:`~soilwater.linalg.krylov_schwarz.Schwarz` if ``smoother`` is ``"schwarz"``,
    every other level by symmetric Gauss-Seidel."""
    import pyamg

    matrix = sp.bsr_matrix(A, blocksize=(blocksize,) * 2) if blocksize > 1 else sp.csr_matrix(A)
    with _seeded():
        ml = pyamg.smoothed_aggregation_solver(matrix, B=modes, max_coarse=MAX_COARSE,
                                               strength=("symmetric", {"theta": strength}),
                                               keep=True, presmoother=GAUSS_SEIDEL,
                                               postsmoother=GAUSS_SEIDEL)
    if smoother == "schwarz" and len(ml.levels) > 1:   # one level: a coarse solve alone
        fine = ml.levels[0]
        fine.A = sp.csr_matrix(A)           # the smoother's matrix serves the cycle too
        schwarz = Schwarz(fine.A, *subdomains(fine.C, fine.AggOp, blocksize))
        fine.presmoother, fine.postsmoother = schwarz.forward, schwarz.backward
    for level in ml.levels:                 # what keep=True held for the smoother's setup
        for name in ("C", "AggOp", "T", "P0"):
            level.__dict__.pop(name, None)
    return partial(_v_cycle, ml.levels, ml.coarse_solver)


def _v_cycle(levels, coarse_solver, b, level=0):
    """One V-cycle from a zero guess on the pyamg hierarchy ``levels[level:]``: the cycle
    of ``MultilevelSolver.solve(b, maxiter=1)``, without the two finest-level residuals
    that ``solve`` computes for its stopping test (a fifth of the displacement cycle's
    time on the 10^5-node EFG tangent)."""
    if len(levels) - level == 1:
        return coarse_solver(levels[level].A, b)
    here = levels[level]
    x = np.zeros_like(b)
    here.presmoother(here.A, x, b)
    coarse_b = here.R @ (b - here.A @ x)
    x += here.P @ _v_cycle(levels, coarse_solver, coarse_b, level + 1)
    here.postsmoother(here.A, x, b)
    return x


@contextmanager
def _seeded():
    """numpy's global random state fixed (and the caller's restored after): pyamg's
    spectral-radius estimates, which weigh the prolongation smoother, start from
    ``np.random.rand`` vectors, so an unseeded setup gives a different preconditioner,
    and a different iteration count, on every run."""
    state = np.random.get_state()
    np.random.seed(0)
    try:
        yield
    finally:
        np.random.set_state(state)


def amg_schur(A, B, C, D, mass, layout):
    """One V-cycle of :func:`amg` (the ``layout``'s smoother and strength) on the
    fixed-stress Schur complement ``D - s mass``, s the sign of ``C A^-1 B`` (from its
    diagonal), multiplied by ``t = -s`` to make its diagonal positive. Returns the cycle
    of ``t S`` and t."""
    simple = sp.csr_matrix(C.multiply(B.T)) @ (1.0 / A.diagonal())
    sign = 1.0 if np.median(simple) >= 0 else -1.0
    return amg(-sign * (D - sign * mass), layout.smoother, layout.strength), -sign
