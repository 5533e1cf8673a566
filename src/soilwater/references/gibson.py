"""Gibson's finite-strain 1-D consolidation: an independent reference solver.

A saturated layer, laterally confined, stands on a fixed base; its initial height is
``H0`` [m]. It shares no code with the coupled solvers (``efg``, ``fem_reference``,
``soilwater.physics.weakform``, ``soilwater.nonlinear.coupling``): it is the reference their large-strain columns are
checked against.

Units and signs: kPa, m, s; unit weights [kN/m3]; permeability k [m/s] (Darcy with the
excess head, flux ``-(k/gamma_w) du/dxi``). Effective vertical stress sigma' and pore
pressures are **compression positive**; heights xi are measured up from the base;
settlement is the fall of the top, **positive down**.

Coordinates
-----------
``z`` is the reduced (solid-volume) coordinate of Gibson, England and Hussey (1967):
``dz = dxi / (1 + e)``, from 0 at the base to ``Z`` at the top, ``Z`` the layer's volume
of solids per unit area (constant in time). A solid particle keeps its z; its height is
``xi(z, t) = int_0^z (1 + e) dz``.

Equations
---------
Equilibrium of the mixture with the pore water pressure split into hydrostatic and excess
``u_e`` (the water table fixed, at the initial top) gives, per unit solid volume,
``d(sigma' + u_e)/dz = -gamma'``, ``gamma' = (Gs - 1) gamma_w`` (zero for a weightless
layer), so

    sigma'(z, t) + u_e(z, t) = sigma'_top(t) + gamma' (Z - z),

with ``sigma'_top(t) = sigma'_0 + q(t)`` the effective stress at the drained top under
the surcharge ``q`` (``sigma'_0`` is 0 for a geostatic start and the deposit's stress for
a freshly deposited layer, below). Continuity of water and solids with Darcy's law for the
discharge relative to the solids, ``F = -(k/gamma_w) du_e/dxi`` (upward positive), is

    de/dt = -dF/dz,   F = K(e) (gamma' + dsigma'/dz),   K = k(e) / (gamma_w (1 + e)),

which with ``sigma' = sigma'(e)`` is Gibson's equation for the void ratio (z upward):

    de/dt + (Gs - 1) d/de[k/(1+e)] de/dz + d/dz[k/(gamma_w (1+e)) dsigma'/de de/dz] = 0.

Boundary conditions: the top is drained, ``u_e = 0`` so ``sigma' = sigma'_top(t)``; the
base is impermeable (``F = 0``) or drained (``sigma' = sigma'_top + gamma' Z``). The
total pore pressure is ``p_w = u_e + gamma_w (H0 - xi)`` (zero hydrostatic part for a
weightless layer).

Compression laws, ``sigma'(e)`` (``Clay.compression``):

- ``"camclay"``: the Cam-clay lines in oedometric form, ``Cc = lambda ln 10``,
  ``Cr = kappa ln 10``: the normal compression line ``e = e_ref - lambda ln(sigma'/
  sigma_v_ref)`` and, below the pre-consolidation stress ``sigma'_p``, the swelling line
  ``e = e_ncl(sigma'_p) + kappa ln(sigma'_p/sigma')``. ``sigma'_p`` is a state per soil
  element (``ocr`` times the initial stress; it grows as the element loads past it), so
  unloading and reloading follow the swelling line. The line has ``e -> inf`` at zero
  stress: a geostatic start needs a surcharge > 0.
- ``"constant-mv"``: ``1 + e = (1 + e_ref) exp(-mv (sigma' - sigma_v_ref))``, the
  constant volume compressibility ``mv = -de/dsigma' / (1 + e)`` [1/kPa] of Xie and Leo
  (2004).

Permeability laws ``k(e)`` (``Clay.permeability_law``), each ``k_ref`` (``permeability``)
at ``e_k`` (``permeability_e``, default ``e_ref``):

- ``"constant"``: ``k = k_ref``;
- ``"taylor"``: ``k = k_ref 10^((e - e_k)/C_k)`` (``permeability_ck`` = C_k);
- ``"kozeny-carman"``: ``k = k_ref (e^3/(1+e)) / (e_k^3/(1+e_k))``;
- ``"xie-leo"``: ``k = k_ref ((1+e)/(1+e_k))^2`` (Xie and Leo's closed-form case).

Initial states (``Column.start``):

- ``"geostatic"``: equilibrium under self-weight and the surcharge ``q(0)``:
  ``sigma'(z) = q(0) + gamma' (Z - z)``, e from the compression law with
  ``sigma'_p = ocr sigma'``; nothing moves until the surcharge changes.
- ``"deposited"``: a freshly deposited layer at a uniform void ratio ``e_deposited``
  whose weight (and the surcharge) the pore water carries: ``u_e = q(0) + gamma' (Z - z)``.
  Its effective stress is the compression law's at ``e_deposited`` (the log law's
  stand-in for zero), ``sigma'_0`` above.

Numerics
--------
Cell-centred finite volumes in z (``cells`` equal cells of solid height ``Z/cells``; the
void ratio per cell is the unknown, so the volume of water is conserved to round-off);
face conductivity at the mean void ratio of the two cells; the drained faces take the
boundary stress half a cell away. ``Z`` is chosen so that the discrete initial height is
exactly ``H0``. Time: TR-BDF2 (one-step, L-stable, second order; Bank et al. 1985,
gamma = 2 - sqrt 2), both stages solved by Newton's method on the tridiagonal Jacobian,
on time levels geometric in t (``steps_per_decade``) from ``t_first`` plus every output
and load-table time. The geostatic discrete state is an exact equilibrium (sigma' linear
in z), so a run without load change stays put to round-off.

References
----------
Gibson, R. E., England, G. L. and Hussey, M. J. L. (1967). The theory of one-dimensional
consolidation of saturated clays. I. Finite non-linear consolidation of thin homogeneous
layers. Geotechnique 17, 261-273.

Xie, K. H. and Leo, C. J. (2004). Analytical solutions of one-dimensional large strain
consolidation of saturated and homogeneous clays. Computers and Geotechnics 31, 301-314
(the closed form in :func:`soilwater.references.closed_forms.xie_leo`).
"""

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import solve_banded
from scipy.optimize import brentq

from soilwater.errors import ConvergenceError, require

COMPRESSION_LAWS = ("camclay", "constant-mv")
PERMEABILITY_LAWS = ("constant", "taylor", "kozeny-carman", "xie-leo")
STARTS = ("geostatic", "deposited")
#: TR-BDF2's stage fraction; both stages share the Newton coefficient ``1 - 1/sqrt 2``.
TRBDF2 = 2.0 - np.sqrt(2.0)


@dataclass(frozen=True)
class Clay:
    """Compression and permeability laws of the clay (module docstring for the forms).

    Parameters
    ----------
    compression : str
        ``"camclay"`` (``lam``, ``kappa``) or ``"constant-mv"`` (``mv``).
    lam, kappa : float
        Slopes of the normal compression and swelling lines in ``e``-``ln sigma'``
        (Cc = lam ln 10, Cr = kappa ln 10), ``lam > kappa > 0``.
    mv : float
        Volume compressibility [1/kPa] of ``"constant-mv"``.
    e_ref, sigma_v_ref : float
        The compression line passes through ``e_ref`` at ``sigma_v_ref`` [kPa] (defaults:
        Table 1's lambda, kappa and e0 at p'0).
    permeability : float
        k_ref [m/s].
    permeability_law : str
        ``"constant"``, ``"taylor"``, ``"kozeny-carman"`` or ``"xie-leo"``.
    permeability_e : float or None
        Void ratio e_k at which k = k_ref (default ``e_ref``).
    permeability_ck : float or None
        Taylor's C_k (> 0), required by ``"taylor"``.
    specific_gravity : float
        Gs of the solids (> 1): ``gamma_s = Gs gamma_w``.
    gamma_w : float
        Unit weight of water [kN/m3].
    """

    compression: str = "camclay"
    lam: float = 0.11
    kappa: float = 0.04
    mv: float | None = None
    e_ref: float = 0.83
    sigma_v_ref: float = 3.0
    permeability: float = 1e-8
    permeability_law: str = "constant"
    permeability_e: float | None = None
    permeability_ck: float | None = None
    specific_gravity: float = 2.65
    gamma_w: float = 9.81

    def __post_init__(self):
        require(self.compression in COMPRESSION_LAWS,
                f"compression = {self.compression!r} is unknown: use one of "
                f"{', '.join(COMPRESSION_LAWS)}")
        if self.compression == "camclay":
            require(self.lam > self.kappa > 0,
                    f"lambda = {self.lam}, kappa = {self.kappa}: need lambda > kappa > 0")
        else:
            require(self.mv is not None and self.mv > 0,
                    f"mv = {self.mv} must be > 0 [1/kPa] with compression = 'constant-mv'")
        require(self.e_ref > 0, f"e_ref = {self.e_ref} must be > 0 (a void ratio)")
        require(self.sigma_v_ref > 0, f"sigma_v_ref = {self.sigma_v_ref} must be > 0 [kPa]")
        require(self.permeability > 0, f"permeability = {self.permeability} must be > 0 "
                "[m/s]")
        require(self.permeability_law in PERMEABILITY_LAWS,
                f"permeability_law = {self.permeability_law!r} is unknown: use one of "
                f"{', '.join(PERMEABILITY_LAWS)}")
        require(self.permeability_e is None or self.permeability_e > 0,
                f"permeability_e = {self.permeability_e} must be > 0 (a void ratio)")
        if self.permeability_law == "taylor":
            require(self.permeability_ck is not None and self.permeability_ck > 0,
                    f"permeability_ck = {self.permeability_ck} must be > 0 with "
                    "permeability_law = 'taylor'")
        require(self.specific_gravity > 1, f"specific_gravity = {self.specific_gravity} "
                "must be > 1 (solids denser than water)")
        require(self.gamma_w > 0, f"gamma_w = {self.gamma_w} must be > 0 [kN/m3]")

    def void_ratio(self, sigma, sigma_p):
        """Void ratio at effective stress ``sigma`` [kPa] with pre-consolidation
        ``sigma_p`` (ignored by ``"constant-mv"``)."""
        sigma = np.asarray(sigma, dtype=float)
        if self.compression == "constant-mv":
            return (1 + self.e_ref) * np.exp(-self.mv * (sigma - self.sigma_v_ref)) - 1
        sigma_p = np.maximum(sigma_p, sigma)
        e_p = self.e_ref - self.lam * np.log(sigma_p / self.sigma_v_ref)
        return e_p + self.kappa * np.log(sigma_p / sigma)

    def virgin_stress(self, e):
        """Effective stress [kPa] on the normal compression line (or the mv law) at e."""
        if self.compression == "constant-mv":
            return self.sigma_v_ref - np.log((1 + e) / (1 + self.e_ref)) / self.mv
        return self.sigma_v_ref * np.exp((self.e_ref - e) / self.lam)

    def effective_stress(self, e, sigma_p):
        """Effective stress sigma'(e) [kPa] and its derivative dsigma'/de (< 0)."""
        if self.compression == "constant-mv":
            return self.virgin_stress(e), -1.0 / (self.mv * (1 + e))
        e_p = self.e_ref - self.lam * np.log(sigma_p / self.sigma_v_ref)
        virgin = e <= e_p
        slope = np.where(virgin, self.lam, self.kappa)
        swelling = sigma_p * np.exp((e_p - e) / self.kappa)
        sigma = np.where(virgin, self.virgin_stress(e), swelling)
        return sigma, -sigma / slope

    def permeability_of(self, e):
        """Permeability k(e) [m/s] and dk/de."""
        e = np.asarray(e, dtype=float)
        e_k = self.e_ref if self.permeability_e is None else self.permeability_e
        law = self.permeability_law
        if law == "constant":
            k = np.full_like(e, self.permeability)
            return k, np.zeros_like(e)
        if law == "taylor":
            k = self.permeability * 10.0 ** ((e - e_k) / self.permeability_ck)
            return k, k * np.log(10.0) / self.permeability_ck
        if law == "kozeny-carman":
            k = self.permeability * (e**3 / (1 + e)) / (e_k**3 / (1 + e_k))
            return k, k * (3 / e - 1 / (1 + e))
        k = self.permeability * ((1 + e) / (1 + e_k)) ** 2
        return k, 2 * k / (1 + e)

    def conductivity(self, e):
        """``K = k / (gamma_w (1 + e))`` [m/s per kPa, per unit solid height] and dK/de."""
        k, dk = self.permeability_of(e)
        K = k / (self.gamma_w * (1 + e))
        return K, (dk - k / (1 + e)) / (self.gamma_w * (1 + e))


@dataclass(frozen=True)
class Column:
    """A layer, its loading, initial state and drainage.

    Parameters
    ----------
    clay : Clay
    height : float
        Initial height H0 [m].
    surcharge : float
        Surcharge q [kPa] on the top up to t = 0 (the initial state's).
    load : sequence of (t, q)
        The surcharge for t > 0: piecewise linear through these points (strictly
        increasing t >= 0), constant after the last; before the first point it keeps
        ``surcharge``. ``((0.0, q1),)`` is a step at t = 0+, ``((0.0, q0), (t1, q1))`` a
        ramp. Empty: no load change.
    start : str
        ``"geostatic"`` or ``"deposited"`` (module docstring).
    ocr : float
        Over-consolidation ratio of the geostatic start (>= 1, ``"camclay"``).
    e_deposited : float or None
        Uniform initial void ratio of the ``"deposited"`` start.
    self_weight : bool
        False: a weightless layer (gamma' = 0, no hydrostatic pressure).
    drained_bottom : bool
        True: double drainage.
    """

    clay: Clay
    height: float
    surcharge: float = 0.0
    load: tuple = ()
    start: str = "geostatic"
    ocr: float = 1.0
    e_deposited: float | None = None
    self_weight: bool = True
    drained_bottom: bool = False
    _load: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        require(self.height > 0, f"height = {self.height} must be > 0 [m]")
        require(self.start in STARTS, f"start = {self.start!r} is unknown: use one of "
                f"{', '.join(STARTS)}")
        require(self.ocr >= 1, f"ocr = {self.ocr} must be >= 1")
        table = np.asarray(self.load, dtype=float).reshape(-1, 2)
        require(np.all(table[:, 0] >= 0) and np.all(np.diff(table[:, 0]) > 0),
                f"load = {self.load}: times must be >= 0 and strictly increasing")
        object.__setattr__(self, "_load", (table[:, 0], table[:, 1]))
        q = np.concatenate([[self.surcharge], table[:, 1]])
        if self.start == "deposited":
            require(self.e_deposited is not None and self.e_deposited > 0,
                    f"e_deposited = {self.e_deposited} must be > 0 with "
                    "start = 'deposited'")
            require(self.ocr == 1, f"ocr = {self.ocr}: a deposited layer is normally "
                    "consolidated (ocr = 1)")
        elif self.clay.compression == "camclay":
            require(np.all(q > 0), f"surcharge and load = {q.tolist()} must be > 0 kPa "
                    "with the camclay law and a geostatic start (e -> inf at zero stress)")

    @property
    def buoyant_weight(self):
        """``gamma' = (Gs - 1) gamma_w`` [kN/m3 of solids], 0 for a weightless layer."""
        if not self.self_weight:
            return 0.0
        return (self.clay.specific_gravity - 1) * self.clay.gamma_w

    def surcharge_at(self, t):
        """The surcharge q(t) [kPa] (``surcharge`` at t <= 0)."""
        times, values = self._load
        if t <= 0 or not len(times) or t < times[0]:
            return self.surcharge
        return float(np.interp(t, times, values))

    def load_times(self):
        """The load table's times after t = 0 (the time levels include them)."""
        return self._load[0][self._load[0] > 0]


@dataclass(frozen=True)
class Result:
    """Gibson solution at the output times; profiles are per cell, bottom to top.

    Attributes
    ----------
    times : ndarray (T,)
        Output times [s].
    settlement : ndarray (T,)
        Fall of the top since t = 0 [m], positive down.
    height : ndarray (T,)
        Current height of the layer [m].
    z : ndarray (N,)
        Solid coordinate of the cell centres [m].
    xi : ndarray (T, N)
        Height of the cell centres above the base [m].
    e, sigma_eff, u_e, p_w, k : ndarray (T, N)
        Void ratio, effective vertical stress [kPa], excess and total pore pressure [kPa]
        (compression positive), permeability [m/s].
    solid_height : float
        Z [m].
    levels : int
        Time levels marched.
    """

    times: np.ndarray
    settlement: np.ndarray
    height: np.ndarray
    z: np.ndarray
    xi: np.ndarray
    e: np.ndarray
    sigma_eff: np.ndarray
    u_e: np.ndarray
    p_w: np.ndarray
    k: np.ndarray
    solid_height: float
    levels: int


class _Discrete:
    """The finite-volume system of a column on ``cells`` cells: rates and Jacobian."""

    def __init__(self, column, cells):
        self.column, self.clay, self.n = column, column.clay, cells
        self.gamma = column.buoyant_weight
        if column.start == "deposited":
            e0 = column.e_deposited
            self.base_stress = float(self.clay.virgin_stress(e0))
            self.Z = column.height / (1 + e0)
            self._grid()
            self.e0 = np.full(cells, float(e0))
            self.sigma_p = np.full(cells, self.base_stress)
        else:
            self.base_stress = 0.0
            q0 = column.surcharge

            def excess_height(Z):
                self.Z = Z
                self._grid()
                return np.sum(1 + self._geostatic(q0)[0]) * self.dz - column.height

            self.Z = brentq(excess_height, 1e-9 * column.height, column.height,
                            xtol=1e-15 * column.height, rtol=8.9e-16)
            self._grid()
            self.e0, self.sigma_p = self._geostatic(q0)

    def _grid(self):
        self.dz = self.Z / self.n
        self.zc = (np.arange(self.n) + 0.5) * self.dz

    def _geostatic(self, q0):
        """Void ratio and pre-consolidation stress of the cells in equilibrium under q0."""
        sigma = q0 + self.gamma * (self.Z - self.zc)
        sigma_p = self.column.ocr * sigma
        return self.clay.void_ratio(sigma, sigma_p), sigma_p

    def top_stress(self, t):
        return self.base_stress + self.column.surcharge_at(t)

    def rates(self, e, t, sigma_p):
        """de/dt per cell and the Jacobian's diagonals (lower, main, upper)."""
        clay, dz, g = self.clay, self.dz, self.gamma
        s, ds = clay.effective_stress(e, sigma_p)
        n = self.n
        F = np.zeros(n + 1)             # upward discharge through faces 0 (base) .. n (top)
        below = np.zeros(n + 1)         # dF_face / de of the cell below it
        above = np.zeros(n + 1)         # ... and of the cell above it
        ef = 0.5 * (e[:-1] + e[1:])
        K, dK = clay.conductivity(ef)
        grad = g + (s[1:] - s[:-1]) / dz
        F[1:-1] = K * grad
        below[1:-1] = 0.5 * dK * grad - K * ds[:-1] / dz
        above[1:-1] = 0.5 * dK * grad + K * ds[1:] / dz
        top = self.top_stress(t)
        Kt = clay.conductivity(clay.void_ratio(top, sigma_p[-1]))[0]
        F[-1] = Kt * (g + (top - s[-1]) * 2 / dz)
        below[-1] = -Kt * 2 * ds[-1] / dz
        if self.column.drained_bottom:
            bottom = top + g * self.Z
            Kb = clay.conductivity(clay.void_ratio(bottom, sigma_p[0]))[0]
            F[0] = Kb * (g + (s[0] - bottom) * 2 / dz)
            above[0] = Kb * 2 * ds[0] / dz
        rate = -(F[1:] - F[:-1]) / dz
        jac = (below[1:-1] / dz, -(below[1:] - above[:-1]) / dz, -above[1:-1] / dz)
        return rate, jac

    def profiles(self, e, t, sigma_p):
        """Height of the cell centres, sigma', u_e, p_w and k of a state."""
        clay, col = self.clay, self.column
        faces = np.concatenate([[0.0], np.cumsum((1 + e) * self.dz)])
        xi = faces[:-1] + 0.5 * (1 + e) * self.dz
        s = clay.effective_stress(e, sigma_p)[0]
        u = self.top_stress(t) + self.gamma * (self.Z - self.zc) - s
        hydro = clay.gamma_w * (col.height - xi) if col.self_weight else np.zeros_like(xi)
        return faces[-1], xi, s, u, u + hydro, clay.permeability_of(e)[0]


def time_levels(times, load_times, t_first, steps_per_decade):
    """Time levels: 0, geometric from ``t_first`` to the last output time, and every output
    and load time (sorted, unique)."""
    t_end = max(times)
    count = max(1, int(np.ceil(np.log10(t_end / t_first) * steps_per_decade)))
    geometric = np.geomspace(t_first, t_end, count + 1) if t_end > t_first else []
    extra = [t for t in load_times if t < t_end]
    return np.unique(np.concatenate([[0.0], geometric, times, extra]))


def solve(column, times, cells=800, steps_per_decade=40, t_first=None, tol=1e-11):
    """March a column and return its settlement and profiles at ``times``.

    Parameters
    ----------
    column : Column
    times : array_like
        Output times [s] (>= 0; 0 gives the initial state).
    cells : int
        Finite volumes in z.
    steps_per_decade : int
        Geometric time levels per decade of t.
    t_first : float or None
        First time level after 0 [s] (default 1e-9 times the last output time).
    tol : float
        Newton tolerance on the void-ratio update (absolute).

    Returns
    -------
    Result
    """
    times = np.atleast_1d(np.asarray(times, dtype=float))
    require(np.all(times >= 0) and times.max() > 0,
            f"times = {times.tolist()} must be >= 0 with at least one > 0")
    require(cells >= 2, f"cells = {cells} must be >= 2")
    require(steps_per_decade >= 1, f"steps_per_decade = {steps_per_decade} must be >= 1")
    system = _Discrete(column, int(cells))
    t_first = 1e-9 * times.max() if t_first is None else t_first
    levels = time_levels(times, column.load_times(), t_first, steps_per_decade)
    e, sigma_p = system.e0.copy(), system.sigma_p.copy()
    states = {0.0: (e.copy(), sigma_p.copy())}
    wanted = set(times.tolist())
    for t0, t1 in zip(levels[:-1], levels[1:]):
        e = _step(system, e, t0, t1 - t0, sigma_p, tol)
        if system.clay.compression == "camclay":
            sigma_p = np.maximum(sigma_p, system.clay.effective_stress(e, sigma_p)[0])
        if t1 in wanted:
            states[t1] = (e.copy(), sigma_p.copy())
    return _result(system, times, states, len(levels) - 1)


def _result(system, times, states, levels):
    e = np.array([states[t][0] for t in times])
    rows = [system.profiles(states[t][0], t, states[t][1]) for t in times]
    height, xi, sigma, u, p_w, k = (np.array(column) for column in zip(*rows))
    return Result(times=times, settlement=system.column.height - height, height=height,
                  z=system.zc, xi=xi, e=e, sigma_eff=sigma, u_e=u, p_w=p_w, k=k,
                  solid_height=system.Z, levels=levels)


def _step(system, e, t, h, sigma_p, tol, depth=0):
    """One TR-BDF2 step; a stage whose Newton iteration fails splits the step in two."""
    try:
        c = 0.5 * TRBDF2 * h      # = (1 - TRBDF2) / (2 - TRBDF2) * h
        f0 = system.rates(e, t, sigma_p)[0]
        eg = _newton(system, e + c * f0, e, t + TRBDF2 * h, c, sigma_p, tol)
        rhs = (eg - (1 - TRBDF2) ** 2 * e) / (TRBDF2 * (2 - TRBDF2))
        return _newton(system, rhs, eg, t + h, c, sigma_p, tol)
    except ConvergenceError:
        if depth >= 12:
            raise
        half = _step(system, e, t, h / 2, sigma_p, tol, depth + 1)
        return _step(system, half, t + h / 2, h / 2, sigma_p, tol, depth + 1)


def _newton(system, rhs, guess, t, c, sigma_p, tol, iterations=30):
    """Solve ``e - c f(e, t) = rhs`` by Newton's method (tridiagonal Jacobian)."""
    e = guess.copy()
    band = np.zeros((3, system.n))
    for _ in range(iterations):
        rate, (lower, diag, upper) = system.rates(e, t, sigma_p)
        residual = e - c * rate - rhs
        band[0, 1:], band[1], band[2, :-1] = -c * upper, 1 - c * diag, -c * lower
        step = solve_banded((1, 1), band, -residual, check_finite=False)
        e = e + step
        if not np.all(np.isfinite(e)) or np.any(e <= 0):
            raise ConvergenceError(f"gibson: Newton left the void ratio range at t = {t}")
        if np.abs(step).max() < tol:
            return e
    raise ConvergenceError(f"gibson: Newton did not converge at t = {t}")


#: The soft clay of the large-strain column (issue 16): Cc = 0.92, Cr = 0.092 (Cr/Cc =
#: 0.1), e = 2.4 at 10 kPa, Gs = 2.65, Taylor's k = 1e-9 m/s at e = 2.4 with C_k = 0.5 e
#: (Tavenas et al. 1983). Table 1's clay (lambda/(1 + e) = 0.06) cannot settle more than
#: 14 % under a tenfold load; this one settles 23 %.
SOFT_CLAY = Clay(lam=0.4, kappa=0.04, e_ref=2.4, sigma_v_ref=10.0, permeability=1e-9,
                 permeability_law="taylor", permeability_ck=1.2, specific_gravity=2.65)


def large_strain_column(**changes):
    """A 10 m normally consolidated layer of :data:`SOFT_CLAY` under self-weight, loaded
    from a 20 kPa surcharge to 200 kPa at t = 0+, drained at the top (fields of
    :class:`Column` in ``changes`` replace these)."""
    return Column(**(dict(clay=SOFT_CLAY, height=10.0, surcharge=20.0,
                          load=((0.0, 200.0),)) | changes))


def consolidation_time(column):
    """``d^2 / cv0`` [s]: the drainage path d (the height, half of it with a drained
    base) over the initial coefficient of consolidation at mid-depth."""
    path = column.height / (2 if column.drained_bottom else 1)
    return path**2 / initial_coefficients(column)[2]


def initial_coefficients(column, at=0.5):
    """Small-strain coefficients of the initial state at a fraction ``at`` of the solid
    height (0 base, 1 top): ``(mv [1/kPa], k [m/s], cv [m2/s])``, ``mv = -de/dsigma' /
    (1 + e)``, ``cv = k / (gamma_w mv)`` (Terzaghi's, for the small-strain comparison)."""
    system = _Discrete(column, 400)
    z = at * system.Z
    if column.start == "deposited":
        e, sigma_p = np.array([column.e_deposited]), np.array([system.base_stress])
    else:
        sigma = column.surcharge + system.gamma * (system.Z - z)
        sigma_p = np.array([column.ocr * sigma])
        e = column.clay.void_ratio(np.array([sigma]), sigma_p)
    ds = column.clay.effective_stress(e, sigma_p)[1]
    mv = float(-1 / (ds[0] * (1 + e[0])))
    k = float(column.clay.permeability_of(e)[0][0])
    return mv, k, k / (column.clay.gamma_w * mv)


def refinement(column, times, levels=((200, 10), (400, 20), (800, 40))):
    """Settlement at ``times`` on successively refined (cells, steps per decade) levels,
    each halving the cell size and the log-time step, and its Richardson extrapolation.

    Returns
    -------
    dict
        ``settlement`` (L, T) [m]; ``order`` (T,), the observed order
        ``log2((S1 - S2)/(S2 - S3))`` of the last three levels; ``extrapolated`` (T,)
        ``S3 + (S3 - S2)/(2^p - 1)``; ``error`` (T,), the finest level's relative
        distance to it; ``levels``.
    """
    S = np.array([solve(column, times, cells=c, steps_per_decade=s).settlement
                  for c, s in levels])
    d1, d2 = S[-2] - S[-3], S[-1] - S[-2]
    order = np.log2(d1 / d2)
    extrapolated = S[-1] + d2 / (2**order - 1)
    return {"settlement": S, "order": order, "extrapolated": extrapolated,
            "error": np.abs(S[-1] / extrapolated - 1), "levels": tuple(levels)}
