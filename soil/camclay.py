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
"""

from dataclasses import dataclass

import numpy as np

from soil.errors import ConvergenceError, InputError, require
from soil.kinematics import (DEVIATORIC, IDENTITY, deviator, double_dot, hughes_winget,
                             invariants)
from soil.material import Material

MODELS = ("original", "modified")


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

    def hardening(self, v):
        """``theta`` in ``dp'c / p'c = theta d eps_v^p`` (compression positive)."""
        if self.model == "modified":
            return v / (self.lam - self.kappa)
        return np.full_like(np.asarray(v, dtype=float), 1.0 / self.MD)

    def yield_value(self, stress, state):
        """Normalised yield function (<= 0 inside): dimensionless for both models."""
        p, q = invariants(stress)
        return self._f(p, q, state["pc"], 1.0 / state["pc"] ** 2)[0]

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
        """The size p'c of the yield surface through ``(p', q)``: ``p' exp(q / (M p'))``
        (original), ``p' + q^2 / (M^2 p')`` (modified)."""
        if self.model == "original":
            return p * np.exp(q / (self.M * p))
        return p + q**2 / (self.M**2 * p)

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
        p = self.p0
        dv = (self.lam - self.kappa) / v if self.model == "modified" else self.MD
        if self.model == "original":
            flow = lambda eta: 1.0 / (self.M - eta)             # d eps_q^p / d eps_v^p
        else:
            flow = lambda eta: 2 * eta / (self.M**2 - eta**2)
        mismatch = lambda eta: (eta * p / (3 * G) + dv * flow(eta)
                                - 2 / 3 * (p / K + dv))
        if mismatch(0.0) > 0:
            raise InputError(f"the {self.model} Cam-clay with lambda = {self.lam}, kappa = "
                             f"{self.kappa}, M = {self.M} has no normally consolidated K0 "
                             "<= 1 (its plastic flow at q = 0 is already deviatoric): give "
                             "initial.k0 a number")
        eta = brentq(mismatch, 0.0, self.M * (1 - 1e-12))
        return float((3 - eta) / (3 + 2 * eta))

    def _f(self, p, q, pc, scale):
        """Yield function and its derivatives ``(f, f_p, f_q, f_pc, f_pp, f_pq, f_qq, f_ppc)``.

        ``scale`` multiplies the modified surface (it keeps f dimensionless).
        """
        M = self.M
        if self.model == "original":
            f = np.log(p / pc) + q / (M * p)
            zero = np.zeros_like(p)
            return (f, 1 / p - q / (M * p**2), 1 / (M * p), -1 / pc,
                    -1 / p**2 + 2 * q / (M * p**3), -1 / (M * p**2), zero, zero)
        s = scale
        f = s * (q**2 / M**2 + p * (p - pc))
        return (f, s * (2 * p - pc), s * 2 * q / M**2, -s * p,
                2 * s + 0 * p, 0 * p, 2 * s / M**2 + 0 * p, -s + 0 * p)

    # -- incremental update ------------------------------------------------------------
    def update(self, stress, state, dstrain, dspin, tol=1e-11, max_iter=60):
        """Integrate one step on every point: implicit return mapping in (p', q).

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
            Newton iterations before :class:`~soil.errors.ConvergenceError`.

        Returns
        -------
        stress : ndarray, shape (N, 4)
        state : dict of ndarray
        tangent : ndarray, shape (N, 4, 4)
            Consistent tangent ``d sigma / d dstrain`` at fixed spin (Voigt, engineering
            shear in the strain), for Newton's method in the solvers.
        """
        stress = hughes_winget(stress, dspin)
        dstrain = np.asarray(dstrain, dtype=float)
        p_n, _ = invariants(stress)
        pc_n, v_n = state["pc"], state["v"]
        if not np.all(p_n > 0):
            raise ConvergenceError(f"Cam-clay needs p' > 0 at every point; a point "
                                   f"starts the step at p' = {p_n.min():.3g}")

        dev = dstrain[:, :3].sum(axis=1)
        vbar, dvbar = _mean_volume(v_n, dev)
        K_n, G = self.moduli(p_n, v_n)
        s_tr = deviator(stress) + 2 * G[:, None] * (dstrain @ DEVIATORIC.T)
        q_tr = np.sqrt(1.5 * double_dot(s_tr, s_tr))
        scale = 1.0 / pc_n**2
        p_tr = p_n * np.exp(-vbar * dev / self.kappa)

        plastic = self._f(p_tr, q_tr, pc_n, scale)[0] > tol
        vertex = np.zeros_like(plastic)
        x = np.stack([np.log(p_tr), q_tr, np.log(pc_n), np.zeros_like(p_n)], axis=1)
        args = (p_n, pc_n, q_tr, dev, vbar, dvbar, G, scale)
        x, J, dRdy = self._solve_local(x, plastic, vertex, args, tol, max_iter)
        if self.model == "original":  # returns past the apex land on the vertex q = 0
            vertex = plastic & (x[:, 1] < 0)
            if vertex.any():
                x[vertex, 1] = 0.0
                x, J, dRdy = self._solve_local(x, plastic, vertex, args, tol, max_iter)

        p, q, pc, dg = np.exp(x[:, 0]), x[:, 1], np.exp(x[:, 2]), x[:, 3]
        dx = -np.linalg.solve(J, dRdy)  # (N, 4, 2): d(ln p, q, ln pc, dg)/d(dev, q_tr)
        fqq = self._f(p, q, pc, scale)[6]
        safe = q_tr > 1e-14 * p_n
        n = np.where(safe[:, None], s_tr, 0.0) / np.where(safe, q_tr, 1.0)[:, None]
        ratio = np.where(safe, q / np.where(safe, q_tr, 1.0),
                         np.where(vertex, 0.0, 1.0 / (1.0 + 3 * G * dg * fqq)))

        new_stress = -p[:, None] * IDENTITY + ratio[:, None] * s_tr
        dp = p[:, None] * dx[:, 0, :]
        dq = dx[:, 1, :]
        m = IDENTITY
        dp_de = dp[:, :1] * m + 3 * G[:, None] * dp[:, 1:] * n
        dq_de = dq[:, :1] * m + 3 * G[:, None] * dq[:, 1:] * n
        tangent = (-m[None, :, None] * dp_de[:, None, :]
                   + n[:, :, None] * dq_de[:, None, :]
                   + (2 * G * ratio)[:, None, None]
                   * (DEVIATORIC - 1.5 * n[:, :, None] * n[:, None, :]))
        new_state = {"pc": pc, "v": v_n * np.exp(dev)}
        return new_stress, new_state, tangent

    def _solve_local(self, x, plastic, vertex, args, tol, max_iter):
        """Newton on ``R(x) = 0`` for x = (ln p', q, ln p'c, dgamma) on all points at once.

        Overflow in a diverging iteration is not warned about: it ends in
        :class:`ConvergenceError`.
        """
        with np.errstate(all="ignore"):
            return self._newton(x, plastic, vertex, args, tol, max_iter)

    def _newton(self, x, plastic, vertex, args, tol, max_iter):
        for _ in range(max_iter):
            R, J, dRdy = self._residual(x, plastic, vertex, *args)
            if np.all(np.abs(R) < tol):
                return x, J, dRdy
            if not np.all(np.isfinite(R)):
                break
            try:
                step = np.linalg.solve(J, -R[:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                raise ConvergenceError("Cam-clay return mapping met a singular local "
                                       "Jacobian: reduce the strain increment per step") from None
            step[:, [0, 2]] = np.clip(step[:, [0, 2]], -0.5, 0.5)
            x = x + step
        bad = int(np.sum(np.any(np.abs(R) >= tol, axis=1)))
        raise ConvergenceError(
            f"Cam-clay return mapping did not converge at {bad} point(s) in {max_iter} "
            "iterations: reduce the time step (strain increment per step)")

    def _residual(self, x, plastic, vertex, p_n, pc_n, q_tr, dev, vbar, dvbar, G, scale):
        """Local residual, its Jacobian and its derivative with respect to (dev, q_tr)."""
        p, q, pc, dg = np.exp(x[:, 0]), x[:, 1], np.exp(x[:, 2]), x[:, 3]
        f, fp, fq, fpc, fpp, fpq, fqq, fppc = self._f(p, q, pc, scale)
        a = vbar / self.kappa
        theta = self.hardening(vbar)
        n = len(p)
        R = np.empty((n, 4))
        J = np.zeros((n, 4, 4))
        dRdy = np.zeros((n, 4, 2))
        # volumetric elasticity: ln p = ln p_n - (vbar/kappa)(dev - deps_v^p)
        R[:, 0] = x[:, 0] - np.log(p_n) + a * (dev + dg * fp)
        J[:, 0] = np.stack([1 + a * dg * fpp * p, a * dg * fpq, a * dg * fppc * pc, a * fp], 1)
        dRdy[:, 0, 0] = (vbar + dvbar * (dev + dg * fp)) / self.kappa
        # deviatoric radial return: q = q_tr - 3 G dg f_q (or q = 0 on the vertex)
        R[:, 1] = np.where(vertex, q, q - q_tr + 3 * G * dg * fq) / p_n
        J[:, 1] = np.where(vertex[:, None], np.array([0, 1.0, 0, 0]),
                           np.stack([3 * G * dg * fpq * p, 1 + 3 * G * dg * fqq,
                                     0 * p, 3 * G * fq], 1)) / p_n[:, None]
        dRdy[:, 1, 1] = np.where(vertex, 0.0, -1.0 / p_n)
        # hardening: ln pc = ln pc_n + theta deps_v^p
        R[:, 2] = x[:, 2] - np.log(pc_n) - theta * dg * fp
        J[:, 2] = np.stack([-theta * dg * fpp * p, -theta * dg * fpq,
                            1 - theta * dg * fppc * pc, -theta * fp], 1)
        if self.model == "modified":
            dRdy[:, 2, 0] = -dvbar / (self.lam - self.kappa) * dg * fp
        # consistency f = 0 on plastic points, dgamma = 0 on elastic ones
        R[:, 3] = np.where(plastic, f, dg)
        J[:, 3] = np.where(plastic[:, None], np.stack([fp * p, fq, fpc * pc, 0 * p], 1),
                           np.array([0, 0, 0, 1.0]))
        return R, J, dRdy

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
        _, fp, fq, fpc = self._f(p, q, pc, 1.0 / pc**2)[:4]
        N = -fp * IDENTITY / 3 + 1.5 * fq * np.array([1, 1, 1, 2.0]) * nhat
        theta = self.hardening(v)
        return Ce, N, -fpc * pc * theta * fp, theta * fp


def _mean_volume(v, dev):
    """Mean specific volume over a step, ``(v_{n+1} - v_n)/dev``, and its derivative.

    With it the elastic volumetric law ``dp'/p' = -v d eps_v / kappa`` integrates
    exactly: ``p'_{n+1} = p'_n exp(-(v_{n+1} - v_n)/kappa)``.
    """
    small = np.abs(dev) < 1e-5
    x = np.where(small, 1.0, dev)
    vbar = np.where(small, v * (1 + dev / 2 + dev**2 / 6), v * np.expm1(x) / x)
    dvbar = np.where(small, v * (0.5 + dev / 3 + dev**2 / 8),
                     v * (x * np.exp(x) - np.expm1(x)) / x**2)
    return vbar, dvbar
