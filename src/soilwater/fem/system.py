"""One FEM step: its discretisation (:func:`discretise`) and Newton system
(:class:`System`).

The residual and tangent are :mod:`soilwater.physics.weakform`'s at the quadrature
points, scattered with the element bases, condensed onto the reduced unknowns of the
exact essential conditions (:class:`soilwater.fem.constraints.Constraints`) and bordered
by the mean-pressure multiplier when the pressure is pinned. The linear solvers treat
the tangents by the element pair's :class:`soilwater.linalg.layout.Policy`
(:func:`_layout`).
"""

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from soilwater.diagnostics.bifurcation import h1_gram, restricted_eigenvalue
from soilwater.fem.assembly import Shapes, block
from soilwater.fem.spaces import cell_bases
from soilwater.linalg.layout import Layout, Policy
from soilwater.material.kinematics import cauchy_traction, prescribed_increment
from soilwater.material.regions import fluid_at
from soilwater.nonlinear.history import timed
from soilwater.nonlinear.newton import material_update
from soilwater.physics import weakform
from soilwater.physics.geostatic import buoyant_weight, total_stress


@dataclass
class Discretisation:
    """Bases of the current mesh: shape data, quadrature weights, external forces."""

    u: Shapes
    p: Shapes
    dx: np.ndarray           # (E, Q) [m2]
    doflocs: np.ndarray      # (2, n_u) current DOF positions [m]
    external: np.ndarray     # (2 n_u,) boundary forces at t_(n+1) [force per thickness]


def discretise(model, topology, vertices, t1, timings, load=None):
    """Bases on the mesh of ``topology`` at ``vertices`` and the boundary forces at
    ``t1`` (under the load factor ``load`` if not the case's at t1); phase times added to
    ``timings``."""
    space = topology.space
    with timed(timings, "cells_s"):
        mesh = space.moved(vertices)
    with timed(timings, "shape_functions_s"):
        ub, pb = cell_bases(mesh, space.pair)
        external = np.zeros(2 * space.n_u)
        factor = model.case.loading.factor(t1) if load is None else load
        for name, edge in model.case.boundary.items():
            if len(space.edge_facets[name]) == 0:
                continue
            fb = space.facet_basis(mesh, name)
            x0 = np.asarray(space.facet_basis(space.mesh0, name).global_coordinates())
            sigma0 = total_stress(model.case, model.material, x0.reshape(2, -1).T)
            traction = cauchy_traction(sigma0.reshape(x0.shape[1:] + (4,)),
                                       np.moveaxis(fb.normals, 0, -1))
            loaded = np.array([edge.ux, edge.uy]) == "free"
            bare = ~topology.constraints.unloaded[name][:, None, None]
            given = edge.traction_at(x0.reshape(2, -1).T).reshape(x0.shape[1:] + (2,))
            traction = traction + bare * loaded * given * factor
            external += Shapes.of(fb).vector(np.concatenate(
                [(fb.dx[..., None] * traction)[..., None],
                 np.zeros(traction.shape + (2,))], -1))
    return Discretisation(Shapes.of(ub), Shapes.of(pb), ub.dx, ub.doflocs, external)


class System:
    """One step's Newton system (:func:`soilwater.nonlinear.newton.newton`) on the reduced
    unknowns.

    The full unknowns ``x = [du_x, du_y, p]`` start from the predictor (the last step's
    velocity x dt, essential values imposed); Newton corrects the free ones and the plate
    through ``Constraints.T``, plus the mean-pressure multiplier when pinned.
    """

    def __init__(self, model, current, disc, t0, t1, timings, load=None):
        case, con, n_u = model.case, current.topology.constraints, disc.u.n
        self.model, self.current, self.disc, self.timings = model, current, disc, timings
        self.con = con
        self.dt, self.t1, self.load, self.n_u = t1 - t0, t1, load, n_u
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
        R, self.total = domain_residual(model, disc, self.current, self.x, self.stress, self.J,
                                  self.Finv, self.dt)
        R += self.lam * self.c_mean
        self.R = R
        reduced = con.T.T @ R
        if len(con.plate):
            reduced[-1] -= model.case.plate_force(self.t1, self.load)
        sc = model.scales
        pin = self.c_mean @ (self.x - np.concatenate([np.zeros(2 * n_u), self.current.p]))
        residual = scaled_norm(reduced, con, sc.force, sc.volume, sc.pin_pressure * pin)
        return (np.append(reduced, pin) if sc.pin_pressure else reduced), residual

    def domain_tangent(self):
        """The tangent of the reduced unknowns (essential conditions eliminated)."""
        T = self.con.T
        return T.T @ _tangent(self.model, self.disc, self.current, self.x, self.stress,
                              self.total, self.material_tangent, self.J, self.Finv,
                              self.dt) @ T

    def tangent(self):
        """:meth:`domain_tangent` bordered by the mean-pressure pin, if any."""
        return bordered(self.domain_tangent(), self.con.T.T @ self.c_mean,
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
        indicator = 0.0
        if self.model.case.diagnostics.uniqueness:
            indicator = uniqueness(self.model, self.con, self.disc, self.domain_tangent())
        reactions = np.array([self.R[dofs].sum() for dofs in self.con.segment_dofs])
        return replace(current, vertices=current.vertices + du, stress=self.stress,
                       state=self.state, p=x[2 * n_u:],
                       weights=self.disc.dx.ravel() * self.J,
                       stretching=self.deps / self.dt, velocity=x[:2 * n_u] / self.dt,
                       uniqueness=indicator, reactions=reactions)


def _layout(T, n_u, u_locations, mass, scales, pair):
    """The :class:`soilwater.linalg.layout.Layout` of the reduced unknowns (``T``'s columns,
    the mean-pressure multiplier last when pinned): a column of one full DOF has its field,
    the plate's column (many) none; solved by the element ``pair``'s :func:`policy`."""
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
    return Layout.of(policy(pair),
                     fields=np.append(reduced, np.full(pin, -1)),
                     locations=np.concatenate([locations[first], np.zeros((pin, 2))]),
                     scales=np.append(scale, [scales.volume] * pin),
                     mass=sp.diags(np.append(np.where(reduced == 2, T.T @ mass, 0.0),
                                             [0.0] * pin)),
                     modulus=scales.modulus)


def policy(pair):
    """How the linear solvers treat the tangents of the element ``pair``
    (:class:`soilwater.fem.spaces.Pair`): its smoother, whether the Krylov back-end suits
    it and whether PARDISO factorises it in single precision; the default forcing cap
    (:data:`soilwater.linalg.layout.FORCING_MAX`) and strength threshold."""
    return Policy(iterative=pair.iterative, single=pair.single, smoother=pair.smoother)


def domain_residual(model, disc, current, x, stress, J, Finv, dt):
    """Full residual ``[R_u, R_p]`` and the total stress at the quadrature points
    (:func:`soilwater.physics.weakform.residual`, scattered with the element bases)."""
    fluid, n_u = fluid_at(model.case.fluid, model.material, current.state), disc.u.n
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
    """The full Jacobian of :func:`domain_residual` with respect to ``[du, p]`` at the
    unknowns x (:func:`soilwater.physics.weakform.tangent`, assembled block by block)."""
    E, Q = disc.dx.shape
    grad_p = disc.p.values(x[2 * disc.u.n:]).reshape(E * Q, 3)[:, 1:]
    c = weakform.tangent(tangent, stress, total, J, Finv, disc.dx.ravel(),
                         fluid_at(model.case.fluid, model.material, current.state), dt,
                         model.beta, current.state["v"], grad_p)
    fields = ((disc.u, range(0, 2)), (disc.p, range(2, 3)))         # (basis, fields)
    return sp.bmat([[block(test, trial, c.block(f, g)) for trial, g in fields]
                    for test, f in fields], format="csr")


def uniqueness(model, con, disc, K):
    """:func:`soilwater.diagnostics.bifurcation.restricted_eigenvalue` of a step's converged
    tangent (essential conditions eliminated, the plate included) over the initial P-wave
    modulus: the displacement block on the undrained constraint (the free pressure rows),
    against the H1 Gram matrix of the displacement basis (length scale: the body's
    height)."""
    gram = h1_gram(disc.dx.ravel(), model.case.geometry.height)
    u = con.T[:, con.is_u][:2 * disc.u.n]
    G = u.T @ block(disc.u, disc.u, gram) @ u
    K = sp.csr_matrix(K)
    value = restricted_eigenvalue(K[con.is_u][:, con.is_u], K[~con.is_u][:, con.is_u], G)
    return value / model.scales.modulus


def bordered(K, c, pin):
    """The condensed tangent, bordered by the mean-pressure pin if any."""
    if not pin:
        return K
    c = sp.csr_matrix(c[:, None])
    return sp.bmat([[K, c], [c.T, None]], format="csr")


def scaled_norm(reduced, con, force, volume, pin):
    """Scaled residual: displacement and plate rows / force, pressure rows / volume, pin."""
    return max(np.abs(reduced[con.is_u]).max(initial=0) / force,
               np.abs(reduced[~con.is_u]).max(initial=0) / volume, abs(pin) / volume)
