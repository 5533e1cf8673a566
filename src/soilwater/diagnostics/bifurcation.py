"""Loss of uniqueness of an undrained solution: the discrete indicator and the continuum one.

An undrained body (no flow, incompressible constituents) deforms under the linearised
constraint ``B du = 0``, ``B`` the pressure-displacement block of the Newton tangent. By
Hill's (1958) sufficient condition the incremental solution is unique while the symmetric
part of the displacement block ``K`` stays positive definite on that constraint. Two
measures of how close a state is to losing it:

* :func:`restricted_eigenvalue`: the smallest eigenvalue of ``sym(K)`` on ``null(B)``,
  relative to the H1 Gram matrix of the displacement space, of a discretised body (both
  solvers record it per step with ``[diagnostics] uniqueness = true``). It passes through
  zero where a non-homogeneous increment costs no work: round-off then decides the branch.
* :func:`ellipticity`: the continuum criterion of Rudnicki and Rice (1975) for an
  incompressible (undrained) material, ``min over band normals n`` of ``t . Q(n) . t``
  with ``Q_fg = n_k A_fkgl n_l`` the acoustic tensor of the tangent ``A`` of ``J sigma
  F^-T`` (:func:`soilwater.material.kinematics.spatial_tangent`) and ``t`` the unit vector normal to
  ``n`` (an isochoric band mode; the pore pressure may jump across the band). It becomes
  zero where a shear band can form in a homogeneous state.

Both are divided by a stress (the initial P-wave modulus in the solvers) and so are
dimensionless; positive means unique (elliptic).
"""

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from soilwater.errors import require
from soilwater.physics.weakform import Coefficients

#: Unknowns (displacements) up to which :func:`restricted_eigenvalue` works densely.
DENSE_LIMIT = 3000


def restricted_eigenvalue(K, B, G):
    """Smallest ``lambda`` with ``sym(K) v = lambda G v`` for ``v`` in ``null(B)``.

    Parameters
    ----------
    K : sparse or dense matrix, shape (n, n)
        Displacement block of the tangent [force / length per unit thickness].
    B : sparse or dense matrix, shape (m, n)
        The linearised undrained constraint (pressure rows of the tangent, displacement
        columns).
    G : sparse or dense matrix, shape (n, n)
        Symmetric positive definite Gram matrix of the displacements (an H1 norm).

    Returns
    -------
    float
        ``min v^T sym(K) v / v^T G v`` over ``B v = 0``; negative once the constrained
        tangent has lost definiteness. Computed densely (null space by pivoted QR, then a
        symmetric-definite eigenproblem).

    Raises
    ------
    InputError
        Beyond :data:`DENSE_LIMIT` unknowns. (Shift-invert Lanczos on the saddle-point
        pencil ``[[sym K, B^T], [B, 0]] - lambda [[G, 0], [0, 0]]`` is not a sparse
        alternative: it can miss the smallest eigenvalue, as on 3 of 25 steps of the
        Taylor-Hood unconfined compression.)

    Examples
    --------
    A stiffness ``diag(2, -1, 3)`` constrained by ``v_0 = v_1``: on ``v = (1, 1, 0)`` the
    quotient is ``(2 - 1)/2``, on ``(0, 0, 1)`` it is 3.

    >>> K = np.diag([2.0, -1.0, 3.0])
    >>> round(restricted_eigenvalue(K, np.array([[1.0, -1.0, 0.0]]), np.eye(3)), 12)
    0.5
    """
    require(K.shape[0] <= DENSE_LIMIT, f"diagnostics.uniqueness: the tangent has "
            f"{K.shape[0]} displacement unknowns, more than the {DENSE_LIMIT} it is computed "
            "for densely: coarsen the discretisation or set diagnostics.uniqueness = false")
    return _dense(_array(K), _array(B), _array(G))


def h1_gram(weights, length):
    """Integrand of the H1 inner product of displacement fields, the Gram matrix ``G`` of
    :func:`restricted_eigenvalue`.

    ``(u, v) = int (u . v / length^2 + grad u : grad v) dOmega``, as coefficients
    ``c[m, f, s, g, t]`` of the test field f, slot s (value, d/dx, d/dy) and the trial
    field g, slot t (:class:`soilwater.physics.weakform.Coefficients`).

    Parameters
    ----------
    weights : ndarray, shape (M,)
        Integration weights [m2].
    length : float
        The length that makes the value term commensurate with the gradient term [m]
        (the solvers use the body's height).

    Returns
    -------
    soilwater.physics.weakform.Coefficients
        2 x 2 fields, the six terms ``(f, s, f, s)``: ``w / length^2`` for the value, ``w``
        for each derivative [m2 per unit thickness; the value term: dimensionless].
    """
    return Coefficients.of({(f, s, f, s): weights / length**2 if s == 0 else weights
                            for f in range(2) for s in range(3)}, (2, 2))


def _array(A):
    return A.toarray() if sp.issparse(A) else np.asarray(A, float)


def _dense(K, B, G):
    Z = _null_space(B, K.shape[0])
    S = Z.T @ (0.5 * (K + K.T)) @ Z
    return float(sla.eigh(S, Z.T @ G @ Z, eigvals_only=True, subset_by_index=[0, 0])[0])


def _null_space(B, n):
    """Orthonormal basis of ``null(B)`` from a column-pivoted QR of ``B^T`` (rank where
    ``|R_ii|`` falls below ``n eps`` times the largest; a rank-deficient B, such as one with
    spurious pressure modes, constrains less)."""
    if B.size == 0:
        return np.eye(n)
    Q, R, _ = sla.qr(B.T, pivoting=True)
    diagonal = np.abs(np.diag(R))
    rank = int(np.sum(diagonal > n * np.finfo(float).eps * diagonal.max(initial=0)))
    return Q[:, rank:]


def ellipticity(A, samples=180):
    """Rudnicki-Rice indicator of an undrained (isochoric) material: ``min_n t.Q(n).t``.

    Parameters
    ----------
    A : ndarray, shape (P, 2, 2, 2, 2)
        Tangent of ``J sigma F^-T`` with respect to the velocity gradient, indices (point,
        f, k, g, l) as in :func:`soilwater.material.kinematics.spatial_tangent` [stress].
    samples : int
        Band normals sampled over half a turn before the minimum is refined.

    Returns
    -------
    value : ndarray, shape (P,)
        The smallest ``t_f n_k A_fkgl t_g n_l`` over unit normals ``n = (cos a, sin a)``,
        ``t = (-sin a, cos a)`` [stress]; zero or negative once a band can form.
    angle : ndarray, shape (P,)
        The band normal's angle ``a`` from the x axis at the minimum [degrees, 0 to 180].

    Examples
    --------
    An isotropic incompressible solid of shear modulus 1 (``A = C`` with ``C_fkgl =
    delta_fg delta_kl + delta_fl delta_kg``): ``t.Q.t = 1`` in every direction.

    >>> d = np.eye(2)
    >>> C = np.einsum("fg,kl->fkgl", d, d) + np.einsum("fl,kg->fkgl", d, d)
    >>> value, _ = ellipticity(C[None])
    >>> round(float(value[0]), 12)
    1.0
    """
    A = np.asarray(A, float)
    angles = np.linspace(0.0, np.pi, samples, endpoint=False)
    start = angles[_quadratic(A, np.broadcast_to(angles, (len(A), samples))).argmin(1)]
    lo, hi = start - np.pi / samples, start + np.pi / samples
    ratio = (np.sqrt(5) - 1) / 2
    for _ in range(60):               # golden section on every point at once: 1e-13 rad
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        left = (_quadratic(A, a[:, None]) < _quadratic(A, b[:, None]))[:, 0]
        hi, lo = np.where(left, b, hi), np.where(left, lo, a)
    best = (lo + hi) / 2
    return _quadratic(A, best[:, None])[:, 0], np.degrees(best) % 180.0


def _quadratic(A, angles):
    """``t_f n_k A_fkgl t_g n_l`` of each point p at its angles ``angles[p]``, (P, K)."""
    n = np.stack([np.cos(angles), np.sin(angles)], -1)
    t = np.stack([-np.sin(angles), np.cos(angles)], -1)
    return np.einsum("paf,pak,pfkgl,pag,pal->pa", t, n, A, t, n)


def onset(strain, indicator):
    """The strain where an indicator first falls to zero, by linear interpolation.

    Parameters
    ----------
    strain, indicator : array_like
        The indicator along increasing strain.

    Returns
    -------
    float
        The interpolated strain of the first sign change from positive to non-positive;
        NaN when the indicator stays positive.

    Examples
    --------
    >>> round(onset([0.0, 0.1, 0.2], [2.0, 1.0, -1.0]), 12)
    0.15
    """
    strain, indicator = np.asarray(strain, float), np.asarray(indicator, float)
    below = np.flatnonzero(indicator <= 0)
    if len(below) == 0:
        return float("nan")
    k = below[0]
    if k == 0:
        return float(strain[0])
    a, b = indicator[k - 1], indicator[k]
    return float(strain[k - 1] + (strain[k] - strain[k - 1]) * a / (a - b))
