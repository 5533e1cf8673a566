"""The coupled u-p weak form at integration points, the one home of its integrand.

Both solvers discretise the same two equations on the start-of-step configuration x_n
(updated Lagrangian, backward Euler), for the displacement increment
``du`` (``F = I + grad_n(du)``, ``J = det F``) and the pore pressure ``p`` at t_(n+1):

* momentum, ``int grad_n(v) : J sigma F^-T dOmega_n + int v_y gamma'_n dOmega_n`` (minus
  the boundary's external work), with ``sigma = sigma' - alpha p I`` (tension positive,
  p compression positive) and ``gamma'_n`` the buoyant weight per start-of-step volume
  under gravity (:func:`soilwater.physics.geostatic.buoyant_weight`, a dead load on x_n);
* continuity, ``-int q [alpha (J - 1) + S (p - p_n)] dOmega_n - int grad(q) . [dt (k /
  gamma_w) grad(p) + beta grad(p - p_n)] dOmega_n`` (Darcy flux ``-(k/gamma_w) grad p``;
  k at the void ratio of ``v = v_n J`` (:meth:`soilwater.material.fluid.Fluid.mobility_at`), so the
  flux depends on the deformation; ``beta`` the optional pressure stabilisation of
  :mod:`soilwater.fem.solver`).

The other pressure stabilisation, the polynomial pressure projection of Dohrmann and
Bochev (2004), is not an integrand at points but a form over cells: ``-tau int (dp -
Pi dp)(q - Pi q)`` with ``dp = p - p_n`` and Pi the L2 projection onto cell-wise
constants (:func:`fluctuation`).

A solver supplies test and trial functions and scatters the coefficients returned here.
They are per integration point, quadrature weight included, in the layout both
assemblies use: fields ``(ux, uy, p)`` and slots ``(value, d/dx, d/dy)`` on x_n.
``residual`` gives ``r[m, f, s]``: the residual of a test function N of field f is
``sum_m sum_s N_s(x_m) r[m, f, s]``. ``tangent`` gives ``c[m, f, s, g, t]``, its exact
linearisation in the trial field g, slot t, as :class:`Coefficients`: only the terms
``(f, s, g, t)`` the weak form has (24 to 35 of the 81), never the dense array. Every
integrand a solver scatters (penalties, elasticity, Gram and mass matrices) takes that
form.
"""

from dataclasses import dataclass
from itertools import product

import numpy as np
import scipy.sparse as sp

from soilwater.material.kinematics import IDENTITY, in_plane, spatial_tangent


@dataclass(frozen=True)
class Coefficients:
    """Integrand coefficients ``c[m, f, s, g, t]`` at M points, stored by the terms in use.

    ``c`` pairs test field f, slot s with trial field g, slot t (slots: 0 value, 1 d/dx,
    2 d/dy on the integration configuration); a block's matrix entry of test function a
    and trial function b is ``sum_m sum_(f s g t) N_a,s(x_m) c[m, f, s, g, t]
    N_b,t(x_m)``. Terms not listed are zero at every point, and no array of all
    ``3 x 3`` slot pairs per point is made: 8 bytes per point and term.

    Attributes
    ----------
    terms : tuple of (int, int, int, int)
        The distinct terms ``(f, s, g, t)``.
    values : ndarray, shape (M, T)
        ``values[m, k] = c[m, *terms[k]]``, quadrature weight included (units: those of
        the integrand times m2 per unit thickness).
    fields : (int, int)
        Number of test and trial fields.

    Examples
    --------
    The mass integrand ``w u v`` of one field at two points:

    >>> c = Coefficients.of({(0, 0, 0, 0): np.array([0.5, 0.25])}, (1, 1))
    >>> c.values.shape, c.pairs, float(c.slots(0, 0)[1, 0, 0])
    ((2, 1), ((0, 0),), 0.25)
    """

    terms: tuple
    values: np.ndarray
    fields: tuple

    @classmethod
    def of(cls, terms, fields):
        """From a dict ``{(f, s, g, t): (M,) array}`` of the terms in use."""
        return cls(tuple(terms), np.stack([np.asarray(v, dtype=float)
                                           for v in terms.values()], axis=1), tuple(fields))

    def columns(self):
        """The terms as a dict ``{(f, s, g, t): (M,) view of values}``."""
        return dict(zip(self.terms, self.values.T))

    def block(self, test, trial):
        """The coefficients of the test fields ``test`` and trial fields ``trial`` (ranges
        of field indices), renumbered from 0; their values are copied (M, T_block)."""
        keep = [k for k, (f, _, g, _) in enumerate(self.terms) if f in test and g in trial]
        terms = tuple((f - test.start, s, g - trial.start, t)
                      for f, s, g, t in (self.terms[k] for k in keep))
        return Coefficients(terms, self.values[:, keep], (len(test), len(trial)))

    @property
    def pairs(self):
        """The field pairs ``(f, g)`` with at least one term, sorted."""
        return tuple(sorted({(f, g) for f, _, g, _ in self.terms}))

    def slots(self, f, g):
        """``c[:, f, :, g, :]``: the (M, 3, 3) slot matrix of one field pair (zero where no
        term): 9 values per point, one pair at a time."""
        out = np.zeros((len(self.values), 3, 3))
        for (tf, s, tg, t), column in self.columns().items():
            if (tf, tg) == (f, g):
                out[:, s, t] = column
        return out


def total_stress(effective, p, fluid):
    """``sigma' - alpha p I`` per point, (M, 4) (tension positive; p compression positive)."""
    return effective - fluid.biot_alpha * np.asarray(p)[:, None] * IDENTITY


def residual(total, J, Finv, w, p, p_n, grad_p, fluid, dt, beta=0.0, grad_p_n=None,
             v_n=1.0, weight=0.0):
    """Residual coefficients ``r[m, f, s]``, (M, 3, 3).

    Parameters
    ----------
    total : ndarray, shape (M, 4)
        Total Cauchy stress at t_(n+1) (:func:`total_stress`).
    J, Finv : ndarray, shapes (M,) and (M, 2, 2)
        ``det F`` and ``F^-1`` of the increment.
    w : ndarray, shape (M,)
        Quadrature weights on x_n [m2].
    p, p_n : ndarray, shape (M,)
        Pore pressure at t_(n+1) and t_n [kPa].
    grad_p : ndarray, shape (M, 2)
        Gradient of p on x_n [kPa/m]; ``grad_p_n`` that of p_n (needed when beta > 0).
    fluid : Fluid
        Biot alpha, storage S [1/kPa], mobility k/gamma_w [m2/(kPa s)] and its law.
    dt : float
        Time step [s].
    beta : float
        Pressure stabilisation [m2/kPa] (0: none).
    v_n : float or ndarray, shape (M,)
        Specific volume ``1 + e`` at t_n (read by a void-ratio-dependent permeability).
    weight : float or ndarray, shape (M,)
        Buoyant unit weight gamma'_n at t_n [kN/m3] (0 without gravity).
    """
    r = np.zeros((len(w), 3, 3))
    r[:, :2, 1:] = (w * J)[:, None, None] * in_plane(total) @ np.swapaxes(Finv, 1, 2)
    r[:, 1, 0] = w * weight
    r[:, 2, 0] = -w * (fluid.biot_alpha * (J - 1) + fluid.storage * (p - p_n))
    mobility, _ = fluid.mobility_at(v_n * J)
    flux = dt * mobility[:, None] * grad_p
    if beta:
        flux = flux + beta * (grad_p - grad_p_n)
    r[:, 2, 1:] = -w[:, None] * flux
    return r


def tangent(C, effective, total, J, Finv, w, fluid, dt, beta=0.0, v_n=1.0, grad_p=None):
    """Tangent coefficients ``c[m, f, s, g, t]`` as :class:`Coefficients` of 3 x 3 fields.

    The momentum block is :func:`soilwater.material.kinematics.spatial_tangent` (material tangent C,
    Jaumann rotation of sigma', change of area and orientation) pulled back to x_n
    gradients; the coupling ``-alpha J F^-T``; storage ``-S`` and flow ``-(dt k/gamma_w +
    beta)``; with a void-ratio-dependent k, the flux's change with the deformation
    through ``dk/dv v_n dJ``, ``dJ = J F^-T : d grad_n(du)`` (``grad_p`` then needed).
    The buoyant weight is a dead load on x_n and adds nothing. Arguments as in
    :func:`residual`, with C the material's consistent tangent (M, 4, 4) and
    ``effective`` the effective stress (M, 4). The one approximation: the Jaumann
    rotation acts on sigma' at t_(n+1) rather than on the rotated start-of-step stress, a
    difference of the order of the strain increment.

    Terms: the 16 momentum ones ``(f, 1 + i, g, 1 + j)`` of the displacements f, g < 2;
    the 4 + 4 couplings ``(f, 1 + i, 2, 0)`` and ``(2, 0, f, 1 + i)``; storage ``(2, 0,
    2, 0)`` when S is not 0; flow ``(2, 1, 2, 1)`` and ``(2, 2, 2, 2)`` when it is not
    0 anywhere; and the 8 flux terms ``(2, 1 + i, g, 1 + j)`` when k depends on the void
    ratio. Units (w in m2): kPa m2 (momentum), m2 (coupling), m2/kPa (storage), m4/kPa
    (flow), m3 (flux).
    """
    wJ = w * J
    Finv_T = np.swapaxes(Finv, 1, 2)                                     # (m, f, k)
    momentum = _pulled_back(
        wJ[:, None, None, None, None] * spatial_tangent(C, in_plane(effective),
                                                       in_plane(total)), Finv)
    terms = {(f, 1 + i, g, 1 + j): momentum[:, f, i, g, j]
             for f, i, g, j in product(range(2), repeat=4)}
    coupling = -fluid.biot_alpha * wJ[:, None, None] * Finv_T
    for f, i in product(range(2), repeat=2):
        terms[f, 1 + i, 2, 0] = terms[2, 0, f, 1 + i] = coupling[:, f, i]
    if fluid.storage:
        terms[2, 0, 2, 0] = -fluid.storage * w
    mobility, slope = fluid.mobility_at(v_n * J)
    flow = -(dt * mobility + beta) * w
    if flow.any():
        terms[2, 1, 2, 1] = terms[2, 2, 2, 2] = flow
    if slope.any():
        dflux = -dt * w * slope * v_n * J
        for i, g, j in product(range(2), repeat=3):
            terms[2, 1 + i, g, 1 + j] = dflux * (grad_p[:, i] * Finv_T[:, g, j])
    return Coefficients.of(terms, (3, 3))


def _pulled_back(A, Finv):
    """``A[m, f, k, g, l]`` on current gradients -> on x_n gradients: ``Finv[m, i, k]
    A[m, f, k, g, l] Finv[m, j, l]`` as batched matrix products."""
    M = len(A)
    right = A.reshape(M, 8, 2) @ np.swapaxes(Finv, 1, 2)               # (m, f k g, j)
    left = Finv[:, None] @ right.reshape(M, 2, 2, 4)                   # (m, f, i, g j)
    return left.reshape(M, 2, 2, 2, 2)


def fluctuation(phi, w, cell):
    """The cell-fluctuation form ``int (p - Pi p)(q - Pi q) dOmega`` [m2], Pi the L2
    projection onto constants on each cell (Dohrmann and Bochev 2004).

    Parameters
    ----------
    phi : sparse matrix, shape (M, N)
        Pressure shape functions at the integration points.
    w : ndarray, shape (M,)
        Quadrature weights [m2].
    cell : ndarray of int, shape (M,)
        The cell each point belongs to.

    Returns
    -------
    sparse matrix, shape (N, N)
        Symmetric, positive semi-definite; zero on fields that are constant on every
        cell: ``phi^T W phi - A^T |c|^-1 A`` with ``A = int_c phi`` per cell.

    Examples
    --------
    Two 1-D cells [0, 1] and [1, 2], hat functions at x = 0, 1, 2 and the two-point Gauss
    rule: the field 1, 1, 1 is constant on both cells, so it is in the null space.

    >>> x = 0.5 + np.array([-1, 1]) / (2 * np.sqrt(3))
    >>> hats = np.column_stack([1 - x, x, 0 * x])
    >>> phi = sp.csr_matrix(np.vstack([hats, np.roll(hats, 1, axis=1)]))
    >>> F = fluctuation(phi, np.full(4, 0.5), np.array([0, 0, 1, 1]))
    >>> bool(np.allclose(F @ np.ones(3), 0)), round(float(F[1, 1]), 4)
    (True, 0.1667)
    """
    phi = sp.csr_matrix(phi)
    cell = np.asarray(cell)
    rows = sp.csr_matrix((w, (cell, np.arange(len(w)))), shape=(cell.max() + 1, len(w)))
    A = rows @ phi
    area = np.asarray(rows.sum(axis=1)).ravel()
    mass = phi.T @ sp.diags(w) @ phi
    return (mass - A.T @ sp.diags(1.0 / area) @ A).tocsr()
