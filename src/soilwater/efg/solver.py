"""Updated-Lagrangian u-p EFG solver: Biot consolidation with finite-strain Cam-clay.

Every node carries a displacement and a pore pressure parameter; displacement and pore
pressure each have their own MLS weight and scale factor (``[efg]`` of the case). A step
from t_n to t_(n+1) is solved on the configuration x_n (shape functions and background
cells rebuilt there) for the displacement increment ``du`` and ``p_w`` at t_(n+1). Its
integrand and consistent tangent are :mod:`soilwater.physics.weakform`'s (equilibrium with
``J sigma F^-T`` on x_n, backward-Euler continuity), shared with the FEM reference; the
stress is the material's return mapping with the midpoint stretching and the
Hughes-Winget spin (:func:`soilwater.nonlinear.coupling.material_update`).

Newton's method, the reuse of a factorisation within a step, the cut-backs and the scales
are :mod:`soilwater.nonlinear.coupling`'s. A step converges when the displacement residual is below
``TOLERANCE`` times the force scale and the continuity residual below ``TOLERANCE`` times
the volume scale, each residual entry counted beyond its round-off level: the penalty
forces on boundary rows are known only to ``eps x sum |terms|`` (:func:`_roundoff`),
which exceeds the tolerance on fine grids. A step that does not converge, inverts a
background cell or fails in the material is halved up to ``soilwater.nonlinear.coupling.MAX_CUTS``
times before the run stops with one clear error.

The initial state (:func:`soilwater.physics.geostatic.initial_state`, uniform or geostatic) is set at
the nodes, and its total stress ``sigma0 . n`` at each boundary point's initial position
loads the boundary, with the edge tractions; under gravity the buoyant weight at the
integration points (:mod:`soilwater.physics.geostatic`) loads the domain.

Material state lives on the nodes (the material points): at the start of a step the
integration points take stress and state from the nodes by MLS interpolation, and after a
converged step the nodes update their own state with the nodal stretching ``D^I`` (the one
that enters ERR, paper eq. 1) and move by ``u^h(x_I)``.

Essential conditions act on total quantities, by penalty or by Nitsche's method
(``efg.essential``; :class:`_Nitsche`): each boundary Gauss point keeps the gap ``u^h -
u_bar`` of its constrained components, so reactions carried in earlier steps are not lost
(a velocity-controlled footing's uy target is -rate x t). A rigid plate (Mandel) or a
load-controlled footing adds one unknown, its settlement, tied to its points by the same
method; its total force equals the edge load or the footing's force. The reaction of each
named segment is the force of the condition over its points: ``-sum alpha w gap_y``
(penalty) or ``sum w (P n - beta gap)_y`` (Nitsche). When no boundary is
drained or free and the constituents are incompressible, the pore pressure is defined up
to a constant: the mean change of p_w over the domain is then pinned to zero by one
Lagrange multiplier.
"""

from dataclasses import dataclass, replace
from functools import cached_property, partial

import numpy as np
import scipy.sparse as sp

from soilwater.efg import nitsche
from soilwater.efg import vci
from soilwater.efg.quadrature import background
from soilwater.efg.assembly import Pattern, scatter
from soilwater.efg.boundary import (BOUNDARY_ORDER, boundary_points, conditions,
                          penalty_coefficients, segment_edges)
from soilwater.efg.mls import ShapeFunctions
from soilwater.physics import weakform
from soilwater.diagnostics.bifurcation import h1_gram, restricted_eigenvalue
from soilwater.nonlinear.coupling import Scales, history_row, material_update, newton, run, timed
from soilwater.linalg.backends import Layout
from soilwater.physics.geostatic import buoyant_weight, initial_state, total_stress
from soilwater.results import Snapshot, permeability
from soilwater.material.kinematics import cauchy_traction, invariants
from soilwater.case.boundary import EDGES

#: Strength-of-connection threshold of the Krylov back-end's AMG on EFG tangents
#: (:attr:`soilwater.linalg.backends.Layout.strength`). An MLS support couples each node to many
#: others, weakly at its rim; counting only couplings of at least 1 % makes smaller
#: aggregates and Schwarz subdomains and fewer FGMRES iterations (README, "Speed").
STRENGTH = 0.01
#: Largest forcing of the Krylov back-end's inexact Newton on EFG
#: (:attr:`soilwater.linalg.backends.Layout.forcing`). The first correction solved to 1e-5 lands where
#: exact Newton's does and Newton converges quadratically from there: the undrained bench
#: step takes 4 residuals at 3e3 to 1e5 nodes against 5 at 1e-4 (whose first iterate is
#: 30 % further off), with fewer FGMRES iterations; 1e-6 as many residuals and more
#: FGMRES iterations (``python docs/krylov_study.py --newton 3000 1e-2 1e-4 1e-5 1e-6``).
FORCING = 1e-5


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
    uniqueness: float = 0.0  # soilwater.diagnostics.bifurcation indicator of the last step (if asked for)
    reactions: np.ndarray = None  # (S,) vertical force on the soil per named segment
    cells: object = None     # soilwater.efg.quadrature.Quadrature on ``nodes`` (the next step's)
    rcond: float = np.nan    # smallest MLS rcond at the last step's integration points


@dataclass
class Model:
    """What stays fixed over a run: case, material, boundary topology, scales."""

    case: object
    material: object
    loop: np.ndarray
    edges: np.ndarray
    scales: Scales
    initial_bp: np.ndarray   # (G, 2) boundary points in the initial configuration [m]
    sigma0_bp: np.ndarray    # (G, 4) initial total stress there [kPa]

    @classmethod
    def build(cls, case):
        material = case.material()
        loop = case.boundary_loop()
        edges = segment_edges(case.nodes(), loop, case.geometry)
        initial_bp = boundary_points(case.nodes(), loop, edges).points
        return cls(case, material, loop, edges, Scales.of(case, material), initial_bp,
                   total_stress(case, material, initial_bp))

    @property
    def beta(self):
        """Coefficient of the flow-equation perturbation [m2/kPa] with
        ``efg.stabilisation = "perturbation"`` (times ``efg.stabilisation_factor``), else
        0."""
        return self._stabilisation("perturbation")

    @property
    def tau(self):
        """Coefficient of the polynomial pressure projection [1/kPa] with
        ``efg.stabilisation = "projection"`` (times ``efg.stabilisation_factor``), else
        0."""
        return self._stabilisation("projection")

    def _stabilisation(self, kind):
        s = self.case.efg
        if s.stabilisation != kind:
            return 0.0
        return getattr(self.scales, kind) * s.stabilisation_factor


def solve(case, progress=True):
    """Run a coupled case with EFG and return its :class:`~soilwater.results.Result`.

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
    return run(case, "efg", case.efg.to_dict(), _initial_points(model),
               partial(_step, model), partial(_history_row, model),
               partial(_snapshot, model),
               {"dofs": 3 * len(case.nodes()), "stabilisation_beta": model.beta,
                "stabilisation_tau": model.tau,
                **_penalties(model, case.times())}, progress)


def _initial_points(model):
    case = model.case
    nodes = case.nodes()
    stress, state = initial_state(case, model.material, nodes)
    n_bp = len(model.loop) * BOUNDARY_ORDER
    return Points(nodes=nodes, stress=stress, state=state,
                  p=np.full(len(nodes), float(case.initial_pore_pressure)),
                  gap=np.zeros((n_bp, 2)), plate=0.0, plate_gap=np.zeros(n_bp),
                  probes=np.array([p.point for p in case.probes]).reshape(-1, 2),
                  stretching=np.zeros((len(nodes), 4)),
                  reactions=np.zeros(len(case.boundary.segments())))


def _step(model, points, t0, t1, stats):
    """One step on the configuration of ``points``: new points, iterations, residual.

    The new points carry the background cells of their own configuration, on which the
    next step integrates (and its history row measures them), and the smallest rcond of
    this step's MLS moment matrices (:func:`_min_rcond`)."""
    disc = _discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                       stats["timings"], points.cells)
    system = _System(model, points, disc, t0, t1, stats["timings"])
    iterations, residual = newton(system, stats)
    done = system.finish()
    with timed(stats["timings"], "cells_s"):
        done.cells = _cells(model, done.nodes)
    done.rcond = _min_rcond(disc)
    if model.case.diagnostics.uniqueness:
        done.uniqueness = _uniqueness(model, disc, system.domain_tangent(), system.n)
    return done, iterations, residual


class _System:
    """One step's Newton system (:func:`soilwater.nonlinear.coupling.newton`).

    Unknowns ``[du (2n, fields blocked), p (n), plate settlement?, mean-pressure
    multiplier?]``; :meth:`residual` keeps the iterate's stresses and tangent for
    :meth:`tangent` and :meth:`finish`.
    """

    def __init__(self, model, points, disc, t0, t1, timings):
        case, bc, su = model.case, disc.bc, disc.su
        self.model, self.points, self.disc, self.timings = model, points, disc, timings
        self.dt, self.n = t1 - t0, len(points.nodes)
        self.stress_n = su.phi @ points.stress
        self.state_n = {k: su.phi @ v for k, v in points.state.items()}
        self.p_n = disc.sp.phi @ points.p
        self.grad_p_n = _pressure_gradient(disc.sp, points.p)
        self.du_bar = bc.target_increment(case.loading.L, disc.bp.points, self.dt)
        self.alpha_u, self.alpha_p = _penalties(model, [0.0, self.dt]).values()
        self.nitsche = None
        if case.efg.essential == "nitsche":
            with timed(timings, "assembly_s"):        # beta's eigenvalue bounds
                self.nitsche = _Nitsche(model, points, disc, self.dt,
                                        (self.stress_n, self.state_n["v"]))
        self.weight = buoyant_weight(case, self.state_n["v"])
        initial = cauchy_traction(model.sigma0_bp, disc.bp.normal)     # (G, 2)
        if self.nitsche is not None:     # held components: their flux carries it
            initial = np.where(self.nitsche.terms.mask[:, :2], 0.0, initial)
        self.traction = initial + bc.traction * bc.loaded * case.loading.factor(t1)
        self.plate_force = case.plate_force(t1)
        self.rigid_w = (self.nitsche is None) * self.alpha_u * disc.bp.weights * bc.rigid
        self.c_mean = disc.tp.phi.T @ disc.w
        self.du, self.p, self.plate, self.lam = (np.zeros(2 * self.n), points.p.copy(),
                                                 points.plate, 0.0)
        self.layout = _layout(points.nodes, partial(_pressure_mass, disc), model.scales,
                              bc.rigid.any(), case.efg)

    def residual(self):
        """``[R_u, R_p, plate?, pin?]`` at the iterate and its scaled size beyond
        round-off."""
        model, points, disc, n = self.model, self.points, self.disc, self.n
        bc, fluid = disc.bc, model.case.fluid
        (self.stress, self.state, self.material_tangent, self.J, self.Finv,
         _) = material_update(model.material, self.stress_n, self.state_n,
                              _gradient(disc.su, self.du, n), self.timings,
                              "a background cell")
        p_q = disc.sp.phi @ self.p
        self.total = weakform.total_stress(self.stress, p_q, fluid)
        self.grad_p = _pressure_gradient(disc.sp, self.p)
        r = weakform.residual(self.total, self.J, self.Finv, disc.w, p_q, self.p_n,
                              self.grad_p, fluid, self.dt, model.beta, self.grad_p_n,
                              self.state_n["v"], self.weight)

        R_u = np.concatenate([disc.tu.tested(r[:, f]) for f in range(2)])
        R_p = disc.tp.tested(r[:, 2])
        ub = disc.sub.phi @ self.du.reshape(2, n).T                          # (G, 2)
        self.gap = points.gap + ub - self.du_bar
        self.plate_gap = points.plate_gap + ub[:, 1] - (self.plate - points.plate)
        self.gaps = np.column_stack([self.gap[:, 0],
                                     np.where(bc.rigid, self.plate_gap, self.gap[:, 1]),
                                     disc.spb.phi @ self.p])                  # (G, 3)
        essential_u, essential_p = self._essential()
        R_u, R_p = R_u + essential_u, R_p + essential_p
        R_u[n:] += disc.sub.phi.T @ (self.rigid_w * self.plate_gap)
        R_u -= np.concatenate([disc.sub.phi.T @ (disc.bp.weights * self.traction[:, f])
                               for f in range(2)])
        if model.tau:
            R_p -= model.tau * (disc.fluctuation @ (self.p - points.p))
        extra_R = []
        if bc.rigid.any():
            extra_R.append(self._plate_reaction() - self.plate_force)
        sc = model.scales
        if sc.pin_pressure:
            R_p += self.c_mean * self.lam
            extra_R.append(self.c_mean @ (self.p - points.p))
        noise_u, noise_p, noise_plate = _roundoff(
            disc, points, self.du.reshape(2, n).T, self.du_bar, self.p, self.plate,
            *self._factors, self.rigid_w)
        residual = max(_excess(R_u, noise_u) / sc.force, _excess(R_p, noise_p) / sc.volume,
                       _excess(extra_R[:1], noise_plate) / sc.force * bc.rigid.any(),
                       np.abs(extra_R[-1:]).max(initial=0) / sc.volume * sc.pin_pressure)
        return np.concatenate([R_u, R_p, extra_R]), residual

    @property
    def _factors(self):
        """The coefficients of the essential conditions' gap forces, u [kPa/m] and p_w
        [m/kPa]: the penalty factors, or Nitsche's stabilisation."""
        if self.nitsche is None:
            return self.alpha_u, self.alpha_p
        return tuple(np.abs(self.nitsche.terms.beta[1:]))

    def _essential(self):
        """The essential conditions' rows of the residual, (2n,) and (n,): penalty forces
        ``alpha w gap`` (p_w's with the continuity equation's sign) or Nitsche's terms."""
        disc, bc, w = self.disc, self.disc.bc, self.disc.bp.weights
        if self.nitsche is None:
            r = np.zeros(self.gaps.shape + (3,))
            r[:, :, 0] = w[:, None] * np.column_stack([self.alpha_u * bc.constrained,
                                                       -self.alpha_p * bc.drained]) * self.gaps
        else:
            r = self.nitsche.residual(self.du, self.p, self.gaps, self.timings)
        return (np.concatenate([disc.sub.tested(r[:, f]) for f in range(2)]),
                disc.spb.tested(r[:, 2]))

    def _essential_tangent(self):
        """Boundary coefficients (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3 fields) of
        the essential conditions, the rigid plate's points included: the penalties' value
        terms ``(f, 0, f, 0)`` or Nitsche's terms."""
        bc, bp = self.disc.bc, self.disc.bp
        if self.nitsche is not None:
            return self.nitsche.tangent()
        rigid = np.column_stack([0 * bc.rigid, bc.rigid]).astype(bool)
        penalty = penalty_coefficients(bp, bc.constrained | rigid, self.alpha_u).columns()
        penalty[2, 0, 2, 0] = -self.alpha_p * bp.weights * bc.drained
        return weakform.Coefficients.of(penalty, (3, 3))

    def _plate_reaction(self):
        """The force of the plate on the soil [kN/m, y up]: ``-sum alpha w gap`` or the
        Nitsche reaction over the plate's points."""
        if self.nitsche is None:
            return -np.sum(self.rigid_w * self.plate_gap)
        return np.sum(self.nitsche.reaction(self.gaps)[:, 1] * self.disc.bc.rigid)

    def _plate_border(self, boundary):
        """Column, row and corner of the plate's settlement in the tangent (None without
        a plate), from the boundary coefficients ``boundary`` of
        :meth:`_essential_tangent`: the residual depends on the settlement a through
        the plate's gap ``u_y - a``, and the plate's equation on u and p_w through its
        reaction."""
        disc, bc, n = self.disc, self.disc.bc, self.n
        if not bc.rigid.any():
            return None
        if self.nitsche is None:
            c = np.zeros(3 * n)
            c[n:2 * n] = -(disc.sub.phi.T @ self.rigid_w)
            return c, c, self.rigid_w.sum()
        rigid = bc.rigid.astype(float)
        by_gap = self.nitsche.terms.residual(                 # d r / d gap_y at the plate
            np.zeros((len(rigid), 3, 3)), np.column_stack([0 * rigid, rigid, 0 * rigid]))
        reaction = -rigid[:, None, None] * np.stack(           # (G, field, slot): the
            [boundary.slots(1, g)[:, 0] for g in range(3)], 1)  # terms (1, 0, g, t)
        shapes = (disc.sub, disc.sub, disc.spb)
        column = -np.concatenate([s.tested(by_gap[:, f]) for f, s in enumerate(shapes)])
        row = np.concatenate([s.tested(reaction[:, g]) for g, s in enumerate(shapes)])
        return column, row, by_gap[:, 1, 0].sum()

    def domain_tangent(self, boundary=None):
        """The tangent of ``(ux, uy, p_w)`` at the iterate, essential conditions
        included (their coefficients ``boundary``, by default
        :meth:`_essential_tangent`)."""
        boundary = self._essential_tangent() if boundary is None else boundary
        return _tangent(self.model, self.disc, self.stress, self.total,
                        self.material_tangent, self.J, self.Finv, self.dt,
                        self.state_n["v"], self.grad_p, boundary)

    def tangent(self):
        """:meth:`domain_tangent` bordered by the plate and the pin, if any."""
        boundary = self._essential_tangent()
        return _bordered(self.domain_tangent(boundary), self._plate_border(boundary),
                         self.c_mean, self.model.scales.pin_pressure)

    def advance(self, dx):
        """Add a Newton correction ``dx = [du, p, plate?, lambda?]`` to the unknowns."""
        n, extra = self.n, dx[3 * self.n:]
        if self.disc.bc.rigid.any():
            self.plate, extra = self.plate + extra[0], extra[1:]
        if self.model.scales.pin_pressure:
            self.lam += extra[0]
        self.du, self.p = self.du + dx[:2 * n], self.p + dx[2 * n:3 * n]

    def finish(self):
        """Nodal update after convergence: state with D^I, positions, gaps, probes."""
        points, disc, n = self.points, self.disc, self.n
        at = disc.at_points
        stress, state, _, _, _, deps = material_update(
            self.model.material, points.stress, points.state,
            _gradient(at.nodes, self.du, n), self.timings, "a node")
        move = self.du.reshape(2, n).T
        bc = disc.bc
        if self.nitsche is None:
            force = -self.alpha_u * disc.bp.weights * bc.constrained[:, 1] * self.gap[:, 1]
            force -= self.rigid_w * self.plate_gap
        else:
            force = self.nitsche.reaction(self.gaps)[:, 1]
        on = bc.segment >= 0
        reactions = np.bincount(bc.segment[on], force[on],
                                minlength=len(self.model.case.boundary.segments()))
        return Points(nodes=points.nodes + at.nodes.phi @ move, stress=stress, state=state,
                      p=self.p, gap=np.where(disc.bc.constrained, self.gap, 0.0),
                      plate=self.plate,
                      plate_gap=np.where(disc.bc.rigid, self.plate_gap, 0.0),
                      probes=points.probes + at.probes.phi @ move,
                      stretching=deps / self.dt, reactions=reactions)


class _Nitsche:
    """Nitsche's method in one step (``efg.essential = "nitsche"``): the weak form at the
    boundary points and the terms of :class:`soilwater.efg.nitsche.Nitsche` on ``(ux, uy, p_w)``.

    The boundary points take stress, state and p_w from the nodes as the integration
    points do, and their material update gives the flux (first Piola stress ``J sigma
    F^-T``, Darcy term) that the consistency term carries through the boundary. The
    reference operators are frozen over the step: the isotropic elastic moduli of the
    start-of-step state for u, ``-dt k/gamma_w`` at the start-of-step void ratio for p_w.
    beta = :data:`soilwater.efg.nitsche.SAFETY` x :func:`soilwater.efg.nitsche.largest_eigenvalue` per field,
    the bound of p_w taken with ``dt k/gamma_w + (S + alpha^2/M) h^2``, the scale of the
    pressure penalty: with k = 0 (no flux, so no consistency or adjoint term) a
    drained condition is then still held, by the stabilisation alone (a penalty of the
    order of that scale over h, not 10^6 times it).
    """

    def __init__(self, model, points, disc, dt, domain):
        sub, spb = disc.sub, disc.spb
        self.model, self.disc, self.dt = model, disc, dt
        stress_n, state_n = sub.phi @ points.stress, {k: sub.phi @ v
                                                      for k, v in points.state.items()}
        self.terms = _nitsche_terms(model, disc, dt, domain, (stress_n, state_n["v"]))
        # the weak form only where a component is held: a free point carries no term
        # (and the soil at a free surface may be past what its return mapping handles)
        self.held = h = np.flatnonzero(self.terms.mask.any(axis=1))
        self.stress_n, self.state_n = stress_n[h], {k: v[h] for k, v in state_n.items()}
        self.p_n = (spb.phi @ points.p)[h]
        self.grad_p_n = _pressure_gradient(spb, points.p)[h]
        initial = cauchy_traction(model.sigma0_bp, disc.bp.normal)          # (G, 2)
        self.initial = (self.terms.mask * disc.bp.weights[:, None]
                        * np.column_stack([initial, np.zeros(len(initial))]))

    def residual(self, du, p, gaps, timings):
        """Residual coefficients (G, 3, 3) of the iterate ``du``, ``p`` with the gaps
        (G, 3) of ``(ux, uy, p_w)``."""
        model, disc, fluid, h = self.model, self.disc, self.model.case.fluid, self.held
        (self.stress, _, self.material_tangent, self.J, self.Finv,
         _) = material_update(model.material, self.stress_n, self.state_n,
                              _gradient(disc.sub, du, len(p))[h], timings,
                              "a boundary point")
        p_b = (disc.spb.phi @ p)[h]
        self.total = weakform.total_stress(self.stress, p_b, fluid)
        self.grad_p = _pressure_gradient(disc.spb, p)[h]
        self.flux = np.zeros(gaps.shape + (3,))
        self.flux[h] = weakform.residual(self.total, self.J, self.Finv,
                                         disc.bp.weights[h], p_b, self.p_n, self.grad_p,
                                         fluid, self.dt, model.beta, self.grad_p_n,
                                         self.state_n["v"])
        return self.terms.residual(self.flux, gaps)

    def tangent(self):
        """Tangent coefficients (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3 fields) at
        the last :meth:`residual`: :meth:`soilwater.efg.nitsche.Nitsche.tangent` of the weak form's
        tangent at the boundary points (zero at the free ones)."""
        c = weakform.tangent(self.material_tangent, self.stress, self.total, self.J,
                             self.Finv, self.disc.bp.weights[self.held],
                             self.model.case.fluid, self.dt, self.model.beta,
                             self.state_n["v"], self.grad_p)
        values = np.zeros((len(self.disc.bp.weights), c.values.shape[1]))
        values[self.held] = c.values
        return self.terms.tangent(replace(c, values=values))

    def reaction(self, gaps):
        """Force of the support on the soil at each point (G, 3) at the last
        :meth:`residual` (:meth:`soilwater.efg.nitsche.Nitsche.reaction`) beyond the initial total
        stress's traction, as the penalty's gap forces are: that traction is the
        boundary's load where free, and part of the flux where held."""
        return self.terms.reaction(self.flux, gaps) - self.initial


def _nitsche_terms(model, disc, dt, domain, boundary):
    """:class:`soilwater.efg.nitsche.Nitsche` of a step on ``(ux, uy, p_w)`` (see :class:`_Nitsche`);
    ``domain`` and ``boundary`` are the start-of-step ``(stress, v)`` at the integration
    and the boundary points."""
    fluid, sc, bc, bp = model.case.fluid, model.scales, disc.bc, disc.bp
    compressibility = (fluid.storage + fluid.biot_alpha**2 / sc.modulus) * sc.h**2
    (stress, v), (stress_b, v_b) = domain, boundary

    def darcy(v, extra=0.0):         # (0, 1 + k, 0, 1 + k) of one field, no weight
        value = dt * fluid.mobility_at(v)[0] + extra
        return weakform.Coefficients.of({(0, 1 + k, 0, 1 + k): value for k in range(2)},
                                        (1, 1))

    mask = np.column_stack([bc.constrained[:, 0], bc.constrained[:, 1] | bc.rigid,
                            bc.drained])
    D = _elastic_operator(model.material, stress_b, v_b).columns()
    for (_, s, _, t), value in darcy(v_b).columns().items():
        D[2, s, 2, t] = -value                     # the continuity equation's sign
    terms = nitsche.Nitsche.build(bp, mask, weakform.Coefficients.of(D, (3, 3)),
                                  np.zeros(3))
    u = range(2)
    lam_u = nitsche.largest_eigenvalue(
        (disc.su, disc.w, _elastic_operator(model.material, stress, v)),
        (disc.sub, bp.weights, terms.operator.block(u, u)))
    lam_p = nitsche.largest_eigenvalue(
        (disc.sp, disc.w, darcy(v, compressibility)),
        (disc.spb, bp.weights, nitsche.flux_operator(bp, mask[:, 2:],
                                                     darcy(v_b, compressibility))))
    return replace(terms, beta=nitsche.SAFETY * np.array([lam_u, lam_u, -lam_p]))


def _elastic_operator(material, stress, v):
    """The gradient operator (:func:`soilwater.efg.nitsche.gradient_operator`) of the material's
    isotropic elastic moduli at the states ``(stress, v)``: the gradient terms of 2 x 2
    fields at the P points [kPa]."""
    p, _ = invariants(stress)
    K, G = material.moduli(p, v)
    return nitsche.gradient_operator(nitsche.isotropic(*np.broadcast_arrays(K, G, p)[:2]))


def _pressure_gradient(shape, p):
    """``grad p`` (P, 2) at the shape functions' points [kPa/m]."""
    return np.stack([shape.dphi_dx @ p, shape.dphi_dy @ p], 1)


def _tangent(model, disc, stress, total, tangent, J, Finv, dt, v_n, grad_p, boundary):
    """The Newton tangent of ``(ux, uy, p_w)`` (fields blocked) at the current iterate:
    :func:`soilwater.physics.weakform.tangent` in the domain, the coefficients ``boundary``
    (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3 fields) of the essential conditions at
    the boundary points."""
    coeff = weakform.tangent(tangent, stress, total, J, Finv, disc.w, model.case.fluid, dt,
                             model.beta, v_n, grad_p)
    K = disc.tangent(coeff, boundary)
    if not model.tau:
        return K
    n = disc.fluctuation.shape[0]
    return K - model.tau * sp.block_diag([sp.csr_matrix((2 * n, 2 * n)),
                                          disc.fluctuation], format="csr")


def _uniqueness(model, disc, K, n):
    """:func:`soilwater.diagnostics.bifurcation.restricted_eigenvalue` of a step's converged tangent over
    the initial P-wave modulus: the displacement block (penalties included) on the
    undrained constraint (the pressure rows), against the H1 Gram matrix of the trial
    functions (length scale: the body's height)."""
    su = disc.su
    pattern = Pattern.build((su, su))
    G = pattern.matrix(scatter(pattern, su, su, h1_gram(disc.w, model.case.geometry.height)),
                       2, 2)
    K = sp.csr_matrix(K)
    value = restricted_eigenvalue(K[:2 * n, :2 * n], K[2 * n:3 * n, :2 * n], G)
    return value / model.scales.modulus


def _pressure_mass(disc, extra=0):
    """The consistent pressure mass ``int N_i N_j dV`` [m2 per unit thickness] on the
    pressure rows and columns of ``[ux, uy, p]`` and ``extra`` more unknowns."""
    n = disc.sp.phi.shape[1]
    M = sp.coo_matrix(disc.tp.phi.T @ sp.diags(disc.w) @ disc.sp.phi)
    size = 3 * n + extra
    return sp.csr_matrix((M.data, (M.row + 2 * n, M.col + 2 * n)), shape=(size, size))


def _layout(nodes, mass, scales, rigid, settings):
    """The :class:`soilwater.linalg.backends.Layout` of the unknowns ``[ux, uy, p, plate?, pin?]``;
    ``mass(extra)`` gives the pressure mass matrix. The Krylov back-end suits EFG with
    Nitsche's conditions (a penalty's diagonal spans 1e6: a small residual says nothing
    of the error) and a pressure stabilisation (``settings``, the case's EFG settings),
    and PARDISO factorises such a tangent in single precision (``Layout.single``,
    measured: ``python docs/krylov_study.py --single``)."""
    n = len(nodes)
    iterative = settings.essential == "nitsche" and settings.stabilisation != "none"
    plate, pin = [scales.force] * int(rigid), [scales.volume] * int(scales.pin_pressure)
    extra = len(plate) + len(pin)
    return Layout(groups=np.concatenate([np.tile(np.arange(n), 3), np.full(extra, -1)]),
                  fields=np.concatenate([np.repeat([0, 1, 2], n), np.full(extra, -1)]),
                  locations=np.concatenate([nodes, nodes, nodes, np.zeros((extra, 2))]),
                  scales=np.concatenate([np.full(2 * n, scales.force),
                                         np.full(n, scales.volume), plate, pin]),
                  mass=partial(mass, extra=extra),
                  modulus=scales.modulus, smoother="schwarz", strength=STRENGTH,
                  iterative=iterative, single=iterative, forcing=FORCING)


def _roundoff(disc, points, du, du_bar, p, plate, alpha_u, alpha_p, rigid_w):
    """Round-off level of the penalty forces in the residual rows, (2n,), (n,) and a float
    (with Nitsche's method, alpha is its beta, some 10^5 times smaller: the level is then
    far below the tolerance).

    A penalty force ``phi^T (alpha w gap)`` has ``alpha`` about ``penalty`` (1e6) times the
    stiffness, and its gap is a difference of displacements (or pressures) of the size of
    the step's increment; in floating point it is then known only to ``eps x sum |terms|``,
    which grows as the spacing shrinks and on fine grids exceeds ``TOLERANCE`` times the
    force scale on the boundary rows, whatever the tangent.
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
    cell: np.ndarray

    @property
    def shared(self):
        """True when u and p_w use the same shape functions: one three-field pattern."""
        return self.tu is self.tp and self.su is self.sp and self.sub is self.spb

    @cached_property
    def fluctuation(self):
        """:func:`soilwater.physics.weakform.fluctuation` of the MLS pressure over the background
        cells."""
        return weakform.fluctuation(self.sp.phi, self.w, self.cell)

    @cached_property
    def boundary_magnitudes(self):
        """``|phi|`` of u and p_w at the boundary points, for :func:`_roundoff`."""
        return abs(self.sub.phi), abs(self.spb.phi)

    @property
    def blocks(self):
        """Block name: its (test, trial) shape functions, domain then boundary points."""
        if self.shared:
            return {"domain": ((self.tu, self.su), (self.sub, self.sub))}
        return {"uu": ((self.tu, self.su), (self.sub, self.sub)),
                "up": ((self.tu, self.sp), (self.sub, self.spb)),
                "pu": ((self.tp, self.su), (self.spb, self.sub)),
                "pp": ((self.tp, self.sp), (self.spb, self.spb))}

    def block(self, name, coeff, boundary):
        """One block's matrix from its domain and boundary coefficients (a boundary block
        without terms, such as the penalty's u-p coupling, adds nothing)."""
        pattern, pairs = self.patterns[name], self.blocks[name]
        values = None
        for (test, trial), c in zip(pairs, (coeff, boundary)):
            values = scatter(pattern, test, trial, c, values)
        return pattern.matrix(values, *coeff.fields)

    def tangent(self, coeff, boundary):
        """Tangent of ``(ux, uy, p_w)``, fields blocked, from the integrand coefficients
        (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3 fields) at the integration points and
        at the boundary points; with separate u and p_w shape functions, each block takes
        a copy of its own terms (Nitsche's couple u and p_w on the boundary too)."""
        if self.shared:
            return self.block("domain", coeff, boundary)
        u, p = range(0, 2), range(2, 3)
        return sp.bmat([
            [self.block("uu", coeff.block(u, u), boundary.block(u, u)),
             self.block("up", coeff.block(u, p), boundary.block(u, p))],
            [self.block("pu", coeff.block(p, u), boundary.block(p, u)),
             self.block("pp", coeff.block(p, p), boundary.block(p, p))]], format="csr")


@dataclass
class _AtPoints:
    nodes: ShapeFunctions
    probes: ShapeFunctions


def _cells(model, nodes):
    """The background cells (:func:`soilwater.efg.quadrature.background`) of the configuration
    ``nodes``."""
    return background(model.case, nodes, model.loop, model.case.efg)


def _min_rcond(disc):
    """Smallest reciprocal condition number of the MLS moment matrices of a step, over
    its integration points: the cells' Gauss points and the boundary points, u and p_w
    (the support-coverage check, :class:`soilwater.efg.mls.ShapeFunctions`)."""
    return float(min(shape.rcond.min(initial=np.inf)
                     for shape in (disc.su, disc.sp, disc.sub, disc.spb)))


def _discretise(model, nodes, evaluation, timings, quad=None):
    """Cells (``quad`` when given: the background cells of ``nodes``, built at the end
    of the step before), shape functions (built once when u and p_w share their
    settings) and block patterns on the configuration ``nodes``; phase times added to
    ``timings``."""
    case, s = model.case, model.case.efg
    with timed(timings, "cells_s"):
        quad = _cells(model, nodes) if quad is None else quad
        bp = boundary_points(nodes, model.loop, model.edges)
    same = (s.weight_u, s.scale_u) == (s.weight_p, s.scale_p)
    supports = {}                        # support radii by scale, searched once

    def build(points, field="u"):
        scale = getattr(s, f"scale_{field}")
        shape = ShapeFunctions.build(nodes, points, getattr(s, f"weight_{field}"), scale,
                                     key=f"efg.scale_{field}", support=supports.get(scale))
        supports.setdefault(scale, shape.support)
        return shape

    with timed(timings, "shape_functions_s"):
        su, sub = build(quad.points), build(bp.points)
        sp_, spb = (su, sub) if same else (build(quad.points, "p"), build(bp.points, "p"))
        tu, tp = su, sp_
        if s.correction == "vci":
            tu = vci.corrected(su, quad.weights, sub, bp.weights, bp.normal)
            tp = tu if same else vci.corrected(sp_, quad.weights, spb, bp.weights, bp.normal)
        at = build(evaluation)
        n = len(nodes)
        at_points = _AtPoints(at.subset(slice(0, n)), at.subset(slice(n, None)))
        disc = _Discretisation(quad.weights, su, sp_, tu, tp, bp, sub, spb,
                               conditions(case, bp, model.initial_bp), at_points, {},
                               quad.cell)
    with timed(timings, "assembly_s"):
        disc.patterns.update({name: Pattern.build(*pairs)
                              for name, pairs in disc.blocks.items()})
    return disc


def _bordered(K, plate, c_mean, pin):
    """Append the rigid plate's settlement (``plate``: its column, row and corner, or
    None) and the mean-pressure multiplier (if ``pin``) to the tangent K of ``(ux, uy,
    p_w)``."""
    cols, rows, corner = [], [], []
    n = K.shape[0] // 3
    if plate is not None:
        cols.append(plate[0])
        rows.append(plate[1])
        corner.append(plate[2])
    if pin:
        c = np.zeros(3 * n)
        c[2 * n:3 * n] = c_mean
        cols.append(c)
        rows.append(c)
        corner.append(0.0)
    if not cols:
        return K
    C, B = sp.csc_matrix(np.column_stack(cols)), sp.csr_matrix(np.vstack(rows))
    return sp.bmat([[K, C], [B, sp.diags(corner)]], format="csr")


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
    """:func:`soilwater.nonlinear.coupling.history_row` of the nodes (equal weights).

    ``min_angle`` and ``min_quality`` are those of the background cells of the
    configuration at the end of the step, which :func:`_step` builds and keeps on the
    points, so the next step integrates on the very cells measured here (no cells are
    built twice); square cells stay squares (90 degrees, quality 1, quarter cells
    included). ``min_rcond`` is the step's (:func:`_min_rcond`; of the last substep of a
    level that was cut back)."""
    case = model.case
    top = model.loop[model.edges == EDGES.index("top")]
    probes = ()
    if len(points.probes):
        s = case.efg
        shape = ShapeFunctions.build(points.nodes, points.probes, s.weight_p, s.scale_p,
                                     key="efg.scale_p")
        probes = zip([pr.name for pr in case.probes], shape.phi @ points.p)
    uniqueness = points.uniqueness if case.diagnostics.uniqueness else None
    nodes0 = case.nodes()
    segments = [(seg, points.nodes[k], nodes0[k], force,
                 points.plate if seg.load_controlled else None)
                for (_, seg), k, force in zip(case.boundary.segments(), case.segment_nodes(),
                                              points.reactions)]
    return history_row(case, t, dt, info, points.stress, points.stretching,
                       points.nodes[top], nodes0[top], probes=probes,
                       uniqueness=uniqueness, segments=segments, cells=points.cells.cells,
                       rcond=points.rcond)


def _snapshot(model, points, t):
    s = model.case.efg
    at = ShapeFunctions.build(points.nodes, points.nodes, s.weight_p, s.scale_p,
                              key="efg.scale_p")
    p, q = invariants(points.stress)
    data = {"u": points.nodes - model.case.nodes(), "p_w": at.phi @ points.p,
            "p_eff": p, "q": q, "stretching": points.stretching,
            "support_radius": at.support}
    data.update({k: v for k, v in points.state.items()})
    data.update(permeability(model.case, points.state["v"]))
    return Snapshot(t, points.nodes.copy(), data)
