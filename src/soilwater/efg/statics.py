"""Static linear elasticity with EFG (plane strain): the proving ground of the EFG core.

One solve of ``(K + K_essential) u = f_traction + f_essential`` on the case's nodes, with
the case's ``[efg]`` settings (weight, scale factor, background cells or nodal
integration, Gauss order, essential conditions by penalty or by Nitsche's method
(:mod:`soilwater.efg.essential.nitsche`, reference operator the elastic stiffness
itself), gradient correction: with ``vci`` the stiffness pairs corrected test gradients
with MLS trial gradients and is not symmetric; SuperLU solves it).
Prescribed displacements are those of the case at ``time.end``: ``fixed`` is zero,
``prescribed`` is ``L x t_end`` and ``exact`` comes from the case's ``[exact]`` solution,
which also gives ``exact`` tractions and the reference for the error norms.

Reported fields are interpolated, ``u^h(x_I) = sum_J phi_J(x_I) u_J``, never the nodal
parameters ``u_J``.
"""

import time
from dataclasses import replace

import numpy as np
import pandas as pd
import scipy.sparse.linalg as spla

from soilwater.efg.essential import nitsche
from soilwater.efg import quadrature
from soilwater.efg import smoothing, vci
from soilwater.efg.assembly import Pattern, elasticity_coefficients, scatter
from soilwater.efg.boundary import (boundary_points, conditions, load_vector, penalty_coefficients,
                          segment_edges)
from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.settings import check
from soilwater.references.closed_forms import strain_from_stress
from soilwater.material.kinematics import cauchy_traction
from soilwater.errors import InputError
from soilwater.geometry.triangulation import delaunay_triangles
from soilwater.results import Result, Snapshot


def penalty_factor(material, case, factor):
    """``factor x M / h``: P-wave modulus of the material over the smallest spacing."""
    return factor * material.constrained_modulus() / min(case.spacing)


def solve(case):
    """Solve the case as static linear elasticity with EFG and return a :class:`Result`.

    Raises
    ------
    InputError
        If the material is not elastic, or the settings are a combination no scheme can
        take (:func:`soilwater.efg.settings.check`).
    """
    check(case.efg)
    material = case.material()
    if material.plastic:
        raise InputError(f"case {case.name!r}: static EFG elasticity needs material.model "
                         "= 'elastic'")
    settings, exact = case.efg, case.exact_solution()
    tic = time.perf_counter()
    nodes = case.nodes()
    loop = case.boundary_loop()
    def build(points):
        return ShapeFunctions.build(nodes, points, settings.weight_u, settings.scale_u)

    if settings.integration == "nodal":
        quad = smoothing.nodal_cells(nodes, delaunay_triangles(nodes, nodes[loop])[0])
        shape = smoothing.shape_functions(quad, build, settings.order)
    else:
        quad = quadrature.background(case, nodes, loop, settings)
        shape = build(quad.points)
    bp = boundary_points(nodes, loop, segment_edges(nodes, loop, case.geometry))
    shape_b = ShapeFunctions.build(nodes, bp.points, settings.weight_u, settings.scale_u)
    test = shape
    if settings.correction == "vci":
        test = vci.corrected(shape, quad.weights, shape_b, bp.weights, bp.normal)
    constrained, u_bar, traction, loaded = boundary_data(case, bp, exact)
    pattern = Pattern.build((test, shape), (shape_b, shape_b))
    values = scatter(pattern, test, shape,
                     elasticity_coefficients(quad.weights, material.stiffness))
    essential = _nitsche if settings.essential == "nitsche" else _penalty
    boundary, f_essential, factors = essential(case, material, (shape, quad.weights),
                                               shape_b, bp, constrained, u_bar)
    K = pattern.matrix(scatter(pattern, shape_b, shape_b, boundary, values), 2, 2)
    rhs = load_vector(shape_b.phi, bp, traction, loaded) + f_essential
    coefficients = spla.spsolve(K.tocsc(), rhs)
    wall = time.perf_counter() - tic

    n = len(nodes)
    at_nodes = ShapeFunctions.build(nodes, nodes, settings.weight_u, settings.scale_u)
    u_nodes = _interpolate(at_nodes, coefficients, n)
    stress_nodes = _strain(at_nodes, coefficients, n) @ material.stiffness.T
    errors = error_norms(shape, quad.weights, coefficients, material, exact, quad.points,
                         at_nodes, u_nodes, nodes) if exact else {}
    summary = {"steps": 1, "dofs": 2 * n, "integration_points": len(quad.weights),
               **factors, "timings": {"solve_s": wall}, "errors": errors}
    history = pd.DataFrame([{"time": case.times()[-1], **errors}])
    snapshot = Snapshot(case.times()[-1], nodes + u_nodes,
                        {"u": u_nodes, "stress": stress_nodes,
                         "support_radius": at_nodes.support})
    return Result(case, "efg", settings.to_dict(), history, [snapshot], summary)


def _penalty(case, material, domain, shape_b, bp, constrained, u_bar):
    """Penalty coefficients (:class:`soilwater.physics.weakform.Coefficients` of 2 x 2
    fields at the G boundary points), right-hand side (2N,) and factor."""
    alpha = penalty_factor(material, case, case.efg.penalty)
    return (penalty_coefficients(bp, constrained, alpha),
            load_vector(shape_b.phi, bp, alpha * u_bar, constrained),
            {"penalty_alpha": alpha})


def _nitsche(case, material, domain, shape_b, bp, constrained, u_bar):
    """Nitsche coefficients (:class:`soilwater.physics.weakform.Coefficients` of 2 x 2
    fields at the G boundary points), right-hand side (2N,) and beta [kPa/m]: the reference operator
    is
    the stiffness itself, so the consistency and adjoint terms cancel in ``v K v``
    (:mod:`soilwater.efg.essential.nitsche`).

    The terms are linear in u: the right-hand side is minus the residual of u = 0, whose
    flux is zero and gap ``-u_bar``, i.e. the terms of the gap ``u_bar``."""
    shape, weights = domain
    K, G = material.moduli()
    D_b, D = (nitsche.gradient_operator(nitsche.isotropic(np.full(m, K), np.full(m, G)))
              for m in (len(bp.weights), len(weights)))
    terms = nitsche.Nitsche.build(bp, constrained, D_b, np.zeros(2))
    beta = nitsche.SAFETY * nitsche.largest_eigenvalue(
        (shape, weights, D), (shape_b, bp.weights, terms.operator))
    terms = replace(terms, beta=np.full(2, beta))
    r = terms.residual(np.zeros(u_bar.shape + (3,)), u_bar)
    coeff = terms.tangent(elasticity_coefficients(bp.weights, material.stiffness))
    return (coeff, np.concatenate([shape_b.tested(r[:, f]) for f in range(2)]),
            {"nitsche_beta": beta})


def boundary_data(case, bp, exact):
    """Constrained components, prescribed values, tractions and loaded components at bp.

    Returns four (G, 2) arrays: bool constrained, prescribed displacement at ``time.end``,
    traction [stress unit], bool loaded (components that carry a traction).
    """
    t_end = case.times()[-1]
    bc = conditions(case, bp)
    u_bar = np.zeros_like(bc.traction)
    prescribed = bc.kind == "prescribed"
    u_bar[prescribed] = (bp.points @ case.loading.L.T * t_end)[prescribed]
    traction = bc.traction * case.loading.factor(t_end)
    if exact is not None:
        u_exact, s_exact = exact(bp.points)
        u_bar[bc.kind == "exact"] = u_exact[bc.kind == "exact"]
        traction[bc.exact_traction] = cauchy_traction(s_exact, bp.normal)[bc.exact_traction]
    return bc.constrained, u_bar, traction, bc.loaded


def _interpolate(shape, coefficients, n):
    """``u^h`` at the shape functions' points, (P, 2)."""
    return np.stack([shape.phi @ coefficients[:n], shape.phi @ coefficients[n:]], axis=1)


def _strain(shape, coefficients, n):
    """Voigt strain ``(xx, yy, zz, 2xy)`` at the shape functions' points, (P, 4)."""
    ux, uy = coefficients[:n], coefficients[n:]
    exx, eyy = shape.dphi_dx @ ux, shape.dphi_dy @ uy
    return np.stack([exx, eyy, 0 * exx, shape.dphi_dy @ ux + shape.dphi_dx @ uy], axis=1)


def error_norms(shape, weights, coefficients, material, exact, points, at_nodes, u_nodes,
                nodes):
    """Relative errors against the exact solution.

    ``displacement``: max ``|u^h - u|`` at the nodes over max ``|u|``; ``stress``: max
    over the integration points of ``|sigma^h - sigma|`` over max ``|sigma|``;
    ``energy``: the energy norm ``sqrt(int (eps^h - eps) : C : (eps^h - eps))`` over that
    of the exact solution.
    """
    n = len(nodes)
    u_ex, _ = exact(nodes)
    _, s_ex = exact(points)
    C = material.stiffness
    eps_h = _strain(shape, coefficients, n)
    eps_ex = strain_from_stress(s_ex, material.E, material.nu)
    de = eps_h - eps_ex
    energy = np.sqrt(np.sum(weights * np.einsum("pi,ij,pj->p", de, C, de))
                     / np.sum(weights * np.einsum("pi,ij,pj->p", eps_ex, C, eps_ex)))
    s_h = eps_h @ C.T
    return {
        "displacement": float(np.abs(u_nodes - u_ex).max() / np.abs(u_ex).max()),
        "stress": float(np.abs(s_h - s_ex).max() / np.abs(s_ex).max()),
        "energy": float(energy),
    }
