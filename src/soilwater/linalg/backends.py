"""The linear solvers of both coupled solvers' Newton tangents.

Three back-ends, one interface (:func:`factorise` returns an object with ``solve(b)``):

- ``"pardiso"``: Intel MKL PARDISO through ``pypardiso`` (extra ``soilwater[fast]``, x86_64
  only). Nested-dissection ordering (METIS), threaded, weighted matching for the zero
  pressure blocks of undrained problems. ``make bench`` installs it.
- ``"superlu"``: ``scipy.sparse.linalg.splu`` with minimum-degree ordering on ``A^T A``
  (:data:`SUPERLU_ORDERING`), always available, single-threaded. Its fill grows fast with
  the 20 to 30 neighbours of an MLS node, so it is slow on large EFG tangents (``make
  bench`` measures both).
- ``"krylov"``: no factorisation; flexible GMRES with a block preconditioner (AMG with a
  Schwarz smoother on the displacements, a fixed-stress Schur complement with the pressure
  mass matrix on the pore pressures; :mod:`soilwater.linalg.krylov`,
  needs pyamg). Each solve stops at the relative residual :func:`forcing` asks for
  (inexact Newton). Its memory grows as N, a factor's faster.

``pardiso`` is used when ``pypardiso`` imports, else ``superlu``; from
:data:`KRYLOV_FROM` unknowns, ``krylov`` for a discretisation it converges on
(:attr:`Layout.iterative`), where pyamg imports. The environment variable
``SOILWATER_LINEAR_SOLVER`` (``superlu``, ``pardiso`` or ``krylov``) forces one. The
direct ones reuse a factorisation while it contracts the Newton residual at least
:data:`CONTRACTION`-fold per iteration (modified Newton), and refactorise the current
tangent otherwise; the Krylov one solves with the current tangent at every iteration
through the preconditioner of the step's first (Newton).

PARDISO factorises the tangent of a discretisation that asks for it
(:attr:`Layout.single`) in single precision (:data:`SINGLE`): half the factor's memory and
about half its time. Each solve refines in double precision against the tangent to a
round-off residual (:data:`REFINED`), and the factor is redone in double precision if a
refinement does not contract the residual :data:`CONTRACTION`-fold.

``factorise(K, layout, symmetric=True)`` asks for the cheaper symmetric factorisation of
``sym(K) = (K + K^T) / 2``, for a tangent that is nearly symmetric: PARDISO factorises
its upper triangle as symmetric indefinite (``mtype = -2``, LDL^T with Bunch-Kaufman 1x1
and 2x2 pivots), half the factor entries of the LU of ``K``. Its solve is the solve of
``sym(K)``, so a Newton correction carries the error of the unsymmetric part; the
modified Newton iteration can start a step with it and falls back to ``K`` when it stops
contracting (:data:`soilwater.nonlinear.coupling.SYMMETRIC_FIRST`, off: it does not pay on our
tangents). SuperLU has no symmetric mode and factorises ``K``.
"""

import ctypes
import os
import weakref
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from importlib.metadata import PackageNotFoundError, version

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.linalg.environment import setting
from soilwater.errors import ConvergenceError, InputError
from soilwater.linalg.krylov import Krylov

#: A factorisation is kept while each iteration divides the residual by at least 1/this.
CONTRACTION = 0.1
#: Largest relative residual an inexact-Newton Krylov solve may stop at, unless the
#: discretisation asks for another (:attr:`Layout.forcing`; EFG does). On the FEM pairs
#: 1e-5 takes as many Newton iterations and more FGMRES iterations (``make bench``'s
#: fem-p1p1-stab step: 127 against 100 at 10^5 nodes, 137 against 108 at 3 x 10^5).
FORCING_MAX = 1e-4
#: From this many unknowns the Krylov back-end is the default for a discretisation that
#: suits it (:attr:`Layout.iterative`): 3 x 10^5 nodes of (ux, uy, p_w), where EFG's
#: PARDISO factor would need about 20 GB and its step is no faster than Krylov's from
#: 10^5 nodes on (``make bench``, which runs both there).
KRYLOV_FROM = 900_000
#: PARDISO factorises the tangent of a discretisation that asks for it
#: (:attr:`Layout.single`) in single precision and refines its solves in double
#: (:class:`_Pardiso`). On the first tangent of the bench step (Nitsche EFG, 10^5 nodes)
#: the single factorisation took 16.2 s against 28.2 s, and each refinement divides the
#: scaled residual by about 3000 (``python docs/krylov_study.py --single``).
SINGLE = True
#: The relative residual (scaled rows) a single-precision solve is refined to, whatever
#: the caller's ``rtol``: round-off, so that modified Newton takes the path of a double
#: factor. Refined only to a tenth of the Newton tolerance, fem-th's unconfined
#: compression (past its peak, where the path is chaotic) took 544 Newton iterations and
#: 4 cut-backs against 590 and 5, q 4e-3 of its range away; refined to 1e-12, the same
#: 590 and 5 and q within 4e-12, as SuperLU and PARDISO in double agree (8e-12).
REFINED = 1e-12
#: SuperLU's column ordering (``permc_spec``): minimum degree on ``A^T A``. On the first
#: tangent of the bench step it factorised EFG's 2.6 times faster than scipy's default,
#: COLAMD, at 10^4 nodes (8.4 s against 21.3 s, a quarter less fill) and 1.7 times at
#: 3 x 10^3, P1/P1's 1.5 and Q2/Q1's 1.1 to 1.35 times; Taylor-Hood's as fast at 3 x 10^3
#: and 11 % slower at 10^4 (``python docs/krylov_study.py --orderings``).
SUPERLU_ORDERING = "MMD_ATA"
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


@dataclass(frozen=True)
class Layout:
    """What the unknowns of a Newton system are, for the linear solvers.

    Attributes
    ----------
    groups : ndarray of int, shape (n,), or None
        The node (location) of each unknown, -1 for a rigid plate or a multiplier:
        PARDISO's node-blocked order (:func:`soilwater.linalg.backends.factorise`).
    fields : ndarray of int, shape (n,), or None
        0 and 1: displacement x and y [m]; 2: pore pressure [kPa]; -1: anything else.
    locations : ndarray, shape (n, 2), or None
        Where each unknown lives [m]: the rigid-body modes of the displacement AMG.
    scales : ndarray, shape (n,), or None
        The residual scale of each row: force or volume per unit thickness.
    mass : scipy.sparse matrix, shape (n, n), a function returning one, or None
        Pressure mass ``int N_i N_j dV`` [m2 per unit thickness] on pressure rows and
        columns, zero elsewhere; a function is called when a solver first needs it
        (:meth:`mass_matrix`). EFG gives the consistent matrix: MLS shape functions
        overlap so widely that the lumped one overstates rough pressure modes.
    modulus : float
        P-wave modulus ``K + 4G/3`` of the initial state [kPa].
    smoother : str
        How the Krylov back-end's AMG V-cycles smooth their finest level:
        ``"gauss_seidel"`` (symmetric Gauss-Seidel on node blocks) or ``"schwarz"``
        (multiplicative Schwarz on overlapping aggregates, :class:`soilwater.linalg.krylov._Schwarz`:
        dearer per sweep, it pays for MLS's wide stencils and for fem-th through a
        softening peak). The discretisation chooses (``python docs/krylov_study.py
        --smoother``); any other value is a ValueError.
    strength : float
        The Krylov back-end's strength-of-connection threshold ``theta`` of its AMG
        hierarchies, ``0 <= theta < 1``: a coupling counts (aggregates and Schwarz
        subdomains grow along it) where ``|a_ij| >= theta sqrt(|a_ii a_jj|)``. 0 (every
        coupling; pyamg's default) unless the discretisation asks for more
        (``python docs/krylov_study.py --strength``).
    iterative : bool
        The discretisation suits the Krylov back-end (EFG with Nitsche's conditions and a
        pressure stabilisation; the inf-sup stable or stabilised FEM pairs), which
        :func:`backend` then picks by default from :data:`KRYLOV_FROM` unknowns. False:
        a direct solver at every size, unless ``SOILWATER_LINEAR_SOLVER`` says otherwise.
    single : bool
        PARDISO factorises the tangent in single precision and refines each solve in
        double (:data:`SINGLE`, :class:`_Pardiso`): the discretisation's choice, where
        measured to pay (``python docs/krylov_study.py --single``; EFG with Nitsche's
        conditions and a stabilisation, fem-th). A penalty's tangent, whose diagonal spans
        10^6, is beyond a single factor's refinement.
    forcing : float
        The largest relative residual of an inexact-Newton Krylov solve
        (:func:`forcing`), ``0 < forcing < 1``: :data:`FORCING_MAX` unless the
        discretisation asks for another (``python docs/krylov_study.py --newton``).
    """

    groups: np.ndarray = None
    fields: np.ndarray = None
    locations: np.ndarray = None
    scales: np.ndarray = None
    mass: object = None
    modulus: float = 1.0
    smoother: str = "gauss_seidel"
    strength: float = 0.0
    iterative: bool = False
    single: bool = False
    forcing: float = FORCING_MAX

    def __post_init__(self):
        """Reject an unknown :attr:`smoother`, a :attr:`strength` outside [0, 1) or a
        :attr:`forcing` outside (0, 1)."""
        if self.smoother not in ("gauss_seidel", "schwarz"):
            raise ValueError(f"Layout.smoother={self.smoother!r}: use 'gauss_seidel' or "
                             "'schwarz'")
        if not 0.0 <= self.strength < 1.0:
            raise ValueError(f"Layout.strength={self.strength!r}: use a threshold in [0, 1)")
        if not 0.0 < self.forcing < 1.0:
            raise ValueError(f"Layout.forcing={self.forcing!r}: use a relative residual "
                             "in (0, 1)")

    @property
    def complete(self):
        """True if the layout names enough for the Krylov back-end."""
        return all(v is not None for v in (self.fields, self.locations, self.scales,
                                           self.mass))

    def mass_matrix(self):
        """The pressure mass matrix (``mass``, built first if it is a function)."""
        return sp.csr_matrix(self.mass() if callable(self.mass) else self.mass)


def available(name):
    """True if the back-end ``name`` (``"pardiso"``, ``"superlu"``, ``"krylov"``) can be
    used here."""
    if name == "superlu":
        return True
    try:
        if name == "krylov":
            import pyamg  # noqa: F401
        else:
            import pypardiso  # noqa: F401
    except ImportError:
        return False
    return True


def backend(unknowns=0, iterative=False):
    """Name of the back-end of a system of ``unknowns`` unknowns: ``"pardiso"``,
    ``"superlu"`` or ``"krylov"``.

    ``SOILWATER_LINEAR_SOLVER`` when it is set; else ``"krylov"`` for a discretisation
    that suits it (``iterative``, :attr:`Layout.iterative`) from :data:`KRYLOV_FROM`
    unknowns where pyamg imports; else ``"pardiso"`` where pypardiso imports; else
    ``"superlu"``.

    Examples
    --------
    >>> backend(KRYLOV_FROM, iterative=False) == backend()
    True
    """
    choice = os.environ.get("SOILWATER_LINEAR_SOLVER", "").lower()
    if choice not in ("", "pardiso", "superlu", "krylov"):
        raise InputError(f"SOILWATER_LINEAR_SOLVER={choice!r} is not a solver; use "
                         "'pardiso', 'superlu' or 'krylov'")
    if choice == "pardiso" and not available("pardiso"):
        raise InputError("SOILWATER_LINEAR_SOLVER=pardiso needs pypardiso: "
                         "pip install 'soilwater[fast]' (x86_64 only)")
    if choice == "krylov" and not available("krylov"):
        raise InputError("SOILWATER_LINEAR_SOLVER=krylov needs pyamg: "
                         "pip install pyamg")
    if choice:
        return choice
    if iterative and unknowns >= KRYLOV_FROM and available("krylov"):
        return "krylov"
    return "pardiso" if available("pardiso") else "superlu"


def identity(name=None):
    """``"name version"`` of the back-end ``name`` (None: :func:`backend`'s), e.g.
    ``"superlu scipy 1.14.1"`` or ``"pardiso pypardiso 0.4.6 mkl 2025.0.1"``: results are
    reproducible only to round-off across back-ends, so caches and sidecars record it."""
    return _described(backend() if name is None else name)


@cache
def _described(name):
    """:func:`identity` of the back-end ``name``, looked up once per process (Newton
    records it at every factorisation)."""
    if name == "superlu":
        import scipy

        return f"superlu scipy {scipy.__version__}"
    if name == "krylov":
        return f"krylov pyamg {_version('pyamg')}"
    return "pardiso " + " ".join(f"{package} {_version(package)}"
                                 for package in ("pypardiso", "mkl"))


def _version(distribution):
    try:
        return version(distribution)
    except PackageNotFoundError:
        return "unknown"


@contextmanager
def linear_solver(name):
    """Use the back-end ``name`` (``"pardiso"``, ``"superlu"``, ``"krylov"``; None: leave
    the choice to :func:`backend`) inside the ``with`` block, through
    ``SOILWATER_LINEAR_SOLVER``."""
    if name is None:
        yield
        return
    with setting("SOILWATER_LINEAR_SOLVER", name):
        backend()
        yield


def must_refactorise(lu, residual, previous):
    """True when no factorisation is kept or it contracted the residual too little."""
    return lu is None or residual > CONTRACTION * previous


def forcing(residual, previous, last, tolerance, cap=FORCING_MAX):
    """The relative residual an inexact-Newton solve stops at (Eisenstat and Walker 1996,
    choice 2 with their safeguard): ``0.9 (r_k / r_k-1)^2``, at least ``0.9 eta_k-1^2``
    when that exceeds 0.1, at most ``cap``, and no less than what takes the scaled
    residual to a tenth of the Newton ``tolerance``.

    Parameters
    ----------
    residual, previous : float
        The scaled Newton residual now and at the last iteration (``inf`` at the first).
    last : float
        The forcing of the last iteration (``cap`` at the first).
    tolerance : float
        The Newton tolerance on the scaled residual.
    cap : float
        The largest forcing (:attr:`Layout.forcing`).

    Examples
    --------
    The first solve stops at the cap; once the residual has dropped a thousandfold, at
    0.9 x (1e-3)^2:

    >>> forcing(1.0, float("inf"), FORCING_MAX, 1e-8)
    0.0001
    >>> round(forcing(1e-3, 1.0, 1e-5, 1e-10, cap=1e-5), 12)
    9e-07
    """
    eta = 0.9 * (residual / previous) ** 2 if np.isfinite(previous) else last
    if 0.9 * last**2 > 0.1:
        eta = max(eta, 0.9 * last**2)
    return float(min(max(eta, 0.1 * tolerance / residual), cap))


def factorise(K, layout=None, symmetric=False):
    """Factorise the square sparse matrix ``K`` (or its symmetric part) with the back-end
    of :func:`backend` (``krylov``: build its preconditioner).

    Parameters
    ----------
    K : scipy.sparse matrix, shape (n, n)
        The tangent, unknowns numbered displacements before pore pressures.
    layout : Layout, optional
        What the unknowns are. With ``layout.groups``, the node (or location) each
        unknown belongs to, PARDISO orders the nodes by
        nested dissection and keeps a node's unknowns together in their index order, so
        its pore pressure is eliminated after its own displacements: the zero pressure
        block of an undrained body needs no pivoting, and the costly weighted matching is
        skipped (one step of iterative refinement instead: the modified Newton iteration
        refines the solution anyway). Unknowns of group -1 (a rigid
        plate, a Lagrange multiplier) are ordered last. SuperLU ignores ``groups``. The
        Krylov back-end needs every attribute of :class:`Layout`.
    symmetric : bool
        Factorise ``sym(K) = (K + K^T) / 2`` as symmetric indefinite (PARDISO,
        :data:`SYMMETRIC_NODE_BLOCKED` or :data:`SYMMETRIC`): ``solve`` then solves with
        ``sym(K)``. SuperLU has no symmetric mode and factorises ``K``.

    Returns
    -------
    object
        ``solve(b, rtol)`` (``rtol``, the relative residual of an iterative solve, is
        ignored by the direct ones); ``symmetric``: whether it is the factorisation of
        ``sym(K)``; ``perturbed_pivots``: pivots PARDISO perturbed (``iparm(14)``; 0 for
        SuperLU, which does not perturb); ``flops``: floating-point operations of the
        factorisation as PARDISO reports them (``iparm(19)``; 0 for the others);
        ``iterations``: Krylov iterations of its solves (0 for the direct ones);
        ``factorisations``: 1, or 2 once a single-precision PARDISO factor was redone
        in double (``flops`` then counts both; ``single``: whether it is still single);
        ``backend``: the back-end's name (:func:`backend`); ``current``: whether Newton
        should hand it each new tangent (``adopt(K)``,
        False when it cannot solve with ``K`` and ``K`` must be factorised anew: the
        direct ones never can, the Krylov one always can, through its preconditioner).

    Raises
    ------
    ConvergenceError
        When the matrix is singular (a mechanism, or an undetermined pressure).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> K = sp.csr_matrix([[4.0, 1.0, 1.0], [1.0, 3.0, 1.0], [1.0, 1.0, 0.0]])
    >>> lu = factorise(K, Layout(groups=np.array([0, 1, -1])))
    >>> bool(np.allclose(K @ lu.solve(np.array([1.0, 2.0, 3.0])), [1.0, 2.0, 3.0]))
    True
    """
    name = backend(K.shape[0], layout is not None and layout.iterative)
    groups = None if layout is None else layout.groups
    if name == "krylov":
        return Krylov(K, layout)
    if name == "pardiso":
        single = SINGLE and not symmetric and layout is not None and layout.single
        return _Pardiso(K, groups, symmetric, layout.scales if single else None)
    return _SuperLU(K)


class _Factor:
    """What the direct factorisations share: no Krylov iterations, one factorisation
    (PARDISO's single precision may add a second, :class:`_Pardiso`), and a factorisation
    solves only with the tangent it factorised (``current`` False; :meth:`adopt`)."""

    iterations, factorisations, single, current = 0, 1, False, False

    def adopt(self, K):
        """False: a new tangent needs a new factorisation."""
        return False

    def release(self):
        """Nothing: a factorisation holds no tangent Newton could free."""


class _SuperLU(_Factor):
    """SuperLU's LU factorisation of ``K`` (it has no symmetric mode)."""

    backend, symmetric, perturbed_pivots, flops = "superlu", False, 0, 0.0

    def __init__(self, K):
        try:
            self.lu = spla.splu(sp.csc_matrix(K), permc_spec=SUPERLU_ORDERING)
        except RuntimeError as err:
            raise ConvergenceError(f"the tangent is singular ({err})") from None

    def solve(self, b, rtol=None):
        return self.lu.solve(b)


class _Pardiso(_Factor):
    """A PARDISO factorisation of one matrix (of ``K``, or of ``sym(K)`` when
    ``symmetric``); its MKL memory is freed with the object.

    With ``scales`` (the residual scale of each row), ``K`` is factorised in single
    precision (``iparm(28) = 1``, :data:`SINGLE_PRECISION`) and each solve is refined
    in double against ``K``, its residual measured with rows divided by ``scales``. A
    refinement that does not divide that residual :data:`CONTRACTION`-fold means the
    single factor is too coarse for ``K``: ``K`` is factorised again in double precision
    (``single`` becomes False; ``flops`` adds the second factorisation's)."""

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
        :data:`CONTRACTION`-fold. Each solve's scaled relative residual is appended to the
        list ``residuals`` if one is given."""
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
            if not residual <= CONTRACTION * previous:      # NaN too
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
    ``_call_pardiso`` with the matrix given as its values ``data`` (float64, or float32 for a
    single-precision factor) and its :func:`_one_based` indices, which pypardiso would
    convert again on every call (0.04 s a call at 10^5 EFG nodes). ``b`` is C-contiguous
    and of the type of ``data``; returns ``x`` of that type."""
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
