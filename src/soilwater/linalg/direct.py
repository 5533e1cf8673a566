"""SuperLU, the direct back-end that is always available, and what direct factors share.

``scipy.sparse.linalg.splu`` with minimum-degree ordering on ``A^T A``
(:data:`SUPERLU_ORDERING`), single-threaded. Its fill grows fast with the 20 to 30
neighbours of an MLS node, so it is slow on large EFG tangents (``make bench`` measures
it against PARDISO, :mod:`soilwater.linalg.pardiso`). It has no symmetric mode: it
factorises ``K`` whatever :func:`soilwater.linalg.backends.factorise` is asked.
"""

import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.errors import ConvergenceError

#: SuperLU's column ordering (``permc_spec``): minimum degree on ``A^T A``. On the first
#: tangent of the bench step it factorised EFG's 2.6 times faster than scipy's default,
#: COLAMD, at 10^4 nodes (8.4 s against 21.3 s, a quarter less fill) and 1.7 times at
#: 3 x 10^3, P1/P1's 1.5 and Q2/Q1's 1.1 to 1.35 times; Taylor-Hood's as fast at 3 x 10^3
#: and 11 % slower at 10^4 (``python docs/experiments/direct_orderings.py``).
SUPERLU_ORDERING = "MMD_ATA"


class _Factor:
    """What the direct factorisations share: no Krylov iterations, one factorisation
    (PARDISO's single precision may add a second,
    :class:`soilwater.linalg.pardiso._Pardiso`), and a factorisation
    solves only with the tangent it factorised (``current`` False; :meth:`adopt`)."""

    iterations, factorisations, single, current = 0, 1, False, False

    def adopt(self, K):
        """False: a new tangent needs a new factorisation."""
        return False

    def release(self):
        """Nothing: a factorisation holds no tangent Newton could free."""


class _SuperLU(_Factor):
    """SuperLU's LU factorisation of ``K`` (it has no symmetric mode)."""

    backend, symmetric, perturbed_pivots, flops = "superlu", False, 0, 0.0

    def __init__(self, K):
        try:
            self.lu = spla.splu(sp.csc_matrix(K), permc_spec=SUPERLU_ORDERING)
        except RuntimeError as err:
            raise ConvergenceError(f"the tangent is singular ({err})") from None

    def solve(self, b, rtol=None):
        return self.lu.solve(b)
