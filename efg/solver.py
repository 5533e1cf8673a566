"""Updated-Lagrangian u-p EFG solver: Biot consolidation with finite-strain Cam-clay.

Every node carries a displacement and a pore pressure parameter; displacement and pore
pressure each have their own MLS weight and scale factor (``[efg]`` of the case). A step
from t_n to t_(n+1) is solved on the configuration x_n (shape functions and background
cells rebuilt there) for the displacement increment ``du`` and ``p_w`` at t_(n+1):

* equilibrium on the current configuration, ``int grad(dv) : sigma dOmega_(n+1) = ext``,
  ``sigma = sigma' - alpha p_w I`` (tension positive stress, p_w compression positive);
  with ``F = I + grad_n(du)`` it reads ``int grad_n(dv) . J sigma F^-T dOmega_n``;
* continuity, backward Euler (compression positive p_w, Darcy flux
  ``-(k/gamma_w) grad p_w``):
  ``int dp [alpha (J - 1) + S (p - p_n)] dOmega_n + dt int grad(dp) . (k/gamma_w)
  grad(p) dOmega_n = 0`` (drained edges by penalty);
* the stress increment from the material's return mapping with the midpoint stretching
  ``sym(grad_n(du) F_(1/2)^-1)`` (its volumetric part set to ``ln J`` so that the specific
  volume follows the volume exactly) and the Hughes-Winget spin.

Newton's method linearises ``J sigma F^-T``: the material's consistent tangent, the
rotation of the effective stress by the spin and the change of area and orientation
(the integrand and its tangent are :mod:`soil.weakform`'s, shared with the FEM
reference); the only approximation is that the spin's
rotation acts on sigma' at t_(n+1) rather than on the rotated start-of-step stress, a
difference of the order of the strain increment. The linear solver and the reuse of its
factorisation within a step are those of :mod:`soil.linear`. A step converges when the
displacement residual is below ``TOLERANCE`` times the force scale (stress scale x nodal
spacing) and the continuity residual below ``TOLERANCE`` times the volume scale (area x
stress scale / P-wave modulus), each residual entry counted beyond its round-off level:
the penalty forces on boundary rows are known only to ``eps x sum |terms|``
(:func:`_roundoff`), which exceeds the tolerance on fine grids.
A step that does not converge, inverts a background cell or fails in the material is cut
back (halved) up to ``soil.coupling.MAX_CUTS`` times before the run stops with one clear
error.

Material state lives on the nodes (the material points): at the start of a step the
integration points take stress and state from the nodes by MLS interpolation, and after a
converged step the nodes update their own state with the nodal stretching ``D^I`` (the one
that enters ERR, paper eq. 1) and move by ``u^h(x_I)``.

Essential conditions are penalties on total quantities: each boundary Gauss point keeps
the gap ``u^h - u_bar`` of its constrained components, so reactions carried in earlier
steps are not lost. A rigid plate (Mandel) adds one unknown, its settlement; its total
force equals the edge load. When no boundary is drained or free and the constituents are
incompressible, the pore pressure is defined up to a constant: the mean change of p_w over
the domain is then pinned to zero by one Lagrange multiplier.
"""

import time
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from efg import vci
from efg.assembly import Pattern, scatter
from efg.boundary import (BOUNDARY_ORDER, boundary_points, conditions,
                          penalty_coefficients, segment_edges)
from efg.mls import ShapeFunctions
from efg.statics import background, cauchy_traction
from soil import weakform
from soil.bifurcation import restricted_eigenvalue
from soil.coupling import (MAX_ITERATIONS, TOLERANCE, Scales, axial_strain, march,
                           stretching_error)
from soil.errors import ConvergenceError
from soil.kinematics import invariants, prescribed_increment, strain_increment
from soil.linear import factorise, identity, must_refactorise
from soil.case import EDGES
from soil.results import Result, Snapshot


@dataclass
class Points:
    """The material points (nodes) and everything that is carried from step to step."""

    nodes: np.ndarray        # (N, 2) current coordinates [m]
    stress: np.ndarray       # (N, 4) effective stress, tension positive
    state: dict              # material state at the nodes
    p: np.ndarray            # (N,) pore pressure parameters, compression positive
    gap: np.ndarray          # (G, 2) u^h - u_bar at boundary points (constrained parts)
    plate: float             # rigid-plate settlement (uy, m)
    plate_gap: np.ndarray    # (G,) u_y^h - plate at the plate's points
    probes: np.ndarray       # (P, 2) current probe positions
    stretching: np.ndarray   # (N, 4) nodal stretching D^I of the last step [1/s]
    uniqueness: float = 0.0  # soil.bifurcation indicator of the last step (if asked for)


@dataclass
class Model:
    """What stays fixed over a run: case, material, boundary topology, scales."""

    case: object
    material: object
    loop: np.ndarray
    edges: np.ndarray
    scales: Scales

    @classmethod
    def build(cls, case):
        material = case.material()
        loop = case.boundary_loop()
        return cls(case, material, loop, segment_edges(case.nodes(), loop, case.geometry),
                   Scales.of(case, material))


def solve(case, progress=True):
    """Run a coupled case with EFG and return its :class:`~soil.results.Result`.

    Parameters
    ----------
    case : Case
        ``analysis = "coupled"``; Cam-clay or linear elastic skeleton.
    progress : bool
        Show a progress bar on the terminal.

    Raises
    ------
    ConvergenceError
        A step that still fails after ``MAX_CUTS`` halvings (the message names the time).
    InputError
        Bad supports (too small a scale factor) and other invalid settings.
    """
    model = Model.build(case)
    stats = {"factorisations": 0,
             "timings": {"cells_s": 0.0, "shape_functions_s": 0.0, "assembly_s": 0.0,
                         "solve_s": 0.0, "material_s": 0.0}}
    tic = time.perf_counter()
    history, snapshots = march(
        case, _initial_points(model),
        step=lambda points, t0, t1: _step(model, points, t0, t1, stats),
        row=lambda points, t, dt, info: _history_row(model, points, t, dt, info),
        snapshot=lambda points, t: _snapshot(model, points, t),
        stats=stats, progress=progress, desc=f"efg {case.name}")
    stats["timings"]["total_s"] = time.perf_counter() - tic
    summary = {"steps": len(history), "dofs": 3 * len(case.nodes()), "tolerance": TOLERANCE,
               "linear_solver": identity(), **stats, **_penalties(model, case.times())}
    return Result(case, "efg", case.efg.to_dict(), history, snapshots, summary)


def _initial_points(model):
    case = model.case
    nodes = case.nodes()
    stress, state = model.material.initial_state(len(nodes))
    n_bp = len(model.loop) * BOUNDARY_ORDER
    return Points(nodes=nodes, stress=stress, state=state,
                  p=np.full(len(nodes), case.initial_pore_pressure),
                  gap=np.zeros((n_bp, 2)), plate=0.0, plate_gap=np.zeros(n_bp),
                  probes=np.array([p.point for p in case.probes]).reshape(-1, 2),
                  stretching=np.zeros((len(nodes), 4)))


def _step(model, points, t0, t1, stats):
    """Newton iterations for one step; returns the new points, iterations, residual."""
    case, dt = model.case, t1 - t0
    disc = _discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                       stats["timings"])
    n = len(points.nodes)
    su = disc.su
    stress_q = su.phi @ points.stress
    state_q = {k: su.phi @ v for k, v in points.state.items()}
    p_n_q = disc.sp.phi @ points.p
    bc = disc.bc
    du_bar = prescribed_increment(case.loading.L, disc.bp.points, dt)
    alpha_u, alpha_p = _penalties(model, [0.0, dt]).values()
    fluid = case.fluid
    traction = (cauchy_traction(np.broadcast_to(model.scales.sigma0,
                                                (len(disc.bp.weights), 4)),
                                disc.bp.normal)
                + bc.traction * bc.loaded * case.loading.factor(t1))
    plate_force = case.plate_force(t1)

    du, p, plate = np.zeros(2 * n), points.p.copy(), points.plate
    lam, lu, previous = 0.0, None, np.inf
    for iteration in range(1, MAX_ITERATIONS + 1):
        H = _gradient(su, du, n)
        F = np.eye(2) + H
        J = np.linalg.det(F)
        if not np.all(J > 0):
            raise ConvergenceError(f"a background cell inverts (J = {J.min():.3g})")
        Finv = np.linalg.inv(F)
        deps, dw = strain_increment(H, J)
        tic = time.perf_counter()
        stress, state, tangent = model.material.update(stress_q, state_q, deps, dw)
        stats["timings"]["material_s"] += time.perf_counter() - tic
        p_q = disc.sp.phi @ p
        total = weakform.total_stress(stress, p_q, fluid)
        grad_p = np.stack([disc.sp.dphi_dx @ p, disc.sp.dphi_dy @ p], 1)
        r = weakform.residual(total, J, Finv, disc.w, p_q, p_n_q, grad_p, fluid, dt)

        # residuals
        tu, tp = disc.tu, disc.tp
        R_u = np.concatenate([_tested(tu, r[:, f]) for f in range(2)])
        ub = disc.sub.phi @ du.reshape(2, n).T                              # (G, 2)
        gap = points.gap + ub - du_bar
        R_u += np.concatenate([disc.sub.phi.T @ (alpha_u * disc.bp.weights
                                                  * bc.constrained[:, f] * gap[:, f])
                               for f in range(2)])
        plate_gap = points.plate_gap + ub[:, 1] - (plate - points.plate)
        rigid_w = alpha_u * disc.bp.weights * bc.rigid
        R_u[n:] += disc.sub.phi.T @ (rigid_w * plate_gap)
        R_u -= np.concatenate([disc.sub.phi.T @ (disc.bp.weights * traction[:, f])
                               for f in range(2)])
        R_p = _tested(tp, r[:, 2])
        pb = disc.spb.phi @ p
        R_p -= disc.spb.phi.T @ (alpha_p * disc.bp.weights * bc.drained * pb)
        c_mean = tp.phi.T @ disc.w
        extra_R = []
        if bc.rigid.any():
            extra_R.append(-np.sum(rigid_w * plate_gap) - plate_force)
        if model.scales.pin_pressure:
            R_p += c_mean * lam
            extra_R.append(c_mean @ (p - points.p))
        R = np.concatenate([R_u, R_p, extra_R])
        sc = model.scales
        noise_u, noise_p, noise_plate = _roundoff(
            disc, points, du.reshape(2, n).T, du_bar, p, plate, alpha_u, alpha_p, rigid_w)
        residual = max(_excess(R_u, noise_u) / sc.force, _excess(R_p, noise_p) / sc.volume,
                       _excess(extra_R[:1], noise_plate) / sc.force * bc.rigid.any(),
                       np.abs(extra_R[-1:]).max(initial=0) / sc.volume * sc.pin_pressure)
        if not np.isfinite(residual):
            raise FloatingPointError("the residual is not finite")
        if residual < TOLERANCE:
            break
        if iteration == MAX_ITERATIONS:
            raise ConvergenceError(f"Newton residual {residual:.2e} after {iteration} "
                                   "iterations")

        if must_refactorise(lu, residual, previous):      # tangent, then factorise it
            tic = time.perf_counter()
            K = _tangent(model, disc, stress, total, tangent, J, Finv, dt, alpha_u, alpha_p)
            K = _bordered(K, disc, n, rigid_w, c_mean, model.scales.pin_pressure)
            toc = time.perf_counter()
            stats["timings"]["assembly_s"] += toc - tic
            lu = factorise(K, groups=np.concatenate([np.tile(np.arange(n), 3),
                                                     np.full(K.shape[0] - 3 * n, -1)]))
            stats["factorisations"] += 1
            stats["timings"]["solve_s"] += time.perf_counter() - toc
        previous = residual
        tic = time.perf_counter()
        dx = lu.solve(-R)
        stats["timings"]["solve_s"] += time.perf_counter() - tic
        du, p, plate, lam = _advance(dx, du, p, plate, lam, n, bc, model)

    done = _finish(model, points, disc, du, p, plate, gap, plate_gap, dt)
    if case.diagnostics.uniqueness:
        K = _tangent(model, disc, stress, total, tangent, J, Finv, dt, alpha_u, alpha_p)
        done.uniqueness = _uniqueness(model, disc, K, n)
    return done, iteration, residual


def _tested(shape, r):
    """``sum_s N_s^T r[:, s]`` over the test functions ``shape`` (slots value, d/dx, d/dy;
    all-zero slots skipped)."""
    out = np.zeros(shape.phi.shape[1])
    for s, N in enumerate((shape.phi, shape.dphi_dx, shape.dphi_dy)):
        if r[:, s].any():
            out += N.T @ r[:, s]
    return out


def _tangent(model, disc, stress, total, tangent, J, Finv, dt, alpha_u, alpha_p):
    """The Newton tangent of ``(ux, uy, p_w)`` (fields blocked) at the current iterate:
    :func:`soil.weakform.tangent` in the domain, the penalties on the boundary."""
    bc = disc.bc
    coeff = weakform.tangent(tangent, stress, total, J, Finv, disc.w, model.case.fluid, dt)
    pen = np.zeros((len(disc.bp.weights), 3, 3, 3, 3))
    constrained = bc.constrained | np.column_stack([0 * bc.rigid, bc.rigid]).astype(bool)
    pen[:, :2, :, :2, :] = penalty_coefficients(disc.bp, constrained, alpha_u)
    pen[:, 2, 0, 2, 0] = -alpha_p * disc.bp.weights * bc.drained
    return disc.tangent(coeff, pen)


def _uniqueness(model, disc, K, n):
    """:func:`soil.bifurcation.restricted_eigenvalue` of a step's converged tangent over
    the initial P-wave modulus: the displacement block (penalties included) on the
    undrained constraint (the pressure rows), against the H1 Gram matrix of the trial
    functions (length scale: the body's height)."""
    su, W = disc.su, sp.diags(disc.w)
    scalar = (su.dphi_dx.T @ W @ su.dphi_dx + su.dphi_dy.T @ W @ su.dphi_dy
              + su.phi.T @ W @ su.phi / model.case.geometry.height**2)
    K = sp.csr_matrix(K)
    value = restricted_eigenvalue(K[:2 * n, :2 * n], K[2 * n:3 * n, :2 * n],
                                  sp.block_diag([scalar, scalar]))
    return value / model.scales.modulus


def _roundoff(disc, points, du, du_bar, p, plate, alpha_u, alpha_p, rigid_w):
    """Round-off level of the penalty forces in the residual rows, (2n,), (n,) and a float.

    A penalty force ``phi^T (alpha w gap)`` has ``alpha`` about ``penalty`` (1e6) times the
    stiffness, and its gap is a difference of displacements (or pressures) of the size of
    the step's increment; in floating point it is then known only to ``eps x sum |terms|``,
    which grows as the spacing shrinks. At 3 x 10^4 nodes and a 0.2 % strain step this is
    1.6e-8 of the force scale on the boundary rows, above :data:`TOLERANCE`; the residual
    stalls at about half of it whatever the tangent.
    """
    eps, bc = np.finfo(float).eps, disc.bc
    phi_u, phi_p = disc.boundary_magnitudes
    size = np.abs(points.gap) + phi_u @ np.abs(du) + np.abs(du_bar)                # (G, 2)
    plate_size = (np.abs(points.plate_gap) + phi_u @ np.abs(du[:, 1])
                  + abs(plate - points.plate)) * np.abs(rigid_w)
    force = alpha_u * disc.bp.weights[:, None] * bc.constrained * size
    noise_u = eps * np.concatenate([phi_u.T @ force[:, 0],
                                    phi_u.T @ (force[:, 1] + plate_size)])
    flow = alpha_p * disc.bp.weights * bc.drained * (phi_p @ np.abs(p))
    return noise_u, eps * (phi_p.T @ flow), eps * plate_size.sum()


def _excess(R, noise):
    """Largest amount by which ``|R|`` exceeds its round-off level (0 when within it)."""
    return np.max(np.abs(R) - noise, initial=0.0)


def _advance(dx, du, p, plate, lam, n, bc, model):
    """Add a Newton correction ``dx = [du, p, plate?, lambda?]`` to the unknowns."""
    extra = dx[3 * n:]
    if bc.rigid.any():
        plate, extra = plate + extra[0], extra[1:]
    if model.scales.pin_pressure:
        lam += extra[0]
    return du + dx[:2 * n], p + dx[2 * n:3 * n], plate, lam


def _finish(model, points, disc, du, p, plate, gap, plate_gap, dt):
    """Nodal update after a converged step: state with D^I, positions, gaps, probes."""
    n = len(points.nodes)
    at = disc.at_points
    H = _gradient(at.nodes, du, n)
    J = np.linalg.det(np.eye(2) + H)
    deps, dw = strain_increment(H, J)
    stress, state, _ = model.material.update(points.stress, points.state, deps, dw)
    move = du.reshape(2, n).T
    return Points(nodes=points.nodes + at.nodes.phi @ move, stress=stress, state=state, p=p,
                  gap=np.where(disc.bc.constrained, gap, 0.0), plate=plate,
                  plate_gap=np.where(disc.bc.rigid, plate_gap, 0.0),
                  probes=points.probes + at.probes.phi @ move,
                  stretching=deps / dt)


@dataclass
class _Discretisation:
    """Shape functions, cells, boundary points and block patterns of one configuration."""

    w: np.ndarray
    su: ShapeFunctions
    sp: ShapeFunctions
    tu: ShapeFunctions
    tp: ShapeFunctions
    bp: object
    sub: ShapeFunctions
    spb: ShapeFunctions
    bc: object
    at_points: object
    patterns: dict

    @property
    def shared(self):
        """True when u and p_w use the same shape functions: one three-field pattern."""
        return self.tu is self.tp and self.su is self.sp and self.sub is self.spb

    @cached_property
    def boundary_magnitudes(self):
        """``|phi|`` of u and p_w at the boundary points, for :func:`_roundoff`."""
        return abs(self.sub.phi), abs(self.spb.phi)

    @property
    def blocks(self):
        """Block name: its (test, trial) shape functions, domain then boundary points."""
        if self.shared:
            return {"domain": ((self.tu, self.su), (self.sub, self.sub))}
        return {"uu": ((self.tu, self.su), (self.sub, self.sub)), "up": ((self.tu, self.sp),),
                "pu": ((self.tp, self.su),), "pp": ((self.tp, self.sp), (self.spb, self.spb))}

    def block(self, name, coeff, boundary):
        """One block's matrix from its domain (and boundary) coefficients."""
        pattern, pairs = self.patterns[name], self.blocks[name]
        values = None
        for (test, trial), c in zip(pairs, (coeff, boundary)):
            values = scatter(pattern, test, trial, c, values)
        return pattern.matrix(values, coeff.shape[1], coeff.shape[3])

    def tangent(self, coeff, boundary):
        """Tangent of ``(ux, uy, p_w)``, fields blocked, from the integrand coefficients at
        the integration points (M, 3, 3, 3, 3) and the boundary points (G, 3, 3, 3, 3)."""
        if self.shared:
            return self.block("domain", coeff, boundary)
        u, p = slice(0, 2), slice(2, 3)
        return sp.bmat([
            [self.block("uu", coeff[:, u, :, u], boundary[:, u, :, u]),
             self.block("up", coeff[:, u, :, p], None)],
            [self.block("pu", coeff[:, p, :, u], None),
             self.block("pp", coeff[:, p, :, p], boundary[:, p, :, p])]], format="csr")


@dataclass
class _AtPoints:
    nodes: ShapeFunctions
    probes: ShapeFunctions


def _discretise(model, nodes, evaluation, timings):
    """Cells, shape functions (built once when u and p_w share their settings) and block
    patterns on the configuration ``nodes``; phase times added to ``timings``."""
    case, s = model.case, model.case.efg
    tic = time.perf_counter()
    quad = background(case, nodes, model.loop, s)
    bp = boundary_points(nodes, model.loop, model.edges)
    toc = time.perf_counter()
    timings["cells_s"] += toc - tic
    same = (s.weight_u, s.scale_u) == (s.weight_p, s.scale_p)

    def build(points, field="u"):
        return ShapeFunctions.build(nodes, points, getattr(s, f"weight_{field}"),
                                    getattr(s, f"scale_{field}"), key=f"efg.scale_{field}")

    su, sub = build(quad.points), build(bp.points)
    sp_, spb = (su, sub) if same else (build(quad.points, "p"), build(bp.points, "p"))
    tu, tp = su, sp_
    if s.correction == "vci":
        tu = vci.corrected(su, quad.weights, sub, bp.weights, bp.normal)
        tp = tu if same else vci.corrected(sp_, quad.weights, spb, bp.weights, bp.normal)
    at = build(evaluation)
    n = len(nodes)
    at_points = _AtPoints(_rows(at, slice(0, n)), _rows(at, slice(n, None)))
    disc = _Discretisation(quad.weights, su, sp_, tu, tp, bp, sub, spb,
                           conditions(case, bp), at_points, {})
    tic = time.perf_counter()
    timings["shape_functions_s"] += tic - toc
    disc.patterns.update({name: Pattern.build(*pairs) for name, pairs in disc.blocks.items()})
    timings["assembly_s"] += time.perf_counter() - tic
    return disc


def _rows(shape, rows):
    """The shape functions at a slice of the evaluation points."""
    return replace(shape, phi=shape.phi[rows], dphi_dx=shape.dphi_dx[rows],
                   dphi_dy=shape.dphi_dy[rows], rcond=shape.rcond[rows])


def _bordered(K, disc, n, rigid_w, c_mean, pin):
    """Append the rigid plate's settlement and the mean-pressure multiplier, if any."""
    cols, rows, corner = [], [], []
    size = K.shape[0]
    if disc.bc.rigid.any():
        c = np.zeros(size)
        c[n:2 * n] = -(disc.sub.phi.T @ rigid_w)
        cols.append(c)
        rows.append(c)
        corner.append(rigid_w.sum())
    if pin:
        c = np.zeros(size)
        c[2 * n:3 * n] = c_mean
        cols.append(c)
        rows.append(c)
        corner.append(0.0)
    if not cols:
        return K
    C = sp.csc_matrix(np.column_stack(cols))
    return sp.bmat([[K, C], [C.T, sp.diags(corner)]], format="csc")


def _gradient(shape, du, n):
    """``grad_n(du)`` (P, 2, 2): ``H[p, i, j] = d du_i / d x_j``."""
    ux, uy = du[:n], du[n:2 * n]
    return np.stack([np.stack([shape.dphi_dx @ ux, shape.dphi_dy @ ux], 1),
                     np.stack([shape.dphi_dx @ uy, shape.dphi_dy @ uy], 1)], 1)


def _penalties(model, times):
    """Penalty factors: displacement (P-wave modulus / h) and pore pressure."""
    case = model.case
    sc = model.scales
    dt = float(np.max(np.diff(times)))
    flow = (dt * case.fluid.mobility + case.fluid.storage * sc.h**2
            + case.fluid.biot_alpha**2 * sc.h**2 / sc.modulus)
    return {"penalty_alpha_u": case.efg.penalty * sc.modulus / sc.h,
            "penalty_alpha_p": case.efg.penalty * flow / sc.h}


def _history_row(model, points, t, dt, info):
    case = model.case
    p, q = invariants(points.stress)
    top = model.loop[model.edges == EDGES.index("top")]
    probes = {}
    if len(points.probes):
        s = case.efg
        shape = ShapeFunctions.build(points.nodes, points.probes, s.weight_p, s.scale_p,
                                     key="efg.scale_p")
        probes = {f"p_w@{pr.name}": v for pr, v in zip(case.probes, shape.phi @ points.p)}
    x0 = case.nodes()[top]
    return {"time": t, "eps_a": axial_strain(case, points.nodes[top, 1]), "p": p.mean(),
            "q": q.mean(), "err": stretching_error(case, points.stretching[:, 1]),
            "gamma": np.mean(points.nodes[top, 0] - x0[:, 0]) / case.geometry.height,
            "dt": dt, "iterations": info["iterations"], "substeps": info["substeps"],
            "residual": info["residual"], **probes,
            **({"uniqueness": points.uniqueness} if case.diagnostics.uniqueness else {})}


def _snapshot(model, points, t):
    s = model.case.efg
    at = ShapeFunctions.build(points.nodes, points.nodes, s.weight_p, s.scale_p,
                              key="efg.scale_p")
    p, q = invariants(points.stress)
    data = {"u": points.nodes - model.case.nodes(), "p_w": at.phi @ points.p,
            "p_eff": p, "q": q, "stretching": points.stretching,
            "support_radius": at.support}
    data.update({k: v for k, v in points.state.items()})
    return Snapshot(t, points.nodes.copy(), data)
