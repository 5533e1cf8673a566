"""The iterative back-end of :mod:`soilwater.linalg.backends`: block-preconditioned FGMRES.

``SOILWATER_LINEAR_SOLVER=krylov`` replaces the factorisation of a Newton tangent

.. math::

    K = \\begin{bmatrix} A & B \\\\ C & D \\end{bmatrix}
    \\quad (A: \\text{displacements}, D: \\text{pore pressures})

by a preconditioner, and each solve by flexible GMRES (``pyamg.krylov.fgmres``, right
preconditioned, so the residual it stops on is the true one). The preconditioner is block
upper triangular,

.. math::

    P^{-1} r: \\quad y_p = \\hat S^{-1} r_p, \\qquad y_u = \\hat A^{-1} (r_u - B y_p),

with one V-cycle of smoothed-aggregation AMG (pyamg) for each block solve:
:math:`\\hat A^{-1}` with rigid-body near-null modes from the unknowns' locations (2 x 2
node blocks when every node carries both displacements), :math:`\\hat S^{-1}` on the
fixed-stress Schur complement

.. math::

    \\hat S = D - s \\, M_p / M,

``M_p`` the pressure mass matrix (``int N_i N_j dV``), ``M`` the P-wave modulus of the
initial state and ``s`` the sign of :math:`C A^{-1} B` (read from its diagonal
:math:`\\sum_j C_{ij} B_{ji} / A_{jj}`). It needs no permeability: at ``k = 0`` the
stabilisation of a stabilised pair is what ``D`` holds, and the mass term keeps
:math:`\\hat S` definite where ``D`` vanishes. EFG's ``M_p`` is the consistent matrix:
its MLS functions overlap so widely that the lumped mass overstates rough pressure modes
(with exact block solves FGMRES takes 319 iterations with it at 10^4 nodes, 11 with the
consistent one: ``python docs/experiments/schur.py``).

Unknowns of neither field (a rigid plate's settlement, the mean-pressure multiplier) are
eliminated exactly through the preconditioner (a dense Schur complement of their few
rows). The V-cycles and their smoothers are :mod:`soilwater.linalg.krylov_amg` and
:mod:`soilwater.linalg.krylov_schwarz`.

Rows are scaled by the residual scales of :class:`soilwater.physics.scales.Scales` (force
or volume per unit thickness), so the relative residual FGMRES stops on weighs equilibrium
and continuity as the Newton tolerance does.
"""

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.errors import ConvergenceError, InputError
from soilwater.linalg.krylov_amg import amg, amg_schur, rigid_modes

#: FGMRES restart length (Krylov vectors kept).
RESTART = 60
#: FGMRES iterations of one solve. A solve that has not reached its tolerance by then
#: still returns its correction if it at least halved the residual (Newton judges it);
#: otherwise it fails.
MAX_ITERATIONS = 600
#: Relative residual above which an unfinished solve fails.
NO_PROGRESS = 0.5


class Krylov:
    """The preconditioner of one tangent, and FGMRES solves with it.

    Parameters
    ----------
    K : scipy.sparse matrix, shape (n, n)
    layout : soilwater.linalg.layout.Layout

    Attributes
    ----------
    iterations : int
        FGMRES iterations of all solves so far.
    backend : str
        ``"krylov"`` (:func:`soilwater.linalg.backends.backend`).
    factorisations, symmetric, single, perturbed_pivots, flops
        1, False, False, 0 and 0.0: the counts :func:`soilwater.nonlinear.newton.newton` keeps of a
        factorisation (one preconditioner build).
    current : bool
        True: solves are as cheap with the current tangent as with the first, so Newton
        hands it over at every iteration (:meth:`adopt`) and converges as Newton, not
        as modified Newton.
    """

    backend, symmetric, perturbed_pivots, flops, current = "krylov", False, 0, 0.0, True
    factorisations, single = 1, False

    def __init__(self, K, layout):
        if layout is None or not layout.complete:
            raise InputError("SOILWATER_LINEAR_SOLVER=krylov needs a solver that describes "
                             "its unknowns (fields, locations, scales, pressure mass); use "
                             "pardiso or superlu here")
        fields, blocked = layout.fields, _node_blocked(layout)
        u = blocked[np.isin(fields[blocked], (0, 1))]
        p, other = np.flatnonzero(fields == 2), np.flatnonzero(fields < 0)
        self.order, self.sizes = np.concatenate([u, p, other]), (len(u), len(p))
        self.row = 1.0 / layout.scales[self.order]
        self.iterations = 0
        nu, nm = len(u), len(u) + len(p)
        scaled = sp.csr_matrix(sp.diags(self.row) @ _permuted(sp.csr_matrix(K), self.order))
        A, self.B, self.F = scaled[:nu, :nu], scaled[:nu, nu:nm], scaled[nm:, :nm]
        border, corner = scaled[:nm, nm:].toarray(), scaled[nm:, nm:].toarray()
        C, D = scaled[nu:nm, :nu], scaled[nu:nm, nu:nm]
        del scaled                                    # the blocks only, from here
        mass = sp.diags(self.row[nu:nm]) @ layout.mass_matrix()[p][:, p] / layout.modulus
        self.amg_p, self.sign_p = amg_schur(A, self.B, C, D, mass, layout)
        del C, D, mass
        self.amg_u = amg(A, layout.smoother, layout.strength,
                          rigid_modes(layout.locations[u], fields[u]),
                          2 if _pairs(layout, u) else 1)
        del A
        if len(other):
            self.Z = np.column_stack([self._main(e) for e in border.T])
            self.schur = np.linalg.inv(corner - self.F @ self.Z)
        self.adopt(K)

    def adopt(self, K):
        """Solve with the tangent ``K`` from now on, keeping the preconditioner (built
        from the first tangent of the Newton step: within a step the tangent changes
        little). Returns True."""
        self.K = sp.csr_matrix(K)
        return True

    def release(self):
        """Drop the tangent (the preconditioner stays) until the next :meth:`adopt`:
        Newton calls it before it assembles the next tangent, so that two are never held
        at once."""
        self.K = None

    def _matvec(self, x):
        """The scaled, reordered tangent times ``x``."""
        y = np.empty_like(x)
        y[self.order] = x
        return self.row * (self.K @ y)[self.order]

    def _main(self, r):
        """The block-triangular preconditioner on displacement and pressure rows."""
        nu = self.sizes[0]
        y_p = self.amg_p(self.sign_p * r[nu:])
        return np.concatenate([self.amg_u(r[:nu] - self.B @ y_p), y_p])

    def _apply(self, r):
        """The preconditioner: :meth:`_main`, the other unknowns eliminated exactly."""
        nm = sum(self.sizes)
        y = self._main(r[:nm])
        if nm == len(r):
            return y
        y_o = self.schur @ (r[nm:] - self.F @ y)
        return np.concatenate([y - self.Z @ y_o, y_o])

    def solve(self, b, rtol=1e-10):
        """FGMRES on ``K x = b`` to the relative residual ``rtol`` of the scaled rows.

        Raises
        ------
        ConvergenceError
            Relative residual above :data:`NO_PROGRESS` after :data:`MAX_ITERATIONS`
            iterations (a near-singular tangent: a limit point, a mechanism).
        """
        from pyamg.krylov import fgmres

        residuals = []
        x, _ = fgmres(spla.LinearOperator(self.K.shape, self._matvec),
                      self.row * np.asarray(b, float)[self.order],
                      M=spla.LinearOperator(self.K.shape, self._apply), tol=rtol,
                      restart=min(RESTART, self.K.shape[0]),    # pyamg's own cap, unwarned
                      maxiter=-(-MAX_ITERATIONS // RESTART),
                      residuals=residuals)
        self.iterations += len(residuals) - 1
        if residuals[0] and residuals[-1] > max(1.01 * rtol, NO_PROGRESS) * residuals[0]:
            raise ConvergenceError(f"FGMRES relative residual {residuals[-1] / residuals[0]:.1e}"
                                   f" after {len(residuals) - 1} iterations (wanted "
                                   f"{rtol:.1e})")
        out = np.empty_like(x)
        out[self.order] = x
        return out


def _permuted(K, order):
    """``K[order][:, order]`` of a CSR matrix, its column indices sorted: the columns
    renumbered rather than indexed (0.6 s against scipy's 1.4 s on the 10^5-node bench
    tangent)."""
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    permuted = sp.csr_matrix((K.data, rank[K.indices], K.indptr), shape=K.shape)[order]
    permuted.sort_indices()
    return permuted


def _node_blocked(layout):
    """All unknowns, sorted by group (node) then field, when groups are known."""
    n = len(layout.fields)
    if layout.groups is None:
        return np.arange(n)
    return np.lexsort((layout.fields, layout.groups))


def _pairs(layout, u):
    """True if the displacement unknowns ``u`` come as (x, y) pairs of one node each."""
    if layout.groups is None or len(u) % 2:
        return False
    g, f = layout.groups[u], layout.fields[u]
    return bool(np.all(g[0::2] == g[1::2]) and np.all(f[0::2] == 0) and np.all(f[1::2] == 1))
