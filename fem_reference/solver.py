"""Updated-Lagrangian u-p FEM (scikit-fem): the reference for the EFG solver.

The same scheme as ``efg/solver.py`` (design.md section 4), with finite elements; the
integrand and its tangent are :mod:`soil.weakform`'s, shared with the EFG solver. A step
from t_n to t_(n+1) is solved on the mesh at x_n (bases rebuilt there) for the
displacement increment ``du`` and ``p_w`` at t_(n+1):

* equilibrium, ``int grad_n(v) . J sigma F^-T dOmega_n = int v . t dGamma_n`` with
  ``F = I + grad_n(du)``, ``sigma = sigma' - alpha p_w I`` (tension positive stress, p_w
  compression positive); ``t`` is the initial total stress ``sigma0 . n`` on every
  boundary facet plus the edge traction x load factor on free components (a dead load
  on the start-of-step facets);
* continuity, backward Euler: ``-int q [alpha (J - 1) + S (p - p_n)] dOmega_n
  - dt (k/gamma_w) int grad(q) . grad(p) dOmega_n = 0``;
* the stress from the material's return mapping with the midpoint strain increment and
  the Hughes-Winget spin (:func:`soil.kinematics.strain_increment`), at the quadrature
  points, which are the material points (their state needs no remapping).

Newton's method starts from the last step's velocity x dt (``L x`` at the first step) and
uses the exact tangent of :func:`soil.weakform.tangent` (material tangent, Jaumann
rotation, change of area and orientation), pulled back to x_n gradients. Convergence,
cut-back and scales are those of :mod:`soil.coupling`, shared with the EFG solver: the
displacement residual below ``TOLERANCE`` times stress scale x spacing, the continuity
residual below ``TOLERANCE`` times area x stress scale / P-wave modulus; a failing step
(no convergence, an element with ``J <= 0``, a material failure) is halved up to
``MAX_CUTS`` times before the run stops with one error naming the step time.

Essential conditions are exact: fixed and prescribed displacement DOFs
(``(exp(L dt) - I) x_n`` at the DOF's current position) and drained pressure DOFs
(p_w = 0) are eliminated; a rigid plate ties every uy DOF of its edge to one unknown
whose equation is the plate's total force; a confined body with incompressible
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

Linear solver: :mod:`soil.linear` (PARDISO when ``pypardiso`` is installed, with its
default weighted matching, SuperLU otherwise) on the condensed, unsymmetric tangent, reused
within a step (modified Newton) while it contracts the residual at least tenfold per
iteration. PARDISO's node-blocked ordering without matching, which the EFG solver uses,
was measured on the 10^4-node compression: faster for Taylor-Hood (analysis 0.47 s against
0.82 s), but 7 Newton iterations instead of 5 for the unstable P1/P1 pair, so the
reference keeps the default.
"""

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fem_reference.assembly import Shapes, block
from fem_reference.spaces import Space, cell_bases
from soil import weakform
from soil.bifurcation import restricted_eigenvalue
from soil.coupling import (MAX_ITERATIONS, TOLERANCE, Scales, axial_strain, march,
                           stretching_error)
from soil.errors import ConvergenceError, InputError
from soil.kinematics import in_plane, invariants, prescribed_increment, strain_increment
from soil.linear import factorise, identity, must_refactorise
from soil.results import Result, Snapshot


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
        sc = self.scales
        return sc.h**2 / (4 * sc.modulus) if self.space.pair.stabilised else 0.0


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
        uy unknowns tied to the rigid plate.
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
    T: object
    is_u: np.ndarray

    @classmethod
    def build(cls, case, space):
        n_u = space.n_u
        sets = {"fixed": [], "prescribed": [], "rigid": []}
        component, drained = [], []
        for name, edge in case.boundary.items():
            dofs = space.u_dofs[name]
            for f, kind in enumerate((edge.ux, edge.uy)):
                if kind in sets:
                    sets[kind].append(f * n_u + dofs)
                    if kind == "prescribed":
                        component.append(np.full(len(dofs), f))
            if edge.drained:
                drained.append(2 * n_u + space.p_dofs[name])
        fixed, plate, drained = (np.unique(np.concatenate(s)) if s else np.zeros(0, int)
                                 for s in (sets["fixed"], sets["rigid"], drained))
        prescribed, first = np.unique(np.concatenate(sets["prescribed"] or [[]]).astype(int),
                                      return_index=True)
        component = np.concatenate(component or [[]]).astype(int)[first]
        n = 2 * n_u + space.n_p
        free = np.setdiff1d(np.arange(n), np.concatenate([fixed, prescribed, drained, plate]))
        rows = np.concatenate([free, plate])
        cols = np.concatenate([np.arange(len(free)), np.full(len(plate), len(free))])
        T = sp.csr_matrix((np.ones(len(rows)), (rows, cols)),
                          shape=(n, len(free) + int(len(plate) > 0)))
        is_u = np.append(free < 2 * n_u, np.ones(int(len(plate) > 0), bool))
        return cls(fixed, prescribed, component, drained, plate, T, is_u)


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
    stats = {"factorisations": 0,
             "timings": {"basis_s": 0.0, "assembly_s": 0.0, "solve_s": 0.0,
                         "material_s": 0.0}}
    tic = time.perf_counter()
    history, snapshots = march(
        case, _initial_state(model),
        step=lambda current, t0, t1: _step(model, current, t0, t1, stats),
        row=lambda current, t, dt, info: _history_row(model, current, t, dt, info),
        snapshot=lambda current, t: _snapshot(model, current, t),
        stats=stats, progress=progress, desc=f"{method} {case.name}")
    stats["timings"]["total_s"] = time.perf_counter() - tic
    space = model.space
    summary = {"steps": len(history), "dofs": int(2 * space.n_u + space.n_p),
               "elements": int(space.mesh0.t.shape[1]), "tolerance": TOLERANCE,
               "linear_solver": identity(), "stabilisation_beta": model.beta,
               **stats}
    options = {"elements": f"{space.pair.u_element.__name__}/"
                           f"{space.pair.p_element.__name__}",
               "intorder": space.pair.intorder, "stabilised": space.pair.stabilised}
    return Result(case, method, options, history, snapshots, summary)


def _initial_state(model):
    case, space = model.case, model.space
    ub, _ = cell_bases(space.mesh0, space.pair)
    n_points = ub.dx.size
    stress, state = model.material.initial_state(n_points)
    return State(vertices=case.nodes(), stress=stress, state=state,
                 p=np.full(space.n_p, float(case.initial_pore_pressure)),
                 weights=ub.dx.ravel(), stretching=np.zeros((n_points, 4)),
                 velocity=(case.loading.L @ ub.doflocs).ravel())


@dataclass
class _Discretisation:
    """Bases of the current mesh: shape data, quadrature weights, external forces."""

    u: Shapes
    p: Shapes
    dx: np.ndarray           # (E, Q) [m2]
    doflocs: np.ndarray      # (2, n_u) current DOF positions [m]
    external: np.ndarray     # (2 n_u,) boundary forces at t_(n+1) [force per thickness]


def _discretise(model, vertices, t1):
    space = model.space
    mesh = space.moved(vertices)
    ub, pb = cell_bases(mesh, space.pair)
    external = np.zeros(2 * space.n_u)
    factor = model.case.loading.factor(t1)
    sigma0 = in_plane(model.scales.sigma0[None])[0]
    for name, edge in model.case.boundary.items():
        if len(space.edge_facets[name]) == 0:
            continue
        fb = space.facet_basis(mesh, name)
        load = np.einsum("ij,jfq->fqi", sigma0, fb.normals)
        loaded = np.array([edge.ux, edge.uy]) == "free"
        load = load + loaded * np.asarray(edge.traction, float) * factor
        external += Shapes.of(fb).vector(np.concatenate(
            [(fb.dx[..., None] * load)[..., None], np.zeros(load.shape + (2,))], -1))
    return _Discretisation(Shapes.of(ub), Shapes.of(pb), ub.dx, ub.doflocs, external)


def _step(model, current, t0, t1, stats):
    """Newton iterations for one step; returns the new state, iterations, residual."""
    case, space, con = model.case, model.space, model.constraints
    dt = t1 - t0
    tic = time.perf_counter()
    disc = _discretise(model, current.vertices, t1)
    stats["timings"]["basis_s"] += time.perf_counter() - tic
    n_u, E, Q = space.n_u, *disc.dx.shape
    x = np.concatenate([current.velocity * dt, current.p])
    x[con.prescribed] = prescribed_increment(
        case.loading.L, disc.doflocs.T[con.prescribed % n_u], dt)[
        np.arange(len(con.prescribed)), con.component]
    x[con.drained] = 0.0
    c_mean = np.zeros(len(x))
    c_mean[2 * n_u:] = disc.p.vector(disc.dx[..., None, None] * [1.0, 0, 0])
    lam, lu, previous = 0.0, None, np.inf
    sc = model.scales
    dw_u = disc.dx.ravel()
    for iteration in range(1, MAX_ITERATIONS + 1):
        grads = disc.u.values(x[:2 * n_u].reshape(2, n_u))[..., 1:].reshape(E * Q, 2, 2)
        J = np.linalg.det(np.eye(2) + grads)
        if not np.all(J > 0):
            raise ConvergenceError(f"an element inverts (J = {J.min():.3g})")
        Finv = np.linalg.inv(np.eye(2) + grads)
        deps, dw = strain_increment(grads, J)
        tic = time.perf_counter()
        stress, state, tangent = model.material.update(current.stress, current.state,
                                                       deps, dw)
        stats["timings"]["material_s"] += time.perf_counter() - tic
        R, total = _residual(model, disc, current, x, stress, J, Finv, dt)
        R += lam * c_mean
        reduced = con.T.T @ R
        if len(con.plate):
            reduced[-1] -= case.plate_force(t1)
        pin = c_mean @ (x - np.concatenate([np.zeros(2 * n_u), current.p]))
        residual = _norm(reduced, con, sc.force, sc.volume, sc.pin_pressure * pin)
        if not np.isfinite(residual):
            raise FloatingPointError("the residual is not finite")
        if residual < TOLERANCE:
            break
        if iteration == MAX_ITERATIONS:
            raise ConvergenceError(f"Newton residual {residual:.2e} after {iteration} "
                                   "iterations")
        tic = time.perf_counter()
        if must_refactorise(lu, residual, previous):
            K = _tangent(model, disc, stress, total, tangent, J, Finv, dt)
            K = _bordered(con.T.T @ K @ con.T, con.T.T @ c_mean, sc.pin_pressure)
            toc = time.perf_counter()
            stats["timings"]["assembly_s"] += toc - tic
            tic = toc
            lu = factorise(K)
            stats["factorisations"] += 1
        previous = residual
        rhs = np.append(reduced, pin) if sc.pin_pressure else reduced
        dz = -lu.solve(rhs)
        stats["timings"]["solve_s"] += time.perf_counter() - tic
        x += con.T @ dz[:con.T.shape[1]]
        if sc.pin_pressure:
            lam += dz[-1]

    n_v = len(current.vertices)
    du = x[:2 * n_u].reshape(2, n_u)[:, :n_v].T
    uniqueness = 0.0
    if case.diagnostics.uniqueness:
        K = con.T.T @ _tangent(model, disc, stress, total, tangent, J, Finv, dt) @ con.T
        uniqueness = _uniqueness(model, disc, K)
    return State(current.vertices + du, stress, state, x[2 * n_u:], dw_u * J,
                 deps / dt, x[:2 * n_u] / dt, uniqueness), iteration, residual


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
    gram = np.zeros((E, Q, 2, 3, 2, 3))
    for f in range(2):
        gram[:, :, f, 0, f, 0] = disc.dx / model.case.geometry.height**2
        gram[:, :, f, 1, f, 1] = gram[:, :, f, 2, f, 2] = disc.dx
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
    """One row of the history: the EFG columns, domain averages weighted by volume."""
    case = model.case
    p, q = invariants(current.stress)
    w = current.weights / current.weights.sum()
    top = model.space.mesh0.p[1] > case.geometry.height * (1 - 1e-9)
    probes = {}
    if model.probes is not None:
        probes = {f"p_w@{pr.name}": v for pr, v in zip(case.probes, model.probes @ current.p)}
    x0 = model.space.mesh0.p[0, top]
    return {"time": t, "eps_a": axial_strain(case, current.vertices[top, 1]), "p": w @ p,
            "q": w @ q, "err": stretching_error(case, current.stretching[:, 1], w),
            "gamma": np.mean(current.vertices[top, 0] - x0) / case.geometry.height,
            "dt": dt, "iterations": info["iterations"], "substeps": info["substeps"],
            "residual": info["residual"], **probes,
            **({"uniqueness": current.uniqueness} if case.diagnostics.uniqueness else {})}


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
