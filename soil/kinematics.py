"""Stretching, spin and the objective (Jaumann) rotation of stress, on arrays of points.

Vectors of four components describe plane-strain symmetric tensors:

* stress-like vectors ``(xx, yy, zz, xy)`` (tensor components);
* strain-like vectors ``(xx, yy, zz, 2xy)`` (Voigt, engineering shear), so that
  ``sigma : eps == stress_vec @ strain_vec``.

The in-plane spin is the scalar ``w = W_xy = (L_xy - L_yx) / 2`` with
``L_ij = d v_i / d x_j``.
"""

import numpy as np

#: The identity as a stress-like vector, ``m = (1, 1, 1, 0)``.
IDENTITY = np.array([1.0, 1.0, 1.0, 0.0])

#: Deviatoric projector mapping a strain-like vector to a stress-like one: ``dev(eps)``.
DEVIATORIC = np.array([
    [2 / 3, -1 / 3, -1 / 3, 0.0],
    [-1 / 3, 2 / 3, -1 / 3, 0.0],
    [-1 / 3, -1 / 3, 2 / 3, 0.0],
    [0.0, 0.0, 0.0, 0.5],
])


def stretching_and_spin(L):
    """Split velocity gradients into stretching and spin.

    Parameters
    ----------
    L : array_like, shape (..., 3, 3)
        Velocity gradients ``L_ij = d v_i / d x_j`` [1/time]; only the in-plane block
        and ``L_zz`` are used (plane strain has no out-of-plane shear).

    Returns
    -------
    D : ndarray, shape (..., 4)
        Stretching as a strain-like vector ``(D_xx, D_yy, D_zz, 2 D_xy)``.
    w : ndarray, shape (...)
        In-plane spin ``W_xy``.
    """
    L = np.asarray(L, dtype=float)
    D = np.stack([L[..., 0, 0], L[..., 1, 1], L[..., 2, 2], L[..., 0, 1] + L[..., 1, 0]], axis=-1)
    return D, 0.5 * (L[..., 0, 1] - L[..., 1, 0])


def hughes_winget(stress, dw):
    """Rotate stresses by the Hughes-Winget increment ``R = (I - dW/2)^-1 (I + dW/2)``.

    Parameters
    ----------
    stress : ndarray, shape (N, 4)
        Stress-like vectors at the start of the step.
    dw : ndarray, shape (N,) or scalar
        Spin increment ``W_xy dt`` over the step.

    Returns
    -------
    ndarray, shape (N, 4)
        ``R sigma R^T``; the invariants p', q are unchanged.
    """
    a = 0.5 * np.asarray(dw, dtype=float)
    c = (1.0 - a**2) / (1.0 + a**2)
    s = 2.0 * a / (1.0 + a**2)
    return rotate(stress, c, s)


def rotate(stress, c, s):
    """Return ``R sigma R^T`` for the in-plane rotation ``R = [[c, s], [-s, c]]``."""
    sxx, syy, szz, sxy = np.moveaxis(np.asarray(stress, dtype=float), -1, 0)
    return np.stack([
        c * c * sxx + 2 * c * s * sxy + s * s * syy,
        s * s * sxx - 2 * c * s * sxy + c * c * syy,
        szz,
        (c * c - s * s) * sxy + c * s * (syy - sxx),
    ], axis=-1)


def rotate_strain(strain, c, s):
    """Rotate strain-like vectors ``(xx, yy, zz, 2xy)`` by ``R = [[c, s], [-s, c]]``."""
    e = np.array(strain, dtype=float)
    e[..., 3] *= 0.5
    e = rotate(e, c, s)
    e[..., 3] *= 2.0
    return e


def invariants(stress):
    """Mean effective stress and deviator stress, compression positive.

    Parameters
    ----------
    stress : ndarray, shape (..., 4)
        Stress-like vectors, tension positive.

    Returns
    -------
    p : ndarray
        ``p' = -tr(sigma) / 3``.
    q : ndarray
        ``q = sqrt(3/2 s:s)``.
    """
    stress = np.asarray(stress, dtype=float)
    p = -stress[..., :3].sum(axis=-1) / 3.0
    s = deviator(stress)
    return p, np.sqrt(1.5 * double_dot(s, s))


def deviator(stress):
    """Deviatoric part of stress-like vectors."""
    s = np.array(stress, dtype=float)
    s[..., :3] -= s[..., :3].mean(axis=-1, keepdims=True)
    return s


def double_dot(a, b):
    """``a : b`` for two stress-like vectors (shear counted twice)."""
    return (a[..., :3] * b[..., :3]).sum(axis=-1) + 2.0 * a[..., 3] * b[..., 3]


def as_strain_like(t):
    """Turn stress-like (tensor) components into strain-like ones (shear doubled)."""
    t = np.array(t, dtype=float)
    t[..., 3] *= 2.0
    return t
