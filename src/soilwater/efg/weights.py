"""MLS weight functions of the normalised distance ``r = d / d_mI``: numba evaluation.

Each weight peaks at ``r = 0``, decreases to 0 at ``r = 1`` and is zero for ``r > 1``:

* quartic spline (``Q``): ``1 - 6r^2 + 8r^3 - 3r^4``;
* cubic spline: ``2/3 - 4r^2 + 4r^3`` for ``r <= 1/2`` and
  ``4/3 - 4r + 4r^2 - 4r^3/3`` for ``1/2 < r <= 1`` (``w(0) = 2/3``);
* exponential with parameter ``c > 0``:
  ``(exp(-(r/c)^2) - exp(-(1/c)^2)) / (1 - exp(-(1/c)^2))``; ``E-A`` is ``c = 0.5`` and
  ``E-B`` is ``c = 0.25`` (sharper, nearly interpolating). It is only C0 at ``r = 1``.

A case names a weight by a string, read once at load time into a
:class:`soilwater.efg.settings.Weight` (the names' grammar, the aliases ``Q``, ``E-A``, ``E-B``,
the range of ``c`` and the integer kind codes live in :mod:`soilwater.efg.settings`, shared with
the load-time validation of a case, which must not import ``efg``). Numba kernels call
:func:`weight_scalar` with the Weight's kind
code and ``c``, and :func:`evaluate` gives ``w`` and ``dw/dr`` on whole arrays. numba's
on-disk cache does not track calls across files: after editing this module, delete the
``*.nbi`` and ``*.nbc`` files in ``efg/__pycache__`` so that the kernels of
:mod:`soilwater.efg.mls` are compiled again.
"""

import math

import numba
import numpy as np

from soilwater.efg.settings import CUBIC, QUARTIC, Weight


@numba.njit(cache=True)
def weight_scalar(kind, c, r):
    """Weight and its derivative at one normalised distance.

    Parameters
    ----------
    kind : int
        ``QUARTIC``, ``CUBIC`` or ``EXPONENTIAL``.
    c : float
        Parameter of the exponential weight (ignored by the splines).
    r : float
        Normalised distance ``d / d_mI`` (dimensionless, >= 0).

    Returns
    -------
    w, dw_dr : float
        Zero for ``r >= 1``.
    """
    if r >= 1.0:
        return 0.0, 0.0
    if kind == QUARTIC:
        return 1.0 - r * r * (6.0 - 8.0 * r + 3.0 * r * r), -12.0 * r * (1.0 - r) ** 2
    if kind == CUBIC:
        if r <= 0.5:
            return 2.0 / 3.0 - 4.0 * r * r + 4.0 * r ** 3, r * (12.0 * r - 8.0)
        return 4.0 / 3.0 - 4.0 * r + 4.0 * r * r - 4.0 * r ** 3 / 3.0, -4.0 * (1.0 - r) ** 2
    tail = math.exp(-1.0 / (c * c))
    g = math.exp(-(r / c) ** 2)
    return (g - tail) / (1.0 - tail), -2.0 * r / (c * c) * g / (1.0 - tail)


@numba.njit(cache=True)
def _evaluate(kind, c, r):
    """``weight_scalar`` over a 1-D array: ``(w, dw_dr)`` arrays."""
    w, dw = np.empty_like(r), np.empty_like(r)
    for k in range(r.size):
        w[k], dw[k] = weight_scalar(kind, c, r[k])
    return w, dw


def evaluate(weight, r):
    """Weight and its derivative on an array of normalised distances.

    Parameters
    ----------
    weight : str or Weight
        The weight function, or a name read by :meth:`soilwater.efg.settings.Weight.parse`.
    r : array_like
        Normalised distances ``d / d_mI`` (any shape, dimensionless, >= 0).

    Returns
    -------
    w, dw_dr : ndarray
        Of the shape of ``r``; zero for ``r >= 1``.

    Examples
    --------
    >>> w, dw = evaluate("Q", [0.5, 1.5])
    >>> w.tolist(), dw.tolist()
    ([0.3125, 0.0], [-1.5, 0.0])
    """
    weight = Weight.parse(weight)
    r = np.asarray(r, dtype=float)
    w, dw = _evaluate(weight.kind, weight.c, r.ravel())
    return w.reshape(r.shape), dw.reshape(r.shape)
