"""The choice of linear solver for both coupled solvers' Newton tangents.

Three back-ends, one interface (:func:`factorise` returns an object with ``solve(b)``):

- ``"pardiso"``: Intel MKL PARDISO, threaded (:mod:`soilwater.linalg.pardiso`; extra
  ``soilwater[fast]``, x86_64 only);
- ``"superlu"``: scipy's SuperLU, always available, single-threaded
  (:mod:`soilwater.linalg.direct`);
- ``"krylov"``: no factorisation; flexible GMRES with a block preconditioner
  (:mod:`soilwater.linalg.krylov`, needs pyamg). Each solve stops at the relative residual
  :func:`soilwater.linalg.layout.forcing` asks for (inexact Newton). Its memory grows as
  N, a factor's faster.

``pardiso`` is used when ``pypardiso`` imports, else ``superlu``; from
:data:`KRYLOV_FROM` unknowns, ``krylov`` for a discretisation whose policy says it suits
it (:attr:`soilwater.linalg.layout.Policy.iterative`), where pyamg imports. The
environment variable ``SOILWATER_LINEAR_SOLVER`` (``superlu``, ``pardiso`` or ``krylov``)
forces one. The direct ones reuse a factorisation while it contracts the Newton residual
(modified Newton, :func:`soilwater.linalg.layout.must_refactorise`); the Krylov one
solves with the current tangent at every iteration through the preconditioner of the
step's first (Newton).

PARDISO factorises the tangent of a discretisation whose policy asks for it
(:attr:`soilwater.linalg.layout.Policy.single`) in single precision while :data:`SINGLE`
is on, and refines each solve in double.

``factorise(K, layout, symmetric=True)`` asks for the cheaper symmetric factorisation of
``sym(K) = (K + K^T) / 2``, for a tangent that is nearly symmetric (PARDISO; SuperLU has
no symmetric mode and factorises ``K``). Its solve is the solve of ``sym(K)``, so a
Newton correction carries the error of the unsymmetric part; the modified Newton
iteration can start a step with it and falls back to ``K`` when it stops contracting
(:data:`soilwater.nonlinear.newton.SYMMETRIC_FIRST`, off: it does not pay on these
tangents).
"""

import os
from contextlib import contextmanager
from functools import cache
from importlib.metadata import PackageNotFoundError, version

from soilwater.errors import InputError
from soilwater.linalg.direct import _SuperLU
from soilwater.linalg.environment import setting
from soilwater.linalg.krylov import Krylov
from soilwater.linalg.pardiso import _Pardiso

#: From this many unknowns the Krylov back-end is the default for a discretisation that
#: suits it (:attr:`soilwater.linalg.layout.Policy.iterative`): 3 x 10^5 nodes of (ux, uy,
#: p_w), where EFG's PARDISO factor would need about 20 GB and its step is no faster than
#: Krylov's from 10^5 nodes on (``make bench``, which runs both there).
KRYLOV_FROM = 900_000
#: PARDISO factorises the tangent of a discretisation that asks for it
#: (:attr:`soilwater.linalg.layout.Policy.single`) in single precision and refines its
#: solves in double (:class:`soilwater.linalg.pardiso._Pardiso`). On the first tangent
#: of the bench step (Nitsche EFG, 10^5 nodes) the single factorisation took 16.2 s against
#: 28.2 s, and each refinement divides the scaled residual by about 3000 (``python
#: docs/experiments/direct_single.py``).
SINGLE = True


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
    that suits it (``iterative``,
    :attr:`soilwater.linalg.layout.Policy.iterative`) from :data:`KRYLOV_FROM`
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


def factorise(K, layout=None, symmetric=False):
    """Factorise the square sparse matrix ``K`` (or its symmetric part) with the back-end
    of :func:`backend` (``krylov``: build its preconditioner).

    Parameters
    ----------
    K : scipy.sparse matrix, shape (n, n)
        The tangent, unknowns numbered displacements before pore pressures.
    layout : soilwater.linalg.layout.Layout, optional
        What the unknowns are. With ``layout.groups``, the node (or location) each
        unknown belongs to, PARDISO orders the nodes by
        nested dissection and keeps a node's unknowns together in their index order, so
        its pore pressure is eliminated after its own displacements: the zero pressure
        block of an undrained body needs no pivoting, and the costly weighted matching is
        skipped (one step of iterative refinement instead: the modified Newton iteration
        refines the solution anyway). Unknowns of group -1 (a rigid
        plate, a Lagrange multiplier) are ordered last. SuperLU ignores ``groups``. The
        Krylov back-end needs every attribute of the layout.
    symmetric : bool
        Factorise ``sym(K) = (K + K^T) / 2`` as symmetric indefinite (PARDISO,
        :data:`soilwater.linalg.pardiso.SYMMETRIC_NODE_BLOCKED` or
        :data:`soilwater.linalg.pardiso.SYMMETRIC`): ``solve`` then solves with
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
    >>> from soilwater.linalg.layout import Layout
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
