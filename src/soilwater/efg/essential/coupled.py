"""Nitsche's method in one coupled EFG step (``efg.essential = "nitsche"``).

:class:`NitscheStep` evaluates the coupled u-p weak form at the boundary points (the
flux that the consistency term carries through the boundary) and applies the terms of
:class:`soilwater.efg.essential.nitsche.Nitsche`, whose stabilisation beta it bounds per
field (:func:`_nitsche_terms`).
"""

from dataclasses import replace

import numpy as np

from soilwater.efg.discretisation import gradient, pressure_gradient
from soilwater.efg.essential import nitsche
from soilwater.material.kinematics import cauchy_traction, invariants
from soilwater.material.regions import fluid_at
from soilwater.nonlinear.newton import material_update
from soilwater.physics import weakform


class NitscheStep:
    """Nitsche's method in one step (``efg.essential = "nitsche"``): the weak form at the
    boundary points and the terms of :class:`soilwater.efg.essential.nitsche.Nitsche` on
    ``(ux, uy, p_w)``.

    The boundary points take stress and state from the nodes as the integration points do
    (``efg.integration = "paper"``) or carry their own (``"gauss"``, ``"nodal"``: those that
    satisfied the last step's equilibrium, :meth:`carried`), take p_w from the nodes, and
    their material update gives the flux (first Piola stress ``J sigma F^-T``, Darcy
    term) that the consistency term carries through the boundary. The reference operators
    are frozen over the step: the isotropic elastic moduli of the start-of-step state for u,
    ``-dt k/gamma_w`` at the start-of-step void ratio for p_w. beta =
    :data:`soilwater.efg.essential.nitsche.SAFETY` x
    :func:`soilwater.efg.essential.nitsche.largest_eigenvalue` per field, the bound of p_w
    taken with ``dt k/gamma_w + (S + alpha^2/M) h^2``, the scale of the pressure penalty:
    with k = 0 (no flux, so no consistency or adjoint term) a drained condition is then
    still held, by the stabilisation alone (a penalty of the order of that scale over h, not
    10^6 times it).
    """

    def __init__(self, model, points, disc, dt, domain):
        sub, spb = disc.sub, disc.spb
        self.model, self.disc, self.dt = model, disc, dt
        if model.consistent:
            stress_n, state_n = points.boundary_stress, points.boundary_state
        else:
            stress_n, state_n = sub.phi @ points.stress, {k: sub.phi @ v
                                                          for k, v in points.state.items()}
        self.all_n = stress_n, state_n
        self.terms = _nitsche_terms(model, disc, dt, domain, (stress_n, state_n))
        # the weak form only where a component is held: a free point carries no term
        # (and the soil at a free surface may be past what its return mapping handles)
        self.held = h = np.flatnonzero(self.terms.mask.any(axis=1))
        self.stress_n, self.state_n = stress_n[h], {k: v[h] for k, v in state_n.items()}
        self.p_n = (spb.phi @ points.p)[h]
        self.grad_p_n = pressure_gradient(spb, points.p)[h]
        initial = cauchy_traction(model.sigma0_bp, disc.bp.normal)          # (G, 2)
        self.initial = (self.terms.mask * disc.bp.weights[:, None]
                        * np.column_stack([initial, np.zeros(len(initial))]))

    def residual(self, du, p, gaps, timings):
        """Residual coefficients (G, 3, 3) of the iterate ``du``, ``p`` with the gaps
        (G, 3) of ``(ux, uy, p_w)``."""
        model, disc, h = self.model, self.disc, self.held
        fluid = fluid_at(model.case.fluid, model.material, self.state_n)
        (self.stress, self.state, self.material_tangent, self.J, self.Finv,
         _) = material_update(model.material, self.stress_n, self.state_n,
                              gradient(disc.sub, du, len(p))[h], timings,
                              "a boundary point")
        p_b = (disc.spb.phi @ p)[h]
        self.total = weakform.total_stress(self.stress, p_b, fluid)
        self.grad_p = pressure_gradient(disc.spb, p)[h]
        self.flux = np.zeros(gaps.shape + (3,))
        self.flux[h] = weakform.residual(self.total, self.J, self.Finv,
                                         disc.bp.weights[h], p_b, self.p_n, self.grad_p,
                                         fluid, self.dt, model.beta, self.grad_p_n,
                                         self.state_n["v"])
        return self.terms.residual(self.flux, gaps)

    def tangent(self):
        """Tangent coefficients (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3
        fields) at the last :meth:`residual`:
        :meth:`soilwater.efg.essential.nitsche.Nitsche.tangent` of the weak form's tangent
        at the boundary points (zero at the free ones)."""
        c = weakform.tangent(self.material_tangent, self.stress, self.total, self.J,
                             self.Finv, self.disc.bp.weights[self.held],
                             fluid_at(self.model.case.fluid, self.model.material,
                                      self.state_n), self.dt, self.model.beta,
                             self.state_n["v"], self.grad_p)
        values = np.zeros((len(self.disc.bp.weights), c.values.shape[1]))
        values[self.held] = c.values
        return self.terms.tangent(replace(c, values=values))

    def carried(self):
        """Stress (G, 4) and state at every boundary point after the last
        :meth:`residual`: the held points' update, the free points' start-of-step values
        (they carry no term, so their state never enters a step)."""
        stress, state = self.all_n
        stress, state = stress.copy(), {k: v.copy() for k, v in state.items()}
        stress[self.held] = self.stress
        for k, v in self.state.items():
            state[k][self.held] = v
        return stress, state

    def reaction(self, gaps):
        """Force of the support on the soil at each point (G, 3) at the last
        :meth:`residual` (:meth:`soilwater.efg.essential.nitsche.Nitsche.reaction`) beyond
        the initial total stress's traction, as the penalty's gap forces are: that traction
        is the boundary's load where free, and part of the flux where held."""
        return self.terms.reaction(self.flux, gaps) - self.initial


def _nitsche_terms(model, disc, dt, domain, boundary):
    """:class:`soilwater.efg.essential.nitsche.Nitsche` of a step on ``(ux, uy, p_w)`` (see
    :class:`NitscheStep`); ``domain`` and ``boundary`` are the start-of-step ``(stress,
    state)`` at the integration and the boundary points."""
    fluid, sc, bc, bp = model.case.fluid, model.scales, disc.bc, disc.bp
    compressibility = (fluid.storage + fluid.biot_alpha**2 / sc.modulus) * sc.h**2
    (stress, state), (stress_b, state_b) = domain, boundary
    v, v_b = state["v"], state_b["v"]

    def darcy(at, extra=0.0):        # (0, 1 + k, 0, 1 + k) of one field, no weight
        value = dt * fluid_at(fluid, model.material, at).mobility_at(at["v"])[0] + extra
        return weakform.Coefficients.of({(0, 1 + k, 0, 1 + k): value for k in range(2)},
                                        (1, 1))

    mask = np.column_stack([bc.constrained[:, 0], bc.constrained[:, 1] | bc.rigid,
                            bc.drained])
    D = _elastic_operator(model.material, stress_b, v_b).columns()
    for (_, s, _, t), value in darcy(state_b).columns().items():
        D[2, s, 2, t] = -value                     # the continuity equation's sign
    terms = nitsche.Nitsche.build(bp, mask, weakform.Coefficients.of(D, (3, 3)),
                                  np.zeros(3))
    u = range(2)
    lam_u = nitsche.largest_eigenvalue(
        (disc.su, disc.w, _elastic_operator(model.material, stress, v)),
        (disc.sub, bp.weights, terms.operator.block(u, u)))
    lam_p = nitsche.largest_eigenvalue(
        (disc.sp, disc.w, darcy(state, compressibility)),
        (disc.spb, bp.weights, nitsche.flux_operator(bp, mask[:, 2:],
                                                     darcy(state_b, compressibility))))
    return replace(terms, beta=nitsche.SAFETY * np.array([lam_u, lam_u, -lam_p]))


def _elastic_operator(material, stress, v):
    """The gradient operator (:func:`soilwater.efg.essential.nitsche.gradient_operator`) of
    the material's isotropic elastic moduli at the states ``(stress, v)``: the gradient
    terms of 2 x 2 fields at the P points [kPa]."""
    p, _ = invariants(stress)
    K, G = material.moduli(p, v)
    return nitsche.gradient_operator(nitsche.isotropic(*np.broadcast_arrays(K, G, p)[:2]))
