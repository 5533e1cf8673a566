"""The numerical inf-sup test of a displacement-pressure pair (Chapelle and Bathe 1993).

A pair (V_h, Q_h) is stable for incompressible and undrained problems when

``beta_h = inf_q sup_v int q div v / (|v|_V |q|_Q)``

stays bounded away from zero as the discretisation is refined. With the matrices of the
three forms,

* ``S``: the H1 inner product of displacements (:func:`soilwater.diagnostics.bifurcation.h1_gram`),
* ``B``: ``int q div v`` (pressure rows, displacement columns),
* ``T``: the L2 inner product of pressures,

``beta_h^2`` is the smallest non-zero eigenvalue of ``B S^-1 B^T q = lambda T q``; the
eigenvalues at zero are the pressure modes that no displacement sees (spurious modes).
The test is discretisation-free: a method supplies the three matrices from its own shape
functions and quadrature (:mod:`soilwater.diagnostics.pairs`).

Chapelle, D. and Bathe, K. J. (1993), "The inf-sup test", Computers & Structures 47,
537-545.
"""

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.diagnostics.bifurcation import h1_gram
from soilwater.physics.weakform import Coefficients

#: Eigenvalues ``lambda`` below this fraction of the largest are zero modes (beta below
#: about 1e-3 of its largest value): far below the smallest non-zero value of the pairs
#: the test is for (beta^2 of P1/P1 at 33 x 33 nodes is 2e-3) and far above round-off.
ZERO = 1e-6


def coefficients(weights, length, perturbation=0.0):
    """Integrand coefficients of ``S``, ``B``, ``T`` and a stabilisation ``C``, as
    :class:`soilwater.physics.weakform.Coefficients` ``c[m, f, s, g, t]`` (slots value, d/dx, d/dy).

    Parameters
    ----------
    weights : ndarray, shape (M,)
        Integration weights [m2].
    length : float
        Length scale of the H1 norm's value term [m]
        (:func:`soilwater.diagnostics.bifurcation.h1_gram`).
    perturbation : float
        A flow-equation perturbation ``beta`` times the stiffness that scales ``S`` [m2]
        (``h^2 / 4`` for :attr:`soilwater.physics.scales.Scales.perturbation`); 0 without one.

    Returns
    -------
    gram : Coefficients
        2 x 2 fields (:func:`soilwater.diagnostics.bifurcation.h1_gram`).
    divergence : Coefficients
        1 x 2 fields, ``q div v``: pressure value against displacement gradients.
    mass : Coefficients
        1 x 1 field, ``p q``.
    stabilisation : Coefficients
        1 x 1 field, ``perturbation grad p . grad q``.
    """
    divergence = Coefficients.of({(0, 0, f, 1 + f): weights for f in range(2)}, (1, 2))
    mass = Coefficients.of({(0, 0, 0, 0): weights}, (1, 1))
    stabilisation = Coefficients.of({(0, s, 0, s): perturbation * weights for s in (1, 2)},
                                    (1, 1))
    return h1_gram(weights, length), divergence, mass, stabilisation


def inf_sup(S, B, T, Z=None, hydrostatic=False, C=None):
    """The inf-sup value and the spurious pressure modes of one discretisation.

    Parameters
    ----------
    S : sparse matrix, shape (n, n)
        H1 Gram matrix of the displacements.
    B : sparse matrix, shape (m, n)
        ``int q div v``.
    T : sparse matrix, shape (m, m)
        Pressure mass matrix.
    Z : sparse or dense matrix, shape (n, k), optional
        A basis of the displacement subspace to test on (e.g. ``v = 0`` on the boundary);
        the whole space by default.
    hydrostatic : bool
        The constant pressure (the coefficient vector of ones: both methods reproduce
        constants) is a zero mode by construction (``v = 0`` on the whole boundary): the
        test then runs on the pressures of zero mean, the quotient space of Chapelle and
        Bathe.
    C : sparse matrix, shape (m, m), optional
        A pressure stabilisation, added to the Schur complement ``B S^-1 B^T`` (in the
        units of ``S``, i.e. divided by the stiffness that scales ``S``).

    Returns
    -------
    beta : float
        ``sqrt`` of the smallest eigenvalue above :data:`ZERO` times the largest (0 when
        there is none).
    zero_modes : int
        Eigenvalues below it.

    Examples
    --------
    One pressure value against two displacement unknowns, ``B = [1, 0]``, ``S = 4 I``:
    ``beta^2 = 1/4``.

    >>> import scipy.sparse as sp
    >>> inf_sup(4 * sp.eye(2), sp.csr_matrix([[1.0, 0.0]]), sp.eye(1))
    (0.5, 0)
    """
    T = _dense(T)
    W = sla.null_space(T.sum(axis=0)[None]) if hydrostatic else np.eye(len(T))
    if Z is not None:
        if Z.shape[1] == 0:                 # no displacement to test with
            return 0.0, W.shape[1]
        S, B = Z.T @ (S @ Z), B @ Z
    B = W.T @ _dense(B)
    if sp.issparse(S):
        X = spla.splu(sp.csc_matrix(S)).solve(B.T)
    else:
        X = sla.cho_solve(sla.cho_factor(S), B.T)
    A = B @ X + (0 if C is None else W.T @ _dense(C) @ W)
    lam = sla.eigh((A + A.T) / 2, W.T @ T @ W, eigvals_only=True)
    zero = lam <= ZERO * max(lam.max(), 0.0)
    beta = float(np.sqrt(lam[~zero].min())) if (~zero).any() else 0.0
    return beta, int(zero.sum())


def _dense(A):
    return A.toarray() if sp.issparse(A) else np.asarray(A)
