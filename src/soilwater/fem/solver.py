"""Updated-Lagrangian u-p FEM (scikit-fem): the reference for the EFG solver.

The same scheme as ``soilwater/efg/solver.py``, with finite elements. A step from t_n to t_(n+1) is
solved on the mesh at x_n (bases rebuilt there) for the displacement increment ``du`` and
``p_w`` at t_(n+1). Its integrand and consistent tangent are :mod:`soilwater.physics.weakform`'s
(equilibrium with ``J sigma F^-T`` on x_n, backward-Euler continuity), at the quadrature
points, which are the material points (their state needs no remapping); the stress is the
material's return mapping with the midpoint strain increment and the Hughes-Winget spin
(:func:`soilwater.nonlinear.coupling.material_update`). The external load is the initial total stress
``sigma0 . n`` on every boundary facet (sigma0 at the facet point's initial position,
:func:`soilwater.physics.geostatic.total_stress`: uniform or geostatic) plus the edge traction x load
factor on free components (a dead load on the start-of-step facets), and under gravity
the buoyant weight of the elements (:mod:`soilwater.physics.geostatic`). The initial state is set at
the quadrature points' initial positions.

Newton's method (:func:`soilwater.nonlinear.coupling.newton`) starts from the last step's velocity x dt
(``L x`` at the first step). Convergence, cut-back and scales are those of
:mod:`soilwater.nonlinear.coupling`, shared with the EFG solver; a failing step (no convergence, an
element with ``J <= 0``, a material failure) is halved up to ``MAX_CUTS`` times before
the run stops with one error naming the step time.

Essential conditions are exact: fixed and prescribed displacement DOFs
(``(exp(L dt) - I) x_n`` at the DOF's current position) and drained pressure DOFs
(p_w = 0) are eliminated, and so are the uy DOFs of a velocity-controlled footing
(increment -rate x dt); a rigid plate (or a load-controlled footing) ties every uy DOF of
its edge (segment) to one unknown whose equation is the plate's total force; the
reaction of a named segment is the residual summed over its uy DOFs; a confined body with incompressible
constituents and no drained edge gets the mean-pressure pin of the EFG solver (one
Lagrange multiplier).

``fem-p1p1-stab`` adds the flow-equation perturbation of Aguilar, Gaspar, Lisbona and
Rodrigo (2008), "Numerical stabilization of Biot's consolidation model by a perturbation
on the flow equation", Int. J. Numer. Meth. Engng 75, 1282-1300:
``- beta int grad(p - p_n) . grad(q) dOmega_n`` with their ``beta = h^2 / (4 M)``,
``M = lambda + 2 mu`` the P-wave modulus at the initial state [kPa] and h the smallest
nodal spacing [m]. Their model has alpha = 1 and no storage; we keep their beta for any
alpha and S (on the Terzaghi column, alpha = 0.6, S = 0.0625, ``alpha^2 h^2 / (4 M)``
leaves a 10 % first-step overshoot, ``h^2 / (4 M)`` 0.3 %).

Re-meshing (``fem.remesh = "delaunay"``, triangle pairs): after a converged step whose
worst element has a :func:`soilwater.geometry.quality.cell_quality` below ``fem.remesh_quality``, the
current vertices are re-triangulated (:func:`soilwater.geometry.triangulation.delaunay_triangles` inside
the current boundary polygon). The vertices, so the vertex DOFs, their values and the
boundary DOF sets, stay; Taylor-Hood's midside DOFs are those of the new edges (a boundary
edge keeps its own, the boundary loop being kept), and its predictor there is the mean of
the edge's ends. The state at the quadrature points (effective stress, every entry of the
material state, the last stretching) is carried by :func:`soilwater.fem.transfer.transfer`
(kept elements keep theirs; new ones get the L2 projection onto the old mesh's vertex
basis, limited to the local range, interpolated at their points), then made admissible
(:meth:`soilwater.material.protocol.Material.admissible`: Cam-clay's p'c raised to put a stress outside
the yield surface on it). The carried stress is not in equilibrium on the new mesh; the
next step's Newton iteration absorbs the imbalance, whose size is recorded
(``remesh_residual``). Nothing changes when the Delaunay triangles are the mesh's own. A
boundary edge that is no Delaunay edge (at a thin concave corner, such as the footing's
edge) leaves a gap, closed by :func:`soilwater.geometry.triangulation.close_boundary` when it is one
triangle. When the triangles still do not tile the boundary polygon
(:func:`soilwater.geometry.triangulation.conforms`), or the carried state cannot be made admissible (a
p' <= 0, which no p'c mends), the old mesh is kept for that step and counted
(``remesh_refused``); the next step tries again. Probes are material points: at a
re-meshing their current position (the old mesh's interpolation of the vertex positions)
is located in the new mesh.

Linear solver: :mod:`soilwater.linalg.backends` (PARDISO when ``pypardiso`` is installed, SuperLU otherwise) on the condensed, unsymmetric
tangent, reused within a step (modified Newton) while it contracts the residual at least
tenfold per iteration. PARDISO keeps its default ordering with weighted matching here, not
the node-blocked ordering of the EFG solver, under which the unstable P1/P1 pair needs
more Newton iterations.
"""

from dataclasses import dataclass, replace
from functools import partial

import numpy as np
import scipy.sparse as sp

from soilwater.fem.assembly import Shapes, block
from soilwater.fem.spaces import Space, cell_bases, vertex_interpolant
from soilwater.fem.transfer import transfer
from soilwater.physics import weakform
from soilwater.diagnostics.bifurcation import h1_gram, restricted_eigenvalue
from soilwater.nonlinear.coupling import Scales, history_row, material_update, newton, run, timed
from soilwater.errors import ConvergenceError, InputError
from soilwater.physics.geostatic import buoyant_weight, initial_state, total_stress
from soilwater.material.kinematics import cauchy_traction, invariants, prescribed_increment
from soilwater.linalg.backends import Layout
from soilwater.geometry.quality import cell_quality
from soilwater.results import Snapshot, permeability
from soilwater.geometry.triangulation import close_boundary, conforms, delaunay_triangles


@dataclass
class Model:
    """What stays fixed over a run: case, method, material, initial space, scales, and
    the boundary loop (vertex indices, counter-clockwise) that re-meshing keeps."""

    case: object
    method: str
    material: object
    space: Space
    scales: Scales
    loop: np.ndarray

    @classmethod
    def build(cls, case, method):
        if case.analysis != "coupled":
            raise InputError(f"--method {method} solves coupled cases; case {case.name!r}"
                             f" is {case.analysis!r}: use --method efg")
        material = case.material()
        space = Space.build(case, method)
        if case.fem.remesh != "never" and space.pair.shape != "triangle":
            raise InputError(f"fem.remesh = {case.fem.remesh!r} re-triangulates the mesh, "
                             f"--method {method} has quadrilaterals: use fem-th, fem-p1p1 "
                             "or fem-p1p1-stab, or fem.remesh = \"never\"")
        return cls(case, method, material, space, Scales.of(case, material),
                   case.boundary_loop())

    @property
    def beta(self):
        """Stabilisation ``h^2 / (4 M)`` of fem-p1p1-stab [m2/kPa], else 0."""
        return self.scales.perturbation if self.space.pair.stabilised else 0.0


@dataclass
class Constraints:
    """Exact essential conditions on the unknowns ``[ux (n_u), uy (n_u), p (n_p)]``.

    Attributes
    ----------
    fixed : ndarray of int
        Unknowns with a zero increment (fixed displacement).
    prescribed : ndarray of int
        Displacement unknowns following ``v = L x``; ``component`` is 0 (x) or 1 (y).
    component : ndarray of int
    drained : ndarray of int
        Pressure unknowns held at p_w = 0.
    plate : ndarray of int
        uy unknowns tied to the rigid plate (a ``rigid`` edge or a load-controlled
        footing).
    footing : ndarray of int
        uy unknowns of velocity-controlled footings, moving by ``-rate dt`` per step;
        ``rate`` [m/s, positive down] is each one's settlement rate.
    rate : ndarray
    segment_dofs : list of ndarray of int
        uy unknowns of each named segment (``case.boundary.segments()`` order), whose
        residuals sum to the segment's vertical reaction.
    unloaded : dict
        Per edge name, (F,) bool over its facets: facets on a named segment, which
        carry no edge traction.
    T : scipy.sparse.csr_matrix
        Full increment = ``T @ reduced``: free unknowns, then the plate (if any).
    is_u : ndarray of bool
        Which reduced unknowns are displacements (the plate included).
    """

    fixed: np.ndarray
    prescribed: np.ndarray
    component: np.ndarray
    drained: np.ndarray
    plate: np.ndarray
    footing: np.ndarray
    rate: np.ndarray
    segment_dofs: list
    unloaded: dict
    T: object
    is_u: np.ndarray

    @classmethod
    def build(cls, case, space):
        """The DOF sets from the kinds at each boundary DOF's initial position (edge and
        named segments, :meth:`soilwater.case.model.Case.edge_conditions`)."""
        n_u = space.n_u
        u_locs, p_locs = space.doflocs0
        sets = {"fixed": [], "prescribed": [], "rigid": [], "footing": []}
        component, drained, rates, segment_dofs, unloaded = [], [], [], [], {}
        rate_of = np.array([seg.settlement_rate if seg.footing else 0.0
                            for _, seg in case.boundary.segments()] + [0.0])
        first = 0
        for name, edge in case.boundary.items():
            dofs = space.u_dofs[name]
            kind, _, seg = case.edge_conditions(name, u_locs[:, dofs].T)
            for f in range(2):
                for k in sets:
                    pick = dofs[kind[:, f] == k]
                    sets[k].append(f * n_u + pick)
                    if k == "prescribed":
                        component.append(np.full(len(pick), f))
                    if k == "footing":
                        rates.append(rate_of[first + seg[kind[:, f] == k]])
            segment_dofs += [n_u + dofs[seg == j] for j in range(len(edge.segments))]
            pdofs = space.p_dofs[name]
            _, wet, _ = case.edge_conditions(name, p_locs[:, pdofs].T)
            drained.append(2 * n_u + pdofs[wet])
            facets = space.edge_facets[name]
            mid = space.mesh0.p[:, space.mesh0.facets[:, facets]].mean(axis=1).T
            unloaded[name] = case.edge_conditions(name, mid)[2] >= 0
            first += len(edge.segments)
        fixed, plate, drained = (np.unique(np.concatenate(s)) if s else np.zeros(0, int)
                                 for s in (sets["fixed"], sets["rigid"], drained))
        footing, first_f = np.unique(np.concatenate(sets["footing"]).astype(int),
                                     return_index=True)
        rate = np.concatenate(rates or [[]])[first_f]
        prescribed, first = np.unique(np.concatenate(sets["prescribed"] or [[]]).astype(int),
                                      return_index=True)
        component = np.concatenate(component or [[]]).astype(int)[first]
        n = 2 * n_u + space.n_p
        free = np.setdiff1d(np.arange(n), np.concatenate([fixed, prescribed, drained, plate,
                                                          footing]))
        rows = np.concatenate([free, plate])
        cols = np.concatenate([np.arange(len(free)), np.full(len(plate), len(free))])
        T = sp.csr_matrix((np.ones(len(rows)), (rows, cols)),
                          shape=(n, len(free) + int(len(plate) > 0)))
        is_u = np.append(free < 2 * n_u, np.ones(int(len(plate) > 0), bool))
        return cls(fixed, prescribed, component, drained, plate, footing, rate,
                   segment_dofs, unloaded, T, is_u)


@dataclass
class Topology:
    """A mesh of the run's vertices and what depends on its elements.

    Attributes
    ----------
    space : Space
    constraints : Constraints
    probes : scipy.sparse matrix, shape (P, n_p), or None
        Pressure at each probe (a material point) from the pressure DOFs.
    """

    space: Space
    constraints: object
    probes: object

    @classmethod
    def initial(cls, case, space):
        """The initial mesh, probes located at their initial positions."""
        _, pb = cell_bases(space.mesh0, space.pair)
        points = np.array([p.point for p in case.probes]).reshape(-1, 2)
        return cls(space, Constraints.build(case, space),
                   pb.probes(points.T) if len(points) else None)

    def remeshed(self, case, vertices, triangles):
        """The topology of new triangles (E, 3) on the current ``vertices`` (N, 2) [m]
        (:meth:`Space.remeshed`); the probes' current positions (this mesh's
        interpolation of the vertex positions) are located in the new mesh."""
        space = self.space.remeshed(case, vertices, triangles)
        probes = None
        if self.probes is not None:
            _, pb = cell_bases(space.moved(vertices), space.pair)
            probes = pb.probes((self.probes @ vertices).T)
        return Topology(space, Constraints.build(case, space), probes)


@dataclass
class State:
    """What is carried from step to step (quadrature arrays flattened element-major)."""

    vertices: np.ndarray     # (N, 2) current mesh vertices [m]
    stress: np.ndarray       # (E Q, 4) effective stress, tension positive
    state: dict              # material state at the quadrature points
    p: np.ndarray            # (n_p,) pore pressure DOFs, compression positive
    weights: np.ndarray      # (E Q,) current quadrature weights [m2]
    stretching: np.ndarray   # (E Q, 4) stretching of the last step [1/s]
    velocity: np.ndarray     # (2 n_u,) du/dt of the last step [m/s]: the predictor
    topology: Topology       # the mesh the next step is solved on
    uniqueness: float = 0.0  # soilwater.diagnostics.bifurcation indicator of the last step (if asked for)
    reactions: np.ndarray = None  # (S,) vertical force on the soil per named segment
    remeshes: int = 0        # re-meshings so far
    refused: int = 0         # re-meshings refused so far (not conforming, inadmissible)
    remesh_residual: float = 0.0  # scaled equilibrium residual after the last re-meshing


def solve(case, method="fem-th", progress=True):
    """Run a coupled case with an FEM element pair and return its Result.

    Parameters
    ----------
    case : Case
        ``analysis = "coupled"``; Cam-clay or linear elastic skeleton.
    method : str
        One of :data:`soilwater.fem.spaces.PAIRS`.
    progress : bool
        Show a progress bar on the terminal.

    Raises
    ------
    ConvergenceError
        A step that still fails after ``MAX_CUTS`` halvings (the message names the time).
    InputError
        A static case, a quadrilateral method on a ``grid+centres`` case or with
        ``fem.remesh``.
    """
    model = Model.build(case, method)
    space = model.space
    pair = space.pair
    options = {"elements": f"{pair.u_element.__name__}/{pair.p_element.__name__}",
               "intorder": pair.intorder, "stabilised": pair.stabilised}
    result = run(case, method, options, _initial_state(model), partial(_step, model),
                 partial(_history_row, model), partial(_snapshot, model),
                 {"dofs": int(2 * space.n_u + space.n_p),
                  "elements": int(space.mesh0.t.shape[1]),
                  "stabilisation_beta": model.beta}, progress)
    if case.fem.remesh != "never":
        last = result.history.iloc[-1]
        result.summary.update(remeshes=int(last["remeshes"]),
                              remesh_refused=int(last["remesh_refused"]))
    return result


def _initial_state(model):
    case, space = model.case, model.space
    ub, _ = cell_bases(space.mesh0, space.pair)
    n_points = ub.dx.size
    stress, state = initial_state(case, model.material,
                                  np.asarray(ub.global_coordinates()).reshape(2, -1).T)
    return State(vertices=case.nodes(), stress=stress, state=state,
                 p=np.full(space.n_p, float(case.initial_pore_pressure)),
                 weights=ub.dx.ravel(), stretching=np.zeros((n_points, 4)),
                 velocity=(case.loading.L @ ub.doflocs).ravel(),
                 topology=Topology.initial(case, space),
                 reactions=np.zeros(len(case.boundary.segments())))


@dataclass
class _Discretisation:
    """Bases of the current mesh: shape data, quadrature weights, external forces."""

    u: Shapes
    p: Shapes
    dx: np.ndarray           # (E, Q) [m2]
    doflocs: np.ndarray      # (2, n_u) current DOF positions [m]
    external: np.ndarray     # (2 n_u,) boundary forces at t_(n+1) [force per thickness]


def _discretise(model, topology, vertices, t1, timings):
    """Bases on the mesh of ``topology`` at ``vertices`` and the boundary forces at
    ``t1``; phase times added to ``timings``."""
    space = topology.space
    with timed(timings, "cells_s"):
        mesh = space.moved(vertices)
    with timed(timings, "shape_functions_s"):
        ub, pb = cell_bases(mesh, space.pair)
        external = np.zeros(2 * space.n_u)
        factor = model.case.loading.factor(t1)
        for name, edge in model.case.boundary.items():
            if len(space.edge_facets[name]) == 0:
                continue
            fb = space.facet_basis(mesh, name)
            x0 = np.asarray(space.facet_basis(space.mesh0, name).global_coordinates())
            sigma0 = total_stress(model.case, model.material, x0.reshape(2, -1).T)
            load = cauchy_traction(sigma0.reshape(x0.shape[1:] + (4,)),
                                   np.moveaxis(fb.normals, 0, -1))
            loaded = np.array([edge.ux, edge.uy]) == "free"
            bare = ~topology.constraints.unloaded[name][:, None, None]
            load = load + bare * loaded * np.asarray(edge.traction, float) * factor
            external += Shapes.of(fb).vector(np.concatenate(
                [(fb.dx[..., None] * load)[..., None], np.zeros(load.shape + (2,))], -1))
    return _Discretisation(Shapes.of(ub), Shapes.of(pb), ub.dx, ub.doflocs, external)


def _step(model, current, t0, t1, stats):
    """One step on the mesh at ``current.vertices``, then the re-meshing if it is due:
    new state, iterations, residual."""
    disc = _discretise(model, current.topology, current.vertices, t1, stats["timings"])
    system = _System(model, current, disc, t0, t1, stats["timings"])
    iterations, residual = newton(system, stats)
    return _remesh(model, system.finish(), t1, stats["timings"]), iterations, residual


def _remesh(model, current, t, timings):
    """``current`` on the Delaunay triangles of its vertices when ``fem.remesh`` asks for
    it and its worst element's quality is below ``fem.remesh_quality`` (module
    docstring); unchanged when those triangles are the mesh's own, and only counted
    (``refused``) when they do not tile the boundary polygon or the carried state
    cannot be made admissible.

    The state is carried (:func:`soilwater.fem.transfer.transfer`) and made admissible;
    the vertices, pore pressures and vertex velocities stay. ``remesh_residual`` is the
    scaled equilibrium residual of the new state at ``t`` (:func:`_imbalance`).
    """
    settings, space, vertices = model.case.fem, current.topology.space, current.vertices
    if settings.remesh == "never":
        return current
    with timed(timings, "cells_s"):
        if cell_quality(vertices[space.corners])[1].min() >= settings.remesh_quality:
            return current
        triangles, _ = delaunay_triangles(vertices, vertices[model.loop])
        triangles = close_boundary(triangles, model.loop, vertices)
        if _same_triangles(triangles, space.corners):
            return current
        if not conforms(triangles, model.loop, len(vertices)):
            return replace(current, refused=current.refused + 1)
    with timed(timings, "shape_functions_s"):
        _, old = cell_bases(space.moved(vertices), space.pair)
        topology = current.topology.remeshed(model.case, vertices, triangles)
        ub, pb = cell_bases(topology.space.moved(vertices), space.pair)
    with timed(timings, "material_s"):
        names = list(current.state)
        carried = transfer(old, pb, np.column_stack(
            [current.stress, current.stretching, *(current.state[k] for k in names)]))
        stress = carried[:, :4]
        try:
            state = model.material.admissible(stress, dict(zip(names, carried[:, 8:].T)))
        except ConvergenceError:
            return replace(current, refused=current.refused + 1)
    velocity = current.velocity.reshape(2, -1)[:, :len(vertices)].T
    new = replace(current, stress=stress, state=state, weights=ub.dx.ravel(),
                  stretching=carried[:, 4:8], topology=topology,
                  velocity=vertex_interpolant(ub, topology.space.mesh0.facets,
                                              velocity).T.ravel(),
                  remeshes=current.remeshes + 1)
    new.remesh_residual = _imbalance(model, new, t, timings)
    return new


def _same_triangles(triangles, corners):
    """Whether two (E, 3) arrays of vertex indices hold the same triangles."""
    return len(triangles) == len(corners) and np.array_equal(
        np.unique(np.sort(triangles, axis=1), axis=0), np.unique(np.sort(corners, axis=1),
                                                                 axis=0))


def _imbalance(model, current, t, timings):
    """The scaled residual (:func:`_norm`, in units of the Newton tolerance's scales) of
    the state ``current`` on its own mesh at time t with no increment: the equilibrium
    imbalance of its stress (the continuity rows vanish with no increment and dt = 0)."""
    topology = current.topology
    disc = _discretise(model, topology, current.vertices, t, timings)
    con, n = topology.constraints, len(current.stress)
    x = np.concatenate([np.zeros(2 * disc.u.n), current.p])
    R, _ = _residual(model, disc, current, x, current.stress, np.ones(n),
                     np.broadcast_to(np.eye(2), (n, 2, 2)), 0.0)
    reduced = con.T.T @ R
    if len(con.plate):
        reduced[-1] -= model.case.plate_force(t)
    return _norm(reduced, con, model.scales.force, model.scales.volume, 0.0)


class _System:
    """One step's Newton system (:func:`soilwater.nonlinear.coupling.newton`) on the reduced unknowns.

    The full unknowns ``x = [du_x, du_y, p]`` start from the predictor (the last step's
    velocity x dt, essential values imposed); Newton corrects the free ones and the plate
    through ``Constraints.T``, plus the mean-pressure multiplier when pinned.
    """

    def __init__(self, model, current, disc, t0, t1, timings):
        case, con, n_u = model.case, current.topology.constraints, disc.u.n
        self.model, self.current, self.disc, self.timings = model, current, disc, timings
        self.con = con
        self.dt, self.t1, self.n_u = t1 - t0, t1, n_u
        x = np.concatenate([current.velocity * self.dt, current.p])
        x[con.prescribed] = prescribed_increment(
            case.loading.L, disc.doflocs.T[con.prescribed % n_u], self.dt)[
            np.arange(len(con.prescribed)), con.component]
        x[con.footing] = -con.rate * self.dt
        x[con.drained] = 0.0
        self.x, self.lam = x, 0.0
        self.c_mean = np.zeros(len(x))
        self.c_mean[2 * n_u:] = disc.p.vector(disc.dx[..., None, None] * [1.0, 0, 0])
        self.layout = _layout(con.T, n_u, disc.doflocs.T, self.c_mean, model.scales,
                              model.space.pair)

    def residual(self):
        """The reduced residual (plus the pin) and its scaled size."""
        model, disc, con, n_u = self.model, self.disc, self.con, self.n_u
        E, Q = disc.dx.shape
        grads = disc.u.values(self.x[:2 * n_u].reshape(2, n_u))[..., 1:]
        (self.stress, self.state, self.material_tangent, self.J, self.Finv,
         self.deps) = material_update(model.material, self.current.stress,
                                      self.current.state, grads.reshape(E * Q, 2, 2),
                                      self.timings, "an element")
        R, self.total = _residual(model, disc, self.current, self.x, self.stress, self.J,
                                  self.Finv, self.dt)
        R += self.lam * self.c_mean
        self.R = R
        reduced = con.T.T @ R
        if len(con.plate):
            reduced[-1] -= model.case.plate_force(self.t1)
        sc = model.scales
        pin = self.c_mean @ (self.x - np.concatenate([np.zeros(2 * n_u), self.current.p]))
        residual = _norm(reduced, con, sc.force, sc.volume, sc.pin_pressure * pin)
        return (np.append(reduced, pin) if sc.pin_pressure else reduced), residual

    def domain_tangent(self):
        """The tangent of the reduced unknowns (essential conditions eliminated)."""
        T = self.con.T
        return T.T @ _tangent(self.model, self.disc, self.current, self.x, self.stress,
                              self.total, self.material_tangent, self.J, self.Finv,
                              self.dt) @ T

    def tangent(self):
        """:meth:`domain_tangent` bordered by the mean-pressure pin, if any."""
        return _bordered(self.domain_tangent(), self.con.T.T @ self.c_mean,
                         self.model.scales.pin_pressure)

    def advance(self, dx):
        """Add a Newton correction of the reduced unknowns (and the multiplier)."""
        T = self.con.T
        self.x += T @ dx[:T.shape[1]]
        if self.model.scales.pin_pressure:
            self.lam += dx[-1]

    def finish(self):
        """The state after convergence (the quadrature points are the material points)."""
        current, n_u, x = self.current, self.n_u, self.x
        du = x[:2 * n_u].reshape(2, n_u)[:, :len(current.vertices)].T
        uniqueness = 0.0
        if self.model.case.diagnostics.uniqueness:
            uniqueness = _uniqueness(self.model, self.con, self.disc,
                                     self.domain_tangent())
        reactions = np.array([self.R[dofs].sum() for dofs in self.con.segment_dofs])
        return replace(current, vertices=current.vertices + du, stress=self.stress,
                       state=self.state, p=x[2 * n_u:],
                       weights=self.disc.dx.ravel() * self.J,
                       stretching=self.deps / self.dt, velocity=x[:2 * n_u] / self.dt,
                       uniqueness=uniqueness, reactions=reactions)


def _layout(T, n_u, u_locations, mass, scales, pair):
    """The :class:`soilwater.linalg.backends.Layout` of the reduced unknowns (``T``'s columns, the
    mean-pressure multiplier last when pinned): a column of one full DOF has its field,
    the plate's column (many) none; the AMG smoother and whether the Krylov back-end
    suits it are the element ``pair``'s."""
    n = T.shape[0]
    fields = np.concatenate([np.zeros(n_u, int), np.ones(n_u, int),
                             np.full(n - 2 * n_u, 2)])
    columns = sp.csc_matrix(T)
    single = np.diff(columns.indptr) == 1
    first = columns.indices[np.minimum(columns.indptr[:-1], len(columns.indices) - 1)]
    reduced = np.where(single, fields[first], -1)
    locations = np.concatenate([u_locations, u_locations, np.zeros((n - 2 * n_u, 2))])
    scale = np.where(reduced == 2, scales.volume, scales.force)
    pin = int(scales.pin_pressure)
    return Layout(fields=np.append(reduced, np.full(pin, -1)),
                  locations=np.concatenate([locations[first], np.zeros((pin, 2))]),
                  scales=np.append(scale, [scales.volume] * pin),
                  mass=sp.diags(np.append(np.where(reduced == 2, T.T @ mass, 0.0), [0.0] * pin)),
                  modulus=scales.modulus, smoother=pair.smoother, iterative=pair.iterative,
                  single=pair.single)


def _residual(model, disc, current, x, stress, J, Finv, dt):
    """Full residual ``[R_u, R_p]`` and the total stress at the quadrature points
    (:func:`soilwater.physics.weakform.residual`, scattered with the element bases)."""
    fluid, n_u = model.case.fluid, disc.u.n
    E, Q = disc.dx.shape
    p_vals = disc.p.values(x[2 * n_u:]).reshape(E * Q, 3)
    pn_vals = disc.p.values(current.p).reshape(E * Q, 3)
    total = weakform.total_stress(stress, p_vals[:, 0], fluid)
    v_n = current.state["v"]
    r = weakform.residual(total, J, Finv, disc.dx.ravel(), p_vals[:, 0], pn_vals[:, 0],
                          p_vals[:, 1:], fluid, dt, model.beta, pn_vals[:, 1:], v_n,
                          buoyant_weight(model.case, v_n))
    R_u = disc.u.vector(r[:, :2].reshape(E, Q, 2, 3)) - disc.external
    R_p = disc.p.vector(r[:, 2:].reshape(E, Q, 1, 3))
    return np.concatenate([R_u, R_p]), total


def _tangent(model, disc, current, x, stress, total, tangent, J, Finv, dt):
    """The full Jacobian of :func:`_residual` with respect to ``[du, p]`` at the unknowns
    x (:func:`soilwater.physics.weakform.tangent`, assembled block by block)."""
    E, Q = disc.dx.shape
    grad_p = disc.p.values(x[2 * disc.u.n:]).reshape(E * Q, 3)[:, 1:]
    c = weakform.tangent(tangent, stress, total, J, Finv, disc.dx.ravel(), model.case.fluid,
                         dt, model.beta, current.state["v"], grad_p)
    fields = ((disc.u, range(0, 2)), (disc.p, range(2, 3)))         # (basis, fields)
    return sp.bmat([[block(test, trial, c.block(f, g)) for trial, g in fields]
                    for test, f in fields], format="csr")


def _uniqueness(model, con, disc, K):
    """:func:`soilwater.diagnostics.bifurcation.restricted_eigenvalue` of a step's converged tangent
    (essential conditions eliminated, the plate included) over the initial P-wave modulus:
    the displacement block on the undrained constraint (the free pressure rows), against
    the H1 Gram matrix of the displacement basis (length scale: the body's height)."""
    gram = h1_gram(disc.dx.ravel(), model.case.geometry.height)
    u = con.T[:, con.is_u][:2 * disc.u.n]
    G = u.T @ block(disc.u, disc.u, gram) @ u
    K = sp.csr_matrix(K)
    value = restricted_eigenvalue(K[con.is_u][:, con.is_u], K[~con.is_u][:, con.is_u], G)
    return value / model.scales.modulus


def _bordered(K, c, pin):
    """The condensed tangent, bordered by the mean-pressure pin if any."""
    if not pin:
        return K
    c = sp.csr_matrix(c[:, None])
    return sp.bmat([[K, c], [c.T, None]], format="csr")


def _norm(reduced, con, force, volume, pin):
    """Scaled residual: displacement and plate rows / force, pressure rows / volume, pin."""
    return max(np.abs(reduced[con.is_u]).max(initial=0) / force,
               np.abs(reduced[~con.is_u]).max(initial=0) / volume, abs(pin) / volume)


def _history_row(model, current, t, dt, info):
    """:func:`soilwater.nonlinear.coupling.history_row` of the quadrature points (weighted by volume);
    ``min_angle`` and ``min_quality`` of the elements on the moved mesh (their corner
    vertices: the straight-sided cell of a Taylor-Hood or Q2 element), the mesh the next
    step is solved on; with ``fem.remesh``, ``remeshes`` and ``remesh_refused`` (counts
    so far) and ``remesh_residual`` (:func:`_imbalance` after the last re-meshing, 0
    before the first; read it where ``remeshes`` grows)."""
    case, topology = model.case, current.topology
    top = model.space.mesh0.p[1] > case.geometry.height * (1 - 1e-9)
    probes = ()
    if topology.probes is not None:
        probes = zip([pr.name for pr in case.probes], topology.probes @ current.p)
    nodes0 = model.space.mesh0.p.T
    segments = [(seg, current.vertices[k], nodes0[k], force,
                 float(current.vertices[k[0], 1] - nodes0[k[0], 1])  # the plate's uy
                 if seg.load_controlled else None)
                for (_, seg), k, force in zip(case.boundary.segments(), case.segment_nodes(),
                                              current.reactions)]
    row = history_row(case, t, dt, info, current.stress, current.stretching,
                      current.vertices[top], nodes0[top],
                      current.weights / current.weights.sum(), probes,
                      current.uniqueness if case.diagnostics.uniqueness else None,
                      segments, cells=current.vertices[topology.space.corners])
    if case.fem.remesh != "never":
        row.update(remeshes=current.remeshes, remesh_refused=current.refused,
                   remesh_residual=current.remesh_residual)
    return row


def _snapshot(model, current, t):
    """Vertex fields with the current cells: u, p_w, and p', q and state averaged to the
    vertices (each vertex: the volume-weighted mean of its elements' means)."""
    mesh0 = current.topology.space.mesh0
    cells = mesh0.t
    E = cells.shape[1]
    p, q = invariants(current.stress)
    quantities = {"p_eff": p, "q": q, **current.state}
    data = {"u": current.vertices - mesh0.p.T, "p_w": current.p[:len(current.vertices)]}
    volume = current.weights.reshape(E, -1)
    share = np.repeat(volume.sum(1), cells.shape[0])
    node_volume = np.bincount(cells.T.ravel(), share, minlength=mesh0.p.shape[1])
    for name, values in quantities.items():
        mean = (volume * values.reshape(E, -1)).sum(1)
        data[name] = np.bincount(cells.T.ravel(), np.repeat(mean, cells.shape[0]),
                                 minlength=mesh0.p.shape[1]) / node_volume
    data.update(permeability(model.case, data["v"]))
    return Snapshot(t, current.vertices.copy(), data,
                    cells=[(current.topology.space.cell_type, cells.T.copy())])
