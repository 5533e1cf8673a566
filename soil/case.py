"""The case model: the immutable, validated description of a problem that the solvers read.

A :class:`Case` is built by :func:`soil.problems.load_case` (a built-in name or a TOML
file) or :func:`soil.validation.case_from_dict`; its TOML layout, defaults and load-time
bounds are documented in :mod:`soil.schema`. Units are those of the case (kPa, m, s in the
built-in cases).

Conventions: x to the right, y up, origin at the lower-left corner of the rectangle;
stress and traction are tension positive (a traction ``[0, -1]`` on the top edge is a
compressive load); pore water pressure p_w is compression positive;
``sigma = sigma' - alpha p_w I``. No body forces.
"""

from dataclasses import asdict, dataclass, field

import numpy as np

from soil.analytical import exact_solution
from soil.errors import require
from soil.materials import material_from_spec
from soil.settings import EFGSettings

EDGES = ("left", "right", "bottom", "top")
KINDS = ("free", "fixed", "prescribed", "rigid", "exact")
WATER = ("drained", "impermeable")
LAYOUTS = ("grid", "grid+centres")
ANALYSES = ("coupled", "static")
MAX_STEPS = 100_000
"""Largest number of time steps of a case (``time.steps``, or geometric steps to the end)."""


@dataclass(frozen=True)
class Geometry:
    """Rectangle ``[0, width] x [0, height]`` [m]."""

    width: float
    height: float
    shape: str = "rectangle"


@dataclass(frozen=True)
class Discretisation:
    """Regular grid of ``nx x ny`` nodes, optionally plus one node per cell centre.

    ``jitter`` moves every interior node by a uniform random offset of up to ``jitter``
    times the grid spacing in each direction (boundary nodes stay on their edges), drawn
    with ``numpy.random.default_rng(seed)``: a perturbation of the node set, used to probe
    how a result depends on round-off-sized changes of the geometry.
    """

    nx: int
    ny: int
    layout: str = "grid"
    jitter: float = 0.0
    seed: int = 0


@dataclass(frozen=True)
class Diagnostics:
    """Optional per-step measurements: ``uniqueness`` (:mod:`soil.bifurcation`)."""

    uniqueness: bool = False


@dataclass(frozen=True)
class Fluid:
    """Pore fluid and coupling: permeability k [m/s], gamma_w [kN/m3], Biot alpha, S [1/kPa].

    The Darcy mobility entering the continuity equation is ``k / gamma_w``.
    """

    permeability: float = 0.0
    gamma_w: float = 9.81
    biot_alpha: float = 1.0
    storage: float = 0.0

    @property
    def mobility(self):
        """``k / gamma_w`` [m2/(kPa s)]."""
        return self.permeability / self.gamma_w


@dataclass(frozen=True)
class Initial:
    """Initial pore pressure: a number [kPa] or ``"balance"`` (total stress zero)."""

    pore_pressure: float | str = 0.0


@dataclass(frozen=True)
class Edge:
    """Conditions on one edge: kinds of ux and uy, total traction [kPa], water condition."""

    ux: str = "free"
    uy: str = "free"
    traction: tuple[float, float] = (0.0, 0.0)
    water: str = "impermeable"

    @property
    def drained(self):
        """True if p_w = 0 is imposed on the edge."""
        return self.water == "drained"


@dataclass(frozen=True)
class Boundary:
    """The four edges of the rectangle."""

    left: Edge
    right: Edge
    bottom: Edge
    top: Edge

    def items(self):
        """``(name, Edge)`` pairs in the order left, right, bottom, top."""
        return tuple((name, getattr(self, name)) for name in EDGES)


@dataclass(frozen=True)
class Loading:
    """Constant velocity gradient ``L_ij = dv_i/dx_j`` [1/s] and the load function.

    ``load`` is a float (step: 0 at t = 0, that factor for t > 0) or ``((t, f), ...)``
    interpolated linearly (constant outside the given times).
    """

    velocity_gradient: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0),
                                                                          (0.0, 0.0))
    load: float | tuple[tuple[float, float], ...] = 1.0

    @property
    def L(self):
        """The velocity gradient as a (2, 2) array."""
        return np.array(self.velocity_gradient)

    def factor(self, t):
        """Load factor at time(s) t (multiplies every edge traction)."""
        if isinstance(self.load, float):
            return np.where(np.asarray(t) > 0, self.load, 0.0)
        times, factors = np.array(self.load).T
        return np.interp(t, times, factors)


@dataclass(frozen=True)
class TimeStepping:
    """End time [s] and either ``steps`` or geometric ``dt0``, ``growth``, ``dt_max``."""

    end: float
    steps: int | None = None
    dt0: float | None = None
    growth: float | None = None
    dt_max: float | None = None

    def levels(self):
        """Time levels ``t_0 = 0, ..., t_end`` [s].

        ``steps`` gives equal steps; otherwise ``t_1 = dt0`` and
        ``t_{n+1} = t_n + min((growth - 1) t_n, dt_max)``, the last step cut to land on
        ``end``. More than :data:`MAX_STEPS` steps raise :class:`~soil.errors.InputError`.
        """
        if self.steps is not None:
            return np.linspace(0.0, self.end, self.steps + 1)
        t = [0.0, min(self.dt0, self.end)]
        while t[-1] < self.end:
            nxt = t[-1] + min((self.growth - 1.0) * t[-1], self.dt_max)
            t.append(self.end if nxt >= self.end * (1 - 1e-9) else nxt)
            require(len(t) <= MAX_STEPS + 1, f"time: more than {MAX_STEPS} steps to reach "
                    f"end = {self.end}: increase time.dt_max or time.growth")
        return np.array(t)


@dataclass(frozen=True)
class Probe:
    """A named point ``(x, y)`` [m] of the initial configuration where histories are kept."""

    name: str
    point: tuple[float, float]


@dataclass(frozen=True)
class Case:
    """A validated problem: geometry, nodes, material, fluid, boundary, loading, time, probes.

    Build it with :func:`soil.problems.load_case` or :func:`soil.validation.case_from_dict`;
    it is immutable, comparable and picklable. ``material_spec`` holds the ``[material]``
    entries other than the fluid keys, as sorted ``(key, value)`` pairs; ``efg`` holds the
    meshless settings, weights parsed into :class:`soil.settings.Weight` objects.
    """

    name: str
    description: str
    analysis: str
    geometry: Geometry
    discretisation: Discretisation
    material_spec: tuple[tuple[str, float | str], ...]
    fluid: Fluid
    initial: Initial
    boundary: Boundary
    loading: Loading
    time: TimeStepping
    probes: tuple[Probe, ...] = ()
    exact: tuple[tuple[str, object], ...] = ()
    efg: EFGSettings = field(default_factory=EFGSettings)
    diagnostics: Diagnostics = Diagnostics()

    def exact_solution(self):
        """``points -> (u, stress)`` of the ``[exact]`` solution, or None (soil.analytical)."""
        if not self.exact:
            return None
        params = dict(self.exact)
        return exact_solution(params.pop("solution"), **params)

    def material(self):
        """The soil skeleton (``CamClay`` or ``LinearElastic``) built from the spec."""
        return material_from_spec(dict(self.material_spec))

    @property
    def spacing(self):
        """Grid spacing ``(hx, hy)`` [m]."""
        d = self.discretisation
        return self.geometry.width / (d.nx - 1), self.geometry.height / (d.ny - 1)

    def nodes(self):
        """Initial node coordinates, shape (N, 2) [m].

        Grid nodes row by row from the bottom (x fastest), then, for ``grid+centres``,
        the cell centres in the same order: ``N = nx ny (+ (nx-1)(ny-1))``.
        """
        d, g = self.discretisation, self.geometry
        x, y = np.linspace(0.0, g.width, d.nx), np.linspace(0.0, g.height, d.ny)
        grid = np.stack(np.meshgrid(x, y), axis=-1).reshape(-1, 2)
        if d.layout == "grid+centres":
            xc, yc = (x[:-1] + x[1:]) / 2, (y[:-1] + y[1:]) / 2
            grid = np.concatenate([grid, np.stack(np.meshgrid(xc, yc), axis=-1).reshape(-1, 2)])
        if d.jitter == 0:
            return grid
        interior = np.ones(len(grid), bool)
        interior[self.boundary_loop()] = False
        offset = np.random.default_rng(d.seed).uniform(-1, 1, (len(grid), 2))
        return grid + interior[:, None] * d.jitter * offset * self.spacing

    def boundary_loop(self):
        """Indices into :meth:`nodes` of the boundary nodes, counter-clockwise, each once.

        From the lower-left corner: bottom edge left to right, right edge up, top edge right
        to left, left edge down; ``2 (nx + ny) - 4`` indices (cell centres are never on the
        boundary). ``nodes[case.boundary_loop()]`` is the boundary polygon.
        """
        nx, ny = self.discretisation.nx, self.discretisation.ny
        i, j = np.arange(nx), np.arange(ny)
        return np.concatenate([i, j[1:] * nx + nx - 1, (ny - 1) * nx + i[-2::-1],
                               j[-2:0:-1] * nx])

    def plate_force(self, t):
        """Total force on the rigid plate at time t, per unit thickness (y, tension +).

        ``traction[1] x load factor x initial edge length`` of the edge whose uy is rigid;
        zero without a plate.
        """
        for _, edge in self.boundary.items():
            if edge.uy == "rigid":
                return float(edge.traction[1] * self.loading.factor(t) * self.geometry.width)
        return 0.0

    def times(self):
        """Time levels [s], from 0 to ``time.end``; ``len - 1`` steps."""
        return self.time.levels()

    @property
    def initial_pore_pressure(self):
        """p_w0 [kPa], compression positive; ``"balance"`` gives ``-p'0 / alpha``."""
        if self.initial.pore_pressure == "balance":
            return -self.material().p0 / self.fluid.biot_alpha
        return self.initial.pore_pressure

    def to_dict(self):
        """The case as a plain nested dict in TOML layout (defaults filled in)."""
        time = {k: v for k, v in asdict(self.time).items() if v is not None}
        return _plain({
            "name": self.name, "description": self.description, "analysis": self.analysis,
            "geometry": asdict(self.geometry),
            "discretisation": asdict(self.discretisation),
            "material": {**dict(self.material_spec), **asdict(self.fluid)},
            "initial": asdict(self.initial),
            "boundary": {name: asdict(edge) for name, edge in self.boundary.items()},
            "loading": asdict(self.loading),
            "time": time,
            "probes": {p.name: p.point for p in self.probes},
            "exact": dict(self.exact),
            "diagnostics": asdict(self.diagnostics),
            "efg": self.efg.to_dict(),
        })


def _plain(value):
    """Tuples to lists, recursively (a JSON- and TOML-shaped copy)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value

