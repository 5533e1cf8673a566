"""PARDISO, the threaded direct back-end: Intel MKL PARDISO through ``pypardiso``.

The extra ``soilwater[fast]`` (x86_64 only) installs it; ``make bench`` needs it.
Nested-dissection ordering (METIS), weighted matching for the zero pressure blocks of
undrained problems, or the node-blocked order of :func:`_grouped_order` that makes them
unnecessary. :class:`_Pardiso` factorises ``K`` (``mtype = 11``) or the upper triangle of
``sym(K) = (K + K^T) / 2`` as symmetric indefinite (``mtype = -2``, LDL^T with
Bunch-Kaufman 1x1 and 2x2 pivots: half the factor entries of the LU of ``K``).

A tangent whose :attr:`soilwater.linalg.layout.Policy.single` asks for it is factorised
in single precision: half the factor's memory and about half its time. Each solve is
refined in double precision against the tangent to a round-off residual
(:data:`REFINED`), and the factor is redone in double precision if a refinement does not
contract the residual :data:`soilwater.linalg.layout.CONTRACTION`-fold.

The ``iparm`` dictionaries use MKL's 1-based numbering.
"""

import ctypes
import os
import weakref

import numpy as np
import scipy.sparse as sp

from soilwater.errors import ConvergenceError
from soilwater.linalg import layout
from soilwater.linalg.direct import _Factor

#: The relative residual (scaled rows) a single-precision solve is refined to, whatever
#: the caller's ``rtol``: round-off, so that modified Newton takes the path of a double
#: factor. Refined only to a tenth of the Newton tolerance, fem-th's unconfined
#: compression (past its peak, where the path is chaotic) took 544 Newton iterations and
#: 4 cut-backs against 590 and 5, q 4e-3 of its range away; refined to 1e-12, the same
#: 590 and 5 and q within 4e-12, as SuperLU and PARDISO in double agree (8e-12).
REFINED = 1e-12
#: PARDISO ``iparm`` (MKL's 1-based numbering) of the node-blocked factorisation: own
#: settings (1), METIS ordering (2), the user's permutation (5), one step of iterative
#: refinement (8), pivots perturbed by 1e-13 (10), no scaling (11) and no weighted
#: matching (13).
NODE_BLOCKED = {1: 1, 2: 2, 5: 1, 8: 1, 10: 13, 11: 0, 13: 0}
#: ``iparm`` of the symmetric indefinite factorisation (``mtype = -2``) in the node-blocked
#: order: as :data:`NODE_BLOCKED`, with Bunch-Kaufman 1x1 and 2x2 pivots (21). The
#: symmetric weighted matching (13 = 1) would cost four times the factorisation, and
#: without the node order (METIS on the unknowns) the zero pressure block perturbs
#: thousands of pivots and the solve fails.
SYMMETRIC_NODE_BLOCKED = {**NODE_BLOCKED, 21: 1}
#: ``iparm`` of the symmetric indefinite factorisation without ``groups``: METIS (2),
#: pivots perturbed by 1e-8 (10), scaling (11) and symmetric weighted matching (13), which
#: pair the zero pressure pivots of a P1/P1 saddle point with 2x2 blocks, Bunch-Kaufman
#: pivots (21); refinement when pivots were perturbed (8 = 0). MKL recommends them for
#: saddle-point problems; its defaults for ``mtype = -2`` (no matching) fail there.
SYMMETRIC = {1: 1, 2: 2, 10: 8, 11: 1, 13: 1, 21: 1}
#: MKL's defaults for an unsymmetric matrix (``mtype = 11``) as own settings (1): METIS
#: (2), pivots perturbed by 1e-13 (10), scaling (11) and weighted matching (13).
UNSYMMETRIC = {1: 1, 2: 2, 10: 13, 11: 1, 13: 1}
#: ``iparm`` added for a single-precision factorisation (28): PARDISO refines by itself
#: (in single precision) only where it perturbed pivots (8 = 0); :class:`_Pardiso`
#: refines in double.
SINGLE_PRECISION = {8: 0, 28: 1}
#: PARDISO ``iparm`` of the ordering-only analysis of the node graph: own settings (1),
#: METIS (2), the permutation returned in ``perm`` (5 = 2), no weighted matching (13).
NODE_ORDERING = {1: 1, 2: 2, 5: 2, 13: 0}


class _Pardiso(_Factor):
    """A PARDISO factorisation of one matrix (of ``K``, or of ``sym(K)`` when
    ``symmetric``); its MKL memory is freed with the object.

    With ``scales`` (the residual scale of each row), ``K`` is factorised in single
    precision (``iparm(28) = 1``, :data:`SINGLE_PRECISION`) and each solve is refined in
    double against ``K``, its residual measured with rows divided by ``scales``. A
    refinement that does not divide that residual
    :data:`soilwater.linalg.layout.CONTRACTION`-fold means the single factor is too coarse
    for ``K``: ``K`` is factorised again in double precision (``single`` becomes False;
    ``flops`` adds the second factorisation's)."""

    backend = "pardiso"

    def __init__(self, K, groups=None, symmetric=False, scales=None):
        self.symmetric, self.scales, self.flops = symmetric, scales, 0.0
        self.A = _upper_symmetric(K) if symmetric else sp.csr_matrix(K, dtype=float)
        self.A.sort_indices()
        self.one_based = _one_based(self.A)
        if not np.diff(self.A.indptr).all():
            raise ConvergenceError("the tangent is singular (it has an empty row)")
        self.grouped, self.solver = groups is not None, _solver(mtype=-2 if symmetric else 11)
        if groups is not None:
            self.solver.perm = _grouped_order(self.A, np.asarray(groups, np.int64)) + 1
        # phase -1: all of MKL's memory for this solver; the default (phase 0) frees
        # only the factor and leaks the analysis of every factorisation (14 MB a step
        # on a 21 x 21 footing, 14 GB over a 41 x 41 run)
        weakref.finalize(self, self.solver.free_memory, everything=True)
        self._factorise(single=scales is not None)

    @property
    def single(self):
        """True while the kept factor is in single precision."""
        return self.A32 is not None

    def solve(self, b, rtol=None):
        """The solution of ``K x = b``; a single-precision factor refines it in double to
        the scaled relative residual :data:`REFINED` (``rtol`` is ignored)."""
        b = np.ascontiguousarray(b, dtype=float)
        if self.single:
            x = self._refined(b)
            if x is not None:
                return x
            self.solver.free_memory(everything=True)
            self._factorise(single=False)
            self.factorisations += 1
        return self._phase(33, b)

    def _refined(self, b, residuals=None):
        """Iterative refinement of the single factor's solution in double to
        :data:`REFINED`; None when a refinement contracts the scaled residual less than
        :data:`soilwater.linalg.layout.CONTRACTION`-fold. Each solve's scaled relative
        residual is appended to the list ``residuals`` if one is given."""
        x, r = np.zeros_like(b), b
        size = previous = np.linalg.norm(b / self.scales)
        while True:
            x += self._phase(33, r.astype(np.float32))
            r = b - self.A @ x
            residual = np.linalg.norm(r / self.scales)
            if residuals is not None:
                residuals.append(residual / size)
            if residual <= REFINED * size:
                return x
            if not residual <= layout.CONTRACTION * previous:      # NaN too
                return None
            previous = residual

    def _factorise(self, single):
        """PARDISO's analysis and factorisation (phase 12) of :attr:`A`, in single
        precision (of a float32 copy, :attr:`A32`) or double."""
        import pypardiso

        self.A32 = sp.csr_matrix(self.A, dtype=np.float32) if single else None
        self.solver.iparm[:] = 0
        for index, value in _settings(self.grouped, self.symmetric, single).items():
            self.solver.set_iparm(index, value)
        self.solver.set_iparm(19, -1)            # report the factorisation's Mflops
        try:
            self._phase(12, np.zeros(self.A.shape[0], np.float32 if single else float))
        except pypardiso.pardiso_wrapper.PyPardisoError as err:
            raise ConvergenceError(f"the tangent is singular ({err})") from None
        self.perturbed_pivots = int(self.solver.get_iparm(14))
        self.flops += 1e6 * float(self.solver.get_iparm(19))

    def _phase(self, phase, b):
        """PARDISO phase 12 (analysis, factorisation) or 33 (solve), on :attr:`A32` while
        the factor is single. ``PyPardisoSolver``'s own ``factorize`` and ``solve`` keep a
        copy of the matrix and compare it on every solve, at a cost that grows with the
        matrix; this object owns its matrix and its 1-based indices (:func:`_pardiso`)."""
        self.solver.set_phase(phase)
        return _pardiso(self.solver, (self.A if self.A32 is None else self.A32).data,
                        self.one_based, b)


def _one_based(A):
    """The CSR index arrays ``(indptr + 1, indices + 1)`` of ``A`` as int32, PARDISO's."""
    return A.indptr.astype(np.int32) + 1, A.indices.astype(np.int32) + 1


def _pardiso(solver, data, one_based, b):
    """One call of MKL's ``pardiso`` in the ``PyPardisoSolver``'s current phase: its
    ``_call_pardiso`` with the matrix given as its values ``data`` (float64, or float32 for
    a single-precision factor) and its :func:`_one_based` indices, which pypardiso would
    convert again on every call (0.04 s a call at 10^5 EFG nodes). ``b`` is C-contiguous and
    of the type of ``data``; returns ``x`` of that type."""
    import pypardiso

    ia, ja = one_based
    x, error = np.zeros_like(b), ctypes.c_int32(0)
    integer, real = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)

    def value(number):
        return ctypes.byref(ctypes.c_int32(number))

    solver._mkl_pardiso(solver.pt.ctypes.data_as(ctypes.POINTER(solver._pt_type[0])),
                        value(1), value(1), value(solver.mtype), value(solver.phase),
                        value(len(ia) - 1), data.ctypes.data_as(real),
                        ia.ctypes.data_as(integer), ja.ctypes.data_as(integer),
                        solver.perm.ctypes.data_as(integer),
                        value(1 if b.ndim == 1 else b.shape[1]),
                        solver.iparm.ctypes.data_as(integer), value(solver.msglvl),
                        b.ctypes.data_as(real), x.ctypes.data_as(real), ctypes.byref(error))
    if error.value:
        raise pypardiso.pardiso_wrapper.PyPardisoError(error.value)
    return x


def _settings(grouped, symmetric, single=False):
    """PARDISO's ``iparm`` for a factorisation in the node-blocked order (``grouped``) or
    not, of ``K`` or of ``sym(K)``, in double or ``single`` precision; an empty dict
    leaves MKL's defaults."""
    if symmetric:
        return SYMMETRIC_NODE_BLOCKED if grouped else SYMMETRIC
    if single:
        return {**(NODE_BLOCKED if grouped else UNSYMMETRIC), **SINGLE_PRECISION}
    return NODE_BLOCKED if grouped else {}


def _upper_symmetric(K):
    """The upper triangle of ``sym(K) = (K + K^T) / 2`` in CSR, PARDISO's input for a
    symmetric matrix: every diagonal entry is stored, zeros of a pressure block too."""
    S = sp.coo_matrix((K + K.T) / 2, dtype=float)
    upper, diagonal = S.row <= S.col, np.arange(K.shape[0])
    return sp.csr_matrix((np.concatenate([S.data[upper], np.zeros(K.shape[0])]),
                          (np.concatenate([S.row[upper], diagonal]),
                           np.concatenate([S.col[upper], diagonal]))), shape=K.shape)


def _solver(**options):
    """A new ``PyPardisoSolver``; the MKL library it found is remembered in
    ``PYPARDISO_MKL_RT``, so later ones skip pypardiso's search of the environment (a
    directory walk)."""
    import pypardiso

    solver = pypardiso.PyPardisoSolver(**options)
    os.environ.setdefault("PYPARDISO_MKL_RT", solver.libmkl._name)
    return solver


def _grouped_order(A, groups):
    """Fill-reducing order of the unknowns of ``A``: nodes by nested dissection (METIS,
    through PARDISO's reordering phase on the node graph), each node's unknowns together
    in index order, unknowns of group -1 last. Returns ``perm`` (0-based int32): row i
    of the permuted matrix is row ``perm[i]`` of ``A``."""
    n, member = A.shape[0], np.flatnonzero(groups >= 0)
    incidence = sp.csr_matrix((np.ones(len(member)), (groups[member], member)),
                              shape=(groups.max() + 1, n))
    pattern = sp.csr_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    graph = incidence @ pattern @ incidence.T
    graph = sp.csr_matrix(graph + graph.T + sp.eye(graph.shape[0]))
    graph.sort_indices()
    ordering = _solver()
    for index, value in NODE_ORDERING.items():
        ordering.set_iparm(index, value)
    ordering.perm = np.zeros(graph.shape[0], np.int32)
    ordering.set_phase(11)           # analysis only: METIS fills ``perm`` (iparm 5 = 2)
    _pardiso(ordering, graph.data, _one_based(graph), np.zeros((graph.shape[0], 1)))
    ordering.free_memory(everything=True)
    rank = np.empty(graph.shape[0] + 1, np.int64)
    rank[ordering.perm - 1] = np.arange(graph.shape[0])
    rank[-1] = graph.shape[0]        # group -1
    return np.lexsort((np.arange(n), rank[groups])).astype(np.int32)
