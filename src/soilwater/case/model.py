"""The case model: the immutable, validated description of a problem that the solvers read.

A :class:`Case` is built by :func:`soilwater.case.loader.load_case` (a built-in name or a TOML
file) or :func:`soilwater.case.validation.case_from_dict`; its TOML layout, defaults and load-time
bounds are documented in :mod:`soilwater.case.schema`. Units are those of the case (kPa, m, s in the
built-in cases).

Conventions: x to the right, y up, origin at the lower-left corner of the rectangle;
stress and traction are tension positive (a traction ``[0, -1]`` on the top edge is a
compressive load); pore water pressure p_w is compression positive;
``sigma = sigma' - alpha p_w I``. Gravity, if any, acts along -y; p_w is then the pore
pressure in excess of hydrostatic (:mod:`soilwater.physics.geostatic`).
"""

from dataclasses import asdict, dataclass, field

import numpy as np

from soilwater.references.closed_forms import exact_solution
from soilwater.errors import require
from soilwater.material.presets import material_from_spec
from soilwater.efg.settings import EFGSettings
from soilwater.fem.settings import FEMSettings

EDGES = ("left", "right", "bottom", "top")
KINDS = ("free", "fixed", "prescribed", "rigid", "exact")
SEGMENT_KINDS = {"ux": ("free", "fixed", "prescribed"),
                 "uy": ("free", "fixed", "prescribed", "footing")}
"""The kinds a named segment of an edge (:class:`Segment`) accepts per component."""
WATER = ("drained", "impermeable")
LAYOUTS = ("grid", "grid+centres")
ANALYSES = ("coupled", "static")
SEGMENT_TOLERANCE = 1e-9
"""A point within this fraction of the smallest grid spacing of a segment's end belongs to
the segment (:meth:`Case.edge_conditions`)."""
ON_FAILURE = ("error", "stop")
PERMEABILITY_LAWS = ("constant", "taylor", "kozeny-carman")
STRESS_STARTS = ("uniform", "geostatic")
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
    """Grid of ``nx x ny`` nodes, optionally plus one node per cell centre.

    The grid lines are regular, or, where ``x`` (``y``) is given, laid out piece by piece
    along x (y): each piece ``(to, spacings, ratio)`` runs from the end of the previous
    one (0 for the first) to ``to`` [m] in ``spacings`` grid spacings, the last of which is
    ``ratio`` times the first, growing geometrically in between (1: equal spacings).
    ``((1.0, 16, 1.0), (20.0, 24, 30.0))`` is 16 equal spacings over the first metre, then
    24 growing thirty-fold to 20 m: fine where a footing sits, coarse far from it. ``nx``
    (``ny``) is then one more than the pieces' spacings.

    ``jitter`` moves every interior node by a uniform random offset of up to ``jitter``
    times the smallest grid spacing in each direction (boundary nodes stay on their
    edges), drawn with ``numpy.random.default_rng(seed)``: a perturbation of the node set,
    used to probe how a result depends on round-off-sized changes of the geometry.
    """

    nx: int
    ny: int
    layout: str = "grid"
    jitter: float = 0.0
    seed: int = 0
    x: tuple[tuple[float, int, float], ...] = ()
    y: tuple[tuple[float, int, float], ...] = ()

    @property
    def regular(self):
        """True when the grid lines are equally spaced along both axes (no pieces)."""
        return not (self.x or self.y)

    def to_dict(self):
        """The ``[discretisation]`` table: ``x`` (``y``) instead of ``nx`` (``ny``) where
        the grid is laid out in pieces."""
        data = {k: v for k, v in asdict(self).items() if k not in ("x", "y")}
        for axis in ("x", "y"):
            if getattr(self, axis):
                data.pop(f"n{axis}")
                data[axis] = getattr(self, axis)
        return data


def grid_line(length, n, pieces=()):
    """Grid coordinates [m] on ``[0, length]``: ``n`` equally spaced, or laid out by
    ``pieces`` ``(to, spacings, ratio)`` (:class:`Discretisation`).

    Examples
    --------
    >>> grid_line(1.0, 3).tolist()
    [0.0, 0.5, 1.0]
    >>> grid_line(8.0, 5, ((1.0, 1, 1.0), (8.0, 3, 4.0))).tolist()
    [0.0, 1.0, 2.0, 4.0, 8.0]
    """
    if not pieces:
        return np.linspace(0.0, length, n)
    lines, start = [[0.0]], 0.0
    for to, spacings, ratio in pieces:
        steps = ratio ** (np.arange(spacings) / max(spacings - 1, 1))
        lines.append(start + (to - start) * np.cumsum(steps) / steps.sum())
        lines[-1][-1] = start = to
    return np.concatenate(lines)


@dataclass(frozen=True)
class Diagnostics:
    """Optional per-step measurements: ``uniqueness`` (:mod:`soilwater.diagnostics.bifurcation`)."""

    uniqueness: bool = False


@dataclass(frozen=True)
class Fluid:
    """Pore fluid and coupling: permeability k [m/s] and its law, gamma_w [kN/m3], Biot
    alpha, S [1/kPa], and the specific gravity Gs of the solids (their weight under
    gravity).

    The Darcy mobility entering the continuity equation is ``k / gamma_w``. With
    ``permeability_law = "constant"`` k is ``permeability``; otherwise it falls with the
    void ratio e (:meth:`mobility_at`): Taylor's ``k = k_ref 10^((e - e_k) / C_k)`` or
    Kozeny-Carman's ``k = k_ref (e^3 / (1 + e)) / (e_k^3 / (1 + e_k))``, with ``k_ref =
    permeability``, ``e_k = permeability_e`` and ``C_k = permeability_ck``.
    """

    permeability: float = 0.0
    gamma_w: float = 9.81
    biot_alpha: float = 1.0
    storage: float = 0.0
    permeability_law: str = "constant"
    permeability_e: float | None = None
    permeability_ck: float | None = None
    specific_gravity: float = 2.65

    @property
    def mobility(self):
        """``k / gamma_w`` [m2/(kPa s)] at the reference void ratio (``k_ref``)."""
        return self.permeability / self.gamma_w

    def mobility_at(self, v):
        """``k(e) / gamma_w`` [m2/(kPa s)] and its derivative with respect to the specific
        volume ``v = 1 + e``, at each point.

        Examples
        --------
        Taylor's law falls tenfold per ``C_k`` of void ratio:

        >>> fluid = Fluid(permeability=1e-8, permeability_law="taylor",
        ...               permeability_e=1.0, permeability_ck=0.5)
        >>> k, dk = fluid.mobility_at(np.array([2.0, 1.5]))
        >>> [round(float(x), 6) for x in k * fluid.gamma_w / 1e-8]
        [1.0, 0.1]
        """
        v = np.asarray(v, dtype=float)
        if self.permeability_law == "constant":
            return np.full_like(v, self.mobility), np.zeros_like(v)
        e, e_k = v - 1.0, self.permeability_e
        if self.permeability_law == "taylor":
            k = self.mobility * 10.0 ** ((e - e_k) / self.permeability_ck)
            return k, k * np.log(10.0) / self.permeability_ck
        k = self.mobility * (e**3 / v) / (e_k**3 / (1.0 + e_k))
        return k, k * (3.0 / e - 1.0 / v)


@dataclass(frozen=True)
class Gravity:
    """Gravitational acceleration g [m/s2] along -y (0: weightless)."""

    g: float = 0.0


@dataclass(frozen=True)
class Initial:
    """The initial state (:mod:`soilwater.physics.geostatic`).

    ``pore_pressure``: a number [kPa] or ``"balance"`` (total stress zero). ``stress``:
    ``"uniform"`` (the material's p'0, e0, ocr everywhere) or ``"geostatic"``: the
    vertical effective stress of the buoyant weight under the ``surcharge`` [kPa] on top,
    horizontal ``k0`` times it (a number, or ``"nc"``: the material's normally
    consolidated value), the void ratio on the compression line anchored at ``e_ref``
    under ``sigma_v_ref`` [kPa] (the oedometer convention; default the material's e0 at
    p'0), and a vertical overconsolidation ratio ``ocr``.
    """

    pore_pressure: float | str = 0.0
    stress: str = "uniform"
    surcharge: float = 0.0
    k0: float | str = "nc"
    e_ref: float | None = None
    sigma_v_ref: float | None = None
    ocr: float = 1.0

    def to_dict(self):
        """The ``[initial]`` table: the geostatic keys only with a geostatic start."""
        if self.stress == "uniform":
            return {"pore_pressure": self.pore_pressure}
        return {k: v for k, v in asdict(self).items() if v is not None}


@dataclass(frozen=True)
class Segment:
    """A named part ``[start, end]`` of an edge with its own displacement kinds.

    ``start`` and ``end`` (TOML ``from`` and ``to``) [m] are the coordinate along the edge
    in the initial configuration: x on the top and bottom edges, y on the left and right.
    A boundary point (EFG) or DOF (FEM) whose initial coordinate lies in ``[start, end]``
    takes the segment's kinds; the segment carries no traction.

    ``uy = "footing"`` makes the segment a rigid strip footing whose uy moves as one body:
    either velocity control, ``settlement_rate`` [m/s, positive down] (uy = -rate x t on
    the segment), or load control, ``force`` [kN/m per unit thickness, compression
    positive] times the load factor ``loading.load`` at t, carried by one unknown
    settlement (the machinery of the ``rigid`` plate). ``ux = "fixed"`` is a rough footing
    (no sideways motion), ``ux = "free"`` a smooth one. ``water`` None keeps the edge's
    water condition.
    """

    name: str
    start: float
    end: float
    ux: str = "free"
    uy: str = "free"
    water: str | None = None
    settlement_rate: float | None = None
    force: float | None = None

    @property
    def footing(self):
        """True for a rigid footing (``uy = "footing"``)."""
        return self.uy == "footing"

    @property
    def load_controlled(self):
        """True for a footing carrying a prescribed force (one unknown settlement)."""
        return self.footing and self.force is not None

    @property
    def uy_kind(self):
        """The uy kind the solvers apply: ``rigid`` for a load-controlled footing (the
        plate unknown), ``footing`` for a velocity-controlled one, else ``uy``."""
        return "rigid" if self.load_controlled else self.uy

    def contains(self, s, tol=0.0):
        """(P,) bool: coordinates along the edge ``s`` [m] within ``[start, end]`` +- tol."""
        s = np.asarray(s, float)
        return (s >= self.start - tol) & (s <= self.end + tol)

    def to_dict(self):
        """The segment's TOML table (``from``, ``to``, its kinds and footing data)."""
        data = {"from": self.start, "to": self.end, "ux": self.ux, "uy": self.uy,
                "water": self.water, "settlement_rate": self.settlement_rate,
                "force": self.force}
        return {k: v for k, v in data.items() if v is not None}


@dataclass(frozen=True)
class Edge:
    """Conditions on one edge: kinds of ux and uy, total traction [kPa], water condition,
    and named segments (:class:`Segment`) that override the kinds on parts of it."""

    ux: str = "free"
    uy: str = "free"
    traction: tuple[float, float] = (0.0, 0.0)
    water: str = "impermeable"
    segments: tuple[Segment, ...] = ()

    @property
    def drained(self):
        """True if p_w = 0 is imposed on the edge."""
        return self.water == "drained"

    def at(self, s, tol=0.0):
        """The conditions at coordinates ``s`` along the edge (initial configuration).

        Parameters
        ----------
        s : array_like, shape (P,)
            Coordinate along the edge [m]: x on top and bottom, y on left and right.
        tol : float
            Points within ``tol`` [m] of a segment's ends belong to it.

        Returns
        -------
        kind : ndarray of str, shape (P, 2)
            ux and uy kinds; a load-controlled footing's uy is ``rigid`` and a
            velocity-controlled one's ``footing`` (:attr:`Segment.uy_kind`).
        drained : ndarray of bool, shape (P,)
        segment : ndarray of int, shape (P,)
            Index into :attr:`segments` of each point's segment, -1 for the bare edge.
        """
        s = np.atleast_1d(np.asarray(s, float))
        kind = np.tile(np.array([self.ux, self.uy], dtype=object), (len(s), 1))
        drained = np.full(len(s), self.drained)
        segment = np.full(len(s), -1)
        for k, seg in enumerate(self.segments):
            inside = seg.contains(s, tol)
            kind[inside] = (seg.ux, seg.uy_kind)
            if seg.water is not None:
                drained[inside] = seg.water == "drained"
            segment[inside] = k
        return kind.astype(str), drained, segment

    def kinds(self, length):
        """The kinds that occur on the edge of ``length`` [m]: ``(ux kinds, uy kinds)``,
        two sets (the edge's own ones unless its segments cover it whole; a footing's uy
        as :attr:`Segment.uy_kind`)."""
        ux, uy = {seg.ux for seg in self.segments}, {seg.uy_kind for seg in self.segments}
        reach, covered = 0.0, bool(self.segments)
        for a, b in sorted((seg.start, seg.end) for seg in self.segments):
            covered &= a <= reach
            reach = max(reach, b)
        if not (covered and reach >= length):
            ux, uy = ux | {self.ux}, uy | {self.uy}
        return ux, uy

    def to_dict(self):
        """The edge's TOML table, segments as sub-tables by name."""
        return {"ux": self.ux, "uy": self.uy, "traction": self.traction,
                "water": self.water, **{seg.name: seg.to_dict() for seg in self.segments}}


def along(side, points):
    """Coordinate along edge ``side`` of points (P, 2) [m]: x on top and bottom, y on
    left and right."""
    return np.asarray(points)[..., 0 if side in ("top", "bottom") else 1]


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

    def segments(self):
        """``(edge name, Segment)`` pairs of every named segment, edges in EDGES order."""
        return tuple((name, seg) for name, edge in self.items() for seg in edge.segments)


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
    """End time [s] and either ``steps`` or geometric ``dt0``, ``growth``, ``dt_max``;
    ``on_failure`` is what a step that fails after every halving does: ``error`` (no
    result) or ``stop`` (the result ends at the last converged level)."""

    end: float
    steps: int | None = None
    dt0: float | None = None
    growth: float | None = None
    dt_max: float | None = None
    on_failure: str = "error"

    def levels(self):
        """Time levels ``t_0 = 0, ..., t_end`` [s].

        ``steps`` gives equal steps; otherwise ``t_1 = dt0`` and
        ``t_{n+1} = t_n + min((growth - 1) t_n, dt_max)``, the last step cut to land on
        ``end``. More than :data:`MAX_STEPS` steps raise :class:`~soilwater.errors.InputError`.
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

    Build it with :func:`soilwater.case.loader.load_case` or :func:`soilwater.case.validation.case_from_dict`;
    it is immutable, comparable and picklable. ``material_spec`` holds the ``[material]``
    entries other than the fluid keys, as sorted ``(key, value)`` pairs; ``efg`` holds the
    meshless settings, weights parsed into :class:`soilwater.efg.settings.Weight` objects, and
    ``fem`` the FEM reference's (:class:`soilwater.fem.settings.FEMSettings`).
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
    fem: FEMSettings = FEMSettings()
    gravity: Gravity = Gravity()

    def exact_solution(self):
        """``points -> (u, stress)`` of the ``[exact]`` solution, or None (soilwater.references.closed_forms)."""
        if not self.exact:
            return None
        params = dict(self.exact)
        return exact_solution(params.pop("solution"), **params)

    def material(self):
        """The soil skeleton (``CamClay`` or ``LinearElastic``) built from the spec."""
        return material_from_spec(dict(self.material_spec))

    @property
    def spacing(self):
        """Smallest grid spacing ``(hx, hy)`` [m]: ``width / (nx - 1)`` and
        ``height / (ny - 1)`` on a regular grid."""
        d, g = self.discretisation, self.geometry
        return tuple(float(np.diff(line).min()) if pieces else length / (n - 1)
                     for length, n, pieces, line in zip((g.width, g.height), (d.nx, d.ny),
                                                        (d.x, d.y), self.grid_lines()))

    def grid_lines(self):
        """Coordinates of the grid lines ``(x (nx,), y (ny,))`` [m] (regular, or laid out
        by the pieces of :class:`Discretisation`)."""
        d, g = self.discretisation, self.geometry
        return grid_line(g.width, d.nx, d.x), grid_line(g.height, d.ny, d.y)

    def nodes(self):
        """Initial node coordinates, shape (N, 2) [m].

        Grid nodes row by row from the bottom (x fastest), then, for ``grid+centres``,
        the cell centres in the same order: ``N = nx ny (+ (nx-1)(ny-1))``.
        """
        d = self.discretisation
        x, y = self.grid_lines()
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

        ``traction[1] x load factor x initial edge length`` of the edge whose uy is rigid,
        or ``-force x load factor`` of a load-controlled footing (:class:`Segment`; at
        most one plate per case); zero without a plate.
        """
        for _, edge in self.boundary.items():
            if edge.uy == "rigid":
                return float(edge.traction[1] * self.loading.factor(t) * self.geometry.width)
        for _, seg in self.boundary.segments():
            if seg.load_controlled:
                return float(-seg.force * self.loading.factor(t))
        return 0.0

    def edge_conditions(self, side, points):
        """:meth:`Edge.at` of edge ``side`` at initial positions ``points`` (P, 2) [m] on it,
        segment ends widened by :data:`SEGMENT_TOLERANCE` times the smallest spacing."""
        return getattr(self.boundary, side).at(along(side, points),
                                               SEGMENT_TOLERANCE * min(self.spacing))

    def segment_nodes(self):
        """Indices into :meth:`nodes` of each named segment's nodes (the boundary nodes of
        its edge within ``[from, to]``), in :meth:`Boundary.segments` order."""
        nodes = self.nodes()
        loop = self.boundary_loop()
        g, tol = self.geometry, SEGMENT_TOLERANCE * min(self.spacing)
        line = {"left": (0, 0.0), "right": (0, g.width), "bottom": (1, 0.0),
                "top": (1, g.height)}
        out = []
        for side, seg in self.boundary.segments():
            axis, value = line[side]
            p = nodes[loop]
            on = (np.abs(p[:, axis] - value) <= tol) & seg.contains(along(side, p), tol)
            out.append(np.sort(loop[on]))
        return out

    def edge_length(self, side):
        """Initial length of edge ``side`` [m]."""
        g = self.geometry
        return g.width if side in ("top", "bottom") else g.height

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
            "discretisation": self.discretisation.to_dict(),
            "material": {**dict(self.material_spec),
                         **{k: v for k, v in asdict(self.fluid).items() if v is not None}},
            "initial": self.initial.to_dict(),
            "gravity": asdict(self.gravity),
            "boundary": {name: edge.to_dict() for name, edge in self.boundary.items()},
            "loading": asdict(self.loading),
            "time": time,
            "probes": {p.name: p.point for p in self.probes},
            "exact": dict(self.exact),
            "diagnostics": asdict(self.diagnostics),
            "efg": self.efg.to_dict(),
            "fem": self.fem.to_dict(),
        })


def _plain(value):
    """Tuples to lists, recursively (a JSON- and TOML-shaped copy)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value

