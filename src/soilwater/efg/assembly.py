"""Sparse assembly of EFG blocks: the pattern once per step, values scattered into it.

Shape functions at integration points come as CSR matrices (points x nodes) whose value
and derivative arrays share one pattern (:class:`soilwater.efg.mls.ShapeFunctions`). A block couples
``ft`` test fields to ``fs`` trial fields; at each integration point q its integrand is

    K[(a, f), (b, g)] += sum_ij  S_a[i](q) * coeff[q, f, i, g, j] * S_b[j](q)

with ``S = (phi, dphi/dx, dphi/dy)`` of the test node a and trial node b, and ``coeff``
holding the integration weight times the material or coupling coefficients. The node-node
pattern of a block is that of ``sum Phi_test^T Phi_trial`` over its point sets (domain and
boundary points: nodes that share a point); it is computed once per step. The global
matrix has its fields blocked (row ``f n_test + a``, column ``g n_trial + b``) and its CSR
layout follows from the node pattern, so a numba kernel adds every point's integrand
straight into the global value array: it walks the pattern row by row (the test node),
marks where each trial node's entry sits, and accumulates over the points in the test
node's support only the (f, g, j) terms the coefficients have. The coefficients come as
:class:`soilwater.physics.weakform.Coefficients`, the terms in use and their values (M, T), so no
(M, ft, 3, fs, 3) array is made or searched. No search, no COO of duplicates, no copy
into a matrix.
"""

from dataclasses import dataclass, field

import numba
import numpy as np
import scipy.sparse as sp

from soilwater.material.kinematics import GRADIENT_TO_VOIGT
from soilwater.linalg.threads import parts, run
from soilwater.physics.weakform import Coefficients


@dataclass
class Pattern:
    """Node-node CSR pattern of one block; the global layouts it implies are kept."""

    indptr: np.ndarray
    indices: np.ndarray
    shape: tuple
    _layouts: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def build(cls, *pairs):
        """Pattern of ``sum_k test_k.phi^T trial_k.phi`` over ``(test, trial)`` pairs of
        :class:`ShapeFunctions`-like objects, each pair at one set of points."""
        def incidence(*shapes):
            blocks = [sp.csr_matrix((np.ones(s.phi.nnz), s.phi.indices, s.phi.indptr),
                                    shape=s.phi.shape) for s in shapes]
            return sp.vstack(blocks, format="csr")

        product = (incidence(*(t for t, _ in pairs)).T
                   @ incidence(*(b for _, b in pairs))).tocsr()
        product.sort_indices()
        return cls(product.indptr.astype(np.int64), product.indices.astype(np.int64),
                   product.shape)

    @property
    def nnz(self):
        """Stored entries per field pair."""
        return len(self.indices)

    def zeros(self, ft, fs):
        """A value array for ``ft`` test and ``fs`` trial fields, in the global layout."""
        return np.zeros(ft * fs * self.nnz)

    def matrix(self, values, ft, fs):
        """Global CSR matrix, fields blocked, of values in the global layout.

        Row ``(f, a)`` holds the pattern row ``a`` once per trial field ``g``, at columns
        ``g * n_trial + b``; ``values`` is used as the matrix's data without a copy.

        Examples
        --------
        >>> import numpy as np
        >>> pattern = Pattern(np.array([0, 2, 3]), np.array([0, 1, 1]), (2, 2))
        >>> pattern.matrix(np.arange(6.0), 1, 2).toarray()
        array([[0., 1., 2., 3.],
               [0., 4., 0., 5.]])
        """
        if (ft, fs) not in self._layouts:   # int32 when it fits, as scipy would make it
            small = ft * fs * max(self.nnz, *self.shape) <= np.iinfo(np.int32).max
            self._layouts[ft, fs] = tuple(
                a.astype(np.int32 if small else np.int64, copy=False)
                for a in _layout(self.indptr, self.indices, ft, fs, self.shape[1]))
        indptr, indices = self._layouts[ft, fs]
        return sp.csr_matrix((values, indices, indptr),
                             shape=(ft * self.shape[0], fs * self.shape[1]))


@numba.njit(cache=True)
def _layout(ptr, idx, ft, fs, n_cols):
    """CSR row pointers and columns of the field-blocked matrix of a node pattern."""
    n_rows, nnz = len(ptr) - 1, len(idx)
    indptr = np.empty(ft * n_rows + 1, np.int64)
    indices = np.empty(ft * fs * nnz, np.int64)
    for f in range(ft):
        for a in range(n_rows):
            start, length = ptr[a], ptr[a + 1] - ptr[a]
            base = f * fs * nnz + fs * start
            indptr[f * n_rows + a] = base
            for g in range(fs):
                for k in range(length):
                    indices[base + g * length + k] = g * n_cols + idx[start + k]
    indptr[-1] = ft * fs * nnz
    return indptr, indices


def components(sf):
    """``(phi, dphi/dx, dphi/dy)`` value arrays (nnz,) of a ShapeFunctions object."""
    return sf.phi.data, sf.dphi_dx.data, sf.dphi_dy.data


def scatter(pattern, test, trial, coeff, out=None):
    """Add one point set's integrand to a block's values in the global layout.

    Parameters
    ----------
    pattern : Pattern
        From ``Pattern.build(..., (test, trial), ...)``.
    test, trial : ShapeFunctions
        Shape functions at the same integration points.
    coeff : soilwater.physics.weakform.Coefficients
        Integrand coefficients at the M points (``ft`` test and ``fs`` trial fields),
        integration weight included; only its terms are scattered.
    out : ndarray, shape (ft * fs * pattern.nnz,), optional
        Values to add to (``pattern.zeros(ft, fs)`` when not given).

    Returns
    -------
    ndarray
        ``out``, for :meth:`Pattern.matrix`.
    """
    ft, fs = coeff.fields
    if out is None:
        out = pattern.zeros(ft, fs)
    tf, tg, j_start, column = _kernel_terms(coeff.terms)
    phi = test.phi
    order = sp.csr_matrix((np.arange(phi.nnz, dtype=np.int64), phi.indices, phi.indptr),
                          shape=phi.shape).tocsc()  # test entries grouped by node
    values = np.ascontiguousarray(coeff.values)
    a_val, b_val = components(test), components(trial)

    def rows(lo, hi):
        _scatter(pattern.indptr, pattern.indices, order.indptr, order.indices, order.data,
                 a_val, trial.phi.indptr, trial.phi.indices, b_val, values, fs, tf, tg,
                 j_start, column, out, pattern.shape[1], lo, hi)

    run(rows, parts(0, pattern.shape[0]))
    return out


def _kernel_terms(terms):
    """The kernel's terms: the distinct ``(f, g, t)`` of the coefficient terms ``(f, s, g,
    t)``, sorted by the trial slot t, each with the value column of each test slot s.

    Returns
    -------
    tf, tg : ndarray of int, shape (K,)
        Test and trial field of each kernel term.
    j_start : ndarray of int, shape (4,)
        Kernel terms of trial slot t are ``j_start[t]:j_start[t + 1]``.
    column : ndarray of int, shape (K, 3)
        The column of ``Coefficients.values`` of test slot s, -1 where no term.

    Examples
    --------
    The first and third terms differ only in the test slot: one kernel term (f, g, t) =
    (0, 0, 1) reading columns 0 and 2; the second is the kernel term (0, 1, 0), first by t.

    >>> tf, tg, j_start, column = _kernel_terms(((0, 1, 0, 1), (0, 0, 1, 0), (0, 2, 0, 1)))
    >>> tf.tolist(), tg.tolist(), j_start.tolist(), column.tolist()
    ([0, 0], [1, 0], [0, 1, 2, 2], [[1, -1, -1], [-1, 0, 2]])
    """
    f, s, g, t = np.array(terms, dtype=np.int64).reshape(-1, 4).T
    keys, kernel = np.unique(np.stack([t, f, g], axis=1), axis=0, return_inverse=True)
    column = np.full((len(keys), 3), -1, dtype=np.int64)
    column[kernel.ravel(), s] = np.arange(len(s))
    tj, tf, tg = keys.T
    return tf.copy(), tg.copy(), np.searchsorted(tj, np.arange(4)), column


@numba.njit(cache=True, nogil=True)
def _scatter(p_ptr, p_idx, a_colptr, a_points, a_entry, a_val, b_ptr, b_idx, b_val, values,
             fs, tf, tg, j_start, column, out, n_cols, lo, hi):
    """Rows ``lo:hi`` of the pattern (test nodes), one by one; each row writes only its
    own entries of ``out``, so row ranges run side by side (:mod:`soilwater.linalg.threads`). A
    column map replaces any search. The test side is contracted once per (node, point)
    into the kernel terms (f, g, j), sorted by trial slot j (``j_start``), from the
    coefficient ``values`` of their test slots (``column``); every trial node of the
    point then adds ``t * S_b[j]`` to a contiguous row buffer (trial node, term), which is
    added to ``out`` once per row."""
    nnz, terms = len(p_idx), len(tf)
    position = np.empty(n_cols, dtype=np.int64)
    widest = np.max(p_ptr[lo + 1:hi + 1] - p_ptr[lo:hi]) if hi > lo else 0
    row_sum = np.zeros(widest * terms)
    t = np.empty(terms)
    for row in range(lo, hi):
        start, length = p_ptr[row], p_ptr[row + 1] - p_ptr[row]
        for k in range(start, p_ptr[row + 1]):
            position[p_idx[k]] = k - start
        for c in range(a_colptr[row], a_colptr[row + 1]):
            q, ka = a_points[c], a_entry[c]
            for m in range(terms):
                s = 0.0
                for i in range(3):
                    if column[m, i] >= 0:
                        s += a_val[i][ka] * values[q, column[m, i]]
                t[m] = s
            for kb in range(b_ptr[q], b_ptr[q + 1]):
                at = position[b_idx[kb]] * terms
                for jj in range(3):
                    value = b_val[jj][kb]
                    for m in range(j_start[jj], j_start[jj + 1]):
                        row_sum[at + m] += t[m] * value
        for m in range(terms):
            base = tf[m] * fs * nnz + fs * start + tg[m] * length
            for k in range(length):
                out[base + k] += row_sum[k * terms + m]
                row_sum[k * terms + m] = 0.0


def elasticity_coefficients(weights, tangent):
    """Coefficients of ``int grad(du) : C : grad(u)`` for the (ux, uy) fields.

    Parameters
    ----------
    weights : ndarray, shape (M,)
        Integration weights [m2 per unit thickness].
    tangent : ndarray, shape (M, 4, 4) or (4, 4)
        ``d sigma / d eps`` from Voigt strain ``(xx, yy, zz, 2xy)`` to stress
        ``(xx, yy, zz, xy)`` [kPa].

    Returns
    -------
    soilwater.physics.weakform.Coefficients
        2 x 2 fields; the gradient terms ``(f, i, g, j)`` (i, j: d/dx, d/dy) whose tangent
        entry is not zero at every point, at most 16 [kPa m2].

    Examples
    --------
    An isotropic tangent has no shear-normal coupling: 8 of the 16 terms.

    >>> from soilwater.references.closed_forms import plane_strain_stiffness
    >>> c = elasticity_coefficients(np.ones(3), plane_strain_stiffness(1.0, 0.25))
    >>> len(c.terms), c.fields
    (8, (2, 2))
    """
    tangent = np.asarray(tangent, dtype=float)
    used = np.reshape(tangent != 0, (-1, 4, 4)).any(axis=0)
    voigt = list(zip(*np.nonzero(GRADIENT_TO_VOIGT)))        # (field, derivative, Voigt)
    return Coefficients.of({(f, 1 + i, g, 1 + j): weights * tangent[..., k, l]
                            for f, i, k in voigt for g, j, l in voigt if used[k, l]}, (2, 2))
