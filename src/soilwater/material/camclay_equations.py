"""The equations of Cam-clay as numba functions of scalars, and their array forms.

Yield functions, written with the size ``p'c`` of the surface (its intercept on the p' axis):

* original: ``f = ln(p'/p'c) + q/(M p')``; with ``p'c = p'0 exp(eps_v^p / MD)`` and
  ``MD = (lambda - kappa)/(1 + e0)`` this is the paper's
  ``MD ln(p'/p'0) + MD q/(M p') - eps_v^p = 0`` divided by MD;
* modified: ``f = q^2/M^2 + p'(p' - p'c)`` with ``dp'c/p'c = v d eps_v^p / (lambda - kappa)``.

p', q, p'c and ``eps_v^p`` are compression positive, in the case's stress unit; the
volumetric strain increment ``dev`` is tension positive.

Each equation has one home here: :func:`yield_function` (the surface and its
derivatives), :func:`surface_size`, :func:`hardening` and :func:`mean_volume`. The return
mapping (:mod:`soilwater.material.camclay_kernel`) and the methods of
:class:`~soilwater.material.camclay.CamClay` call them; :func:`elementwise` applies one
to whole arrays. numba caches their machine code in ``__pycache__``; it is compiled again
when this file changes.
"""

import math
from collections import namedtuple

import numba
import numpy as np

#: A clay's parameters as the numba functions read them
#: (:attr:`~soilwater.material.camclay.CamClay.constants`): ``modified`` (bool), M,
#: lambda, kappa and MD.
Constants = namedtuple("Constants", "modified M lam kappa MD")

#: numba options of every function here: division by zero gives inf or nan (a diverging
#: iteration ends in a status, not an exception inside numba).
jit = numba.njit(cache=True, error_model="numpy", nogil=True)


def elementwise(kernel, constants, *arrays):
    """``kernel(constants, *flat, out)`` on the broadcast arrays; the result has their
    shape (a numpy scalar for scalars).

    ``kernel`` is one of :func:`yield_values`, :func:`surface_sizes` and
    :func:`hardenings`.
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in arrays))
    out = np.empty(arrays[0].shape)
    kernel(constants, *(np.ascontiguousarray(a).ravel() for a in arrays), out.ravel())
    return out[()]


@jit
def yield_function(c, p, q, pc, scale):
    """Yield function and its derivatives at one point.

    Parameters
    ----------
    c : Constants
    p, q, pc : float
        p', q and the size p'c of the surface (compression positive, stress unit).
    scale : float
        Multiplies the modified surface (``1 / p'c^2`` keeps f dimensionless); the
        original's f is dimensionless and ignores it.

    Returns
    -------
    tuple of float
        ``(f, f_p, f_q, f_pc, f_pp, f_pq, f_qq, f_ppc)``; f <= 0 inside.

    Examples
    --------
    >>> c = Constants(False, 1.42, 0.11, 0.04, 0.07 / 1.83)
    >>> f, fp, fq = yield_function(c, 2.0, 1.42 * 2.0, 2.0 * math.e, 1.0)[:3]
    >>> round(f, 12), round(fp, 12), fq == 1 / (1.42 * 2.0)    # critical state: f_p = 0
    (0.0, 0.0, True)
    """
    M = c.M
    if c.modified:
        s = scale
        return (s * (q * q / M**2 + p * (p - pc)), s * (2 * p - pc), 2 * s * q / M**2,
                -s * p, 2 * s, 0.0, 2 * s / M**2, -s)
    return (math.log(p / pc) + q / (M * p), 1 / p - q / (M * p * p), 1 / (M * p), -1 / pc,
            -1 / p**2 + 2 * q / (M * p**3), -1 / (M * p * p), 0.0, 0.0)


@jit
def surface_size(c, p, q):
    """The size p'c of the yield surface through ``(p', q)``: ``p' exp(q / (M p'))``
    (original), ``p' + q^2 / (M^2 p')`` (modified); compression positive, stress unit."""
    if c.modified:
        return p + q * q / (c.M**2 * p)
    return p * math.exp(q / (c.M * p))


@jit
def hardening(c, v):
    """``theta`` in ``dp'c / p'c = theta d eps_v^p`` at specific volume v, and
    ``d theta / d v``: ``v / (lambda - kappa)`` (modified), ``1 / MD`` (original)."""
    if c.modified:
        return v / (c.lam - c.kappa), 1.0 / (c.lam - c.kappa)
    return 1.0 / c.MD, 0.0


@jit
def mean_volume(v, dev):
    """Mean specific volume over a step, ``(v_{n+1} - v_n) / dev``, and its derivative
    with respect to the volumetric strain increment dev (tension positive).

    With ``v_{n+1} = v_n exp(dev)`` the elastic volumetric law ``dp'/p' = -v d eps_v /
    kappa`` integrates exactly: ``p'_{n+1} = p'_n exp(-(v_{n+1} - v_n)/kappa)``.
    """
    if abs(dev) < 1e-5:
        return v * (1 + dev / 2 + dev**2 / 6), v * (0.5 + dev / 3 + dev**2 / 8)
    return v * math.expm1(dev) / dev, v * (dev * math.exp(dev) - math.expm1(dev)) / dev**2


@jit
def yield_values(c, p, q, pc, out):
    """:func:`yield_function`'s f on 1-D arrays, scaled by ``1 / p'c^2`` (modified)."""
    for i in range(len(out)):
        out[i] = yield_function(c, p[i], q[i], pc[i], 1.0 / pc[i] ** 2)[0]


@jit
def surface_sizes(c, p, q, out):
    """:func:`surface_size` on 1-D arrays."""
    for i in range(len(out)):
        out[i] = surface_size(c, p[i], q[i])


@jit
def hardenings(c, v, out):
    """:func:`hardening`'s theta on a 1-D array."""
    for i in range(len(out)):
        out[i] = hardening(c, v[i])[0]

