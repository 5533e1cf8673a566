"""Sparse assembly of EFG blocks: the pattern once per step, values scattered into it.

Shape functions at integration points come as CSR matrices (points x nodes) whose value
and derivative arrays share one pattern (:class:`efg.mls.ShapeFunctions`). A block couples
``ft`` test fields to ``fs`` trial fields; at each integration point q its integrand is

    K[(a, f), (b, g)] += sum_ij  S_a[i](q) * coeff[q, f, i, g, j] * S_b[j](q)

with ``S = (phi, dphi/dx, dphi/dy)`` of the test node a and trial node b, and ``coeff``
holding the integration weight times the material or coupling coefficients. The node-node
pattern of a block is that of ``Phi_test^T Phi_trial`` (nodes that share a point); it is
computed once per step and every Newton iteration scatters into it: a numba kernel walks
the pattern row by row (the test node), marks where each trial node's entry sits, and
accumulates the integrand of every point in the test node's support; no search, no COO of
duplicates.
"""

from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class Pattern:
    """Node-node CSR pattern of one block and the point incidence of its two sides."""

    indptr: np.ndarray
    indices: np.ndarray
    shape: tuple

    @classmethod
    def build(cls, test, trial):
        """Pattern of ``test.phi^T trial.phi`` (both :class:`ShapeFunctions`-like)."""
        a = sp.csr_matrix((np.ones_like(test.phi.data), test.phi.indices, test.phi.indptr),
                          shape=test.phi.shape)
        b = sp.csr_matrix((np.ones_like(trial.phi.data), trial.phi.indices,
                           trial.phi.indptr), shape=trial.phi.shape)
        product = (a.T @ b).tocsr()
        product.sort_indices()
        return cls(product.indptr.astype(np.int64), product.indices.astype(np.int64),
                   product.shape)

    @property
    def nnz(self):
        """Stored entries per field pair."""
        return len(self.indices)


def components(sf):
    """``(3, nnz)`` array of (phi, dphi/dx, dphi/dy) values of a ShapeFunctions object."""
    return np.stack([sf.phi.data, sf.dphi_dx.data, sf.dphi_dy.data])


def scatter(pattern, test, trial, coeff):
    """Assemble one block's values on its pattern.

    Parameters
    ----------
    pattern : Pattern
        From ``Pattern.build(test, trial)``.
    test, trial : ShapeFunctions
        Shape functions at the same integration points.
    coeff : ndarray, shape (M, ft, 3, fs, 3)
        Integrand coefficients at the M points, integration weight included.

    Returns
    -------
    ndarray, shape (ft, fs, nnz)
        Values of every field pair on the pattern.
    """
    out = np.zeros((coeff.shape[1], coeff.shape[3], pattern.nnz))
    phi = test.phi
    order = sp.csr_matrix((np.arange(phi.nnz, dtype=np.int64), phi.indices, phi.indptr),
                          shape=phi.shape).tocsc()  # test entries grouped by node
    used = coeff != 0  # slots (phi, d/dx, d/dy) that the integrand touches
    slots_a = np.flatnonzero(used.any(axis=(0, 1, 3, 4)))
    slots_b = np.flatnonzero(used.any(axis=(0, 1, 2, 3)))
    _scatter(pattern.indptr, pattern.indices, order.indptr.astype(np.int64),
             order.indices.astype(np.int64), order.data.astype(np.int64), components(test),
             trial.phi.indptr.astype(np.int64), trial.phi.indices.astype(np.int64),
             components(trial), np.ascontiguousarray(coeff), slots_a, slots_b, out)
    return out


@numba.njit(cache=True)
def _scatter(p_ptr, p_idx, a_colptr, a_points, a_entry, a_val, b_ptr, b_idx, b_val, coeff,
             slots_a, slots_b, out):
    """Row by row of the pattern: a column map replaces any search."""
    ft, fs = coeff.shape[1], coeff.shape[3]
    position = np.empty(p_idx.max() + 1 if len(p_idx) else 0, dtype=np.int64)
    t = np.empty((ft, fs, 3))
    for row in range(len(p_ptr) - 1):
        for k in range(p_ptr[row], p_ptr[row + 1]):
            position[p_idx[k]] = k
        for c in range(a_colptr[row], a_colptr[row + 1]):
            q, ka = a_points[c], a_entry[c]
            for f in range(ft):  # t = S_a . coeff[q]: the test side contracted once
                for g in range(fs):
                    for j in slots_b:
                        s = 0.0
                        for i in slots_a:
                            s += a_val[i, ka] * coeff[q, f, i, g, j]
                        t[f, g, j] = s
            for kb in range(b_ptr[q], b_ptr[q + 1]):
                pos = position[b_idx[kb]]
                for f in range(ft):
                    for g in range(fs):
                        s = 0.0
                        for j in slots_b:
                            s += t[f, g, j] * b_val[j, kb]
                        out[f, g, pos] += s


def to_matrix(pattern, values):
    """Global CSR matrix of a block, fields blocked: rows ``f * n_test + a``.

    Built directly in CSR (no COO of blocks): row ``(f, a)`` holds the pattern row ``a``
    once per trial field ``g``, at columns ``g * n_trial + b``.

    Parameters
    ----------
    pattern : Pattern
    values : ndarray, shape (ft, fs, nnz)

    Examples
    --------
    >>> import numpy as np
    >>> pattern = Pattern(np.array([0, 2, 3]), np.array([0, 1, 1]), (2, 2))
    >>> to_matrix(pattern, np.arange(6.0).reshape(1, 2, 3)).toarray()
    array([[0., 1., 3., 4.],
           [0., 2., 0., 5.]])
    """
    ft, fs, nnz = values.shape
    (n_rows, n_cols), ptr = pattern.shape, pattern.indptr
    lengths = np.diff(ptr)
    row_ptr = np.concatenate([[0], np.cumsum(lengths * fs)])          # one test field
    row = np.repeat(np.arange(n_rows), lengths * fs)
    within = np.arange(fs * nnz) - row_ptr[row]
    g, j = within // lengths[row], within % lengths[row]
    gather = g * nnz + ptr[row] + j                                   # into values[f]
    columns = g * n_cols + pattern.indices[ptr[row] + j]
    indptr = np.concatenate([row_ptr[:-1] + f * fs * nnz for f in range(ft)]
                            + [[ft * fs * nnz]])
    return sp.csr_matrix((values.reshape(ft, fs * nnz)[:, gather].ravel(),
                          np.tile(columns, ft), indptr),
                         shape=(ft * n_rows, fs * n_cols))


def elasticity_coefficients(weights, tangent):
    """Coefficients of ``int grad(du) : C : grad(u)`` for the (ux, uy) fields.

    Parameters
    ----------
    weights : ndarray, shape (M,)
        Integration weights [m2 per unit thickness].
    tangent : ndarray, shape (M, 4, 4) or (4, 4)
        ``d sigma / d eps`` from Voigt strain ``(xx, yy, zz, 2xy)`` to stress
        ``(xx, yy, zz, xy)``.

    Returns
    -------
    ndarray, shape (M, 2, 3, 2, 3)
    """
    tangent = np.broadcast_to(tangent, (len(weights), 4, 4))
    # B maps (field f, derivative i) to a Voigt strain component
    B = np.zeros((2, 3, 4))
    B[0, 1, 0] = B[1, 2, 1] = 1.0    # eps_xx = d ux/dx, eps_yy = d uy/dy
    B[0, 2, 3] = B[1, 1, 3] = 1.0    # 2 eps_xy = d ux/dy + d uy/dx
    return np.einsum("fik,mkl,gjl,m->mfigj", B, tangent, B, weights)
