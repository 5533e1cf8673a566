"""One EFG step's Newton system (:class:`System`) and the linear-solver policy of EFG.

Unknowns ``[du (2n, fields blocked), p (n), plate settlement?, mean-pressure
multiplier?]``. The residual and tangent are :mod:`soilwater.physics.weakform`'s in the
domain, with the essential conditions by penalty or by Nitsche's method
(:mod:`soilwater.efg.essential`); each residual entry counts beyond its round-off level
(:func:`soilwater.efg.essential.penalty.roundoff`). :func:`policy` is how the linear
solvers treat EFG's tangents (:class:`soilwater.linalg.layout.Policy`), chosen from the
case's EFG settings.
"""

from functools import partial

import numpy as np
import scipy.sparse as sp

from soilwater.efg.boundary import penalty_coefficients
from soilwater.efg.discretisation import gradient, pressure_gradient
from soilwater.efg.essential.coupled import NitscheStep
from soilwater.efg.essential.penalty import excess, factors, roundoff
from soilwater.efg.essential.plate import bordered
from soilwater.efg.model import Points
from soilwater.linalg.layout import Layout, Policy
from soilwater.material.kinematics import cauchy_traction
from soilwater.material.regions import fluid_at
from soilwater.nonlinear.history import timed
from soilwater.nonlinear.newton import material_update
from soilwater.physics import weakform
from soilwater.physics.geostatic import buoyant_weight

#: Strength-of-connection threshold of the Krylov back-end's AMG on EFG tangents
#: (:attr:`soilwater.linalg.layout.Policy.strength`). An MLS support couples each node to
#: many others, weakly at its rim; counting only couplings of at least 1 % makes smaller
#: aggregates and Schwarz subdomains and fewer FGMRES iterations (docs, studies, "Krylov").
STRENGTH = 0.01
#: Largest forcing of the Krylov back-end's inexact Newton on EFG
#: (:attr:`soilwater.linalg.layout.Policy.forcing`). The first correction solved to 1e-5
#: lands where exact Newton's does and Newton converges quadratically from there: the
#: undrained bench step takes 4 residuals at 3e3 to 1e5 nodes against 5 at 1e-4 (whose first
#: iterate is 30 % further off), with fewer FGMRES iterations; 1e-6 as many residuals and
#: more FGMRES iterations (``python docs/experiments/krylov_newton.py --nodes 3000
#: --forcings 1e-2 1e-4 1e-5 1e-6``).
FORCING = 1e-5


class System:
    """One step's Newton system (:func:`soilwater.nonlinear.newton.newton`).

    Unknowns ``[du (2n, fields blocked), p (n), plate settlement?, mean-pressure
    multiplier?]``; :meth:`residual` keeps the iterate's stresses and tangent for
    :meth:`tangent` and :meth:`finish`.
    """

    def __init__(self, model, points, disc, t0, t1, timings, load=None):
        case, bc, su = model.case, disc.bc, disc.su
        self.model, self.points, self.disc, self.timings = model, points, disc, timings
        self.dt, self.n = t1 - t0, len(points.nodes)
        if model.consistent:             # the state that satisfied equilibrium
            self.stress_n, self.state_n = points.stress, points.state
        else:                            # the paper's: MLS of the nodal state
            self.stress_n = su.phi @ points.stress
            self.state_n = {k: su.phi @ v for k, v in points.state.items()}
        self.p_n = disc.sp.phi @ points.p
        self.grad_p_n = pressure_gradient(disc.sp, points.p)
        self.du_bar = bc.target_increment(case.loading.L, disc.bp.points, self.dt)
        self.alpha_u, self.alpha_p = factors(model, [0.0, self.dt]).values()
        self.nitsche = None
        if case.efg.essential == "nitsche":
            with timed(timings, "assembly_s"):        # beta's eigenvalue bounds
                self.nitsche = NitscheStep(model, points, disc, self.dt,
                                           (self.stress_n, self.state_n))
        self.weight = buoyant_weight(case, self.state_n["v"])
        initial = cauchy_traction(model.sigma0_bp, disc.bp.normal)     # (G, 2)
        if self.nitsche is not None:     # held components: their flux carries it
            initial = np.where(self.nitsche.terms.mask[:, :2], 0.0, initial)
        load = case.loading.factor(t1) if load is None else load
        self.traction = initial + bc.traction * bc.loaded * load
        self.plate_force = case.plate_force(t1, load)
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
        bc, fluid = disc.bc, fluid_at(model.case.fluid, model.material, self.state_n)
        (self.stress, self.state, self.material_tangent, self.J, self.Finv,
         self.deps) = material_update(model.material, self.stress_n, self.state_n,
                                      gradient(disc.su, self.du, n), self.timings,
                                      "a background cell")
        p_q = disc.sp.phi @ self.p
        self.total = weakform.total_stress(self.stress, p_q, fluid)
        self.grad_p = pressure_gradient(disc.sp, self.p)
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
        noise_u, noise_p, noise_plate = roundoff(
            disc, points, self.du.reshape(2, n).T, self.du_bar, self.p, self.plate,
            *self._factors, self.rigid_w)
        residual = max(excess(R_u, noise_u) / sc.force, excess(R_p, noise_p) / sc.volume,
                       excess(extra_R[:1], noise_plate) / sc.force * bc.rigid.any(),
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
        """Boundary coefficients (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3
        fields) of the essential conditions, the rigid plate's points included: the
        penalties' value terms ``(f, 0, f, 0)`` or Nitsche's terms."""
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
                        self.state_n, self.grad_p, boundary)

    def tangent(self):
        """:meth:`domain_tangent` bordered by the plate and the pin, if any."""
        boundary = self._essential_tangent()
        return bordered(self.domain_tangent(boundary), self._plate_border(boundary),
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
        """The points after convergence: the converged state at the integration points
        (``gauss``, ``nodal``) or the nodes' own update with D^I (``paper``), positions,
        gaps, probes; with no time increment (a re-equilibration,
        :mod:`soilwater.efg.rebuild`) the stretching of the last step."""
        points, disc, n = self.points, self.disc, self.n
        at = disc.at_points
        if self.model.consistent:
            stress, state, deps = self.stress, self.state, self.deps
        else:
            stress, state, _, _, _, deps = material_update(
                self.model.material, points.stress, points.state,
                gradient(at.nodes, self.du, n), self.timings, "a node")
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
        boundary = (None, None)
        if self.model.consistent and self.nitsche is not None:
            boundary = self.nitsche.carried()
        return Points(nodes=points.nodes + at.nodes.phi @ move, stress=stress, state=state,
                      boundary_stress=boundary[0], boundary_state=boundary[1],
                      p=self.p, gap=np.where(disc.bc.constrained, self.gap, 0.0),
                      plate=self.plate,
                      plate_gap=np.where(disc.bc.rigid, self.plate_gap, 0.0),
                      probes=points.probes + at.probes.phi @ move,
                      stretching=deps / self.dt if self.dt else points.stretching,
                      reactions=reactions)


def _tangent(model, disc, stress, total, tangent, J, Finv, dt, state_n, grad_p, boundary):
    """The Newton tangent of ``(ux, uy, p_w)`` (fields blocked) at the current iterate:
    :func:`soilwater.physics.weakform.tangent` in the domain, the coefficients ``boundary``
    (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3 fields) of the essential
    conditions at the boundary points."""
    coeff = weakform.tangent(tangent, stress, total, J, Finv, disc.w,
                             fluid_at(model.case.fluid, model.material, state_n), dt,
                             model.beta, state_n["v"], grad_p)
    K = disc.tangent(coeff, boundary)
    if not model.tau:
        return K
    n = disc.fluctuation.shape[0]
    return K - model.tau * sp.block_diag([sp.csr_matrix((2 * n, 2 * n)),
                                          disc.fluctuation], format="csr")


def _pressure_mass(disc, extra=0):
    """The consistent pressure mass ``int N_i N_j dV`` [m2 per unit thickness] on the
    pressure rows and columns of ``[ux, uy, p]`` and ``extra`` more unknowns."""
    n = disc.sp.phi.shape[1]
    M = sp.coo_matrix(disc.tp.phi.T @ sp.diags(disc.w) @ disc.sp.phi)
    size = 3 * n + extra
    return sp.csr_matrix((M.data, (M.row + 2 * n, M.col + 2 * n)), shape=(size, size))


def policy(settings):
    """How the linear solvers treat EFG's tangents under the case's EFG ``settings``.

    The Krylov back-end suits EFG with Nitsche's conditions (a penalty's diagonal spans
    10^6: a small residual says nothing of the error) and a pressure stabilisation, and
    PARDISO factorises such a tangent in single precision (measured: ``python
    docs/experiments/direct_single.py``); any other EFG is solved directly in double. Every
    EFG tangent takes the Schwarz smoother, the threshold :data:`STRENGTH` and the
    forcing cap :data:`FORCING` (read when called).

    Examples
    --------
    >>> from soilwater.efg.settings import EFGSettings
    >>> policy(EFGSettings(essential="nitsche", stabilisation="projection")).single
    True
    >>> policy(EFGSettings(essential="penalty")).iterative
    False
    """
    suits = settings.essential == "nitsche" and settings.stabilisation != "none"
    return Policy(iterative=suits, single=suits, forcing=FORCING, smoother="schwarz",
                  strength=STRENGTH)


def _layout(nodes, mass, scales, rigid, settings):
    """The :class:`soilwater.linalg.layout.Layout` of the unknowns ``[ux, uy, p, plate?,
    pin?]`` under the :func:`policy` of ``settings`` (the case's EFG settings);
    ``mass(extra)`` gives the pressure mass matrix."""
    n = len(nodes)
    plate, pin = [scales.force] * int(rigid), [scales.volume] * int(scales.pin_pressure)
    extra = len(plate) + len(pin)
    return Layout.of(policy(settings),
                     groups=np.concatenate([np.tile(np.arange(n), 3), np.full(extra, -1)]),
                     fields=np.concatenate([np.repeat([0, 1, 2], n), np.full(extra, -1)]),
                     locations=np.concatenate([nodes, nodes, nodes, np.zeros((extra, 2))]),
                     scales=np.concatenate([np.full(2 * n, scales.force),
                                            np.full(n, scales.volume), plate, pin]),
                     mass=partial(mass, extra=extra), modulus=scales.modulus)
