"""Updated-Lagrangian u-p FEM (scikit-fem): the reference for the EFG solver.

The same scheme as ``efg/solver.py``, with finite elements. A step from t_n to t_(n+1) is
solved on the mesh at x_n (bases rebuilt there) for the displacement increment ``du`` and
``p_w`` at t_(n+1). Its integrand and consistent tangent are :mod:`soil.weakform`'s
(equilibrium with ``J sigma F^-T`` on x_n, backward-Euler continuity), at the quadrature
points, which are the material points (their state needs no remapping); the stress is the
material's return mapping with the midpoint strain increment and the Hughes-Winget spin
(:func:`soil.coupling.material_update`). The external load is the initial total stress
``sigma0 . n`` on every boundary facet plus the edge traction x load factor on free
components (a dead load on the start-of-step facets).

Newton's method (:func:`soil.coupling.newton`) starts from the last step's velocity x dt
(``L x`` at the first step). Convergence, cut-back and scales are those of
:mod:`soil.coupling`, shared with the EFG solver; a failing step (no convergence, an
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

Linear solver: :mod:`soil.linear` (PARDISO when ``pypardiso`` is installed, SuperLU otherwise) on the condensed, unsymmetric
tangent, reused within a step (modified Newton) while it contracts the residual at least
tenfold per iteration. PARDISO keeps its default ordering with weighted matching here, not
the node-blocked ordering of the EFG solver, under which the unstable P1/P1 pair needs
more Newton iterations.
"""

from dataclasses import dataclass
from functools import partial

import numpy as np
import scipy.sparse as sp

from fem_reference.assembly import Shapes, block
from fem_reference.spaces import Space, cell_bases
from soil import weakform
from soil.bifurcation import h1_gram, restricted_eigenvalue
from soil.coupling import Scales, history_row, material_update, newton, run, timed
from soil.errors import InputError
from soil.kinematics import cauchy_traction, invariants, prescribed_increment
from soil.results import Snapshot


@dataclass
class Model:
    """What stays fixed over a run: case, method, material, space, constraints, scales."""

    case: object
    method: str
    material: object
    space: Space
    scales: Scales
    constraints: object
    probes: object           # (P, n_p) pressure basis at the probes (reference coords)

    @classmethod
    def build(cls, case, method):
        if case.analysis != "coupled":
            raise InputError(f"--method {method} solves coupled cases; case {case.name!r}"
                             f" is {case.analysis!r}: use --method efg")
        material = case.material()
        space = Space.build(case, method)
        _, pb = cell_bases(space.mesh0, space.pair)
        points = np.array([p.point for p in case.probes]).reshape(-1, 2)
        return cls(case, method, material, space, Scales.of(case, material),
                   Constraints.build(case, space),
                   pb.probes(points.T) if len(points) else None)

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
        named segments, :meth:`soil.case.Case.edge_conditions`)."""
        n_u = space.n_u
        ub, pb = cell_bases(space.mesh0, space.pair)
        sets = {"fixed": [], "prescribed": [], "rigid": [], "footing": []}
        component, drained, rates, segment_dofs, unloaded = [], [], [], [], {}
        rate_of = np.array([seg.settlement_rate if seg.footing else 0.0
                            for _, seg in case.boundary.segments()] + [0.0])
        first = 0
        for name, edge in case.boundary.items():
            dofs = space.u_dofs[name]
            kind, _, seg = case.edge_conditions(name, ub.doflocs[:, dofs].T)
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
            _, wet, _ = case.edge_conditions(name, pb.doflocs[:, pdofs].T)
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
class State:
    """What is carried from step to step (quadrature arrays flattened element-major)."""

    vertices: np.ndarray     # (N, 2) current mesh vertices [m]
    stress: np.ndarray       # (E Q, 4) effective stress, tension positive
    state: dict              # material state at the quadrature points
    p: np.ndarray            # (n_p,) pore pressure DOFs, compression positive
    weights: np.ndarray      # (E Q,) current quadrature weights [m2]
    stretching: np.ndarray   # (E Q, 4) stretching of the last step [1/s]
    velocity: np.ndarray     # (2 n_u,) du/dt of the last step [m/s]: the predictor
    uniqueness: float = 0.0  # soil.bifurcation indicator of the last step (if asked for)
    reactions: np.ndarray = None  # (S,) vertical force on the soil per named segment


def solve(case, method="fem-th", progress=True):
    """Run a coupled case with an FEM element pair and return its Result.

    Parameters
    ----------
    case : Case
        ``analysis = "coupled"``; Cam-clay or linear elastic skeleton.
    method : str
        One of :data:`fem_reference.spaces.PAIRS`.
    progress : bool
        Show a progress bar on the terminal.

    Raises
    ------
    ConvergenceError
        A step that still fails after ``MAX_CUTS`` halvings (the message names the time).
    InputError
        A static case, or a quadrilateral method on a ``grid+centres`` case.
    """
    model = Model.build(case, method)
    space = model.space
    pair = space.pair
    options = {"elements": f"{pair.u_element.__name__}/{pair.p_element.__name__}",
               "intorder": pair.intorder, "stabilised": pair.stabilised}
    return run(case, method, options, _initial_state(model), partial(_step, model),
               partial(_history_row, model), partial(_snapshot, model),
               {"dofs": int(2 * space.n_u + space.n_p),
                "elements": int(space.mesh0.t.shape[1]), "stabilisation_beta": model.beta},
               progress)


def _initial_state(model):
    case, space = model.case, model.space
    ub, _ = cell_bases(space.mesh0, space.pair)
    n_points = ub.dx.size
    stress, state = model.material.initial_state(n_points)
    return State(vertices=case.nodes(), stress=stress, state=state,
                 p=np.full(space.n_p, float(case.initial_pore_pressure)),
                 weights=ub.dx.ravel(), stretching=np.zeros((n_points, 4)),
                 velocity=(case.loading.L @ ub.doflocs).ravel(),
                 reactions=np.zeros(len(case.boundary.segments())))


@dataclass
class _Discretisation:
    """Bases of the current mesh: shape data, quadrature weights, external forces."""

    u: Shapes
    p: Shapes
    dx: np.ndarray           # (E, Q) [m2]
    doflocs: np.ndarray      # (2, n_u) current DOF positions [m]
    external: np.ndarray     # (2 n_u,) boundary forces at t_(n+1) [force per thickness]


def _discretise(model, vertices, t1, timings):
    """Bases on the mesh at ``vertices`` and the boundary forces at ``t1``; phase times
    added to ``timings``."""
    space = model.space
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
            load = cauchy_traction(model.scales.sigma0, np.moveaxis(fb.normals, 0, -1))
            loaded = np.array([edge.ux, edge.uy]) == "free"
            bare = ~model.constraints.unloaded[name][:, None, None]
            load = load + bare * loaded * np.asarray(edge.traction, float) * factor
            external += Shapes.of(fb).vector(np.concatenate(
                [(fb.dx[..., None] * load)[..., None], np.zeros(load.shape + (2,))], -1))
    return _Discretisation(Shapes.of(ub), Shapes.of(pb), ub.dx, ub.doflocs, external)


def _step(model, current, t0, t1, stats):
    """One step on the mesh at ``current.vertices``: new state, iterations, residual."""
    disc = _discretise(model, current.vertices, t1, stats["timings"])
    system = _System(model, current, disc, t0, t1, stats["timings"])
    iterations, residual = newton(system, stats)
    return system.finish(), iterations, residual


class _System:
    """One step's Newton system (:func:`soil.coupling.newton`) on the reduced unknowns.

    The full unknowns ``x = [du_x, du_y, p]`` start from the predictor (the last step's
    velocity x dt, essential values imposed); Newton corrects the free ones and the plate
    through ``Constraints.T``, plus the mean-pressure multiplier when pinned.
    """

    def __init__(self, model, current, disc, t0, t1, timings):
        case, con, n_u = model.case, model.constraints, model.space.n_u
        self.model, self.current, self.disc, self.timings = model, current, disc, timings
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
        self.groups = None

    def residual(self):
        """The reduced residual (plus the pin) and its scaled size."""
        model, disc, con, n_u = self.model, self.disc, self.model.constraints, self.n_u
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
        T = self.model.constraints.T
        return T.T @ _tangent(self.model, self.disc, self.stress, self.total,
                              self.material_tangent, self.J, self.Finv, self.dt) @ T

    def tangent(self):
        """:meth:`domain_tangent` bordered by the mean-pressure pin, if any."""
        return _bordered(self.domain_tangent(), self.model.constraints.T.T @ self.c_mean,
                         self.model.scales.pin_pressure)

    def advance(self, dx):
        """Add a Newton correction of the reduced unknowns (and the multiplier)."""
        T = self.model.constraints.T
        self.x += T @ dx[:T.shape[1]]
        if self.model.scales.pin_pressure:
            self.lam += dx[-1]

    def finish(self):
        """The state after convergence (the quadrature points are the material points)."""
        current, n_u, x = self.current, self.n_u, self.x
        du = x[:2 * n_u].reshape(2, n_u)[:, :len(current.vertices)].T
        uniqueness = 0.0
        if self.model.case.diagnostics.uniqueness:
            uniqueness = _uniqueness(self.model, self.disc, self.domain_tangent())
        reactions = np.array([self.R[dofs].sum()
                              for dofs in self.model.constraints.segment_dofs])
        return State(current.vertices + du, self.stress, self.state, x[2 * n_u:],
                     self.disc.dx.ravel() * self.J, self.deps / self.dt,
                     x[:2 * n_u] / self.dt, uniqueness, reactions)


def _residual(model, disc, current, x, stress, J, Finv, dt):
    """Full residual ``[R_u, R_p]`` and the total stress at the quadrature points
    (:func:`soil.weakform.residual`, scattered with the element bases)."""
    fluid, n_u = model.case.fluid, model.space.n_u
    E, Q = disc.dx.shape
    p_vals = disc.p.values(x[2 * n_u:]).reshape(E * Q, 3)
    pn_vals = disc.p.values(current.p).reshape(E * Q, 3)
    total = weakform.total_stress(stress, p_vals[:, 0], fluid)
    r = weakform.residual(total, J, Finv, disc.dx.ravel(), p_vals[:, 0], pn_vals[:, 0],
                          p_vals[:, 1:], fluid, dt, model.beta, pn_vals[:, 1:])
    R_u = disc.u.vector(r[:, :2].reshape(E, Q, 2, 3)) - disc.external
    R_p = disc.p.vector(r[:, 2:].reshape(E, Q, 1, 3))
    return np.concatenate([R_u, R_p]), total


def _tangent(model, disc, stress, total, tangent, J, Finv, dt):
    """The full Jacobian of :func:`_residual` with respect to ``[du, p]``
    (:func:`soil.weakform.tangent`, assembled block by block)."""
    E, Q = disc.dx.shape
    c = weakform.tangent(tangent, stress, total, J, Finv, disc.dx.ravel(), model.case.fluid,
                         dt, model.beta).reshape(E, Q, 3, 3, 3, 3)
    u, p = slice(0, 2), slice(2, 3)
    return sp.bmat([[block(disc.u, disc.u, c[:, :, u, :, u]),
                     block(disc.u, disc.p, c[:, :, u, :, p])],
                    [block(disc.p, disc.u, c[:, :, p, :, u]),
                     block(disc.p, disc.p, c[:, :, p, :, p])]], format="csr")


def _uniqueness(model, disc, K):
    """:func:`soil.bifurcation.restricted_eigenvalue` of a step's converged tangent
    (essential conditions eliminated, the plate included) over the initial P-wave modulus:
    the displacement block on the undrained constraint (the free pressure rows), against
    the H1 Gram matrix of the displacement basis (length scale: the body's height)."""
    E, Q = disc.dx.shape
    gram = h1_gram(disc.dx.ravel(), model.case.geometry.height).reshape(E, Q, 2, 3, 2, 3)
    con = model.constraints
    u = con.T[:, con.is_u][:2 * model.space.n_u]
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
    """:func:`soil.coupling.history_row` of the quadrature points (weighted by volume);
    ``min_angle`` and ``min_quality`` of the elements on the moved mesh (their corner
    vertices: the straight-sided cell of a Taylor-Hood or Q2 element)."""
    case = model.case
    top = model.space.mesh0.p[1] > case.geometry.height * (1 - 1e-9)
    probes = ()
    if model.probes is not None:
        probes = zip([pr.name for pr in case.probes], model.probes @ current.p)
    nodes0 = model.space.mesh0.p.T
    segments = [(seg, current.vertices[k], nodes0[k], force,
                 float(current.vertices[k[0], 1] - nodes0[k[0], 1])  # the plate's uy
                 if seg.load_controlled else None)
                for (_, seg), k, force in zip(case.boundary.segments(), case.segment_nodes(),
                                              current.reactions)]
    return history_row(case, t, dt, info, current.stress, current.stretching,
                       current.vertices[top], nodes0[top],
                       current.weights / current.weights.sum(), probes,
                       current.uniqueness if case.diagnostics.uniqueness else None,
                       segments, cells=current.vertices[model.space.corners])


def _snapshot(model, current, t):
    """Vertex fields with cells: u, p_w, and p', q and state averaged to the vertices."""
    mesh0 = model.space.mesh0
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
    return Snapshot(t, current.vertices.copy(), data,
                    cells=[(model.space.cell_type, cells.T.copy())])
