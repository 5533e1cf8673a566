"""The iterative back-end of :mod:`soilwater.linalg.backends`: block-preconditioned FGMRES.

``SOILWATER_LINEAR_SOLVER=krylov`` replaces the factorisation of a Newton tangent

.. math::

    K = \\begin{bmatrix} A & B \\\\ C & D \\end{bmatrix}
    \\quad (A: \\text{displacements}, D: \\text{pore pressures})

by a preconditioner, and each solve by flexible GMRES (``pyamg.krylov.fgmres``, right
preconditioned, so the residual it stops on is the true one). The preconditioner is block
upper triangular,

.. math::

    P^{-1} r: \\quad y_p = \\hat S^{-1} r_p, \\qquad y_u = \\hat A^{-1} (r_u - B y_p),

with one V-cycle of smoothed-aggregation AMG (pyamg) for each block solve:
:math:`\\hat A^{-1}` with rigid-body near-null modes from the unknowns' locations (2 x 2
node blocks when every node carries both displacements), :math:`\\hat S^{-1}` on the
fixed-stress Schur complement

.. math::

    \\hat S = D - s \\, M_p / M,

``M_p`` the pressure mass matrix (``int N_i N_j dV``), ``M`` the P-wave modulus of the
initial state and ``s`` the sign of :math:`C A^{-1} B` (read from its diagonal
:math:`\\sum_j C_{ij} B_{ji} / A_{jj}`). It needs no permeability: at ``k = 0`` the
stabilisation of a stabilised pair is what ``D`` holds, and the mass term keeps
:math:`\\hat S` definite where ``D`` vanishes. EFG's ``M_p`` is the consistent matrix:
its MLS functions overlap so widely that the lumped mass overstates rough pressure modes
(with exact block solves FGMRES takes 319 iterations with it at 10^4 nodes, 11 with the
consistent one: ``python docs/krylov_study.py --schur``).

The V-cycles smooth by symmetric Gauss-Seidel on node blocks (pyamg's default), except
where the discretisation asks for Schwarz (``Layout.smoother``): then the finest level is
smoothed by multiplicative Schwarz on overlapping aggregates (:func:`_subdomains`,
:class:`_Schwarz`): the first coarsening's aggregates, each grown by every unknown with
at least :data:`OVERLAP` of its matrix neighbours in it, solved exactly in turn (their
inverses kept), forward before the coarse correction and backward after it (the cycle
stays symmetric at half the cost of symmetric sweeps on both sides), in an order whose
independent subdomains are solved side by side on every core.
Gauss-Seidel smooths a wide MLS stencil poorly (77 FGMRES iterations against 19 at 10^4
nodes, the Schur complement solved exactly), and P1 and Q2 elements well enough that
Schwarz's dearer sweeps do not pay (``python docs/krylov_study.py --smoother``).
Unknowns of neither field (a rigid plate's settlement, the mean-pressure multiplier) are
eliminated exactly through the preconditioner (a dense Schur complement of their few
rows). The AMG setup runs under a fixed random seed (:func:`_seeded`), so a
preconditioner, and a run's iteration counts, repeat.

Rows are scaled by the residual scales of :class:`soilwater.nonlinear.coupling.Scales` (force or volume per
unit thickness), so the relative residual FGMRES stops on weighs equilibrium and continuity
as the Newton tolerance does.
"""

from contextlib import contextmanager
from functools import partial

import numba
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.errors import ConvergenceError, InputError
from soilwater.linalg.threads import parts, run

#: FGMRES restart length (Krylov vectors kept).
RESTART = 60
#: FGMRES iterations of one solve. A solve that has not reached its tolerance by then
#: still returns its correction if it at least halved the residual (Newton judges it);
#: otherwise it fails.
MAX_ITERATIONS = 600
#: Relative residual above which an unfinished solve fails.
NO_PROGRESS = 0.5
#: Smallest coarse grid of the AMG hierarchies (solved by a pseudo-inverse).
MAX_COARSE = 500
#: An unknown joins the Schwarz subdomain of an aggregate when at least this share of
#: its matrix neighbours (nodes, for node blocks) belongs to the aggregate.
OVERLAP = 0.25
#: Runs of consecutive Schwarz subdomains whose inner ones are solved side by side
#: (:class:`_Schwarz`); a constant, so that the sweep is the same on any machine.
GROUPS = 2
#: Unknowns (summed over the subdomains) from which a Schwarz sweep is split into
#: :data:`GROUPS` runs; a smaller one keeps the subdomains' own order, one after another:
#: there the split gains little time.
SPLIT_FROM = 100_000
#: Unknowns (summed over its subdomains) from which a stage of a Schwarz sweep is solved
#: side by side; a smaller one costs less than handing it to the threads.
SIDE_BY_SIDE_FROM = 10_000
#: Precision of the Schwarz smoother's kept inverses and rows (:class:`_Schwarz`): single.
#: A smoother needs no more (FGMRES's residual stays double): on the 10^5-node EFG tangent
#: FGMRES takes 25 iterations to 1e-8 either way, the inverses take half the memory, the
#: rows two thirds, and the solve about a tenth less time (scratch timing).
INVERSES = ROWS = np.float32
#: The smoother of every level Schwarz does not smooth: symmetric Gauss-Seidel on the
#: matrix's blocks (nodes; pyamg's default).
GAUSS_SEIDEL = ("block_gauss_seidel", {"sweep": "symmetric"})


class Krylov:
    """The preconditioner of one tangent, and FGMRES solves with it.

    Parameters
    ----------
    K : scipy.sparse matrix, shape (n, n)
    layout : soilwater.linalg.backends.Layout

    Attributes
    ----------
    iterations : int
        FGMRES iterations of all solves so far.
    backend : str
        ``"krylov"`` (:func:`soilwater.linalg.backends.backend`).
    factorisations, symmetric, single, perturbed_pivots, flops
        1, False, False, 0 and 0.0: the counts :func:`soilwater.nonlinear.coupling.newton` keeps of a
        factorisation (one preconditioner build).
    current : bool
        True: solves are as cheap with the current tangent as with the first, so Newton
        hands it over at every iteration (:meth:`adopt`) and converges as Newton, not
        as modified Newton.
    """

    backend, symmetric, perturbed_pivots, flops, current = "krylov", False, 0, 0.0, True
    factorisations, single = 1, False

    def __init__(self, K, layout):
        if layout is None or not layout.complete:
            raise InputError("SOILWATER_LINEAR_SOLVER=krylov needs a solver that describes "
                             "its unknowns (fields, locations, scales, pressure mass); use "
                             "pardiso or superlu here")
        fields, blocked = layout.fields, _node_blocked(layout)
        u = blocked[np.isin(fields[blocked], (0, 1))]
        p, other = np.flatnonzero(fields == 2), np.flatnonzero(fields < 0)
        self.order, self.sizes = np.concatenate([u, p, other]), (len(u), len(p))
        self.row = 1.0 / layout.scales[self.order]
        self.iterations = 0
        nu, nm = len(u), len(u) + len(p)
        scaled = sp.csr_matrix(sp.diags(self.row) @ _permuted(sp.csr_matrix(K), self.order))
        A, self.B, self.F = scaled[:nu, :nu], scaled[:nu, nu:nm], scaled[nm:, :nm]
        border, corner = scaled[:nm, nm:].toarray(), scaled[nm:, nm:].toarray()
        C, D = scaled[nu:nm, :nu], scaled[nu:nm, nu:nm]
        del scaled                                    # the blocks only, from here
        mass = sp.diags(self.row[nu:nm]) @ layout.mass_matrix()[p][:, p] / layout.modulus
        self.amg_p, self.sign_p = _amg_schur(A, self.B, C, D, mass, layout)
        del C, D, mass
        self.amg_u = _amg(A, layout.smoother, layout.strength,
                          _rigid_modes(layout.locations[u], fields[u]),
                          2 if _pairs(layout, u) else 1)
        del A
        if len(other):
            self.Z = np.column_stack([self._main(e) for e in border.T])
            self.schur = np.linalg.inv(corner - self.F @ self.Z)
        self.adopt(K)

    def adopt(self, K):
        """Solve with the tangent ``K`` from now on, keeping the preconditioner (built
        from the first tangent of the Newton step: within a step the tangent changes
        little). Returns True."""
        self.K = sp.csr_matrix(K)
        return True

    def release(self):
        """Drop the tangent (the preconditioner stays) until the next :meth:`adopt`:
        Newton calls it before it assembles the next tangent, so that two are never held
        at once."""
        self.K = None

    def _matvec(self, x):
        """The scaled, reordered tangent times ``x``."""
        y = np.empty_like(x)
        y[self.order] = x
        return self.row * (self.K @ y)[self.order]

    def _main(self, r):
        """The block-triangular preconditioner on displacement and pressure rows."""
        nu = self.sizes[0]
        y_p = self.amg_p(self.sign_p * r[nu:])
        return np.concatenate([self.amg_u(r[:nu] - self.B @ y_p), y_p])

    def _apply(self, r):
        """The preconditioner: :meth:`_main`, the other unknowns eliminated exactly."""
        nm = sum(self.sizes)
        y = self._main(r[:nm])
        if nm == len(r):
            return y
        y_o = self.schur @ (r[nm:] - self.F @ y)
        return np.concatenate([y - self.Z @ y_o, y_o])

    def solve(self, b, rtol=1e-10):
        """FGMRES on ``K x = b`` to the relative residual ``rtol`` of the scaled rows.

        Raises
        ------
        ConvergenceError
            Relative residual above :data:`NO_PROGRESS` after :data:`MAX_ITERATIONS`
            iterations (a near-singular tangent: a limit point, a mechanism).
        """
        from pyamg.krylov import fgmres

        residuals = []
        x, _ = fgmres(spla.LinearOperator(self.K.shape, self._matvec),
                      self.row * np.asarray(b, float)[self.order],
                      M=spla.LinearOperator(self.K.shape, self._apply), tol=rtol,
                      restart=min(RESTART, self.K.shape[0]),    # pyamg's own cap, unwarned
                      maxiter=-(-MAX_ITERATIONS // RESTART),
                      residuals=residuals)
        self.iterations += len(residuals) - 1
        if residuals[0] and residuals[-1] > max(1.01 * rtol, NO_PROGRESS) * residuals[0]:
            raise ConvergenceError(f"FGMRES relative residual {residuals[-1] / residuals[0]:.1e}"
                                   f" after {len(residuals) - 1} iterations (wanted "
                                   f"{rtol:.1e})")
        out = np.empty_like(x)
        out[self.order] = x
        return out


def _permuted(K, order):
    """``K[order][:, order]`` of a CSR matrix, its column indices sorted: the columns
    renumbered rather than indexed (0.6 s against scipy's 1.4 s on the 10^5-node bench
    tangent)."""
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    permuted = sp.csr_matrix((K.data, rank[K.indices], K.indptr), shape=K.shape)[order]
    permuted.sort_indices()
    return permuted


def _node_blocked(layout):
    """All unknowns, sorted by group (node) then field, when groups are known."""
    n = len(layout.fields)
    if layout.groups is None:
        return np.arange(n)
    return np.lexsort((layout.fields, layout.groups))


def _pairs(layout, u):
    """True if the displacement unknowns ``u`` come as (x, y) pairs of one node each."""
    if layout.groups is None or len(u) % 2:
        return False
    g, f = layout.groups[u], layout.fields[u]
    return bool(np.all(g[0::2] == g[1::2]) and np.all(f[0::2] == 0) and np.all(f[1::2] == 1))


def _rigid_modes(locations, fields):
    """The 2-D rigid-body modes (translations, rotation) on displacement unknowns."""
    xy = locations - locations.mean(axis=0)
    modes = np.zeros((len(xy), 3))
    modes[fields == 0, 0] = 1.0
    modes[fields == 1, 1] = 1.0
    modes[:, 2] = np.where(fields == 0, -xy[:, 1], xy[:, 0])
    return modes


def _amg(A, smoother, strength, modes=None, blocksize=1):
    """One V-cycle of smoothed-aggregation AMG on ``A`` (near-null ``modes``; unknowns in
    node blocks of ``blocksize``; couplings of at least ``strength``, pyamg's symmetric
    measure), its finest level smoothed by :class:`_Schwarz` if ``smoother`` is
    ``"schwarz"``, every other level by symmetric Gauss-Seidel."""
    import pyamg

    matrix = sp.bsr_matrix(A, blocksize=(blocksize,) * 2) if blocksize > 1 else sp.csr_matrix(A)
    with _seeded():
        ml = pyamg.smoothed_aggregation_solver(matrix, B=modes, max_coarse=MAX_COARSE,
                                               strength=("symmetric", {"theta": strength}),
                                               keep=True, presmoother=GAUSS_SEIDEL,
                                               postsmoother=GAUSS_SEIDEL)
    if smoother == "schwarz" and len(ml.levels) > 1:   # one level: a coarse solve alone
        fine = ml.levels[0]
        fine.A = sp.csr_matrix(A)           # the smoother's matrix serves the cycle too
        schwarz = _Schwarz(fine.A, *_subdomains(fine.C, fine.AggOp, blocksize))
        fine.presmoother, fine.postsmoother = schwarz.forward, schwarz.backward
    for level in ml.levels:                 # what keep=True held for the smoother's setup
        for name in ("C", "AggOp", "T", "P0"):
            level.__dict__.pop(name, None)
    return partial(_v_cycle, ml.levels, ml.coarse_solver)


def _v_cycle(levels, coarse_solver, b, level=0):
    """One V-cycle from a zero guess on the pyamg hierarchy ``levels[level:]``: the cycle
    of ``MultilevelSolver.solve(b, maxiter=1)``, without the two finest-level residuals
    that ``solve`` computes for its stopping test (a fifth of the displacement cycle's
    time on the 10^5-node EFG tangent)."""
    if len(levels) - level == 1:
        return coarse_solver(levels[level].A, b)
    here = levels[level]
    x = np.zeros_like(b)
    here.presmoother(here.A, x, b)
    coarse_b = here.R @ (b - here.A @ x)
    x += here.P @ _v_cycle(levels, coarse_solver, coarse_b, level + 1)
    here.postsmoother(here.A, x, b)
    return x


@contextmanager
def _seeded():
    """numpy's global random state fixed (and the caller's restored after): pyamg's
    spectral-radius estimates, which weigh the prolongation smoother, start from
    ``np.random.rand`` vectors, so an unseeded setup gives a different preconditioner,
    and a different iteration count, on every run."""
    state = np.random.get_state()
    np.random.seed(0)
    try:
        yield
    finally:
        np.random.set_state(state)


def _subdomains(strength, aggregates, blocksize):
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


class _Schwarz:
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
        The subdomains, as :func:`_subdomains` returns them.

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
    >>> smoother = _Schwarz(A, np.array([0, 1, 1, 2], np.int32), np.array([0, 2, 4]))
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
    """The subdomains' sweep order of :class:`_Schwarz` and its stages (lists of
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
    """:attr:`_Schwarz.calls` of the ``stages`` (subdomains ``d`` holding the unknowns
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
    are the CSR rows of the ``subdomain`` unknowns in turn (:attr:`_Schwarz.rows`)."""
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


def _amg_schur(A, B, C, D, mass, layout):
    """One V-cycle of :func:`_amg` (the ``layout``'s smoother and strength) on the
    fixed-stress Schur complement ``D - s mass``, s the sign of ``C A^-1 B`` (from its
    diagonal), multiplied by ``t = -s`` to make its diagonal positive. Returns the cycle
    of ``t S`` and t."""
    simple = sp.csr_matrix(C.multiply(B.T)) @ (1.0 / A.diagonal())
    sign = 1.0 if np.median(simple) >= 0 else -1.0
    return _amg(-sign * (D - sign * mass), layout.smoother, layout.strength), -sign
