"""Multiplicative Schwarz on overlapping aggregates: the finest-level AMG smoother of MLS.

Where a discretisation asks for it (``Layout.smoother == "schwarz"``), the finest level of
the displacement and Schur V-cycles (:mod:`soilwater.linalg.krylov_amg`) is smoothed by
exact solves on overlapping subdomains (:func:`subdomains`) in turn (:class:`Schwarz`),
their independent ones side by side on every core (:mod:`soilwater.linalg.threads`); the
sweep itself is a numba kernel.
"""

import numba
import numpy as np
import scipy.sparse as sp

from soilwater.linalg.threads import parts, run

#: An unknown joins the Schwarz subdomain of an aggregate when at least this share of
#: its matrix neighbours (nodes, for node blocks) belongs to the aggregate.
OVERLAP = 0.25
#: Runs of consecutive Schwarz subdomains whose inner ones are solved side by side
#: (:class:`Schwarz`); a constant, so that the sweep is the same on any machine.
GROUPS = 2
#: Unknowns (summed over the subdomains) from which a Schwarz sweep is split into
#: :data:`GROUPS` runs; a smaller one keeps the subdomains' own order, one after another:
#: there the split gains little time.
SPLIT_FROM = 100_000
#: Unknowns (summed over its subdomains) from which a stage of a Schwarz sweep is solved
#: side by side; a smaller one costs less than handing it to the threads.
SIDE_BY_SIDE_FROM = 10_000
#: Precision of the Schwarz smoother's kept inverses and rows (:class:`Schwarz`): single.
#: A smoother needs no more (FGMRES's residual stays double): on the 10^5-node EFG tangent
#: FGMRES takes 25 iterations to 1e-8 either way, the inverses take half the memory, the
#: rows two thirds, and the solve about a tenth less time (scratch timing).
INVERSES = ROWS = np.float32


def subdomains(strength, aggregates, blocksize):
    """The overlapping Schwarz subdomains of ``aggregates`` (nodes x aggregates): an
    aggregate's nodes and every node with at least :data:`OVERLAP` of its ``strength``
    neighbours in it, and each node of no aggregate (no strong neighbour) alone.

    Returns
    -------
    subdomain : ndarray of int32
        The unknowns (``blocksize`` per node) of every subdomain in turn, each sorted.
    pointer : ndarray of int64, shape (subdomains + 1,)
        Subdomain ``d`` is ``subdomain[pointer[d]:pointer[d + 1]]``.
    """
    graph = sp.csr_matrix(strength != 0, dtype=float)       # a copy: pyamg's C stays
    aggregates = sp.csr_matrix(aggregates, dtype=float)
    degree = np.asarray(graph.sum(axis=1)).ravel()
    share = sp.csr_matrix(sp.diags(1.0 / np.maximum(degree, 1.0)) @ graph @ aggregates)
    member = sp.csr_matrix(aggregates + (share >= OVERLAP).astype(float))
    alone = np.diff(member.indptr) == 0                     # unaggregated: isolated nodes
    member = sp.csc_matrix(sp.hstack([member, sp.eye(len(alone), format="csc")[:, alone]]))
    member = member[:, np.diff(member.indptr) > 0]          # no empty aggregate
    member.sort_indices()
    subdomain = (blocksize * member.indices[:, None] + np.arange(blocksize)).ravel()
    return subdomain.astype(np.int32), blocksize * member.indptr.astype(np.int64)


class Schwarz:
    """Multiplicative Schwarz on overlapping subdomains of a CSR matrix ``A``: in turn,
    each subdomain's residual rows solved exactly by the kept inverse of its block of
    ``A``, the correction added at once. The smoother keeps its own copy of each
    subdomain's rows of ``A``, in sweep order (a row in two subdomains twice): read
    straight through, their residuals cost half of what the rows gathered from ``A``
    cost. Inverses and rows are kept in single precision (:data:`INVERSES`,
    :data:`ROWS`); the residuals and corrections are summed in double.

    From :data:`SPLIT_FROM` unknowns the order runs on every core (:mod:`soilwater.linalg.threads`)
    and is the same on any number of them: the subdomains are split into :data:`GROUPS`
    runs of consecutive ones; those that touch no other run's (neither reads what the
    other writes) come first, each run's in its own order and the runs side by side; the
    others follow colour by colour (:func:`_greedy`; no two of a colour touch), each
    colour's side by side. The backward sweep is the forward one reversed.

    Parameters
    ----------
    A : scipy.sparse.csr_matrix, shape (n, n)
    subdomain, pointer : ndarray
        The subdomains, as :func:`subdomains` returns them.

    Attributes
    ----------
    subdomain, pointer : ndarray
        The subdomains in sweep order.
    runs : list of list of (int, int)
        The forward sweep: stages in turn, each a list of subdomain ranges that are
        solved side by side.
    calls : list of list of (int, int)
        The stages as the sweep calls them: a stage of at least :data:`SIDE_BY_SIDE_FROM`
        unknowns keeps its ranges, solved side by side; consecutive smaller ones are
        merged into one range, solved in the calling thread in the same order.
    inverses, inverse_pointer : ndarray
        Subdomain ``d``'s block inverse, row-major, is
        ``inverses[inverse_pointer[d]:inverse_pointer[d + 1]]``.
    rows : scipy.sparse.csr_matrix, shape (len(subdomain), n)
        Row ``k`` is row ``subdomain[k]`` of ``A``.

    Examples
    --------
    Two subdomains sharing the middle unknown of a 3 x 3 matrix; a forward sweep from
    zero solves the first exactly, then the second against the updated residual:

    >>> A = sp.csr_matrix([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
    >>> smoother = Schwarz(A, np.array([0, 1, 1, 2], np.int32), np.array([0, 2, 4]))
    >>> x = np.zeros(3)
    >>> smoother.forward(A, x, np.ones(3))
    >>> np.round(x, 6).tolist()
    [1.0, 1.666667, 1.333333]
    """

    def __init__(self, A, subdomain, pointer):
        A.sort_indices()
        order, self.runs = _sweep_order(A, subdomain, pointer)
        sizes = np.diff(pointer)[order]
        self.pointer = np.concatenate([[0], np.cumsum(sizes)])
        self.calls = _calls(self.runs, self.pointer)
        self.subdomain = subdomain[np.repeat(pointer[order] - self.pointer[:-1], sizes)
                                   + np.arange(self.pointer[-1])].view(np.uint32)
        self.inverse_pointer = np.concatenate([[0], np.cumsum(sizes**2)])
        self.inverses = np.empty(self.inverse_pointer[-1], dtype=INVERSES)
        for size in np.unique(sizes):                       # in batches of one size
            at = np.flatnonzero(sizes == size)
            rows = self.subdomain[self.pointer[at][:, None] + np.arange(size)].ravel()
            inverse = np.linalg.inv(_blocks(A, rows, size)).reshape(len(at), -1)
            at = self.inverse_pointer[at][:, None] + np.arange(size * size)
            self.inverses[at] = inverse
        self.rows = A[self.subdomain].astype(ROWS)

    def forward(self, A, x, b):
        """One sweep, ``x`` updated in place (pyamg's smoother signature; ``A`` is the
        matrix the smoother was built on, whose rows it keeps)."""
        self._sweep(x, b, self.calls, False)

    def backward(self, A, x, b):
        """The forward sweep reversed."""
        self._sweep(x, b, self.calls[::-1], True)

    def _sweep(self, x, b, stages, reverse):
        x, b, rows = x.reshape(-1), np.ravel(b), self.rows
        columns = rows.indices.view(np.uint32 if rows.indices.itemsize == 4 else np.uint64)

        def solve(lo, hi):
            _solve_subdomains(rows.indptr, columns, rows.data, x, b, self.subdomain,
                              self.pointer, self.inverses, self.inverse_pointer, lo, hi,
                              reverse)

        for ranges in stages:
            run(solve, ranges)


def _sweep_order(A, subdomain, pointer):
    """The subdomains' sweep order of :class:`Schwarz` and its stages (lists of
    subdomain ranges, in that order, solved side by side)."""
    n, count = A.shape[0], len(pointer) - 1
    member = sp.csc_matrix((np.ones(len(subdomain), np.float32), subdomain, pointer),
                           shape=(n, count))
    reach = sp.csr_matrix((np.ones(A.nnz, np.float32), A.indices, A.indptr), shape=A.shape)
    touch = sp.csr_matrix(member.T @ (reach @ member) + member.T @ member)
    touch = sp.csr_matrix(touch + touch.T)                  # d reads what e writes, or e d's
    runs = max(min(GROUPS if pointer[-1] >= SPLIT_FROM else 1, count), 1)
    group = np.arange(count) * runs // max(count, 1)
    rows = np.repeat(np.arange(count), np.diff(touch.indptr))
    shared = np.zeros(count, bool)
    shared[rows[group[touch.indices] != group[rows]]] = True
    inner, outer = np.flatnonzero(~shared), np.flatnonzero(shared)
    between = sp.csr_matrix(touch[outer][:, outer])
    colour = _greedy(between.indptr, between.indices)
    outer = outer[np.argsort(colour, kind="stable")]
    ends = np.cumsum(np.concatenate([np.bincount(group[inner], minlength=runs),
                                     np.bincount(colour)])).tolist()
    starts = [0, *ends[:-1]]
    stages = [list(zip(starts[:runs], ends[:runs]))]
    stages += [parts(lo, hi) for lo, hi in zip(starts[runs:], ends[runs:])]
    return np.concatenate([inner, outer]), stages


def _calls(stages, pointer):
    """:attr:`Schwarz.calls` of the ``stages`` (subdomains ``d`` holding the unknowns
    ``pointer[d]:pointer[d + 1]``)."""
    calls = []
    for ranges in stages:
        lo, hi = ranges[0][0], ranges[-1][1]
        if len(ranges) > 1 and pointer[hi] - pointer[lo] >= SIDE_BY_SIDE_FROM:
            calls.append(ranges)
        elif calls and len(calls[-1]) == 1:
            calls[-1] = [(calls[-1][0][0], hi)]
        else:
            calls.append([(lo, hi)])
    return calls


def _blocks(A, rows, size):
    """The dense blocks ``A[s][:, s]`` (m, size, size) of the m subdomains ``s`` of
    ``size`` unknowns each, ``rows`` their unknowns in turn."""
    from pyamg import amg_core

    count, index = len(rows) // size, A.indices.dtype
    local = np.arange(count + 1) * size
    blocks = np.zeros(count * size * size)
    amg_core.extract_subblocks(A.indptr, A.indices, A.data, blocks,
                               (local * size).astype(index), rows.astype(index),
                               local.astype(index), count, A.shape[0])
    return blocks.reshape(count, size, size)


@numba.njit(cache=True)
def _greedy(indptr, indices):
    """Greedy colouring of a graph's vertices in order: each takes the smallest colour
    none of its coloured neighbours has."""
    count = len(indptr) - 1
    colour, seen = np.full(count, -1), np.full(count + 1, -1)
    for v in range(count):
        for k in range(indptr[v], indptr[v + 1]):
            if colour[indices[k]] >= 0:
                seen[colour[indices[k]]] = v
        c = 0
        while seen[c] == v:
            c += 1
        colour[v] = c
    return colour


@numba.njit(cache=True, nogil=True)
def _solve_subdomains(indptr, indices, data, x, b, subdomain, pointer, inverses,
                      inverse_pointer, lo, hi, reverse):
    """Subdomains ``lo:hi`` solved in turn (``reverse``: from the last): each one's
    residual rows multiplied by its inverse and added to ``x``; ``indptr, indices, data``
    are the CSR rows of the ``subdomain`` unknowns in turn (:attr:`Schwarz.rows`)."""
    r = np.empty(np.max(pointer[lo + 1:hi + 1] - pointer[lo:hi]) if hi > lo else 0)
    for k in range(lo, hi):
        d = hi - 1 - (k - lo) if reverse else k
        rows = subdomain[pointer[d]:pointer[d + 1]]
        for i in range(len(rows)):
            start, stop = indptr[pointer[d] + i], indptr[pointer[d] + i + 1]
            r[i] = b[rows[i]] - _dot(data[start:stop], indices[start:stop], x)
        _block_solve(inverses[inverse_pointer[d]:inverse_pointer[d + 1]], r, rows, x)


@numba.njit(cache=True, nogil=True)
def _dot(values, columns, x):
    """``sum values * x[columns]``: a sparse row times ``x``, summed in order."""
    s = 0.0
    for k in range(len(values)):
        s += values[k] * x[columns[k]]
    return s


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _block_solve(inverse, r, rows, x):
    """``x[rows] += inverse @ r[:n]``, the inverse n x n, row-major (its sums
    reassociated, so they vectorise)."""
    n = len(rows)
    for i in range(n):
        line = inverse[i * n:(i + 1) * n]
        s = 0.0
        for j in range(n):
            s += line[j] * r[j]
        x[rows[i]] += s
