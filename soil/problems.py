"""Problem definitions: the :class:`Case`, its TOML form, validation and the built-in cases.

A case is a TOML file (or a built-in name, see :func:`builtin_cases`) read by
:func:`load_case`. This module only defines and validates problems; the solvers read a
:class:`Case`. Units are those of the case (kPa, m, s in the built-in cases).

Conventions (design.md section 2): x to the right, y up, origin at the lower-left corner
of the rectangle; stress and traction are tension positive (a traction ``[0, -1]`` on the
top edge is a compressive load); pore water pressure p_w is compression positive;
``sigma = sigma' - alpha p_w I``. No body forces.

Schema (every case has the same one; unknown keys are an error)::

    name = "my-case"                  # default: the file's stem
    description = "one line"
    analysis = "coupled"              # "coupled" (Biot u-p, default) or "static" (dry,
                                      # one load step, no pore pressure)

    [geometry]
    shape = "rectangle"               # the only shape
    width = 3.0                       # m, along x, in [1e-6, 1e6]
    height = 4.0                      # m, along y, in [1e-6, 1e6]

    [discretisation]
    nx = 7                            # grid nodes along x (>= 2): spacing width/(nx-1)
    ny = 9                            # grid nodes along y (>= 2): spacing height/(ny-1)
    layout = "grid+centres"           # "grid" (default) or grid plus one node per cell centre
                                      # (spacing aspect hx/hy in [1e-3, 1e3])
    jitter = 0.0                      # interior nodes moved at random by up to this
                                      # fraction of the spacing (0 <= jitter < 0.25)
    seed = 0                          # seed of the jitter (numpy default_rng)

    [material]                        # soil.materials.material_from_spec, plus fluid keys:
    preset = "table1"
    model = "original"                # "original", "modified" or "elastic"
    permeability = 0.0                # k [m/s] >= 0 (Darcy: q = -(k/gamma_w) grad p_w)
    gamma_w = 9.81                    # unit weight of water [kN/m3] > 0
    biot_alpha = 1.0                  # Biot coefficient in (0, 1]
    storage = 0.0                     # S = 1/M_biot [1/kPa] >= 0

    [initial]                         # optional
    pore_pressure = "balance"         # a number (default 0) or "balance": p_w0 = -p'0/alpha,
                                      # total stress zero; sigma'0 = -p'0 I (material p0)

    [boundary.left]                   # each of left, right, bottom, top exactly once
    ux = "fixed"                      # "free" (default), "fixed", "prescribed", "rigid"
    uy = "free"
    # displacement = "roller"         # shorthand instead of ux/uy: "roller" (normal
                                      # component fixed), "fixed" or "free"
    traction = [0.0, 0.0]             # total traction [kPa] x load factor (default zero)
    water = "impermeable"             # or "drained" (p_w = 0); drained wins at a corner

    [loading]                         # optional
    velocity_gradient = [[0.0, 0.0], [0.0, -0.01]]   # L [1/s], constant (default zero)
    load = 1.0                        # a factor from t = 0+ (step load, the default) or
                                      # [[t0, f0], [t1, f1], ...] piecewise linear

    [time]
    end = 20.0                        # s
    steps = 100                       # equal steps, or instead: dt0, growth, dt_max

    [probes]                          # optional: name = [x, y] inside the domain;
    centre = [1.5, 2.0]               # history columns are named like "p_w@centre"

    [exact]                           # optional: a closed form of soil.analytical
    solution = "timoshenko-beam"      # boundary data for "exact" edges, error reference
    P = 1000.0                        # ... and the solution's parameters

    [diagnostics]                     # optional, both solvers
    uniqueness = false                # per step, the smallest eigenvalue of the tangent
                                      # restricted to the undrained constraint
                                      # (soil.bifurcation; history column "uniqueness")

    [efg]                             # optional meshless settings (defaults shown)
    weight_u = "quartic"              # MLS weight of u: quartic (Q), cubic or exp:C with
                                      # 1e-3 <= C <= 1e3 (E-A = exp:0.5, E-B = exp:0.25)
    scale_u = 1.3                     # support = scale x distance to the 8th nearest node,
                                      # 1 <= scale <= 1000
    weight_p = "quartic"              # the same for the pore pressure p_w
    scale_p = 1.3
    cells = "delaunay"                # background cells: delaunay or squares
    order = 2                         # Gauss order (squares: per direction; triangles:
                                      # degree, at most 19)
    penalty = 1e6                     # penalty factor relative to the stiffness scale
    correction = "vci"                # consistent test gradients (efg.vci) or "none"

Boundary kinds of a displacement component:

* ``free``: natural; the edge's traction component acts there.
* ``fixed``: zero displacement.
* ``prescribed``: velocity ``v = L x`` at the node's current position, L from
  ``loading.velocity_gradient`` (which must then be non-zero).
* ``exact``: displacement from the case's ``[exact]`` solution; ``traction = "exact"``
  likewise takes the traction ``sigma n`` from it.
* ``rigid`` (``uy`` of the top or bottom edge only): the whole edge settles by one unknown
  uniform vertical displacement (a frictionless rigid plate, Mandel's problem) whose total
  force is ``traction[1] x load factor x (initial edge length)`` per unit thickness.

At a corner both edges' conditions apply; two different non-free kinds on the same
component of a corner are an error. Tractions are loads in excess of the initial state,
which is taken as in equilibrium.

Every number must be finite. Load-time bounds (:func:`case_from_dict` refuses a case
outside them, naming the key, so that ``soilwater show`` fails wherever ``run`` would):

* ``geometry.width`` and ``height`` in [1e-6, 1e6] m, and the grid spacing aspect
  ``hx/hy = (width/(nx-1)) / (height/(ny-1))`` in [1e-3, 1e3]: bounds against absurd
  input (a width of 1e300 overflows the EFG's cell search, inf breaks both solvers).
  Within them a stretched plain grid still needs a larger EFG scale factor, about a
  quarter of the aspect (long over short spacing) beyond an aspect of 4; the solver
  reports that, naming the scale factor's key.
* The displacement must be restrained against the three rigid motions: some edge's ``ux``
  and some edge's ``uy`` ``fixed``, ``prescribed`` or ``exact`` (a ``rigid`` plate is
  load-controlled and stops no translation), and rotation stopped by ``ux`` restrained on
  the left or right edge, ``uy`` on the top or bottom edge, or ``ux`` on both the top and
  bottom (``uy`` on both the left and right).
* ``efg.scale_u`` and ``scale_p`` in [1, 1000]: below 1 a node's support stops short of
  its 8th nearest node, the distance that defines it, and whether each point still sees
  3 non-collinear nodes depends on the layout (on the built-in cases and their variants
  the smallest working factor ranges from 0.69 to 0.90, with condition numbers down to
  1e-7, and stretched grids need more); above 1000 the supports cover the body many times
  over and the moment matrices' conditioning, falling as 1/scale^2, nears the MLS
  safeguard (reached near 1e4 to 1e5).
* ``efg.weight_u`` and ``weight_p``: :func:`weight_form` (outside 1e-3 <= C <= 1e3 the
  exponential weight underflows to a spike or, above, equals its limit ``1 - r^2`` to
  1e-6 while its formula loses digits and divides by zero near C = 1e8).
* ``efg.order`` an integer >= 1, at most 19 with Delaunay cells (the highest triangle
  rule of scikit-fem).

Time stepping: ``steps`` gives equal steps; otherwise ``t_1 = dt0`` and
``t_{n+1} = t_n + min((growth - 1) t_n, dt_max)`` (time levels grow geometrically until the
step reaches ``dt_max``), the last step cut to land on ``end``. This is MOOSE's Terzaghi
stepping (``dt = min(0.5 t, 0.1)``, peer-data case A): 118 steps to t = 10.

:func:`load_case` also takes overrides ``"section.key=value"`` (value in TOML syntax, a bare
word is read as a string), e.g. ``material.permeability=1e-6`` or
``boundary.top.water="drained"``. Setting ``time.steps`` drops the geometric keys (and the
reverse); setting an edge's ``displacement`` replaces its ``ux`` and ``uy``.
"""

import copy
import math
import re
import tomllib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from soil.analytical import exact_solution
from soil.errors import InputError, require
from soil.materials import FLUID_KEYS, material_from_spec

EDGES = ("left", "right", "bottom", "top")
KINDS = ("free", "fixed", "prescribed", "rigid", "exact")
WATER = ("drained", "impermeable")
LAYOUTS = ("grid", "grid+centres")
SECTIONS = ("geometry", "discretisation", "material", "initial", "boundary", "loading",
            "time", "probes", "exact", "diagnostics", "efg")
MAX_STEPS = 100_000
#: Default MLS support scale factor of u and p_w (support = scale x distance to the 8th
#: nearest node).
DEFAULT_SCALE = 1.3

_KEYS = {
    "geometry": ("shape", "width", "height"),
    "discretisation": ("nx", "ny", "layout", "jitter", "seed"),
    "diagnostics": ("uniqueness",),
    "initial": ("pore_pressure",),
    "edge": ("ux", "uy", "displacement", "traction", "water"),
    "loading": ("velocity_gradient", "load"),
    "time": ("end", "steps", "dt0", "growth", "dt_max"),
    "efg": ("weight_u", "scale_u", "weight_p", "scale_p", "cells", "order", "penalty",
            "correction"),
}
CORRECTIONS = ("vci", "none")
CELLS = ("delaunay", "squares")
ANALYSES = ("coupled", "static")
LENGTHS = (1e-6, 1e6)
"""Accepted range of ``geometry.width`` and ``height`` [m]."""
ASPECTS = (1e-3, 1e3)
"""Accepted range of the grid spacing aspect ``hx/hy``."""
SCALES = (1.0, 1e3)
"""Accepted range of the MLS support scale factors ``efg.scale_u`` and ``scale_p``."""
MAX_TRIANGLE_ORDER = 19
"""Highest degree of scikit-fem's triangle rules (``efg.order`` with Delaunay cells)."""
WEIGHT_ALIASES = {"q": "quartic", "e-a": "exp:0.5", "e-b": "exp:0.25"}
EXP_C = (1e-3, 1e3)
"""Accepted range of the parameter C of the exponential weight ``exp:C``."""
WEIGHT_FORMS = (f"quartic (alias Q), cubic, exp:C with {EXP_C[0]:g} <= C <= {EXP_C[1]:g} "
                "(E-A = exp:0.5, E-B = exp:0.25)")
_RESTRAINED = ("fixed", "prescribed", "exact")
_GEOMETRIC = ("dt0", "growth", "dt_max")
_NORMAL = {"left": "ux", "right": "ux", "bottom": "uy", "top": "uy"}
_CORNERS = (("left", "bottom"), ("left", "top"), ("right", "bottom"), ("right", "top"))
_REQUIRED = object()


# -- the case ------------------------------------------------------------------------------
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
        """Time levels ``t_0 = 0, ..., t_end`` (see the module docstring for the rule)."""
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
class EFGSettings:
    """Meshless settings: MLS weight and support scale factor for u and p_w, cells, penalty.

    Weights are named as :func:`weight_form` reads them (``quartic``, ``exp:0.5``, ...);
    ``cells`` is ``delaunay`` (rebuilt every step) or ``squares`` (quarter cells along
    the boundary); ``order`` is the Gauss order of the cells; ``penalty`` is the penalty
    factor relative to the stiffness scale (P-wave modulus over nodal spacing);
    ``correction`` is ``vci`` (variationally consistent test-function gradients, which
    pass the patch test with any quadrature; :mod:`efg.vci`) or ``none`` (plain Gauss
    quadrature of the MLS gradients, as in the paper).
    """

    weight_u: str = "quartic"
    scale_u: float = DEFAULT_SCALE
    weight_p: str = "quartic"
    scale_p: float = DEFAULT_SCALE
    cells: str = "delaunay"
    order: int = 2
    penalty: float = 1e6
    correction: str = "vci"

    def to_dict(self):
        """The settings as a plain dict."""
        return asdict(self)


@dataclass(frozen=True)
class Case:
    """A validated problem: geometry, nodes, material, fluid, boundary, loading, time, probes.

    Build it with :func:`load_case` or :func:`case_from_dict`; it is immutable, comparable
    and picklable. ``material_spec`` holds the ``[material]`` entries other than the fluid
    keys, as sorted ``(key, value)`` pairs.
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
    efg: EFGSettings = EFGSettings()
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


# -- MLS weight names ----------------------------------------------------------------------
def weight_form(name, key=None):
    """The family and parameter of an MLS weight name: the grammar of weight names.

    :mod:`efg.weights` evaluates the weights and builds them through this function, so
    that load-time validation (which must not import ``efg``) and the solver accept
    exactly the same names.

    Parameters
    ----------
    name : str
        ``quartic``, ``cubic`` or ``exp:C`` (see :data:`EXP_C`), case-insensitive,
        surrounding blanks ignored; aliases ``Q``, ``E-A`` (``exp:0.5``) and ``E-B``
        (``exp:0.25``).
    key : str, optional
        The case entry holding the name (e.g. ``efg.weight_u``), for the message.

    Returns
    -------
    family : str
        ``"quartic"``, ``"cubic"`` or ``"exp"``.
    c : float
        The parameter C of ``exp:C`` (0 for the splines).

    Raises
    ------
    InputError
        For any other name, listing the valid forms.

    Examples
    --------
    >>> weight_form(" E-B "), weight_form("Q")
    (('exp', 0.25), ('quartic', 0.0))
    >>> weight_form("exp:0", "efg.weight_p")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soil.errors.InputError: efg.weight_p = 'exp:0' is unknown: use quartic (alias Q), ...
    """
    text = str(name).strip().lower()
    text = WEIGHT_ALIASES.get(text, text)
    if text in ("quartic", "cubic"):
        return text, 0.0
    head, _, value = text.partition(":")
    try:
        c = float(value) if head == "exp" else math.nan
    except ValueError:
        c = math.nan
    label = f"weight {name!r}" if key is None else f"{key} = {name!r}"
    require(EXP_C[0] <= c <= EXP_C[1], f"{label} is unknown: use {WEIGHT_FORMS}")
    return "exp", c


# -- reading and validating ----------------------------------------------------------------
def load_case(name_or_path, overrides=()):
    """A built-in case name or a TOML file, with ``"section.key=value"`` overrides.

    Parameters
    ----------
    name_or_path : str or Path
        One of :func:`builtin_cases` or the path of a ``.toml`` file.
    overrides : iterable of str
        Entries such as ``"material.permeability=1e-6"``, applied before validation.

    Returns
    -------
    Case

    Raises
    ------
    InputError
        One line naming the bad parameter and the fix.

    Examples
    --------
    >>> load_case("terzaghi", ["time.steps=10"]).times().size
    11
    """
    data = _raw(name_or_path)
    for text in overrides:
        _apply_override(data, text)
    return case_from_dict(data)


def _raw(name_or_path):
    """The case's plain dict: a copy of a built-in spec or the parsed TOML file."""
    text = str(name_or_path)
    if text in _BUILTINS:
        return copy.deepcopy(_BUILTINS[text])
    path = Path(name_or_path)
    require(path.suffix == ".toml" or path.exists(), f"case {text!r} is neither a built-in "
            f"case ({', '.join(_BUILTINS)}) nor a TOML file")
    require(path.is_file(), f"case file {text!r} does not exist")
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"case file {text!r} is not valid TOML: {err}") from None
    data.setdefault("name", path.stem)
    return data


def _apply_override(data, text):
    """Set ``section.key[.key]=value`` in the raw dict (see the module docstring)."""
    key, sep, value = text.partition("=")
    path = [part.strip() for part in key.split(".")]
    require(sep and all(path), f"override {text!r}: write section.key=value, "
            "e.g. material.permeability=1e-6")
    try:
        value = tomllib.loads(f"v = {value}")["v"]
    except tomllib.TOMLDecodeError:
        value = value.strip()
    table = data
    for depth, part in enumerate(path[:-1]):
        table = table.setdefault(part, {})
        require(isinstance(table, dict), f"override {text!r}: "
                f"{'.'.join(path[:depth + 1])} is a value, not a section")
    last = path[-1]
    for other in _replaced_keys(path):
        table.pop(other, None)
    if len(path) == 3 and last in ("ux", "uy") and "displacement" in table:
        table.update(_expand_displacement(table.pop("displacement"), path[1]))
    table[last] = value


def _replaced_keys(path):
    """Keys that an override of ``path`` replaces (the other way of saying the same)."""
    if path[0] == "time" and path[-1] == "steps":
        return _GEOMETRIC
    if path[0] == "time" and path[-1] in _GEOMETRIC:
        return ("steps",)
    if path[0] == "boundary" and path[-1] == "displacement":
        return ("ux", "uy")
    return ()


def case_from_dict(data):
    """Validate a plain dict in TOML layout and build the :class:`Case`.

    Raises
    ------
    InputError
        On any bad or unknown entry, including material errors from
        :func:`soil.materials.material_from_spec`.
    """
    require(isinstance(data, dict), "a case must be a table of sections")
    _check_keys(data, ("name", "description", "analysis") + SECTIONS, "case", "section")
    geometry = _geometry(_section(data, "geometry"))
    material_spec, fluid = _material(_section(data, "material"))
    probes = _probes(_section(data, "probes", {}), geometry)
    loading = _loading(_section(data, "loading", {}))
    case = Case(
        name=_string(data, "name", "case", "case"),
        description=_string(data, "description", "case", ""),
        analysis=_string(data, "analysis", "case", "coupled", ANALYSES),
        geometry=geometry,
        discretisation=_discretisation(_section(data, "discretisation")),
        material_spec=material_spec, fluid=fluid,
        initial=_initial(_section(data, "initial", {})),
        boundary=_boundary(_section(data, "boundary"), loading),
        loading=loading,
        time=_time(_section(data, "time")),
        probes=probes,
        exact=_exact(_section(data, "exact", {})),
        efg=_efg(_section(data, "efg", {})),
        diagnostics=_diagnostics(_section(data, "diagnostics", {})),
    )
    _require_aspect(case)
    _require_exact_if_used(case)
    case.times()
    return case


def _section(data, name, default=_REQUIRED):
    """``data[name]`` as a table; required unless a default is given."""
    require(name in data or default is not _REQUIRED,
            f"case: section [{name}] is missing: add it (see soil/problems.py)")
    table = data.get(name, default)
    require(isinstance(table, dict), f"{name} must be a section [{name}], not a value")
    return table


def _check_keys(table, allowed, where, what="key"):
    """Reject keys of ``table`` outside ``allowed``."""
    for key in table:
        require(key in allowed, f"{where}: unknown {what} {key!r}: "
                f"allowed are {', '.join(allowed)}")


def _number(table, key, where, default=_REQUIRED):
    """A finite float entry (ints accepted, bools not)."""
    require(key in table or default is not _REQUIRED, f"{where}.{key} is missing: set it")
    value = table.get(key, default)
    require(isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value), f"{where}.{key} = {value!r} must be a finite number")
    return float(value)


def _integer(table, key, where):
    """A required integer entry."""
    require(key in table, f"{where}.{key} is missing: set it")
    value = table[key]
    require(isinstance(value, int) and not isinstance(value, bool),
            f"{where}.{key} = {value!r} must be an integer")
    return value


def _string(table, key, where, default, choices=None):
    """A string entry, optionally one of ``choices``."""
    value = table.get(key, default)
    require(isinstance(value, str), f"{where}.{key} = {value!r} must be a string")
    if choices is not None:
        require(value in choices,
                f"{where}.{key} = {value!r} is unknown: use one of {', '.join(choices)}")
    return value


def _pair(value, where):
    """Two numbers ``[a, b]`` as a tuple of floats."""
    require(isinstance(value, (list, tuple)) and len(value) == 2,
            f"{where} = {value!r} must be a pair of numbers [a, b]")
    return tuple(_number({"v": v}, "v", where) for v in value)


def _geometry(table):
    _check_keys(table, _KEYS["geometry"], "geometry")
    _string(table, "shape", "geometry", "rectangle", ("rectangle",))
    width, height = _number(table, "width", "geometry"), _number(table, "height", "geometry")
    for key, value in (("width", width), ("height", height)):
        require(LENGTHS[0] <= value <= LENGTHS[1], f"geometry.{key} = {value:g} must lie "
                f"in [{LENGTHS[0]:g}, {LENGTHS[1]:g}] m: give the size of the rectangle in m")
    return Geometry(width=width, height=height)


def _discretisation(table):
    _check_keys(table, _KEYS["discretisation"], "discretisation")
    nx, ny = _integer(table, "nx", "discretisation"), _integer(table, "ny", "discretisation")
    require(nx >= 2, f"discretisation.nx = {nx} must be at least 2 (nodes along x)")
    require(ny >= 2, f"discretisation.ny = {ny} must be at least 2 (nodes along y)")
    jitter = _number(table, "jitter", "discretisation", 0.0)
    require(0 <= jitter < 0.25, f"discretisation.jitter = {jitter} must lie in [0, 0.25) "
            "(a fraction of the nodal spacing)")
    seed = table.get("seed", 0)
    require(isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0,
            f"discretisation.seed = {seed!r} must be a non-negative integer")
    return Discretisation(nx=nx, ny=ny,
                          layout=_string(table, "layout", "discretisation", "grid", LAYOUTS),
                          jitter=jitter, seed=seed)


def _require_aspect(case):
    """Refuse sliver cells: the spacing aspect hx/hy must lie in :data:`ASPECTS`."""
    hx, hy = case.spacing
    require(ASPECTS[0] <= hx / hy <= ASPECTS[1], f"discretisation: the grid spacing aspect "
            f"hx/hy = {hx:g}/{hy:g} = {hx / hy:g} (geometry.width/(discretisation.nx - 1) "
            f"over geometry.height/(discretisation.ny - 1)) must lie in [{ASPECTS[0]:g}, "
            f"{ASPECTS[1]:g}]: change discretisation.nx or discretisation.ny")


def _diagnostics(table):
    _check_keys(table, _KEYS["diagnostics"], "diagnostics")
    value = table.get("uniqueness", False)
    require(isinstance(value, bool), f"diagnostics.uniqueness = {value!r} must be true or "
            "false")
    return Diagnostics(uniqueness=value)


def _material(table):
    """Split ``[material]`` into the skeleton spec (validated by building it) and Fluid."""
    spec = {}
    for key, value in table.items():
        if key in FLUID_KEYS:
            continue
        spec[key] = (_string(table, key, "material", None) if key in ("model", "preset")
                     else _number(table, key, "material"))
    material_from_spec(spec)
    fluid = Fluid(**{key: _number(table, key, "material", getattr(Fluid, key))
                     for key in FLUID_KEYS})
    require(fluid.permeability >= 0, f"material.permeability = {fluid.permeability} must "
            "be >= 0 (m/s; 0 means undrained)")
    require(fluid.gamma_w > 0, f"material.gamma_w = {fluid.gamma_w} must be positive")
    require(0 < fluid.biot_alpha <= 1,
            f"material.biot_alpha = {fluid.biot_alpha} must lie in (0, 1]")
    require(fluid.storage >= 0, f"material.storage = {fluid.storage} must be >= 0 "
            "(S = 1/M_biot; 0 for incompressible constituents)")
    return tuple(sorted(spec.items())), fluid


def _initial(table):
    _check_keys(table, _KEYS["initial"], "initial")
    value = table.get("pore_pressure", 0.0)
    if value == "balance":
        return Initial("balance")
    require(not isinstance(value, str), f"initial.pore_pressure = {value!r} must be a "
            "number or \"balance\"")
    return Initial(_number(table, "pore_pressure", "initial", 0.0))


def _expand_displacement(value, side):
    """The ``displacement`` shorthand as ``{"ux": ..., "uy": ...}``."""
    require(value in ("roller", "fixed", "free"), f"boundary.{side}.displacement = "
            f"{value!r} is unknown: use roller, fixed or free (or set ux and uy)")
    if value == "roller":
        return {"ux": "free", "uy": "free", _NORMAL[side]: "fixed"}
    return {"ux": value, "uy": value}


def _boundary(table, loading):
    _check_keys(table, EDGES, "boundary", "edge")
    for side in EDGES:
        require(side in table, f"boundary: edge {side!r} is missing: add [boundary.{side}] "
                "(every edge of the rectangle exactly once)")
    boundary = Boundary(**{side: _edge(_section(table, side), side, loading)
                           for side in EDGES})
    for a, b in _CORNERS:
        for comp in ("ux", "uy"):
            kinds = {getattr(getattr(boundary, a), comp), getattr(getattr(boundary, b), comp)}
            require(len(kinds - {"free"}) <= 1, f"boundary.{a}.{comp} and boundary.{b}."
                    f"{comp} conflict at their corner ({' vs '.join(sorted(kinds))}): "
                    "make them agree or set one free")
    _require_supports(boundary)
    return boundary


def _require_supports(boundary):
    """Refuse a body free to move rigidly: x and y translation and rotation must be stopped.

    ``fixed``, ``prescribed`` and ``exact`` restrain a component; a ``rigid`` plate is
    load-controlled and lets its edge settle. It would stop rotation, but never decides:
    the uy that stops y translation is on a horizontal edge (stopping rotation too) or
    on a vertical one, which may not meet the plate's edge with another kind.
    """
    ux = {side for side, edge in boundary.items() if edge.ux in _RESTRAINED}
    uy = {side for side, edge in boundary.items() if edge.uy in _RESTRAINED}
    kinds = '"fixed", "prescribed" or "exact"'
    require(ux, "boundary: the body is not supported along x (no edge restrains ux): set "
            f"an edge's ux to {kinds}, e.g. boundary.left.ux = \"fixed\"")
    require(uy, "boundary: the body is not supported along y (no edge restrains uy; a "
            f"rigid plate carries a load): set an edge's uy to {kinds}, e.g. "
            "boundary.bottom.uy = \"fixed\"")
    require(ux & {"left", "right"} or uy & {"bottom", "top"}
            or {"bottom", "top"} <= ux or {"left", "right"} <= uy,
            "boundary: the body is not supported against rotation: restrain ux on the left "
            "or right edge or uy on the top or bottom edge (e.g. boundary.left.ux = "
            "\"fixed\")")


def _edge(table, side, loading):
    where = f"boundary.{side}"
    _check_keys(table, _KEYS["edge"], where)
    table = dict(table)
    if "displacement" in table:
        require("ux" not in table and "uy" not in table,
                f"{where}: give either displacement or ux/uy, not both")
        table.update(_expand_displacement(table.pop("displacement"), side))
    edge = Edge(ux=_string(table, "ux", where, "free", KINDS),
                uy=_string(table, "uy", where, "free", KINDS),
                traction=_traction(table.get("traction", (0.0, 0.0)), f"{where}.traction"),
                water=_string(table, "water", where, "impermeable", WATER))
    require(edge.ux != "rigid" and (edge.uy != "rigid" or side in ("top", "bottom")),
            f"{where}: 'rigid' applies to uy of the top or bottom edge only")
    for comp, t in zip(("ux", "uy"), np.broadcast_to(np.asarray(edge.traction, object), 2)):
        kind = getattr(edge, comp)
        require(kind != "prescribed" or np.any(loading.L),
                f"{where}.{comp} = 'prescribed' needs a non-zero "
                "loading.velocity_gradient: set it, or use 'fixed'")
        require(edge.traction == "exact" or t == 0 or kind in ("free", "rigid"),
                f"{where}.traction acts on {comp}, "
                f"which is {kind!r}: set that traction component to 0 or {comp} free")
    return edge


def _traction(value, where):
    """``[tx, ty]`` or ``"exact"`` (from the case's exact solution)."""
    return "exact" if value == "exact" else _pair(value, where)


def _exact(table):
    """``[exact]``: ``solution`` (see soil.analytical.SOLUTIONS) and its parameters."""
    if not table:
        return ()
    require("solution" in table, "exact: name the solution, e.g. solution = "
            "\"timoshenko-beam\" (see soil/analytical.py)")
    params = {k: v for k, v in table.items() if k != "solution"}
    try:
        exact_solution(table["solution"], **params)(np.zeros((1, 2)))
    except TypeError as err:
        raise InputError(f"exact: bad parameters for {table['solution']!r}: {err}") from None
    return tuple(sorted((k, _frozen(v)) for k, v in table.items()))


def _frozen(value):
    """Lists to tuples, recursively (hashable, comparable)."""
    return tuple(_frozen(v) for v in value) if isinstance(value, list) else value


def _require_exact_if_used(case):
    uses = [f"boundary.{name}" for name, edge in case.boundary.items()
            if "exact" in (edge.ux, edge.uy, edge.traction)]
    require(not uses or case.exact, f"{uses[0] if uses else ''} uses 'exact' but the case "
            "has no [exact] section: add one naming the solution")


def _efg(table):
    _check_keys(table, _KEYS["efg"], "efg")
    defaults = EFGSettings()
    order = table.get("order", defaults.order)
    require(isinstance(order, int) and not isinstance(order, bool) and order >= 1,
            f"efg.order = {order!r} must be an integer >= 1")
    settings = EFGSettings(
        weight_u=_string(table, "weight_u", "efg", defaults.weight_u),
        scale_u=_number(table, "scale_u", "efg", defaults.scale_u),
        weight_p=_string(table, "weight_p", "efg", defaults.weight_p),
        scale_p=_number(table, "scale_p", "efg", defaults.scale_p),
        cells=_string(table, "cells", "efg", defaults.cells, CELLS),
        order=order,
        penalty=_number(table, "penalty", "efg", defaults.penalty),
        correction=_string(table, "correction", "efg", defaults.correction, CORRECTIONS))
    require(settings.cells != "delaunay" or order <= MAX_TRIANGLE_ORDER,
            f"efg.order = {order} must be at most {MAX_TRIANGLE_ORDER} with efg.cells = "
            "\"delaunay\" (the highest triangle rule): lower it or use efg.cells = "
            "\"squares\"")
    for field in ("u", "p"):
        key, scale = f"efg.scale_{field}", getattr(settings, f"scale_{field}")
        weight_form(getattr(settings, f"weight_{field}"), f"efg.weight_{field}")
        require(scale >= SCALES[0], f"{key} = {scale:g} must be >= {SCALES[0]:g} (each "
                "node's support must reach its 8th nearest node): increase the scale "
                f"factor, e.g. to {DEFAULT_SCALE:g}")
        require(scale <= SCALES[1], f"{key} = {scale:g} must be <= {SCALES[1]:g} (beyond, "
                "the MLS moment matrices approach singularity): use 1.2 to 2, e.g. "
                f"{DEFAULT_SCALE:g}")
    require(settings.penalty > 0, f"efg.penalty = {settings.penalty:g} must be positive")
    return settings


def _loading(table):
    _check_keys(table, _KEYS["loading"], "loading")
    L = table.get("velocity_gradient", ((0.0, 0.0), (0.0, 0.0)))
    require(isinstance(L, (list, tuple)) and len(L) == 2, "loading.velocity_gradient "
            "must be [[L11, L12], [L21, L22]] (1/s)")
    L = tuple(_pair(row, "loading.velocity_gradient row") for row in L)
    load = table.get("load", 1.0)
    if not isinstance(load, (list, tuple)):
        return Loading(L, _number(table, "load", "loading", 1.0))
    points = tuple(_pair(p, "loading.load point [t, factor]") for p in load)
    times = [t for t, _ in points]
    require(points and times[0] >= 0 and all(np.diff(times) > 0), "loading.load: give "
            "[t, factor] points with increasing times t >= 0, or one number (step load)")
    return Loading(L, points)


def _time(table):
    _check_keys(table, _KEYS["time"], "time")
    end = _number(table, "end", "time")
    require(end > 0, f"time.end = {end} must be positive (s)")
    if "steps" in table:
        require(not set(_GEOMETRIC) & set(table), "time: give either steps or dt0, "
                "growth, dt_max, not both")
        steps = _integer(table, "steps", "time")
        require(1 <= steps <= MAX_STEPS, f"time.steps = {steps} must lie in 1..{MAX_STEPS}")
        return TimeStepping(end=end, steps=steps)
    require(set(_GEOMETRIC) <= set(table), "time: give steps (equal steps) or all of dt0, "
            "growth, dt_max (geometric steps)")
    dt0, growth, dt_max = (_number(table, key, "time") for key in _GEOMETRIC)
    require(0 < dt0 <= dt_max, f"time.dt0 = {dt0} must be positive and at most "
            f"time.dt_max = {dt_max}")
    require(growth > 1, f"time.growth = {growth} must exceed 1 (t_(n+1) = growth t_n)")
    return TimeStepping(end=end, dt0=dt0, growth=growth, dt_max=dt_max)


def _probes(table, geometry):
    probes = []
    for name, point in table.items():
        require(re.fullmatch(r"[A-Za-z0-9_-]+", name), f"probes.{name}: use letters, "
                "digits, _ and - in probe names (they become column names)")
        x, y = _pair(point, f"probes.{name}")
        tol = 1e-9 * max(geometry.width, geometry.height)
        require(-tol <= x <= geometry.width + tol and -tol <= y <= geometry.height + tol,
                f"probes.{name} = [{x}, {y}] lies outside the domain [0, {geometry.width}]"
                f" x [0, {geometry.height}]: move it inside")
        probes.append(Probe(name, (x, y)))
    return tuple(probes)


# -- built-in cases ------------------------------------------------------------------------
def builtin_cases():
    """The built-in cases, ``{name: Case}`` in a stable order.

    Each has a TOML twin ``cases/<name>.toml`` in the repository that loads to an equal
    Case.
    """
    return {name: case_from_dict(copy.deepcopy(spec)) for name, spec in _BUILTINS.items()}


def _edges(left, right, bottom, top):
    """The four edge tables, each its own copy (an override of one edge leaves the others)."""
    return {"left": dict(left), "right": dict(right), "bottom": dict(bottom), "top": dict(top)}


_EXACT = {"ux": "exact", "uy": "exact"}
_ROLLER_X = {"ux": "fixed"}
_FIXED = {"ux": "fixed", "uy": "fixed"}
_SHEAR = {"ux": "prescribed", "uy": "prescribed"}

_BUILTINS = {
    "unconfined-compression": {
        "name": "unconfined-compression",
        "description": "Paper Fig. 3: undrained unconfined compression, plane strain, quarter "
                       "specimen 3 x 4 m, frictionless base, D22 = -0.01/s to 20 % strain; "
                       "111 nodes reconstructed as a 7 x 9 grid + 48 cell centres",
        "geometry": {"width": 3.0, "height": 4.0},
        "discretisation": {"nx": 7, "ny": 9, "layout": "grid+centres"},
        "material": {"preset": "table1", "model": "original", "ocr": 1.0,
                     "permeability": 0.0},
        "initial": {"pore_pressure": "balance"},
        "boundary": _edges({"ux": "fixed"}, {}, {"uy": "fixed"}, {"uy": "prescribed"}),
        "loading": {"velocity_gradient": [[0.0, 0.0], [0.0, -0.01]]},
        "time": {"end": 20.0, "steps": 100},
        "probes": {"centre": [1.5, 2.0], "corner": [3.0, 4.0]},
    },
    "simple-shear": {
        "name": "simple-shear",
        "description": "Undrained simple shear of a unit square, plane strain, every edge "
                       "moving with L12 = 0.01/s to shear strain 0.3",
        "geometry": {"width": 1.0, "height": 1.0},
        "discretisation": {"nx": 11, "ny": 11},
        "material": {"preset": "table1", "model": "original", "permeability": 0.0},
        "boundary": _edges(_SHEAR, _SHEAR, _SHEAR, _SHEAR),
        "loading": {"velocity_gradient": [[0.0, 0.01], [0.0, 0.0]]},
        "time": {"end": 30.0, "steps": 100},
        "probes": {"centre": [0.5, 0.5]},
    },
    "soil-column": {
        "name": "soil-column",
        "description": "Paper Fig. 8 (Zienkiewicz et al. 1986): saturated Cam-clay column "
                       "1 x 10 m, step load 1 kPa on the drained top, k = 1e-5 m/s; first "
                       "step 40 s, h^2/(c_v dt) = 30 at the initial stiffness",
        "geometry": {"width": 1.0, "height": 10.0},
        "discretisation": {"nx": 3, "ny": 21},
        "material": {"preset": "table1", "model": "original", "permeability": 1e-5},
        "boundary": _edges(_ROLLER_X, _ROLLER_X, _FIXED,
                           {"traction": [0.0, -1.0], "water": "drained"}),
        "time": {"end": 1e5, "dt0": 40.0, "growth": 1.5, "dt_max": 1e4},
        "probes": {"top": [0.5, 10.0], "mid": [0.5, 5.0], "base": [0.5, 0.0]},
    },
    "terzaghi": {
        "name": "terzaghi",
        "description": "Terzaghi consolidation, linear elastic Biot column 2 x 10 "
                       "(peer-data case A, MOOSE), step load 1e-3 on the drained top (MOOSE: "
                       "1; small so that our finite-strain solvers stay linear)",
        "geometry": {"width": 2.0, "height": 10.0},
        "discretisation": {"nx": 2, "ny": 11},
        "material": {"model": "elastic", "E": 7.2, "nu": 0.2, "biot_alpha": 0.6,
                     "storage": 0.0625, "permeability": 1.5, "gamma_w": 1.0},
        "boundary": _edges(_ROLLER_X, _ROLLER_X, _FIXED,
                           {"traction": [0.0, -1e-3], "water": "drained"}),
        "time": {"end": 10.0, "dt0": 1e-4, "growth": 1.5, "dt_max": 0.1},
        "probes": {**{f"p{k}": [1.0, float(k)] for k in range(10)}, "p99": [1.0, 10.0]},
    },
    "mandel": {
        "name": "mandel",
        "description": "Mandel's problem, linear elastic Biot quarter domain a = 1, b = 0.1 "
                       "under a rigid frictionless plate carrying force 1e-3 (small: the "
                       "solvers are finite strain), drained right side",
        "geometry": {"width": 1.0, "height": 0.1},
        "discretisation": {"nx": 41, "ny": 5},
        "material": {"model": "elastic", "E": 1.8, "nu": 0.2, "permeability": 1.5,
                     "gamma_w": 1.0},
        "boundary": _edges({"ux": "fixed"}, {"water": "drained"}, {"uy": "fixed"},
                           {"uy": "rigid", "traction": [0.0, -1e-3]}),
        "time": {"end": 1.0, "dt0": 1e-3, "growth": 1.5, "dt_max": 0.02},
        "probes": {"centre": [0.0, 0.0], "mid": [0.5, 0.0]},
    },
    "patch-test": {
        "name": "patch-test",
        "description": "Static elastic patch test: the linear field of soil.analytical "
                       "imposed on every boundary node by penalty, unit square, 6 x 6 grid",
        "analysis": "static",
        "geometry": {"width": 1.0, "height": 1.0},
        "discretisation": {"nx": 6, "ny": 6},
        "material": {"model": "elastic", "E": 1.0, "nu": 0.3},
        "boundary": _edges(_EXACT, _EXACT, _EXACT, _EXACT),
        "time": {"end": 1.0, "steps": 1},
        "exact": {"solution": "linear", "E": 1.0, "nu": 0.3},
    },
    "cantilever": {
        "name": "cantilever",
        "description": "Timoshenko cantilever 48 x 12, plane strain, E = 3e7, nu = 0.3, "
                       "end shear P = 1000: clamped (exact) left end, parabolic shear right",
        "analysis": "static",
        "geometry": {"width": 48.0, "height": 12.0},
        "discretisation": {"nx": 25, "ny": 7},
        "material": {"model": "elastic", "E": 3e7, "nu": 0.3},
        "boundary": _edges(_EXACT, {"traction": "exact"}, {}, {}),
        "time": {"end": 1.0, "steps": 1},
        "exact": {"solution": "timoshenko-beam", "E": 3e7, "nu": 0.3, "P": 1000.0,
                  "length": 48.0, "depth": 12.0},
    },
}
