"""The Cam-clay return mapping: a numba kernel that integrates one step point by point.

Each point solves its local problem in ``x = (ln p', q, ln p'c, dgamma)`` by Newton's
method (a 4 x 4 LU with partial pivoting, no LAPACK call), re-solves on the vertex
``q = 0`` when the original surface's return passes the apex, and forms its consistent
tangent. :func:`return_mapping` runs the kernel on parts of the points side by side;
:func:`raise_on` turns the points' statuses into one error.

Signs: stress tension positive ``(xx, yy, zz, xy)``; p', q and p'c compression positive;
the volumetric strain increment ``dev`` tension positive. The equations themselves live in
:mod:`soilwater.material.camclay_equations`.
"""

import math

import numpy as np

from soilwater.errors import ConvergenceError
from soilwater.linalg.threads import parts, run
from soilwater.material.camclay_equations import hardening, jit, mean_volume, yield_function
from soilwater.material.kinematics import DEVIATORIC, IDENTITY

#: Status of a point after the return mapping.
CONVERGED, NOT_CONVERGED, SINGULAR = 0, 1, 2

#: The local problem a point solves: elastic (dgamma = 0), plastic on the smooth surface,
#: plastic on the vertex q = 0 of the original surface.
ELASTIC, SMOOTH, VERTEX = 0, 1, 2


def raise_on(status, max_iter):
    """Raise :class:`ConvergenceError` if any point's status is not ``CONVERGED``."""
    if not status.any():
        return
    if np.any(status == SINGULAR):
        raise ConvergenceError("Cam-clay return mapping met a singular local Jacobian: "
                               "reduce the strain increment per step")
    bad = int(np.count_nonzero(status == NOT_CONVERGED))
    raise ConvergenceError(
        f"Cam-clay return mapping did not converge at {bad} point(s) in {max_iter} "
        "iterations: reduce the time step (strain increment per step)")


def return_mapping(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter):
    """Return mapping and consistent tangent of every point: the numba kernel
    :func:`_return_mapping` on parts of the points side by side (:mod:`soilwater.linalg.threads`;
    each point's result is the same on any number of them).

    Parameters
    ----------
    c : Constants
    s_tr : ndarray, shape (N, 4)
        Trial deviatoric stress (tension positive, ``(xx, yy, zz, xy)``).
    q_tr, p_n, pc_n, v_n, dev, G : ndarray, shape (N,)
        Trial q; p', p'c (compression positive) and specific volume at the start of the
        step; volumetric strain increment (extension positive); shear modulus at the
        start of the step. Stresses and G in the case's stress unit.
    tol : float
        Tolerance on the scaled local residual.
    max_iter : int
        Newton iterations per solve.

    Returns
    -------
    stress : ndarray, shape (N, 4)
    pc : ndarray, shape (N,)
    tangent : ndarray, shape (N, 4, 4)
    status : ndarray of int8, shape (N,)
        ``CONVERGED``, ``NOT_CONVERGED`` or ``SINGULAR``; the other outputs of a point
        that did not converge are undefined.
    """
    n = len(p_n)
    out = np.empty((n, 4)), np.empty(n), np.empty((n, 4, 4)), np.empty(n, np.int8)
    run(lambda lo, hi: _return_mapping(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter,
                                       lo, hi, *out),
        parts(0, n))
    return out


@jit
def _return_mapping(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter, lo, hi, stress,
                    pc, tangent, status):
    """:func:`return_mapping` of the points ``lo:hi``, one after another, into the rows
    ``lo:hi`` of ``stress``, ``pc``, ``tangent`` and ``status`` (numba kernel; the GIL
    released)."""
    x, work = np.empty(4), _workspace()
    for i in range(lo, hi):
        status[i], pc[i] = _point(c, s_tr[i], q_tr[i], p_n[i], pc_n[i], v_n[i], dev[i],
                                  G[i], tol, max_iter, x, work, stress[i], tangent[i])


@jit
def _workspace():
    """Scratch of one point: residual R (4,), Jacobian J (4, 4), ``dR/d(dev, q_tr)``
    (4, 2), LU factors (4, 4) and pivots (4,)."""
    return (np.empty(4), np.empty((4, 4)), np.empty((4, 2)), np.empty((4, 4)),
            np.empty(4, np.int64))


@jit
def _point(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter, x, work, stress, tangent):
    """One point: elastic trial, Newton in x = (ln p', q, ln p'c, dgamma), the vertex
    re-solve of the original model, then stress (4,) and tangent (4, 4) into the given
    rows. Returns ``(status, p'c)``."""
    vbar, dvbar = mean_volume(v_n, dev)
    scale = 1.0 / pc_n**2
    p_tr = p_n * math.exp(-vbar * dev / c.kappa)
    kind = SMOOTH if yield_function(c, p_tr, q_tr, pc_n, scale)[0] > tol else ELASTIC
    x[0], x[1], x[2], x[3] = math.log(p_tr), q_tr, math.log(pc_n), 0.0
    known = (math.log(p_n), p_n, math.log(pc_n), q_tr, dev, vbar, dvbar, G, scale)
    while True:  # one call site: numba compiles _newton once, for any kind
        status = _newton(c, x, kind, known, tol, max_iter, work)
        if status != CONVERGED or kind != SMOOTH or c.modified or x[1] >= 0:
            break
        kind, x[1] = VERTEX, 0.0  # returns past the apex land on the vertex q = 0
    if status == CONVERGED and not _stress_and_tangent(c, x, kind, known, s_tr, work,
                                                       stress, tangent):
        status = SINGULAR
    return status, math.exp(x[2])


@jit
def _newton(c, x, kind, known, tol, max_iter, work):
    """Newton on ``R(x) = 0`` from x (updated in place), steps of ln p' and ln p'c
    clipped to +-0.5; J and ``dR/dy`` in ``work`` are left at the solution.

    Returns ``CONVERGED``, ``NOT_CONVERGED`` (also on a non-finite residual) or
    ``SINGULAR``.
    """
    R, J, _, lu, piv = work
    for _ in range(max_iter):
        _residual(c, x, kind, known, work)
        if _largest(R) < tol:
            return CONVERGED
        if not np.isfinite(_largest(R)):
            return NOT_CONVERGED
        if not _lu_factor(J, lu, piv):
            return SINGULAR
        for k in range(4):
            R[k] = -R[k]
        _lu_solve(lu, piv, R)
        for k in range(4):
            step = R[k]
            if k != 1 and k != 3:
                step = 0.5 if step > 0.5 else (-0.5 if step < -0.5 else step)
            x[k] += step
    return NOT_CONVERGED


@jit
def _largest(R):
    """``max |R_k|``, nan if any entry is nan."""
    big = 0.0
    for r in R:
        if abs(r) > big or r != r:
            big = abs(r)
    return big


@jit
def _residual(c, x, kind, known, work):
    """Local residual R of a point's problem ``kind``, its Jacobian J and its derivative
    with respect to (dev, q_tr), into ``work``."""
    R, J, dRdy = work[0], work[1], work[2]
    ln_p_n, p_n, ln_pc_n, q_tr, dev, vbar, dvbar, G, scale = known
    p, q, pc, dg = math.exp(x[0]), x[1], math.exp(x[2]), x[3]
    f, fp, fq, fpc, fpp, fpq, fqq, fppc = yield_function(c, p, q, pc, scale)
    a = vbar / c.kappa
    theta, dtheta_dv = hardening(c, vbar)
    J.fill(0.0)
    dRdy.fill(0.0)
    # volumetric elasticity: ln p = ln p_n - (vbar/kappa)(dev - deps_v^p)
    R[0] = x[0] - ln_p_n + a * (dev + dg * fp)
    J[0, 0], J[0, 1], J[0, 2], J[0, 3] = (1 + a * dg * fpp * p, a * dg * fpq,
                                          a * dg * fppc * pc, a * fp)
    dRdy[0, 0] = (vbar + dvbar * (dev + dg * fp)) / c.kappa
    # deviatoric radial return: q = q_tr - 3 G dg f_q (or q = 0 on the vertex)
    if kind == VERTEX:
        R[1], J[1, 1] = q / p_n, 1.0 / p_n
    else:
        R[1] = (q - q_tr + 3 * G * dg * fq) / p_n
        J[1, 0], J[1, 1], J[1, 3] = (3 * G * dg * fpq * p / p_n,
                                     (1 + 3 * G * dg * fqq) / p_n, 3 * G * fq / p_n)
        dRdy[1, 1] = -1.0 / p_n
    # hardening: ln pc = ln pc_n + theta deps_v^p
    R[2] = x[2] - ln_pc_n - theta * dg * fp
    J[2, 0], J[2, 1], J[2, 2], J[2, 3] = (-theta * dg * fpp * p, -theta * dg * fpq,
                                          1 - theta * dg * fppc * pc, -theta * fp)
    dRdy[2, 0] = -dtheta_dv * dvbar * dg * fp
    # consistency f = 0 on plastic points, dgamma = 0 on elastic ones
    if kind != ELASTIC:
        R[3], J[3, 0], J[3, 1], J[3, 2] = f, fp * p, fq, fpc * pc
    else:
        R[3], J[3, 3] = dg, 1.0


@jit
def _stress_and_tangent(c, x, kind, known, s_tr, work, stress, tangent):
    """Stress (4,) and consistent tangent (4, 4) at the solution x of a point; False
    when its local Jacobian is singular.

    The tangent follows from ``dx/dy = -J^-1 dR/dy`` with y = (dev, q_tr),
    ``d dev / d eps = m`` and ``d q_tr / d eps = 3 G n``, n the unit trial direction.
    """
    R, _, dRdy, lu, piv = work
    if not _lu_factor(work[1], lu, piv):
        return False
    for k in range(2):                      # dRdy becomes dx/dy
        for i in range(4):
            R[i] = -dRdy[i, k]
        _lu_solve(lu, piv, R)
        for i in range(4):
            dRdy[i, k] = R[i]
    _, p_n, _, q_tr, _, _, _, G, scale = known
    p, q, pc, dg = math.exp(x[0]), x[1], math.exp(x[2]), x[3]
    safe = q_tr > 1e-14 * p_n
    inv_q = 1.0 / q_tr if safe else 0.0     # n = s_tr / q_tr, zero at q_tr = 0
    if safe:
        ratio = q / q_tr
    elif kind == VERTEX:
        ratio = 0.0
    else:
        ratio = 1.0 / (1.0 + 3 * G * dg * yield_function(c, p, q, pc, scale)[6])
    for i in range(4):
        stress[i] = -p * IDENTITY[i] + ratio * s_tr[i]
    for i in range(4):
        for j in range(4):
            dp = p * (dRdy[0, 0] * IDENTITY[j] + 3 * G * dRdy[0, 1] * s_tr[j] * inv_q)
            dq = dRdy[1, 0] * IDENTITY[j] + 3 * G * dRdy[1, 1] * s_tr[j] * inv_q
            tangent[i, j] = (-IDENTITY[i] * dp + s_tr[i] * inv_q * dq + 2 * G * ratio
                             * (DEVIATORIC[i, j] - 1.5 * s_tr[i] * s_tr[j] * inv_q**2))
    return True


@jit
def _lu_factor(J, A, piv):
    """LU factors of a 4 x 4 matrix J into A, with partial pivoting; False at a zero
    pivot (exactly singular, as LAPACK's getrf reports)."""
    for i in range(4):
        for j in range(4):
            A[i, j] = J[i, j]
    for k in range(4):
        m = k
        for i in range(k + 1, 4):
            if abs(A[i, k]) > abs(A[m, k]):
                m = i
        piv[k] = m
        if A[m, k] == 0.0:
            return False
        for j in range(4):
            A[k, j], A[m, j] = A[m, j], A[k, j]
        for i in range(k + 1, 4):
            A[i, k] /= A[k, k]
            for j in range(k + 1, 4):
                A[i, j] -= A[i, k] * A[k, j]
    return True


@jit
def _lu_solve(A, piv, b):
    """Solve ``A x = b`` in place from :func:`_lu_factor`'s factors."""
    for k in range(4):
        b[k], b[piv[k]] = b[piv[k]], b[k]
    for i in range(1, 4):
        for j in range(i):
            b[i] -= A[i, j] * b[j]
    for i in range(3, -1, -1):
        for j in range(i + 1, 4):
            b[i] -= A[i, j] * b[j]
        b[i] /= A[i, i]
