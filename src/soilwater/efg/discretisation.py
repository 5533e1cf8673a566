"""One configuration of an EFG step: shape functions, cells, boundary points and patterns.

:func:`discretise` builds a :class:`Discretisation` on the nodes of the start of a step
(the updated-Lagrangian configuration x_n): the background cells and their Gauss points,
the MLS shape functions of u and p_w there and at the boundary points (VCI-corrected
test functions with ``efg.correction = "vci"``), the essential conditions at the
boundary points and the sparsity patterns of the tangent's blocks. :func:`gradient` and
:func:`pressure_gradient` differentiate nodal parameters at its points.
"""

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from soilwater.efg import smoothing, vci
from soilwater.efg.assembly import Pattern, scatter
from soilwater.efg.boundary import boundary_points, conditions
from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.quadrature import background
from soilwater.nonlinear.history import timed
from soilwater.physics import weakform


@dataclass
class Discretisation:
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
    triangles: np.ndarray | None = None

    @property
    def shared(self):
        """True when u and p_w use the same shape functions: one three-field pattern."""
        return self.tu is self.tp and self.su is self.sp and self.sub is self.spb

    @cached_property
    def fluctuation(self):
        """:func:`soilwater.physics.weakform.fluctuation` of the MLS pressure over the
        background cells."""
        return weakform.fluctuation(self.sp.phi, self.w, self.cell)

    @cached_property
    def boundary_magnitudes(self):
        """``|phi|`` of u and p_w at the boundary points, for
        :func:`soilwater.efg.essential.penalty.roundoff`."""
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
        (:class:`soilwater.physics.weakform.Coefficients` of 3 x 3 fields) at the
        integration points and at the boundary points; with separate u and p_w shape
        functions, each block takes a copy of its own terms (Nitsche's couple u and p_w on
        the boundary too)."""
        if self.shared:
            return self.block("domain", coeff, boundary)
        u, p = range(0, 2), range(2, 3)
        return sp.bmat([
            [self.block("uu", coeff.block(u, u), boundary.block(u, u)),
             self.block("up", coeff.block(u, p), boundary.block(u, p))],
            [self.block("pu", coeff.block(p, u), boundary.block(p, u)),
             self.block("pp", coeff.block(p, p), boundary.block(p, p))]], format="csr")


@dataclass
class AtPoints:
    nodes: ShapeFunctions
    probes: ShapeFunctions


def background_cells(model, nodes):
    """The background cells (:func:`soilwater.efg.quadrature.background`) of the
    configuration ``nodes``."""
    return background(model.case, nodes, model.loop, model.case.efg)


def min_rcond(disc):
    """Smallest reciprocal condition number of the MLS moment matrices of a step, over
    its integration points: the cells' Gauss points and the boundary points, u and p_w
    (the support-coverage check, :class:`soilwater.efg.mls.ShapeFunctions`)."""
    return float(min(shape.rcond.min(initial=np.inf)
                     for shape in (disc.su, disc.sp, disc.sub, disc.spb)))


def discretise(model, nodes, evaluation, timings, quad=None):
    """Cells (``quad`` when given: the background cells of ``nodes``, built at the end
    of the step before), shape functions (built once when u and p_w share their
    settings) and block patterns on the configuration ``nodes``; phase times added to
    ``timings``."""
    case, s = model.case, model.case.efg
    with timed(timings, "cells_s"):
        quad = background_cells(model, nodes) if quad is None else quad
        bp = boundary_points(nodes, model.loop, model.edges)
    same = (s.weight_u, s.scale_u) == (s.weight_p, s.scale_p)
    supports = {}                        # support radii by scale, searched once

    def build(points, field="u"):
        scale = getattr(s, f"scale_{field}")
        shape = ShapeFunctions.build(nodes, points, getattr(s, f"weight_{field}"), scale,
                                     key=f"efg.scale_{field}", support=supports.get(scale))
        supports.setdefault(scale, shape.support)
        return shape

    def domain(field="u"):
        """At the integration points: MLS, or at the nodes with smoothed gradients."""
        if s.integration != "nodal":
            return build(quad.points, field)
        return smoothing.shape_functions(quad, lambda at: build(at, field), s.order)

    with timed(timings, "shape_functions_s"):
        su, sub = domain(), build(bp.points)
        sp_, spb = (su, sub) if same else (domain("p"), build(bp.points, "p"))
        tu, tp = su, sp_
        if s.correction == "vci":
            tu = vci.corrected(su, quad.weights, sub, bp.weights, bp.normal)
            tp = tu if same else vci.corrected(sp_, quad.weights, spb, bp.weights, bp.normal)
        at = build(evaluation)
        n = len(nodes)
        at_points = AtPoints(at.subset(slice(0, n)), at.subset(slice(n, None)))
        disc = Discretisation(quad.weights, su, sp_, tu, tp, bp, sub, spb,
                               conditions(case, bp, model.initial_bp), at_points, {},
                               quad.cell, quad.triangles)
    with timed(timings, "assembly_s"):
        disc.patterns.update({name: Pattern.build(*pairs)
                              for name, pairs in disc.blocks.items()})
    return disc


def gradient(shape, du, n):
    """``grad_n(du)`` (P, 2, 2): ``H[p, i, j] = d du_i / d x_j``."""
    ux, uy = du[:n], du[n:2 * n]
    return np.stack([np.stack([shape.dphi_dx @ ux, shape.dphi_dy @ ux], 1),
                     np.stack([shape.dphi_dx @ uy, shape.dphi_dy @ uy], 1)], 1)


def pressure_gradient(shape, p):
    """``grad p`` (P, 2) at the shape functions' points [kPa/m]."""
    return np.stack([shape.dphi_dx @ p, shape.dphi_dy @ p], 1)
