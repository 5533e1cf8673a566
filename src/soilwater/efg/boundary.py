"""Boundary integration points, penalty essential conditions and traction loads.

The boundary is the closed loop of boundary nodes (counter-clockwise) in the current
configuration; each segment between two consecutive loop nodes belongs to one edge of the
case (left, right, bottom, top, or a mesh's boundary group), fixed from the initial
configuration. Gauss points on the
segments carry line weights [m per unit thickness] and outward normals.

Essential conditions are imposed by penalty (Zhu and Atluri 1998): for a constrained
component f, ``alpha int_Gamma phi_a phi_b dGamma`` joins the stiffness and
``alpha int_Gamma phi_a u_bar dGamma`` the right-hand side. ``alpha`` is a factor times the
stiffness scale of the material divided by the nodal spacing, so it has the units of a
stiffness per area and its size relative to the bulk stiffness is the factor itself.
"""

from dataclasses import dataclass

import numpy as np

from soilwater.material.kinematics import prescribed_increment
from soilwater.physics.weakform import Coefficients


@dataclass(frozen=True)
class BoundaryPoints:
    """Gauss points on the boundary segments.

    Attributes
    ----------
    points : ndarray, shape (G, 2)
        Current coordinates [m].
    weights : ndarray, shape (G,)
        Line weights [m per unit thickness].
    edge : ndarray, shape (G,)
        Index into ``case.boundary.items()`` of each point's edge.
    normal : ndarray, shape (G, 2)
        Unit outward normals.
    """

    points: np.ndarray
    weights: np.ndarray
    edge: np.ndarray
    normal: np.ndarray


def segment_edges(initial_nodes, loop, geometry):
    """Edge index of each loop segment ``(loop[k], loop[k + 1])``, from initial positions
    (:meth:`soilwater.case.domain.Geometry.edge_of`)."""
    return geometry.edge_of(initial_nodes[loop], initial_nodes[np.roll(loop, -1)])


#: Gauss points per boundary segment (penalties, tractions, the solver's gaps).
BOUNDARY_ORDER = 2


def boundary_points(nodes, loop, edges, order=BOUNDARY_ORDER):
    """Gauss points of every boundary segment in the current configuration.

    Parameters
    ----------
    nodes : ndarray, shape (N, 2)
        Current node coordinates [m].
    loop : ndarray of int
        Boundary nodes, counter-clockwise.
    edges : ndarray of int
        Edge index of each segment (:func:`segment_edges`): its position in
        ``case.boundary.items()``.
    order : int
        Gauss points per segment.
    """
    xi, w = np.polynomial.legendre.leggauss(order)
    a, b = nodes[loop], nodes[np.roll(loop, -1)]
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    points = a[:, None, :] + (0.5 * (1 + xi))[None, :, None] * d[:, None, :]
    normal = np.stack([d[:, 1], -d[:, 0]], axis=1) / length[:, None]
    return BoundaryPoints(points.reshape(-1, 2), (0.5 * length[:, None] * w).ravel(),
                          np.repeat(edges, order), np.repeat(normal, order, axis=0))


@dataclass(frozen=True)
class Conditions:
    """Kinds of condition at each boundary point, from the case's edges and segments.

    Attributes
    ----------
    kind : ndarray of str, shape (G, 2)
        ``free``, ``fixed``, ``prescribed``, ``exact``, ``rigid`` (the plate: a ``rigid``
        edge or a load-controlled footing) or ``footing`` (uy of a velocity-controlled
        footing) per component.
    traction : ndarray, shape (G, 2)
        The edge's traction at each point [stress unit] (zero where ``exact``, see
        ``exact_traction``, and on named segments, which carry none but a mesh group's whole
        one).
    exact_traction : ndarray of bool, shape (G,)
        Whether the edge takes its traction from the case's exact solution.
    drained : ndarray of bool, shape (G,)
        Whether p_w = 0 is imposed.
    segment : ndarray of int, shape (G,)
        Index into ``case.boundary.segments()`` of each point's segment, -1 for none.
    rate : ndarray, shape (G,)
        Settlement rate [m/s, positive down] of a velocity-controlled footing, else 0.
    """

    kind: np.ndarray
    traction: np.ndarray
    exact_traction: np.ndarray
    drained: np.ndarray
    segment: np.ndarray
    rate: np.ndarray

    @property
    def constrained(self):
        """(G, 2) bool: components whose displacement is imposed by penalty."""
        return np.isin(self.kind, ("fixed", "prescribed", "exact", "footing"))

    @property
    def loaded(self):
        """(G, 2) bool: components that carry the edge's traction (rigid ones pass it to
        the plate)."""
        return self.kind == "free"

    @property
    def rigid(self):
        """(G,) bool: points whose uy follows the rigid plate."""
        return self.kind[:, 1] == "rigid"

    def target_increment(self, L, points, dt):
        """(G, 2) increment of the imposed displacement over a step dt [m]: ``(exp(L dt) -
        I) x`` on ``prescribed`` components (at the current points x), ``-rate dt`` on a
        footing's uy, 0 elsewhere."""
        du = np.where(self.kind == "prescribed", prescribed_increment(L, points, dt), 0.0)
        du[:, 1] -= self.rate * dt
        return du


def conditions(case, bpoints, initial=None):
    """The case's boundary conditions at the boundary points (vectorised per edge).

    Parameters
    ----------
    case : Case
    bpoints : BoundaryPoints
    initial : ndarray, shape (G, 2), optional
        The points' positions in the initial configuration [m], which decide whether a
        point lies on a named segment; ``bpoints.points`` by default.
    """
    initial = bpoints.points if initial is None else initial
    G = len(bpoints.weights)
    kind, drained = np.full((G, 2), "free", dtype="<U10"), np.zeros(G, bool)
    segment, traction = np.full(G, -1), np.zeros((G, 2))
    exact = np.zeros(G, bool)
    first = 0
    for k, (side, edge) in enumerate(case.boundary.items()):
        on = bpoints.edge == k
        kind[on], drained[on], seg = case.edge_conditions(side, initial[on])
        segment[on] = np.where(seg >= 0, seg + first, -1)
        exact[on] = edge.traction == "exact"
        if edge.traction != "exact":
            traction[on] = np.where(edge.loaded(seg)[:, None], edge.traction_at(initial[on]),
                                    0.0)
        first += len(edge.segments)
    rates = np.array([seg.settlement_rate if seg.footing and not seg.load_controlled
                      else 0.0 for _, seg in case.boundary.segments()] + [0.0])
    return Conditions(kind, traction, exact, drained, segment, rates[segment])


def penalty_coefficients(bpoints, constrained, alpha):
    """Coefficients of the penalty block for the displacement fields at the G points.

    Parameters
    ----------
    bpoints : BoundaryPoints
    constrained : ndarray of bool, shape (G, 2)
        Whether component x / y is prescribed at each boundary point.
    alpha : float
        Penalty factor [stiffness per area].

    Returns
    -------
    soilwater.physics.weakform.Coefficients
        2 x 2 fields, the value terms ``(f, 0, f, 0) = alpha w`` where component f is
        constrained, else 0 [alpha's unit times m].
    """
    return Coefficients.of({(f, 0, f, 0): alpha * bpoints.weights * constrained[:, f]
                            for f in range(2)}, (2, 2))


def load_vector(phi_boundary, bpoints, values, mask):
    """``int_Gamma phi_a v_f dGamma`` on the masked points, fields blocked (2N,).

    Parameters
    ----------
    phi_boundary : scipy.sparse matrix, shape (G, N)
        Shape functions at the boundary points.
    values : ndarray, shape (G, 2)
        Traction [kPa], or penalty factor times prescribed displacement.
    mask : ndarray of bool, shape (G, 2)
    """
    weighted = np.where(mask, values, 0.0) * bpoints.weights[:, None]
    return np.concatenate([phi_boundary.T @ weighted[:, 0], phi_boundary.T @ weighted[:, 1]])
