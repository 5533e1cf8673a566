"""The coupled u-p weak form at integration points, the one home of its integrand.

Both solvers discretise the same two equations on the start-of-step configuration x_n
(updated Lagrangian, backward Euler), for the displacement increment
``du`` (``F = I + grad_n(du)``, ``J = det F``) and the pore pressure ``p`` at t_(n+1):

* momentum, ``int grad_n(v) : J sigma F^-T dOmega_n + int v_y gamma'_n dOmega_n`` (minus
  the boundary's external work), with ``sigma = sigma' - alpha p I`` (tension positive,
  p compression positive) and ``gamma'_n`` the buoyant weight per start-of-step volume
  under gravity (:func:`soil.geostatic.buoyant_weight`, a dead load on x_n);
* continuity, ``-int q [alpha (J - 1) + S (p - p_n)] dOmega_n - int grad(q) . [dt (k /
  gamma_w) grad(p) + beta grad(p - p_n)] dOmega_n`` (Darcy flux ``-(k/gamma_w) grad p``;
  k at the void ratio of ``v = v_n J`` (:meth:`soil.case.Fluid.mobility_at`), so the
  flux depends on the deformation; ``beta`` the optional pressure stabilisation of
  :mod:`fem_reference.solver`).

The other pressure stabilisation, the polynomial pressure projection of Dohrmann and
Bochev (2004), is not an integrand at points but a form over cells: ``-tau int (dp -
Pi dp)(q - Pi q)`` with ``dp = p - p_n`` and Pi the L2 projection onto cell-wise
constants (:func:`fluctuation`).

A solver supplies test and trial functions and scatters the coefficients returned here.
They are per integration point, quadrature weight included, in the layout both
assemblies use: fields ``(ux, uy, p)`` and slots ``(value, d/dx, d/dy)`` on x_n.
``residual`` gives ``r[m, f, s]``: the residual of a test function N of field f is
``sum_m sum_s N_s(x_m) r[m, f, s]``. ``tangent`` gives ``c[m, f, s, g, t]``, its exact
linearisation in the trial field g, slot t.
"""

import numpy as np
import scipy.sparse as sp

from soil.kinematics import IDENTITY, in_plane, spatial_tangent


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
    """Tangent coefficients ``c[m, f, s, g, t]``, (M, 3, 3, 3, 3).

    The momentum block is :func:`soil.kinematics.spatial_tangent` (material tangent C,
    Jaumann rotation of sigma', change of area and orientation) pulled back to x_n
    gradients; the coupling ``-alpha J F^-T``; storage ``-S`` and flow ``-(dt k/gamma_w +
    beta)``; with a void-ratio-dependent k, the flux's change with the deformation
    through ``dk/dv v_n dJ``, ``dJ = J F^-T : d grad_n(du)`` (``grad_p`` then needed).
    The buoyant weight is a dead load on x_n and adds nothing. Arguments as in
    :func:`residual`, with C the material's consistent tangent (M, 4, 4) and
    ``effective`` the effective stress (M, 4). The one approximation: the Jaumann
    rotation acts on sigma' at t_(n+1) rather than on the rotated start-of-step stress, a
    difference of the order of the strain increment.
    """
    wJ = w * J
    A = spatial_tangent(C, in_plane(effective), in_plane(total))
    c = np.zeros((len(w), 3, 3, 3, 3))
    c[:, :2, 1:, :2, 1:] = _pulled_back(wJ[:, None, None, None, None] * A, Finv)
    c[:, :2, 1:, 2, 0] = -fluid.biot_alpha * wJ[:, None, None] * np.swapaxes(Finv, 1, 2)
    c[:, 2, 0, :2, 1:] = c[:, :2, 1:, 2, 0]
    c[:, 2, 0, 2, 0] = -fluid.storage * w
    mobility, slope = fluid.mobility_at(v_n * J)
    c[:, 2, 1, 2, 1] = c[:, 2, 2, 2, 2] = -(dt * mobility + beta) * w
    if slope.any():
        dflux = (dt * w * slope * v_n * J)[:, None, None, None] * (
            grad_p[:, :, None, None] * np.swapaxes(Finv, 1, 2)[:, None])
        c[:, 2, 1:, :2, 1:] = -dflux
    return c


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
