"""Finite-strain Cam-clay, original (Sekiguchi-Ohta form) and modified, on arrays of points.

Rate form on the current configuration: the Jaumann rate of the
Cauchy effective stress is ``C^ep : D``. Hypoelasticity with ``K = v p'/kappa`` and a
constant Poisson ratio (or, optionally, a constant shear modulus ``G``); associated flow.

Yield functions, written with the size ``p'c`` of the surface (its intercept on the p' axis):

* original: ``f = ln(p'/p'c) + q/(M p')``; with ``p'c = p'0 exp(eps_v^p / MD)`` and
  ``MD = (lambda - kappa)/(1 + e0)`` this is the paper's
  ``MD ln(p'/p'0) + MD q/(M p') - eps_v^p = 0`` divided by MD;
* modified: ``f = q^2/M^2 + p'(p' - p'c)`` with ``dp'c/p'c = v d eps_v^p / (lambda - kappa)``.

Sign conventions: stress is tension positive, stored as ``(xx, yy, zz, xy)``; strain
increments are Voigt vectors ``(xx, yy, zz, 2xy)``; p', q, p'c and ``eps_v^p`` are
compression positive. Units are those of the case (p'0 sets the stress unit).

Each equation has one home, a numba function of scalars: :func:`yield_function` (the
surface and its derivatives), :func:`surface_size`, :func:`hardening` and
:func:`mean_volume`. The return mapping (:func:`return_mapping`, a Newton iteration per
point) and the methods of :class:`CamClay` call them. numba caches their machine code in
``soil/__pycache__``; it is compiled again when this file changes.
"""

import math
from collections import namedtuple
from dataclasses import dataclass

import numba
import numpy as np

from soilwater.errors import ConvergenceError, InputError, require
from soilwater.material.kinematics import (DEVIATORIC, IDENTITY, deviator, double_dot, hughes_winget,
                             invariants)
from soilwater.material.protocol import Material
from soilwater.linalg.threads import parts, run

MODELS = ("original", "modified")

#: A clay's parameters as the numba functions read them (:attr:`CamClay.constants`):
#: ``modified`` (bool), M, lambda, kappa and MD.
Constants = namedtuple("Constants", "modified M lam kappa MD")

#: Status of a point after the return mapping.
CONVERGED, NOT_CONVERGED, SINGULAR = 0, 1, 2

#: The local problem a point solves: elastic (dgamma = 0), plastic on the smooth surface,
#: plastic on the vertex q = 0 of the original surface.
ELASTIC, SMOOTH, VERTEX = 0, 1, 2

#: numba options of every function here: division by zero gives inf or nan (a diverging
#: iteration ends in a status, not an exception inside numba).
jit = numba.njit(cache=True, error_model="numpy", nogil=True)


@dataclass(frozen=True)
class CamClay(Material):
    """Finite-strain Cam-clay parameters and its vectorised stress update.

    Parameters
    ----------
    lam, kappa : float
        Compression and swelling indices (slopes of v against ln p').
    M : float
        Critical state stress ratio.
    nu : float
        Poisson ratio, in (-1, 0.5); sets ``G = 3K(1 - 2 nu) / (2(1 + nu))``.
    e0 : float
        Initial void ratio (``v0 = 1 + e0``).
    p0 : float
        Initial (isotropic) mean effective stress p'0, compression positive.
    ocr : float
        Isotropic overconsolidation ratio ``p'c0 / p'0`` (>= 1).
    model : {"original", "modified"}
        Yield surface and hardening law.
    G : float or None
        Constant shear modulus; if given it replaces the Poisson-ratio rule.

    Examples
    --------
    >>> import numpy as np
    >>> clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0)
    >>> stress, state = clay.initial_state(2)
    >>> d = np.array([[0.002, -0.002, 0.0, 0.0]] * 2)
    >>> stress, state, tangent = clay.update(stress, state, d, np.zeros(2))
    >>> bool(np.all(clay.yield_value(stress, state) < 1e-10))
    True
    """

    lam: float
    kappa: float
    M: float
    nu: float
    e0: float
    p0: float
    ocr: float = 1.0
    model: str = "original"
    G: float | None = None

    def __post_init__(self):
        require(self.model in MODELS,
                f"material.model = {self.model!r} is unknown: use one of {', '.join(MODELS)}")
        require(self.kappa > 0, f"material.kappa = {self.kappa} must be positive")
        require(self.lam > self.kappa,
                f"material.lambda = {self.lam} must exceed kappa = {self.kappa}: "
                "the compression index is the larger slope")
        require(-1.0 < self.nu < 0.5,
                f"material.nu = {self.nu} must lie in (-1, 0.5): use a Poisson ratio such as 0.3")
        require(self.e0 > 0, f"material.e0 = {self.e0} must be positive (void ratio)")
        require(self.p0 > 0,
                f"material.p0 = {self.p0} must be positive: it is the initial mean effective "
                "stress p'0, compression positive")
        require(self.M > 0, f"material.M = {self.M} must be positive (critical state ratio)")
        require(self.ocr >= 1.0, f"material.ocr = {self.ocr} must be at least 1")
        require(self.G is None or self.G > 0, f"material.G = {self.G} must be positive")

    # -- derived constants -------------------------------------------------------------
    @property
    def v0(self):
        """Initial specific volume ``1 + e0``."""
        return 1.0 + self.e0

    @property
    def Lambda(self):
        """Plastic volumetric ratio ``(lambda - kappa) / lambda``."""
        return (self.lam - self.kappa) / self.lam

    @property
    def MD(self):
        """Dilatancy coefficient ``(lambda - kappa) / (1 + e0)`` of the original model."""
        return (self.lam - self.kappa) / self.v0

    # -- state -------------------------------------------------------------------------
    def initial_state(self, n, p=None):
        """Isotropic stress ``-p I`` (default p'0) and state ``{"pc", "v"}`` for n points."""
        p = self.p0 if p is None else p
        stress = -np.outer(np.broadcast_to(p, (n,)), IDENTITY)
        state = {"pc": np.full(n, self.ocr * self.p0), "v": np.full(n, self.v0)}
        return stress, state

    #: Cam-clay yields: it has rates for the stress-point driver.
    plastic = True

    def moduli(self, p=None, v=None):
        """Bulk and shear moduli ``K = v p'/kappa`` and G at mean stress p' and volume v
        (default: the initial p'0 and v0)."""
        p = self.p0 if p is None else p
        v = self.v0 if v is None else v
        K = v * p / self.kappa
        if self.G is not None:
            return K, np.full_like(K, self.G)
        return K, 1.5 * (1 - 2 * self.nu) / (1 + self.nu) * K

    @property
    def constants(self):
        """The parameters the numba functions read, as :data:`Constants`."""
        return Constants(self.model == "modified", float(self.M), float(self.lam),
                         float(self.kappa), float(self.MD))

    def hardening(self, v):
        """``theta`` in ``dp'c / p'c = theta d eps_v^p`` (compression positive) at
        specific volumes v (array or scalar): :func:`hardening` on each."""
        return _elementwise(_hardenings, self.constants, v)

    def yield_value(self, stress, state):
        """Normalised yield function (<= 0 inside): dimensionless for both models."""
        p, q = invariants(stress)
        return _elementwise(_yield_values, self.constants, p, q, state["pc"])

    def admissible(self, stress, state):
        """The state with p'c raised where the stress lies outside the yield surface, to
        the size that puts it on the surface: ``p'c = p' exp(q / (M p'))`` (original),
        ``p'c = p' + q^2 / (M^2 p')`` (modified); elsewhere unchanged.

        Raising p'c is plastic compaction without a stress change; the stress itself, an
        equilibrium quantity, is kept.

        Raises
        ------
        ConvergenceError
            Where p' <= 0: no surface passes through the stress.

        Examples
        --------
        >>> clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0)
        >>> stress = np.array([[-3.0, -1.0, -2.0, 1.5]])          # p' = 2, q > M p'
        >>> state = clay.admissible(stress, {"pc": np.array([3.0]), "v": np.array([1.83])})
        >>> float(state["pc"][0]) > 3.0, abs(float(clay.yield_value(stress, state)[0])) < 1e-12
        (True, True)
        """
        p, q = invariants(stress)
        if not np.all(p > 0):
            raise ConvergenceError(f"Cam-clay needs p' > 0 at every point; a carried stress "
                                   f"has p' = {p.min():.3g}")
        return {**state, "pc": np.maximum(state["pc"], self.size(p, q))}

    def size(self, p, q):
        """The size p'c of the yield surface through ``(p', q)`` (arrays or scalars):
        :func:`surface_size` on each."""
        return _elementwise(_sizes, self.constants, p, q)

    def volume(self, p, pc, anchor):
        """Specific volume of a state ``(p', p'c)`` on the swelling line of p'c's normal
        compression, ``v = N - (lambda - kappa) ln p'c - kappa ln p'``, with N such that
        the state ``anchor = (p', p'c, v)`` lies on it.

        Exact for the modified model, whose hardening ``dp'c / p'c = v d eps_v^p /
        (lambda - kappa)`` and swelling ``dp'/p' = -v d eps_v / kappa`` keep N constant;
        the original model's constant MD makes ``dv^p = (v / v0)(lambda - kappa) d ln
        p'c``, the same to first order in the change of v.
        """
        p_a, pc_a, v_a = anchor
        N = v_a + (self.lam - self.kappa) * np.log(pc_a) + self.kappa * np.log(p_a)
        return N - (self.lam - self.kappa) * np.log(pc) - self.kappa * np.log(p)

    def k0_nc(self, v=None):
        """K0 of normally consolidated one-dimensional compression (``eps_xx = eps_zz =
        0``) at specific volume v (default v0): the stress ratio ``eta = q / p'`` of the
        proportional path whose elastic and plastic strains are purely axial, ``d eps_q =
        (2/3) d eps_v``, and ``K0 = (3 - eta) / (3 + 2 eta)``. The modified model's is the
        same at every v; the original's plastic strain per ``d ln p'c``, MD, is fixed by
        e0 while the elastic one, ``kappa / v``, is not, so its K0 drifts as v falls.

        Examples
        --------
        >>> clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0,
        ...                model="modified")
        >>> round(clay.k0_nc(), 4), round(clay.k0_nc(v=1.5), 4)
        (0.5671, 0.5671)
        """
        from scipy.optimize import brentq

        v = self.v0 if v is None else v
        K, G = self.moduli(self.p0, v)
        p, c = float(self.p0), self.constants
        dv = 1.0 / hardening(c, float(v))[0]                    # d eps_v^p per d ln p'c

        def flow(eta):                                # d eps_q^p / d eps_v^p = f_q / f_p
            _, fp, fq = yield_function(c, p, eta * p, surface_size(c, p, eta * p), 1.0)[:3]
            return fq / fp

        mismatch = lambda eta: (eta * p / (3 * G) + dv * flow(eta)
                                - 2 / 3 * (p / K + dv))
        if mismatch(0.0) > 0:
            raise InputError(f"the {self.model} Cam-clay with lambda = {self.lam}, kappa = "
                             f"{self.kappa}, M = {self.M} has no normally consolidated K0 "
                             "<= 1 (its plastic flow at q = 0 is already deviatoric): give "
                             "initial.k0 a number")
        eta = brentq(mismatch, 0.0, self.M * (1 - 1e-12))
        return float((3 - eta) / (3 + 2 * eta))

    # -- incremental update ------------------------------------------------------------
    def update(self, stress, state, dstrain, dspin, tol=1e-11, max_iter=60):
        """Integrate one step on every point: implicit return mapping in (p', q).

        The stress is rotated (Hughes-Winget) and the elastic trial formed on whole arrays;
        :func:`return_mapping` (a numba kernel, on parts of the points side by side) then
        solves each point's local problem in (ln p', q, ln p'c, dgamma) by Newton's method
        and forms its consistent tangent.

        Parameters
        ----------
        stress : ndarray, shape (N, 4)
            Cauchy effective stress at the start of the step (tension positive).
        state : dict of ndarray, shape (N,)
            ``pc`` (size of the yield surface p'c) and ``v`` (specific volume).
        dstrain : ndarray, shape (N, 4)
            Stretching increment ``D dt`` as ``(xx, yy, zz, 2xy)``.
        dspin : ndarray, shape (N,)
            Spin increment ``W_xy dt``; the stress is first rotated by Hughes-Winget.
        tol : float
            Tolerance on the scaled local residual.
        max_iter : int
            Newton iterations before :class:`~soilwater.errors.ConvergenceError`.

        Returns
        -------
        stress : ndarray, shape (N, 4)
        state : dict of ndarray
        tangent : ndarray, shape (N, 4, 4)
            Consistent tangent ``d sigma / d dstrain`` at fixed spin (Voigt, engineering
            shear in the strain), for Newton's method in the solvers.

        Raises
        ------
        ConvergenceError
            Where a point starts the step at p' <= 0, or its Newton iteration does not
            converge or meets a singular local Jacobian.
        """
        stress = hughes_winget(stress, dspin)
        dstrain = np.asarray(dstrain, dtype=float)
        p_n, _ = invariants(stress)
        pc_n, v_n = (np.ascontiguousarray(state[key], dtype=float) for key in ("pc", "v"))
        if not np.all(p_n > 0):
            raise ConvergenceError(f"Cam-clay needs p' > 0 at every point; a point "
                                   f"starts the step at p' = {p_n.min():.3g}")
        dev = dstrain[:, :3].sum(axis=1)
        _, G = self.moduli(p_n, v_n)
        s_tr = deviator(stress) + 2 * G[:, None] * (dstrain @ DEVIATORIC.T)
        q_tr = np.sqrt(1.5 * double_dot(s_tr, s_tr))
        new_stress, pc, tangent, status = return_mapping(
            self.constants, s_tr, q_tr, p_n, pc_n, v_n, dev, G, float(tol), int(max_iter))
        _raise_on(status, max_iter)
        return new_stress, {"pc": pc, "v": v_n * np.exp(dev)}, tangent

    # -- continuum (rate) form, for the stress-point driver ------------------------------
    def rates(self, stress, state, D):
        """Continuum rates under a stretching D, for one point (plastic if loading).

        Parameters
        ----------
        stress : ndarray, shape (4,)
        state : dict of float
        D : ndarray, shape (4,)
            Stretching ``(xx, yy, zz, 2xy)``; only its direction matters at the vertex.

        Returns
        -------
        Ce, N, H, theta_fp : elastic tangent (4, 4), flow direction N = df/dsigma as a
        strain-like vector (4,), plastic modulus ``H``, and ``theta f_p`` with
        ``d pc / pc = theta f_p dgamma``.
        """
        p, q = invariants(stress)
        pc, v = state["pc"], state["v"]
        K, G = self.moduli(p, v)
        Ce = K * np.outer(IDENTITY, IDENTITY) + 2 * G * DEVIATORIC
        if q > 1e-12 * p:
            nhat = deviator(stress) / q
        else:  # vertex of the original surface: follow the trial deviatoric rate
            sdot = 2 * G * DEVIATORIC @ D
            qdot = np.sqrt(1.5 * double_dot(sdot, sdot))
            nhat = sdot / qdot if qdot > 0 else np.zeros(4)
        c, p, q, pc = self.constants, float(p), float(q), float(pc)
        _, fp, fq, fpc = yield_function(c, p, q, pc, 1.0 / pc**2)[:4]
        N = -fp * IDENTITY / 3 + 1.5 * fq * np.array([1, 1, 1, 2.0]) * nhat
        theta = hardening(c, float(v))[0]
        return Ce, N, -fpc * pc * theta * fp, theta * fp


def _elementwise(kernel, constants, *arrays):
    """``kernel(constants, *flat, out)`` on the broadcast arrays; the result has their
    shape (a numpy scalar for scalars)."""
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in arrays))
    out = np.empty(arrays[0].shape)
    kernel(constants, *(np.ascontiguousarray(a).ravel() for a in arrays), out.ravel())
    return out[()]


def _raise_on(status, max_iter):
    """Raise :class:`ConvergenceError` if any point's status is not ``CONVERGED``."""
    if not status.any():
        return
    if np.any(status == SINGULAR):
        raise ConvergenceError("Cam-clay return mapping met a singular local Jacobian: "
                               "reduce the strain increment per step")
    bad = int(np.count_nonzero(status == NOT_CONVERGED))
    raise ConvergenceError(
        f"Cam-clay return mapping did not converge at {bad} point(s) in {max_iter} "
        "iterations: reduce the time step (strain increment per step)")


# -- the equations: numba functions of scalars ---------------------------------------------
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
def _yield_values(c, p, q, pc, out):
    """:func:`yield_function`'s f on 1-D arrays, scaled by ``1 / p'c^2`` (modified)."""
    for i in range(len(out)):
        out[i] = yield_function(c, p[i], q[i], pc[i], 1.0 / pc[i] ** 2)[0]


@jit
def _sizes(c, p, q, out):
    """:func:`surface_size` on 1-D arrays."""
    for i in range(len(out)):
        out[i] = surface_size(c, p[i], q[i])


@jit
def _hardenings(c, v, out):
    """:func:`hardening`'s theta on a 1-D array."""
    for i in range(len(out)):
        out[i] = hardening(c, v[i])[0]


# -- the return mapping: one point after another ---------------------------------------------
def return_mapping(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter):
    """Return mapping and consistent tangent of every point: the numba kernel
    :func:`_return_mapping` on parts of the points side by side (:mod:`soilwater.linalg.threads`;
    each point's result is the same on any number of them).

    Parameters
    ----------
    c : Constants
    s_tr : ndarray, shape (N, 4)
        Trial deviatoric stress (tension positive, ``(xx, yy, zz, xy)``).
    q_tr, p_n, pc_n, v_n, dev, G : ndarray, shape (N,)
        Trial q; p', p'c (compression positive) and specific volume at the start of the
        step; volumetric strain increment (extension positive); shear modulus at the
        start of the step. Stresses and G in the case's stress unit.
    tol : float
        Tolerance on the scaled local residual.
    max_iter : int
        Newton iterations per solve.

    Returns
    -------
    stress : ndarray, shape (N, 4)
    pc : ndarray, shape (N,)
    tangent : ndarray, shape (N, 4, 4)
    status : ndarray of int8, shape (N,)
        ``CONVERGED``, ``NOT_CONVERGED`` or ``SINGULAR``; the other outputs of a point
        that did not converge are undefined.
    """
    n = len(p_n)
    out = np.empty((n, 4)), np.empty(n), np.empty((n, 4, 4)), np.empty(n, np.int8)
    run(lambda lo, hi: _return_mapping(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter,
                                       lo, hi, *out),
        parts(0, n))
    return out


@jit
def _return_mapping(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter, lo, hi, stress,
                    pc, tangent, status):
    """:func:`return_mapping` of the points ``lo:hi``, one after another, into the rows
    ``lo:hi`` of ``stress``, ``pc``, ``tangent`` and ``status`` (numba kernel; the GIL
    released)."""
    x, work = np.empty(4), _workspace()
    for i in range(lo, hi):
        status[i], pc[i] = _point(c, s_tr[i], q_tr[i], p_n[i], pc_n[i], v_n[i], dev[i],
                                  G[i], tol, max_iter, x, work, stress[i], tangent[i])


@jit
def _workspace():
    """Scratch of one point: residual R (4,), Jacobian J (4, 4), ``dR/d(dev, q_tr)``
    (4, 2), LU factors (4, 4) and pivots (4,)."""
    return (np.empty(4), np.empty((4, 4)), np.empty((4, 2)), np.empty((4, 4)),
            np.empty(4, np.int64))


@jit
def _point(c, s_tr, q_tr, p_n, pc_n, v_n, dev, G, tol, max_iter, x, work, stress, tangent):
    """One point: elastic trial, Newton in x = (ln p', q, ln p'c, dgamma), the vertex
    re-solve of the original model, then stress (4,) and tangent (4, 4) into the given
    rows. Returns ``(status, p'c)``."""
    vbar, dvbar = mean_volume(v_n, dev)
    scale = 1.0 / pc_n**2
    p_tr = p_n * math.exp(-vbar * dev / c.kappa)
    kind = SMOOTH if yield_function(c, p_tr, q_tr, pc_n, scale)[0] > tol else ELASTIC
    x[0], x[1], x[2], x[3] = math.log(p_tr), q_tr, math.log(pc_n), 0.0
    known = (math.log(p_n), p_n, math.log(pc_n), q_tr, dev, vbar, dvbar, G, scale)
    while True:  # one call site: numba compiles _newton once, for any kind
        status = _newton(c, x, kind, known, tol, max_iter, work)
        if status != CONVERGED or kind != SMOOTH or c.modified or x[1] >= 0:
            break
        kind, x[1] = VERTEX, 0.0  # returns past the apex land on the vertex q = 0
    if status == CONVERGED and not _stress_and_tangent(c, x, kind, known, s_tr, work,
                                                       stress, tangent):
        status = SINGULAR
    return status, math.exp(x[2])


@jit
def _newton(c, x, kind, known, tol, max_iter, work):
    """Newton on ``R(x) = 0`` from x (updated in place), steps of ln p' and ln p'c
    clipped to +-0.5; J and ``dR/dy`` in ``work`` are left at the solution.

    Returns ``CONVERGED``, ``NOT_CONVERGED`` (also on a non-finite residual) or
    ``SINGULAR``.
    """
    R, J, _, lu, piv = work
    for _ in range(max_iter):
        _residual(c, x, kind, known, work)
        if _largest(R) < tol:
            return CONVERGED
        if not np.isfinite(_largest(R)):
            return NOT_CONVERGED
        if not _lu_factor(J, lu, piv):
            return SINGULAR
        for k in range(4):
            R[k] = -R[k]
        _lu_solve(lu, piv, R)
        for k in range(4):
            step = R[k]
            if k != 1 and k != 3:
                step = 0.5 if step > 0.5 else (-0.5 if step < -0.5 else step)
            x[k] += step
    return NOT_CONVERGED


@jit
def _largest(R):
    """``max |R_k|``, nan if any entry is nan."""
    big = 0.0
    for r in R:
        if abs(r) > big or r != r:
            big = abs(r)
    return big


@jit
def _residual(c, x, kind, known, work):
    """Local residual R of a point's problem ``kind``, its Jacobian J and its derivative
    with respect to (dev, q_tr), into ``work``."""
    R, J, dRdy = work[0], work[1], work[2]
    ln_p_n, p_n, ln_pc_n, q_tr, dev, vbar, dvbar, G, scale = known
    p, q, pc, dg = math.exp(x[0]), x[1], math.exp(x[2]), x[3]
    f, fp, fq, fpc, fpp, fpq, fqq, fppc = yield_function(c, p, q, pc, scale)
    a = vbar / c.kappa
    theta, dtheta_dv = hardening(c, vbar)
    J.fill(0.0)
    dRdy.fill(0.0)
    # volumetric elasticity: ln p = ln p_n - (vbar/kappa)(dev - deps_v^p)
    R[0] = x[0] - ln_p_n + a * (dev + dg * fp)
    J[0, 0], J[0, 1], J[0, 2], J[0, 3] = (1 + a * dg * fpp * p, a * dg * fpq,
                                          a * dg * fppc * pc, a * fp)
    dRdy[0, 0] = (vbar + dvbar * (dev + dg * fp)) / c.kappa
    # deviatoric radial return: q = q_tr - 3 G dg f_q (or q = 0 on the vertex)
    if kind == VERTEX:
        R[1], J[1, 1] = q / p_n, 1.0 / p_n
    else:
        R[1] = (q - q_tr + 3 * G * dg * fq) / p_n
        J[1, 0], J[1, 1], J[1, 3] = (3 * G * dg * fpq * p / p_n,
                                     (1 + 3 * G * dg * fqq) / p_n, 3 * G * fq / p_n)
        dRdy[1, 1] = -1.0 / p_n
    # hardening: ln pc = ln pc_n + theta deps_v^p
    R[2] = x[2] - ln_pc_n - theta * dg * fp
    J[2, 0], J[2, 1], J[2, 2], J[2, 3] = (-theta * dg * fpp * p, -theta * dg * fpq,
                                          1 - theta * dg * fppc * pc, -theta * fp)
    dRdy[2, 0] = -dtheta_dv * dvbar * dg * fp
    # consistency f = 0 on plastic points, dgamma = 0 on elastic ones
    if kind != ELASTIC:
        R[3], J[3, 0], J[3, 1], J[3, 2] = f, fp * p, fq, fpc * pc
    else:
        R[3], J[3, 3] = dg, 1.0


@jit
def _stress_and_tangent(c, x, kind, known, s_tr, work, stress, tangent):
    """Stress (4,) and consistent tangent (4, 4) at the solution x of a point; False
    when its local Jacobian is singular.

    The tangent follows from ``dx/dy = -J^-1 dR/dy`` with y = (dev, q_tr),
    ``d dev / d eps = m`` and ``d q_tr / d eps = 3 G n``, n the unit trial direction.
    """
    R, _, dRdy, lu, piv = work
    if not _lu_factor(work[1], lu, piv):
        return False
    for k in range(2):                      # dRdy becomes dx/dy
        for i in range(4):
            R[i] = -dRdy[i, k]
        _lu_solve(lu, piv, R)
        for i in range(4):
            dRdy[i, k] = R[i]
    _, p_n, _, q_tr, _, _, _, G, scale = known
    p, q, pc, dg = math.exp(x[0]), x[1], math.exp(x[2]), x[3]
    safe = q_tr > 1e-14 * p_n
    inv_q = 1.0 / q_tr if safe else 0.0     # n = s_tr / q_tr, zero at q_tr = 0
    if safe:
        ratio = q / q_tr
    elif kind == VERTEX:
        ratio = 0.0
    else:
        ratio = 1.0 / (1.0 + 3 * G * dg * yield_function(c, p, q, pc, scale)[6])
    for i in range(4):
        stress[i] = -p * IDENTITY[i] + ratio * s_tr[i]
    for i in range(4):
        for j in range(4):
            dp = p * (dRdy[0, 0] * IDENTITY[j] + 3 * G * dRdy[0, 1] * s_tr[j] * inv_q)
            dq = dRdy[1, 0] * IDENTITY[j] + 3 * G * dRdy[1, 1] * s_tr[j] * inv_q
            tangent[i, j] = (-IDENTITY[i] * dp + s_tr[i] * inv_q * dq + 2 * G * ratio
                             * (DEVIATORIC[i, j] - 1.5 * s_tr[i] * s_tr[j] * inv_q**2))
    return True


@jit
def _lu_factor(J, A, piv):
    """LU factors of a 4 x 4 matrix J into A, with partial pivoting; False at a zero
    pivot (exactly singular, as LAPACK's getrf reports)."""
    for i in range(4):
        for j in range(4):
            A[i, j] = J[i, j]
    for k in range(4):
        m = k
        for i in range(k + 1, 4):
            if abs(A[i, k]) > abs(A[m, k]):
                m = i
        piv[k] = m
        if A[m, k] == 0.0:
            return False
        for j in range(4):
            A[k, j], A[m, j] = A[m, j], A[k, j]
        for i in range(k + 1, 4):
            A[i, k] /= A[k, k]
            for j in range(k + 1, 4):
                A[i, j] -= A[i, k] * A[k, j]
    return True


@jit
def _lu_solve(A, piv, b):
    """Solve ``A x = b`` in place from :func:`_lu_factor`'s factors."""
    for k in range(4):
        b[k], b[piv[k]] = b[piv[k]], b[k]
    for i in range(1, 4):
        for j in range(i):
            b[i] -= A[i, j] * b[j]
    for i in range(3, -1, -1):
        for j in range(i + 1, 4):
            b[i] -= A[i, j] * b[j]
        b[i] /= A[i, i]
