"""Finite-strain Cam-clay, original (Sekiguchi-Ohta form) and modified, on arrays of points.

Rate form on the current configuration: the Jaumann rate of the
Cauchy effective stress is ``C^ep : D``. Hypoelasticity with ``K = v p'/kappa`` and a
constant Poisson ratio (or, optionally, a constant shear modulus ``G``); associated flow.
The yield surfaces and hardening laws are written out in
:mod:`soilwater.material.camclay_equations`; the implicit return mapping of
:meth:`CamClay.update` is :mod:`soilwater.material.camclay_kernel`.

Sign conventions: stress is tension positive, stored as ``(xx, yy, zz, xy)``; strain
increments are Voigt vectors ``(xx, yy, zz, 2xy)``; p', q, p'c and ``eps_v^p`` are
compression positive. Units are those of the case (p'0 sets the stress unit).
"""

from dataclasses import dataclass

import numpy as np

from soilwater.errors import ConvergenceError, InputError, require
from soilwater.material.camclay_equations import (Constants, elementwise, hardening,
                                                  hardenings, surface_size, surface_sizes,
                                                  yield_function, yield_values)
from soilwater.material.camclay_kernel import raise_on, return_mapping
from soilwater.material.kinematics import (DEVIATORIC, IDENTITY, deviator, double_dot,
                                           hughes_winget, invariants)
from soilwater.material.protocol import Material

MODELS = ("original", "modified")
#: The largest isotropic overconsolidation ratio p'c0 / p'0 taken (``material.ocr``,
#: ``initial.ocr``, ``soilwater path --ocr``).
MAX_OCR = 1e4


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
    e_ref, sigma_v_ref : float or None
        The oedometer's anchor of the normal compression line: the void ratio of the
        normally consolidated one-dimensional state at the vertical effective stress
        ``sigma_v_ref`` [kPa] (both or neither; default: the line through the initial
        state, :attr:`anchor`).

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
    e_ref: float | None = None
    sigma_v_ref: float | None = None

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
        require(1.0 <= self.ocr <= MAX_OCR, f"material.ocr = {self.ocr} must lie in "
                f"[1, {MAX_OCR:g}] (no soil is more overconsolidated)")
        require(self.G is None or self.G > 0, f"material.G = {self.G} must be positive")
        require((self.e_ref is None) == (self.sigma_v_ref is None), "material.e_ref and "
                "material.sigma_v_ref anchor the compression line together: set both or "
                "neither")
        require(self.e_ref is None or (self.e_ref > 0 and self.sigma_v_ref > 0),
                f"material.e_ref = {self.e_ref} and sigma_v_ref = {self.sigma_v_ref} must "
                "be positive (a void ratio, and kPa compression positive)")

    # -- derived constants -------------------------------------------------------------
    @property
    def v0(self):
        """Initial specific volume ``1 + e0``."""
        return 1.0 + self.e0

    @property
    def anchor(self):
        """A state ``(p', p'c, v)`` on the normal compression line: the normally
        consolidated one-dimensional state at ``sigma_v_ref`` with ``e_ref`` (K0 of
        :meth:`k0_nc`), or the initial state ``(p'0, ocr p'0, v0)``; the line of
        :meth:`volume` and of a geostatic start (:mod:`soilwater.physics.geostatic`).

        Examples
        --------
        >>> clay = CamClay(lam=0.4, kappa=0.04, M=1.2, nu=0.3, e0=2.4, p0=10.0,
        ...                model="modified", e_ref=2.4, sigma_v_ref=10.0)
        >>> p, pc, v = clay.anchor
        >>> round(float(p), 3), round(float(pc), 3), v
        (7.733, 8.771, 3.4)
        """
        if self.e_ref is None:
            return self.p0, self.ocr * self.p0, self.v0
        nc = self.k0_nc()
        p = (1 + 2 * nc) / 3 * self.sigma_v_ref
        return p, float(self.size(p, (1 - nc) * self.sigma_v_ref)), 1.0 + self.e_ref

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
        return elementwise(hardenings, self.constants, v)

    def yield_value(self, stress, state):
        """Normalised yield function (<= 0 inside): dimensionless for both models."""
        p, q = invariants(stress)
        return elementwise(yield_values, self.constants, p, q, state["pc"])

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
        return elementwise(surface_sizes, self.constants, p, q)

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
        raise_on(status, max_iter)
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
