"""The numba kernel of MLS shape functions: values, gradients and conditioning per point.

The linear basis, its moment matrix and the derivatives are those of
:mod:`soilwater.efg.mls`; the kernel fills the values on a CSR pattern of the nodes each
point sees (:func:`soilwater.efg.mls_supports.neighbours`), one point after another, and
inverts each 3 x 3 moment matrix in closed form.
"""

import numba
import numpy as np

from soilwater.efg.weights import weight_scalar


@numba.njit(cache=True)
def shape_kernel(points, nodes, support, indptr, indices, kind, c, rcond_min):
    """Shape-function values and gradients on the CSR pattern, and each point's rcond.

    Points with fewer than 3 nodes or ``rcond < rcond_min`` get zeros (the caller raises).
    The output arrays first hold the weights and their derivatives, then the shape
    functions; the moment matrices live in one (3, 3, 3) buffer: ``A``, ``A_,x``, ``A_,y``.
    """
    nnz = indices.size
    phi, dx, dy = np.zeros(nnz), np.zeros(nnz), np.zeros(nnz)
    rcond = np.zeros(len(points))
    moments = np.empty((3, 3, 3))
    inverse, gamma = np.empty((3, 3)), np.empty(3)
    gamma_x, gamma_y, rhs = np.empty(3), np.empty(3), np.empty(3)
    for p in range(len(points)):
        start, stop = indptr[p], indptr[p + 1]
        if stop - start < 3:
            continue
        x, y = points[p, 0], points[p, 1]
        h = 0.0
        for k in range(start, stop):
            h += support[indices[k]]
        h /= stop - start
        inv_h = 1.0 / h
        moments[:] = 0.0
        for k in range(start, stop):
            j = indices[k]
            phi[k], dx[k], dy[k] = _weight(x - nodes[j, 0], y - nodes[j, 1], support[j],
                                           kind, c)
            _accumulate(moments, (nodes[j, 0] - x) * inv_h, (nodes[j, 1] - y) * inv_h,
                        phi[k], dx[k], dy[k])
        _symmetrise(moments)
        rcond[p] = _inverse3(moments[0], inverse)
        if rcond[p] < rcond_min:
            phi[start:stop], dx[start:stop], dy[start:stop] = 0.0, 0.0, 0.0
            continue
        gamma[:] = inverse[:, 0]
        _gamma_derivative(inverse, moments[1], gamma, 1, h, rhs, gamma_x)
        _gamma_derivative(inverse, moments[2], gamma, 2, h, rhs, gamma_y)
        for k in range(start, stop):
            j = indices[k]
            bx, by = (nodes[j, 0] - x) * inv_h, (nodes[j, 1] - y) * inv_h
            base = gamma[0] + bx * gamma[1] + by * gamma[2]
            dx[k] = phi[k] * (gamma_x[0] + bx * gamma_x[1] + by * gamma_x[2]) + dx[k] * base
            dy[k] = phi[k] * (gamma_y[0] + bx * gamma_y[1] + by * gamma_y[2]) + dy[k] * base
            phi[k] *= base
    return phi, dx, dy, rcond


@numba.njit(cache=True)
def _weight(ex, ey, support, kind, c):
    """Weight of a node at offset ``(ex, ey) = x - x_J`` [m] and its x and y derivatives."""
    d = np.sqrt(ex * ex + ey * ey)
    w, dw_dr = weight_scalar(kind, c, d / support)
    slope = dw_dr / (d * support) if d > 0 else 0.0
    return w, slope * ex, slope * ey


@numba.njit(cache=True)
def _accumulate(moments, bx, by, w, wx, wy):
    """Add ``(w, w_,x, w_,y) b b^T`` of one node, ``b = [1, bx, by]``, to the moments."""
    b = (1.0, bx, by)
    for a in range(3):          # upper triangle; :func:`_symmetrise` fills the rest
        for e in range(a, 3):
            bb = b[a] * b[e]
            moments[0, a, e] += w * bb
            moments[1, a, e] += wx * bb
            moments[2, a, e] += wy * bb


@numba.njit(cache=True)
def _symmetrise(moments):
    """Lower triangles of the three moment matrices from their upper ones."""
    for m in range(3):
        moments[m, 1, 0], moments[m, 2, 0] = moments[m, 0, 1], moments[m, 0, 2]
        moments[m, 2, 1] = moments[m, 1, 2]


@numba.njit(cache=True)
def _gamma_derivative(inverse, moment_i, gamma, i, h, rhs, out):
    """``out = gamma_,i = A^-1 (p_,i - A_,i gamma)`` with ``p_,i = e_i / h``."""
    for a in range(3):
        rhs[a] = 1.0 / h if a == i else 0.0
        for e in range(3):
            rhs[a] -= moment_i[a, e] * gamma[e]
    for a in range(3):
        out[a] = 0.0
        for e in range(3):
            out[a] += inverse[a, e] * rhs[e]


@numba.njit(cache=True)
def _inverse3(a, inverse):
    """Inverse of a symmetric 3x3 matrix by cofactors into ``inverse``; returns its 1-norm
    rcond (0 if singular)."""
    inverse[0, 0] = a[1, 1] * a[2, 2] - a[1, 2] ** 2
    inverse[0, 1] = a[0, 2] * a[1, 2] - a[0, 1] * a[2, 2]
    inverse[0, 2] = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    inverse[1, 1] = a[0, 0] * a[2, 2] - a[0, 2] ** 2
    inverse[1, 2] = a[0, 1] * a[0, 2] - a[0, 0] * a[1, 2]
    inverse[2, 2] = a[0, 0] * a[1, 1] - a[0, 1] ** 2
    det = a[0, 0] * inverse[0, 0] + a[0, 1] * inverse[0, 1] + a[0, 2] * inverse[0, 2]
    if not det > 0:
        return 0.0
    inverse[1, 0], inverse[2, 0], inverse[2, 1] = inverse[0, 1], inverse[0, 2], inverse[1, 2]
    inverse /= det
    norm_a, norm_inv = 0.0, 0.0
    for e in range(3):
        norm_a = max(norm_a, abs(a[0, e]) + abs(a[1, e]) + abs(a[2, e]))
        norm_inv = max(norm_inv, abs(inverse[0, e]) + abs(inverse[1, e]) + abs(inverse[2, e]))
    return 1.0 / (norm_a * norm_inv)
