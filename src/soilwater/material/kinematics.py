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


#: Voigt strain component of (displacement field f, spatial derivative k): ``B[f, k, :]``.
GRADIENT_TO_VOIGT = np.zeros((2, 2, 4))
GRADIENT_TO_VOIGT[0, 0, 0] = GRADIENT_TO_VOIGT[1, 1, 1] = 1.0
GRADIENT_TO_VOIGT[0, 1, 3] = GRADIENT_TO_VOIGT[1, 0, 3] = 1.0


def in_plane(stress):
    """The in-plane block (P, 2, 2) of stress-like vectors (P, 4)."""
    return np.stack([np.stack([stress[:, 0], stress[:, 3]], 1),
                     np.stack([stress[:, 3], stress[:, 1]], 1)], 1)


def cauchy_traction(stress, normal):
    """The traction ``sigma n`` (..., 2) of stress-like vectors (..., 4) on unit normals
    (..., 2), leading axes broadcast.

    Examples
    --------
    >>> cauchy_traction(np.array([-2.0, -1.0, -1.0, 0.5]), np.array([[0.0, 1.0]]))
    array([[ 0.5, -1. ]])
    """
    stress, normal = np.asarray(stress), np.asarray(normal)
    return np.stack([stress[..., 0] * normal[..., 0] + stress[..., 3] * normal[..., 1],
                     stress[..., 3] * normal[..., 0] + stress[..., 1] * normal[..., 1]],
                    axis=-1)


def determinant(A):
    """Determinant of each 2 x 2 matrix, in closed form (numpy's batched LAPACK call costs
    twenty times more on small matrices).

    Parameters
    ----------
    A : ndarray, shape (..., 2, 2)

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    >>> float(determinant(np.array([[2.0, 1.0], [1.0, 3.0]])))
    5.0
    """
    return A[..., 0, 0] * A[..., 1, 1] - A[..., 0, 1] * A[..., 1, 0]


def inverse(A):
    """Inverse of each 2 x 2 matrix, in closed form (the adjugate over the determinant).

    Parameters
    ----------
    A : ndarray, shape (..., 2, 2)
        Regular matrices: a singular one gives infinite or NaN entries.

    Returns
    -------
    ndarray, shape (..., 2, 2)

    Examples
    --------
    >>> A = np.array([[2.0, 1.0], [1.0, 3.0]])
    >>> bool(np.allclose(inverse(A) @ A, np.eye(2)))
    True
    """
    adjugate = np.stack([np.stack([A[..., 1, 1], -A[..., 0, 1]], -1),
                         np.stack([-A[..., 1, 0], A[..., 0, 0]], -1)], -2)
    return adjugate / determinant(A)[..., None, None]


def strain_increment(H, J):
    """Midpoint stretching increment and spin of a step from its displacement gradient.

    Parameters
    ----------
    H : ndarray, shape (P, 2, 2)
        ``grad_n(du)``, ``H[p, i, j] = d du_i / d x_j`` on the start-of-step configuration.
    J : ndarray, shape (P,)
        ``det(I + H)``.

    Returns
    -------
    deps : ndarray, shape (P, 4)
        ``sym(H F_(1/2)^-1)`` as Voigt ``(xx, yy, zz, 2xy)``, its trace replaced by
        ``ln J`` (spread over xx and yy) so that volumes are tracked exactly.
    dw : ndarray, shape (P,)
        Spin increment ``skew(H F_(1/2)^-1)_xy`` for the Hughes-Winget rotation.
    """
    L = H @ inverse(np.eye(2) + 0.5 * H)
    exx, eyy = L[:, 0, 0], L[:, 1, 1]
    shift = 0.5 * (np.log(J) - exx - eyy)
    deps = np.stack([exx + shift, eyy + shift, 0 * exx, L[:, 0, 1] + L[:, 1, 0]], 1)
    return deps, 0.5 * (L[:, 0, 1] - L[:, 1, 0])


def spatial_tangent(C, effective, total):
    """``T[m, f, k, g, l]``: the linearisation of ``J sigma F^-T`` on the current configuration.

    With ``l = grad_(n+1) d(du)`` (``l_gl = d du_g / d x_l``) and its skew part ``w``, the
    change of ``J sigma F^-T F^T / J`` is ``C : sym(l) + w sigma' - sigma' w +
    sigma tr(l) - sigma l^T``: the material tangent C (Voigt, from
    :meth:`soilwater.material.camclay.CamClay.update`), the Jaumann rotation of the effective stress
    sigma' and the change of area and orientation acting on the total stress sigma.

    Parameters
    ----------
    C : ndarray, shape (P, 4, 4)
    effective, total : ndarray, shape (P, 2, 2)
        In-plane effective and total Cauchy stress.

    Returns
    -------
    ndarray, shape (P, 2, 2, 2, 2)
        Indices (point, test field f, test derivative k, trial field g, trial derivative l).
    """
    B = GRADIENT_TO_VOIGT.reshape(4, 4)                     # (f k, Voigt)
    T = (B @ C @ B.T).reshape(-1, 2, 2, 2, 2)
    half, turned = 0.5 * effective, 0.5 * np.swapaxes(effective, 1, 2)
    for i in range(2):                                      # the Kronecker deltas
        T[:, i, :, i, :] += turned                          # d_gf s'_lk / 2
        T[:, i, :, :, i] -= turned                          # -d_lf s'_gk / 2
        T[:, :, i, :, i] -= half                            # -s'_fg d_lk / 2
        T[:, :, i, i, :] += half - total                    # (s'_fl / 2 - s_fl) d_gk
        T[:, :, :, i, i] += total                           # s_fk d_gl
    return T


def prescribed_increment(L, x, dt):
    """Displacement increment ``(exp(L dt) - I) x`` of points moving with a constant
    velocity gradient L (2, 2) [1/s] over dt, from positions x (P, 2)."""
    from scipy.linalg import expm

    return x @ (expm(np.asarray(L) * dt) - np.eye(2)).T
