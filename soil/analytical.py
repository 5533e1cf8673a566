"""Closed-form solutions used as boundary data and as references (plane strain).

Each solution is a function of current coordinates returning displacement (N, 2) and
Cauchy stress (N, 4) as ``(xx, yy, zz, xy)``, tension positive, in the case's units.
Cases name one in their ``[exact]`` table (``solution = "..."`` plus its parameters), and
boundary components marked ``exact`` take their displacement or traction from it.
"""

import numpy as np

from soil.errors import InputError


def linear_field(points, E, nu, gradient=((1e-3, 2e-3), (-1e-3, 5e-4)), offset=(1e-3, -2e-3)):
    """The patch test field ``u = offset + gradient x`` and its constant stress.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    E, nu : float
        Young's modulus and Poisson ratio (plane strain).
    gradient : 2 x 2 nested sequence
        Displacement gradient ``du_i/dx_j``.
    offset : 2 sequence
        Rigid translation.
    """
    G = np.asarray(gradient, dtype=float)
    u = np.asarray(offset, dtype=float) + points @ G.T
    eps = np.array([G[0, 0], G[1, 1], 0.0, G[0, 1] + G[1, 0]])
    stress = plane_strain_stiffness(E, nu) @ eps
    return u, np.broadcast_to(stress, (len(points), 4)).copy()


def timoshenko_beam(points, E, nu, P, length, depth):
    """Cantilever under an end shear load, plane strain (Timoshenko and Goodier).

    The beam occupies ``[0, length] x [0, depth]``, its axis at ``y = depth/2``; it is
    clamped (exact displacements) at ``x = 0`` and carries a parabolic shear traction of
    resultant ``P`` (upward for P > 0) at ``x = length``. Plane strain uses the plane-stress
    formulas with ``E/(1 - nu^2)`` and ``nu/(1 - nu)``.

    Returns
    -------
    u : ndarray, shape (N, 2)
    stress : ndarray, shape (N, 4)
    """
    Eb, nb = E / (1 - nu**2), nu / (1 - nu)
    x, y = points[:, 0], points[:, 1] - depth / 2
    L, D = length, depth
    inertia = D**3 / 12
    ux = -P * y / (6 * Eb * inertia) * ((6 * L - 3 * x) * x + (2 + nb) * (y**2 - D**2 / 4))
    uy = P / (6 * Eb * inertia) * (3 * nb * y**2 * (L - x) + (4 + 5 * nb) * D**2 * x / 4
                                   + (3 * L - x) * x**2)
    sxx = -P * (L - x) * y / inertia
    sxy = P / (2 * inertia) * (D**2 / 4 - y**2)
    stress = np.stack([sxx, 0 * x, nu * sxx, sxy], axis=1)
    return np.stack([ux, uy], axis=1), stress


def plane_strain_stiffness(E, nu):
    """Elastic tangent (4, 4) from Voigt strain ``(xx, yy, zz, 2xy)`` to stress."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = lam * np.outer([1, 1, 1, 0], [1, 1, 1, 0]) + 2 * mu * np.diag([1, 1, 1, 0.5])
    return C


def strain_from_stress(stress, E, nu):
    """Voigt strain of a plane-strain stress (inverse of :func:`plane_strain_stiffness`)."""
    return np.linalg.solve(plane_strain_stiffness(E, nu), np.asarray(stress).T).T


#: Solutions a case can name in ``[exact] solution = ...``.
SOLUTIONS = {"linear": linear_field, "timoshenko-beam": timoshenko_beam}


def exact_solution(name, **parameters):
    """A function ``points -> (u, stress)`` for a named solution and its parameters."""
    if name not in SOLUTIONS:
        raise InputError(f"exact.solution = {name!r} is unknown: use one of "
                         f"{', '.join(SOLUTIONS)}")

    def field(points):
        return SOLUTIONS[name](np.asarray(points, dtype=float), **parameters)

    return field
