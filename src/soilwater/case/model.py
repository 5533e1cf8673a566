"""The case model: the immutable, validated description of a problem that the solvers read.

A :class:`Case` is built by :func:`soilwater.case.loader.load_case` (a built-in name or a
TOML file) or :func:`soilwater.case.validation.case_from_dict`; its TOML layout, defaults
and load-time bounds are documented in :mod:`soilwater.case.schema`. Units are those of the
case (kPa, m, s in the built-in cases).

The parts live where their concept does: the domain (:class:`~soilwater.case.domain.Geometry`,
a rectangle or a user's mesh) in :mod:`soilwater.case.domain`, the boundary conditions
(:class:`~soilwater.case.boundary.Boundary`, :class:`~soilwater.case.boundary.Edge`,
:class:`~soilwater.case.boundary.Segment`) in :mod:`soilwater.case.boundary`, the node
layout (:class:`~soilwater.case.grid.Discretisation`) in :mod:`soilwater.case.grid`, the
pore fluid (:class:`~soilwater.material.fluid.Fluid`) in :mod:`soilwater.material.fluid`.

Conventions: x to the right, y up, origin at the lower-left corner of the rectangle;
stress and traction are tension positive (a traction ``[0, -1]`` on the top edge is a
compressive load); pore water pressure p_w is compression positive;
``sigma = sigma' - alpha p_w I``. Gravity, if any, acts along -y; p_w is then the pore
pressure in excess of hydrostatic (:mod:`soilwater.physics.geostatic`).
"""

from dataclasses import asdict, dataclass, field

import numpy as np

from soilwater.case.boundary import SEGMENT_TOLERANCE, Boundary, along
from soilwater.case.domain import Geometry
from soilwater.case.grid import Discretisation, grid_line
from soilwater.case.timeline import Loading, TimeStepping
from soilwater.efg.settings import EFGSettings
from soilwater.fem.settings import FEMSettings
from soilwater.material.fluid import Fluid
from soilwater.material.presets import material_from_spec
from soilwater.material.regions import Regions
from soilwater.references.closed_forms import exact_solution

#: Analyses: the coupled u-p march, or static elasticity (EFG only).
ANALYSES = ("coupled", "static")
#: Initial stress states (:class:`Initial`).
STRESS_STARTS = ("uniform", "geostatic", "gravity")
#: Default number of equal increments of the gravity start's self-weight.
GRAVITY_INCREMENTS = 10


@dataclass(frozen=True)
class Diagnostics:
    """Optional per-step measurements: ``uniqueness``
    (:mod:`soilwater.diagnostics.bifurcation`)."""

    uniqueness: bool = False


@dataclass(frozen=True)
class Gravity:
    """Gravitational acceleration g [m/s2] along -y (0: weightless)."""

    g: float = 0.0


@dataclass(frozen=True)
class Initial:
    """The initial state (:mod:`soilwater.physics.geostatic`).

    ``pore_pressure``: a number [kPa] or ``"balance"`` (total stress zero). ``stress``:
    ``"uniform"`` (the material's p'0, e0, ocr everywhere), ``"geostatic"``: the
    vertical effective stress of the buoyant weight under the ``surcharge`` [kPa] on top,
    horizontal ``k0`` times it (a number, or ``"nc"``: the material's normally
    consolidated value), the void ratio on the material's compression line (anchored by
    ``material.e_ref`` and ``sigma_v_ref``, or through its e0 at p'0), and a vertical
    overconsolidation ratio ``ocr``; or ``"gravity"``: the uniform state loaded by its
    self-weight, drained, in ``increments`` equal steps before t = 0
    (:mod:`soilwater.nonlinear.gravity_start`).
    """

    pore_pressure: float | str = 0.0
    stress: str = "uniform"
    surcharge: float = 0.0
    k0: float | str = "nc"
    ocr: float = 1.0
    increments: int = GRAVITY_INCREMENTS

    def to_dict(self):
        """The ``[initial]`` table: the keys of its start only."""
        if self.stress == "uniform":
            return {"pore_pressure": self.pore_pressure}
        if self.stress == "gravity":
            return {"stress": self.stress, "increments": self.increments}
        return {k: v for k, v in asdict(self).items() if k != "increments"}


@dataclass(frozen=True)
class Probe:
    """A named point ``(x, y)`` [m] of the initial configuration where histories are kept."""

    name: str
    point: tuple[float, float]


@dataclass(frozen=True)
class Case:
    """A validated problem: geometry, nodes, material, fluid, boundary, loading, time, probes.

    Build it with :func:`soilwater.case.loader.load_case` or
    :func:`soilwater.case.validation.case_from_dict`; it is immutable, comparable and
    picklable. Change it with :meth:`replace`, which validates the changed case again
    (:func:`dataclasses.replace` does not). ``material_spec`` holds the skeleton's
    parameters, resolved (a preset and ``Cc``, ``Cr`` written out as
    :func:`soilwater.material.presets.parameters` gives them), as sorted ``(key, value)``
    pairs; ``regions``, on a mesh with ``[material.NAME]`` tables, each physical
    surface's ``(name, spec)``, its spec resolved the same way and with its
    ``permeability`` (:mod:`soilwater.case.regions`); ``efg`` holds the
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
    regions: tuple[tuple[str, tuple], ...] = ()
    exact: tuple[tuple[str, object], ...] = ()
    efg: EFGSettings = field(default_factory=EFGSettings)
    diagnostics: Diagnostics = Diagnostics()
    fem: FEMSettings = FEMSettings()
    gravity: Gravity = Gravity()

    def replace(self, *overrides):
        """A copy with ``"section.key=value"`` overrides, validated again.

        The case goes back to its plain dict (:meth:`to_dict`), takes the overrides
        (:func:`soilwater.case.schema.apply_override`) and goes through
        :func:`soilwater.case.validation.case_from_dict`, so a bad value is refused as it
        would be in a TOML file. :func:`dataclasses.replace` skips this validation (and
        the checks across sections): use this method instead.

        Parameters
        ----------
        *overrides : str
            Entries such as ``"material.permeability=1e-6"``.

        Returns
        -------
        Case

        Raises
        ------
        InputError
            One line naming the bad key and the fix.

        Examples
        --------
        >>> from soilwater.case.loader import load_case
        >>> load_case("terzaghi").replace("time.steps=4").times().size
        5
        >>> load_case("terzaghi").replace("material.permeability=-1")  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        soilwater.errors.InputError: material.permeability = -1.0 must be >= 0 ...
        """
        from soilwater.case.schema import apply_override
        from soilwater.case.validation import case_from_dict

        data = self.to_dict()
        for text in overrides:
            apply_override(data, text)
        return case_from_dict(data)

    def exact_solution(self):
        """``points -> (u, stress)`` of the ``[exact]`` solution, or None
        (:func:`soilwater.references.closed_forms.exact_solution`)."""
        if not self.exact:
            return None
        params = dict(self.exact)
        return exact_solution(params.pop("solution"), **params)

    def material(self):
        """The soil skeleton (``CamClay`` or ``LinearElastic``) built from the spec; with
        regions (``[material.NAME]`` on a mesh), their
        :class:`~soilwater.material.regions.Regions`."""
        if not self.regions:
            return material_from_spec(dict(self.material_spec))
        specs = [dict(spec) for _, spec in self.regions]
        return Regions(tuple(name for name, _ in self.regions),
                       tuple(material_from_spec(spec) for spec in specs),
                       tuple(spec["permeability"] for spec in specs))

    @property
    def spacing(self):
        """Smallest grid spacing ``(hx, hy)`` [m]: ``width / (nx - 1)`` and
        ``height / (ny - 1)`` on a regular grid; on a mesh, its shortest edge twice."""
        d, g = self.discretisation, self.geometry
        if g.mesh is not None:
            return (g.mesh.spacing,) * 2
        return tuple(float(np.diff(line).min()) if pieces else length / (n - 1)
                     for length, n, pieces, line in zip((g.width, g.height), (d.nx, d.ny),
                                                        (d.x, d.y), self.grid_lines()))

    def grid_lines(self):
        """Coordinates of the grid lines ``(x (nx,), y (ny,))`` [m] (regular, or laid out
        by the pieces of :class:`~soilwater.case.grid.Discretisation`)."""
        d, g = self.discretisation, self.geometry
        return grid_line(g.width, d.nx, d.x), grid_line(g.height, d.ny, d.y)

    def nodes(self):
        """Initial node coordinates, shape (N, 2) [m].

        Grid nodes row by row from the bottom (x fastest), then, for ``grid+centres``,
        the cell centres in the same order: ``N = nx ny (+ (nx-1)(ny-1))``; a mesh's
        vertices.
        """
        if self.geometry.mesh is not None:
            return self.geometry.mesh.points.copy()
        d = self.discretisation
        x, y = self.grid_lines()
        grid = np.stack(np.meshgrid(x, y), axis=-1).reshape(-1, 2)
        if d.layout == "grid+centres":
            xc, yc = (x[:-1] + x[1:]) / 2, (y[:-1] + y[1:]) / 2
            centres = np.stack(np.meshgrid(xc, yc), axis=-1).reshape(-1, 2)
            grid = np.concatenate([grid, centres])
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
        boundary); a mesh's boundary loop. ``nodes[case.boundary_loop()]`` is the boundary
        polygon.
        """
        if self.geometry.mesh is not None:
            return self.geometry.mesh.loop.copy()
        nx, ny = self.discretisation.nx, self.discretisation.ny
        i, j = np.arange(nx), np.arange(ny)
        return np.concatenate([i, j[1:] * nx + nx - 1, (ny - 1) * nx + i[-2::-1],
                               j[-2:0:-1] * nx])

    def plate_force(self, t, load=None):
        """Total force on the rigid plate at time t, per unit thickness (y, tension +).

        ``traction[1] x load factor x initial edge length`` of the edge whose uy is rigid,
        or ``-force x load factor`` of a load-controlled footing
        (:class:`~soilwater.case.boundary.Segment`; at most one plate per case); zero
        without a plate. ``load``: the load factor, if not the case's at t (a step load
        spread over a cut-back level, :func:`soilwater.nonlinear.march.march`).
        """
        load = self.loading.factor(t) if load is None else load
        for _, edge in self.boundary.items():
            if edge.uy == "rigid":
                return float(edge.traction[1] * load * self.geometry.width)
        for _, seg in self.boundary.segments():
            if seg.load_controlled:
                return float(-seg.force * load)
        return 0.0

    def edge_conditions(self, side, points):
        """:meth:`~soilwater.case.boundary.Edge.at` of edge ``side`` at initial positions
        ``points`` (P, 2) [m] on it, segment ends widened by
        :data:`~soilwater.case.boundary.SEGMENT_TOLERANCE` times the smallest spacing (a
        mesh's boundary group has at most its whole segment, which every point is on)."""
        return getattr(self.boundary, side).at(along(side, points),
                                               SEGMENT_TOLERANCE * min(self.spacing))

    def segment_nodes(self):
        """Indices into :meth:`nodes` of each named segment's nodes (the boundary nodes of
        its edge within ``[from, to]``; a mesh group's vertices for a
        :attr:`~soilwater.case.boundary.Segment.whole` one), in
        :meth:`~soilwater.case.boundary.Boundary.segments` order."""
        nodes = self.nodes()
        loop = self.boundary_loop()
        g, tol = self.geometry, SEGMENT_TOLERANCE * min(self.spacing)
        line = {"left": (0, 0.0), "right": (0, g.width), "bottom": (1, 0.0),
                "top": (1, g.height)}
        out = []
        for side, seg in self.boundary.segments():
            if seg.whole:
                out.append(g.mesh.group_nodes(side))
                continue
            axis, value = line[side]
            p = nodes[loop]
            on = (np.abs(p[:, axis] - value) <= tol) & seg.contains(along(side, p), tol)
            out.append(np.sort(loop[on]))
        return out

    def edge_length(self, side):
        """Initial length of edge (or mesh boundary group) ``side`` [m]."""
        g = self.geometry
        if g.mesh is not None:
            return g.mesh.group_length(side)
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

    def _fluid_dict(self):
        """The fluid's ``[material]`` keys that act in this case: the permeability law's
        own parameters only with that law, ``specific_gravity`` only under gravity."""
        fluid = {k: v for k, v in asdict(self.fluid).items() if v is not None}
        if self.gravity.g == 0:
            fluid.pop("specific_gravity")
        return fluid

    def to_dict(self):
        """The case as a plain nested dict in TOML layout (defaults filled in, every
        material parameter resolved: a preset's values written out)."""
        time = {k: v for k, v in asdict(self.time).items() if v is not None}
        return _plain({
            "name": self.name, "description": self.description, "analysis": self.analysis,
            "geometry": self.geometry.to_dict(),
            "discretisation": self.discretisation.to_dict(),
            "material": {**dict(self.material_spec), **self._fluid_dict(),
                         **{name: dict(spec) for name, spec in self.regions}},
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

