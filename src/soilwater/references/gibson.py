"""Gibson's finite-strain 1-D consolidation: an independent reference solver.

A saturated layer, laterally confined, stands on a fixed base; its initial height is
``H0`` [m]. It shares no code with the coupled solvers (:mod:`soilwater.efg`,
:mod:`soilwater.fem`, :mod:`soilwater.physics.weakform`, :mod:`soilwater.nonlinear`): it is
the reference their large-strain columns are checked against. The clay's laws are
:mod:`soilwater.references.gibson_clay`, the finite-volume system in z
:mod:`soilwater.references.gibson_discrete`; here are the layer, its time march and its
refinement study.

Units and signs: kPa, m, s; unit weights [kN/m3]; permeability k [m/s] (Darcy with the
excess head, flux ``-(k/gamma_w) du/dxi``). Effective vertical stress sigma' and pore
pressures are **compression positive**; heights xi are measured up from the base;
settlement is the fall of the top, **positive down**.

Initial states (``Column.start``):

- ``"geostatic"``: equilibrium under self-weight and the surcharge ``q(0)``:
  ``sigma'(z) = q(0) + gamma' (Z - z)``, e from the compression law with
  ``sigma'_p = ocr sigma'``; nothing moves until the surcharge changes.
- ``"deposited"``: a freshly deposited layer at a uniform void ratio ``e_deposited``
  whose weight (and the surcharge) the pore water carries: ``u_e = q(0) + gamma' (Z - z)``.
  Its effective stress is the compression law's at ``e_deposited`` (the log law's
  stand-in for zero): the ``sigma'_0`` of the equilibrium in
  :mod:`soilwater.references.gibson_discrete`.

Time integration
----------------
TR-BDF2 (one-step, L-stable, second order; Bank et al. 1985, gamma = 2 - sqrt 2), both
stages solved by Newton's method on the tridiagonal Jacobian, on time levels geometric in
t (``steps_per_decade``) from ``t_first`` plus every output and load-table time
(:func:`~soilwater.references.gibson_discrete.time_levels`); a stage whose Newton
iteration fails splits its step in two.

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

from soilwater.errors import ConvergenceError, require
from soilwater.references.gibson_clay import SOFT_CLAY, Clay
from soilwater.references.gibson_discrete import Discrete, time_levels

STARTS = ("geostatic", "deposited")
#: TR-BDF2's stage fraction; both stages share the Newton coefficient ``1 - 1/sqrt 2``.
TRBDF2 = 2.0 - np.sqrt(2.0)


@dataclass(frozen=True)
class Column:
    """A layer, its loading, initial state and drainage.

    Parameters
    ----------
    clay : ~soilwater.references.gibson_clay.Clay
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
    system = Discrete(column, int(cells))
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
    system = Discrete(column, 400)
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
