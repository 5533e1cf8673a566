"""The numpy return mapping of Cam-clay that
:meth:`soilwater.material.camclay.CamClay.update` replaced: the test oracle of its numba
kernel.

It is the package's former vectorised ``CamClay.update``, kept verbatim as a function of
a :class:`~soilwater.material.camclay.CamClay` (``update(clay, ...)``): a Newton iteration
over all points at once in (ln p', q, ln p'c, dgamma), the vertex re-solve of the original
model, the consistent tangent. It keeps its own copies of the yield function, the
hardening law and the mean specific volume, so that it checks the package's numba scalar
functions too; from the clay it takes only parameters and ``moduli``.

Conventions as in :mod:`soilwater.material.camclay`: stress tension positive
``(xx, yy, zz, xy)``, strain Voigt ``(xx, yy, zz, 2xy)``, p', q, p'c compression positive.
"""

import numpy as np

from soilwater.errors import ConvergenceError
from soilwater.material.kinematics import (DEVIATORIC, IDENTITY, deviator, double_dot,
                                           hughes_winget, invariants)


def update(clay, stress, state, dstrain, dspin, tol=1e-11, max_iter=60):
    """Integrate one step on every point: the same arguments and returns as
    :meth:`soilwater.material.camclay.CamClay.update` (after ``clay``)."""
    stress = hughes_winget(stress, dspin)
    dstrain = np.asarray(dstrain, dtype=float)
    p_n, _ = invariants(stress)
    pc_n, v_n = state["pc"], state["v"]
    if not np.all(p_n > 0):
        raise ConvergenceError(f"Cam-clay needs p' > 0 at every point; a point "
                               f"starts the step at p' = {p_n.min():.3g}")

    dev = dstrain[:, :3].sum(axis=1)
    vbar, dvbar = _mean_volume(v_n, dev)
    K_n, G = clay.moduli(p_n, v_n)
    s_tr = deviator(stress) + 2 * G[:, None] * (dstrain @ DEVIATORIC.T)
    q_tr = np.sqrt(1.5 * double_dot(s_tr, s_tr))
    scale = 1.0 / pc_n**2
    p_tr = p_n * np.exp(-vbar * dev / clay.kappa)

    plastic = _f(clay, p_tr, q_tr, pc_n, scale)[0] > tol
    vertex = np.zeros_like(plastic)
    x = np.stack([np.log(p_tr), q_tr, np.log(pc_n), np.zeros_like(p_n)], axis=1)
    args = (p_n, pc_n, q_tr, dev, vbar, dvbar, G, scale)
    x, J, dRdy = _solve_local(clay, x, plastic, vertex, args, tol, max_iter)
    if clay.model == "original":  # returns past the apex land on the vertex q = 0
        vertex = plastic & (x[:, 1] < 0)
        if vertex.any():
            x[vertex, 1] = 0.0
            x, J, dRdy = _solve_local(clay, x, plastic, vertex, args, tol, max_iter)

    p, q, pc, dg = np.exp(x[:, 0]), x[:, 1], np.exp(x[:, 2]), x[:, 3]
    dx = -np.linalg.solve(J, dRdy)  # (N, 4, 2): d(ln p, q, ln pc, dg)/d(dev, q_tr)
    fqq = _f(clay, p, q, pc, scale)[6]
    safe = q_tr > 1e-14 * p_n
    n = np.where(safe[:, None], s_tr, 0.0) / np.where(safe, q_tr, 1.0)[:, None]
    ratio = np.where(safe, q / np.where(safe, q_tr, 1.0),
                     np.where(vertex, 0.0, 1.0 / (1.0 + 3 * G * dg * fqq)))

    new_stress = -p[:, None] * IDENTITY + ratio[:, None] * s_tr
    dp = p[:, None] * dx[:, 0, :]
    dq = dx[:, 1, :]
    m = IDENTITY
    dp_de = dp[:, :1] * m + 3 * G[:, None] * dp[:, 1:] * n
    dq_de = dq[:, :1] * m + 3 * G[:, None] * dq[:, 1:] * n
    tangent = (-m[None, :, None] * dp_de[:, None, :]
               + n[:, :, None] * dq_de[:, None, :]
               + (2 * G * ratio)[:, None, None]
               * (DEVIATORIC - 1.5 * n[:, :, None] * n[:, None, :]))
    new_state = {"pc": pc, "v": v_n * np.exp(dev)}
    return new_stress, new_state, tangent


def _f(clay, p, q, pc, scale):
    """Yield function and its derivatives ``(f, f_p, f_q, f_pc, f_pp, f_pq, f_qq, f_ppc)``.

    ``scale`` multiplies the modified surface (it keeps f dimensionless).
    """
    M = clay.M
    if clay.model == "original":
        f = np.log(p / pc) + q / (M * p)
        zero = np.zeros_like(p)
        return (f, 1 / p - q / (M * p**2), 1 / (M * p), -1 / pc,
                -1 / p**2 + 2 * q / (M * p**3), -1 / (M * p**2), zero, zero)
    s = scale
    f = s * (q**2 / M**2 + p * (p - pc))
    return (f, s * (2 * p - pc), s * 2 * q / M**2, -s * p,
            2 * s + 0 * p, 0 * p, 2 * s / M**2 + 0 * p, -s + 0 * p)


def _hardening(clay, v):
    """``theta`` in ``dp'c / p'c = theta d eps_v^p`` (compression positive)."""
    if clay.model == "modified":
        return v / (clay.lam - clay.kappa)
    return np.full_like(np.asarray(v, dtype=float), 1.0 / clay.MD)


def _solve_local(clay, x, plastic, vertex, args, tol, max_iter):
    """Newton on ``R(x) = 0`` for x = (ln p', q, ln p'c, dgamma) on all points at once.

    Overflow in a diverging iteration is not warned about: it ends in
    :class:`ConvergenceError`.
    """
    with np.errstate(all="ignore"):
        return _newton(clay, x, plastic, vertex, args, tol, max_iter)


def _newton(clay, x, plastic, vertex, args, tol, max_iter):
    for _ in range(max_iter):
        R, J, dRdy = _residual(clay, x, plastic, vertex, *args)
        if np.all(np.abs(R) < tol):
            return x, J, dRdy
        if not np.all(np.isfinite(R)):
            break
        try:
            step = np.linalg.solve(J, -R[:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            raise ConvergenceError("Cam-clay return mapping met a singular local "
                                   "Jacobian: reduce the strain increment per step") from None
        step[:, [0, 2]] = np.clip(step[:, [0, 2]], -0.5, 0.5)
        x = x + step
    bad = int(np.sum(np.any(np.abs(R) >= tol, axis=1)))
    raise ConvergenceError(
        f"Cam-clay return mapping did not converge at {bad} point(s) in {max_iter} "
        "iterations: reduce the time step (strain increment per step)")


def _residual(clay, x, plastic, vertex, p_n, pc_n, q_tr, dev, vbar, dvbar, G, scale):
    """Local residual, its Jacobian and its derivative with respect to (dev, q_tr)."""
    p, q, pc, dg = np.exp(x[:, 0]), x[:, 1], np.exp(x[:, 2]), x[:, 3]
    f, fp, fq, fpc, fpp, fpq, fqq, fppc = _f(clay, p, q, pc, scale)
    a = vbar / clay.kappa
    theta = _hardening(clay, vbar)
    n = len(p)
    R = np.empty((n, 4))
    J = np.zeros((n, 4, 4))
    dRdy = np.zeros((n, 4, 2))
    # volumetric elasticity: ln p = ln p_n - (vbar/kappa)(dev - deps_v^p)
    R[:, 0] = x[:, 0] - np.log(p_n) + a * (dev + dg * fp)
    J[:, 0] = np.stack([1 + a * dg * fpp * p, a * dg * fpq, a * dg * fppc * pc, a * fp], 1)
    dRdy[:, 0, 0] = (vbar + dvbar * (dev + dg * fp)) / clay.kappa
    # deviatoric radial return: q = q_tr - 3 G dg f_q (or q = 0 on the vertex)
    R[:, 1] = np.where(vertex, q, q - q_tr + 3 * G * dg * fq) / p_n
    J[:, 1] = np.where(vertex[:, None], np.array([0, 1.0, 0, 0]),
                       np.stack([3 * G * dg * fpq * p, 1 + 3 * G * dg * fqq,
                                 0 * p, 3 * G * fq], 1)) / p_n[:, None]
    dRdy[:, 1, 1] = np.where(vertex, 0.0, -1.0 / p_n)
    # hardening: ln pc = ln pc_n + theta deps_v^p
    R[:, 2] = x[:, 2] - np.log(pc_n) - theta * dg * fp
    J[:, 2] = np.stack([-theta * dg * fpp * p, -theta * dg * fpq,
                        1 - theta * dg * fppc * pc, -theta * fp], 1)
    if clay.model == "modified":
        dRdy[:, 2, 0] = -dvbar / (clay.lam - clay.kappa) * dg * fp
    # consistency f = 0 on plastic points, dgamma = 0 on elastic ones
    R[:, 3] = np.where(plastic, f, dg)
    J[:, 3] = np.where(plastic[:, None], np.stack([fp * p, fq, fpc * pc, 0 * p], 1),
                       np.array([0, 0, 0, 1.0]))
    return R, J, dRdy


def _mean_volume(v, dev):
    """Mean specific volume over a step, ``(v_{n+1} - v_n)/dev``, and its derivative.

    With it the elastic volumetric law ``dp'/p' = -v d eps_v / kappa`` integrates
    exactly: ``p'_{n+1} = p'_n exp(-(v_{n+1} - v_n)/kappa)``.
    """
    small = np.abs(dev) < 1e-5
    x = np.where(small, 1.0, dev)
    vbar = np.where(small, v * (1 + dev / 2 + dev**2 / 6), v * np.expm1(x) / x)
    dvbar = np.where(small, v * (0.5 + dev / 3 + dev**2 / 8),
                     v * (x * np.exp(x) - np.expm1(x)) / x**2)
    return vbar, dvbar


# -- inputs to compare the kernel with the oracle on -------------------------------------
#: Uniform numbers in [0, 1) that :func:`admissible_points` reads per point.
UNIFORMS = 15


def admissible_points(clay, u, largest=0.02):
    """Admissible states and increments of points, each drawn from a row of uniform
    numbers (a numpy generator's or hypothesis's, which then shrinks towards zeros).

    Parameters
    ----------
    clay : CamClay
    u : ndarray, shape (n, UNIFORMS)
        Numbers in [0, 1].
    largest : float
        Largest strain increment (Euclidean norm of the Voigt vector).

    Returns
    -------
    stress, state, dstrain, dspin
        Arguments of ``update(clay, ...)``: p' log-uniform in [0.2, 5] p'0 and a random
        deviatoric direction with ``q / p'`` uniform in [0, 1.5 M] (both sides of the
        critical state); p'c puts half the points on the yield surface and the others
        inside it (up to four times its size); v uniform in [1.4, 2.4]. The strain
        increment has a random direction and a size log-uniform in [1e-6, largest]; a
        quarter of the points start near the p' axis (``q / p' < 0.05``) and are
        compressed nearly isotropically, which takes the original model to its vertex.
        Spin increment uniform in [-0.1, 0.1].
    """
    u = np.atleast_2d(u)
    near_axis = u[:, 0] < 0.25
    p = clay.p0 * 0.2 * 25.0 ** u[:, 1]
    eta = np.where(near_axis, 0.05, 1.5 * clay.M) * u[:, 2]
    stress = _unit_deviator(2 * u[:, 3:7] - 1) * (eta * p)[:, None] - p[:, None] * IDENTITY
    inside = np.where(u[:, 7] < 0.5, 1.0, 1.0 + 6.0 * (u[:, 7] - 0.5))
    state = {"pc": clay.size(p, eta * p) * inside, "v": 1.4 + u[:, 8]}
    size = 1e-6 * (largest / 1e-6) ** u[:, 9]
    direction = 2 * u[:, 10:14] - 1
    direction[near_axis, :3] = -1.0 + 0.1 * direction[near_axis, :3]
    direction[near_axis, 3] = 0.0
    direction[np.all(direction == 0, axis=1)] = (1.0, 0.0, 0.0, 0.0)
    dstrain = size[:, None] * direction / np.linalg.norm(direction, axis=1)[:, None]
    return stress, state, dstrain, 0.2 * u[:, 14] - 0.1


def _unit_deviator(a):
    """The deviators of rows a (n, 4) scaled to q = 1; ``(1, -1, 0, 0) / sqrt(3)`` for
    an isotropic row."""
    s = deviator(a)
    q = invariants(s)[1]
    s[q == 0] = np.array([1.0, -1.0, 0.0, 0.0]) / np.sqrt(3)
    return s / np.where(q == 0, 1.0, q)[:, None]
