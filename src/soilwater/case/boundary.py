"""Boundary conditions of a case: the edges, their kinds and named segments.

Each edge of the rectangle, or boundary group of a mesh (a physical curve,
:mod:`soilwater.geometry.mesh`), is an :class:`Edge` (kinds of ux and uy, a total traction
[kPa], tension positive, and a water condition); a :class:`Segment` overrides the kinds on
a part of a rectangle's edge, e.g. a rigid strip footing, or names a mesh's whole boundary
group that is a footing, displaced or loaded (its history columns). :class:`Boundary` holds the
edges by name: the rectangle's four in :data:`EDGES` order, or the mesh's groups.
Coordinates are those of the initial configuration [m].
"""

from dataclasses import dataclass

import numpy as np

#: The edges of the rectangle, in the order every per-edge loop uses.
EDGES = ("left", "right", "bottom", "top")
#: The kinds of an edge's ux and uy.
KINDS = ("free", "fixed", "prescribed", "rigid", "exact")
SEGMENT_KINDS = {"ux": ("free", "fixed", "prescribed"),
                 "uy": ("free", "fixed", "prescribed", "footing")}
"""The kinds a named segment of an edge (:class:`Segment`) accepts per component."""
#: Water conditions of an edge or segment: p_w = 0 imposed, or no flow across it.
WATER = ("drained", "impermeable")
SEGMENT_TOLERANCE = 1e-9
"""A point within this fraction of the smallest grid spacing of a segment's end belongs to
the segment (:meth:`soilwater.case.model.Case.edge_conditions`)."""


@dataclass(frozen=True)
class Segment:
    """A named part ``[start, end]`` of an edge with its own displacement kinds.

    ``start`` and ``end`` (TOML ``from`` and ``to``) [m] are the coordinate along the edge
    in the initial configuration: x on the top and bottom edges, y on the left and right.
    A boundary point (EFG) or DOF (FEM) whose initial coordinate lies in ``[start, end]``
    takes the segment's kinds; the segment carries no traction. A mesh's boundary group
    that is a footing, displaced (``prescribed``) or loaded is one :attr:`whole` segment,
    ``[-inf, inf]`` and named for the group, carrying the group's kinds and ``traction``
    (None on every other segment).

    ``uy = "footing"`` makes the segment a rigid strip footing whose uy moves as one body:
    either velocity control, ``settlement_rate`` [m/s, positive down] (uy = -rate x t on
    the segment), or load control, ``force`` [kN/m per unit thickness, compression
    positive] times the load factor ``loading.load`` at t, carried by one unknown
    settlement (the machinery of the ``rigid`` plate). ``ux = "fixed"`` is a rough footing
    (no sideways motion), ``ux = "free"`` a smooth one. ``water`` None keeps the edge's
    water condition.
    """

    name: str
    start: float
    end: float
    ux: str = "free"
    uy: str = "free"
    water: str | None = None
    settlement_rate: float | None = None
    force: float | None = None
    traction: tuple | None = None

    @property
    def whole(self):
        """True for a mesh's whole boundary group (``[-inf, inf]``)."""
        return self.start == -np.inf and self.end == np.inf

    @property
    def footing(self):
        """True for a rigid footing (``uy = "footing"``)."""
        return self.uy == "footing"

    @property
    def load_controlled(self):
        """True for a footing carrying a prescribed force (one unknown settlement)."""
        return self.footing and self.force is not None

    @property
    def uy_kind(self):
        """The uy kind the solvers apply: ``rigid`` for a load-controlled footing (the
        plate unknown), ``footing`` for a velocity-controlled one, else ``uy``."""
        return "rigid" if self.load_controlled else self.uy

    def contains(self, s, tol=0.0):
        """(P,) bool: coordinates along the edge ``s`` [m] within ``[start, end]`` +- tol."""
        s = np.asarray(s, float)
        return (s >= self.start - tol) & (s <= self.end + tol)

    def to_dict(self):
        """The segment's TOML table (``from`` and ``to`` unless :attr:`whole`, its kinds
        and footing data)."""
        data = {"ux": self.ux, "uy": self.uy, "water": self.water,
                "settlement_rate": self.settlement_rate, "force": self.force}
        if not self.whole:
            data = {"from": self.start, "to": self.end, **data}
        return {k: v for k, v in data.items() if v is not None}


@dataclass(frozen=True)
class Edge:
    """Conditions on one edge: kinds of ux and uy, total traction [kPa], water condition,
    and named segments (:class:`Segment`) that override the kinds on parts of it.

    ``traction`` is ``(tx, ty)``, ``"exact"`` (the case's exact solution's), or a
    profile ``((x, tx, ty), ...)``: piecewise linear in the initial x [m], constant
    beyond its ends (an embankment's trapezoid on the ground surface).
    """

    ux: str = "free"
    uy: str = "free"
    traction: tuple = (0.0, 0.0)
    water: str = "impermeable"
    segments: tuple[Segment, ...] = ()

    @property
    def profiled(self):
        """True when the traction varies along x (a profile)."""
        return self.traction != "exact" and len(self.traction) > 0 and isinstance(
            self.traction[0], tuple)

    def traction_at(self, points):
        """The traction (P, 2) [kPa] at initial positions ``points`` (P, 2) [m] (not
        for ``"exact"``; :func:`traction_at`)."""
        return traction_at(self.traction, points)

    @property
    def largest_traction(self):
        """The largest traction component in size [kPa] (0 for ``"exact"``)."""
        if self.traction == "exact":
            return 0.0
        values = np.asarray(self.traction, float)
        return float(np.abs(values[:, 1:] if self.profiled else values).max())

    @property
    def drained(self):
        """True if p_w = 0 is imposed on the edge."""
        return self.water == "drained"

    def at(self, s, tol=0.0):
        """The conditions at coordinates ``s`` along the edge (initial configuration).

        Parameters
        ----------
        s : array_like, shape (P,)
            Coordinate along the edge [m]: x on top and bottom, y on left and right.
        tol : float
            Points within ``tol`` [m] of a segment's ends belong to it.

        Returns
        -------
        kind : ndarray of str, shape (P, 2)
            ux and uy kinds; a load-controlled footing's uy is ``rigid`` and a
            velocity-controlled one's ``footing`` (:attr:`Segment.uy_kind`).
        drained : ndarray of bool, shape (P,)
        segment : ndarray of int, shape (P,)
            Index into :attr:`segments` of each point's segment, -1 for the bare edge.
        """
        s = np.atleast_1d(np.asarray(s, float))
        kind = np.tile(np.array([self.ux, self.uy], dtype=object), (len(s), 1))
        drained = np.full(len(s), self.drained)
        segment = np.full(len(s), -1)
        for k, seg in enumerate(self.segments):
            inside = seg.contains(s, tol)
            kind[inside] = (seg.ux, seg.uy_kind)
            if seg.water is not None:
                drained[inside] = seg.water == "drained"
            segment[inside] = k
        return kind.astype(str), drained, segment

    def loaded(self, segment):
        """(P,) bool: points that carry the edge's traction, from their ``segment`` index
        (:meth:`at`): off every segment, or on a whole group's segment that carries it."""
        carries = [seg.traction is not None for seg in self.segments]
        return np.array(carries + [True])[np.asarray(segment)]

    def kinds(self, length):
        """The kinds that occur on the edge of ``length`` [m]: ``(ux kinds, uy kinds)``,
        two sets (the edge's own ones unless its segments cover it whole; a footing's uy
        as :attr:`Segment.uy_kind`)."""
        ux, uy = {seg.ux for seg in self.segments}, {seg.uy_kind for seg in self.segments}
        reach, covered = 0.0, bool(self.segments)
        for a, b in sorted((seg.start, seg.end) for seg in self.segments):
            covered &= a <= reach
            reach = max(reach, b)
        if not (covered and reach >= length):
            ux, uy = ux | {self.ux}, uy | {self.uy}
        return ux, uy

    def to_dict(self):
        """The edge's TOML table, segments as sub-tables by name; a mesh group's
        :attr:`~Segment.whole` segment as the group's own keys."""
        data = {"ux": self.ux, "uy": self.uy, "traction": self.traction, "water": self.water}
        if self.segments and self.segments[0].whole:
            return {**data, **self.segments[0].to_dict(), "water": self.water}
        return {**data, **{seg.name: seg.to_dict() for seg in self.segments}}


def traction_at(traction, points):
    """The traction (P, 2) [kPa] at initial positions ``points`` (P, 2) [m]: ``(tx, ty)``
    everywhere, or a profile ``((x, tx, ty), ...)`` interpolated in x.

    Examples
    --------
    >>> traction_at(((0.0, 0.0, -10.0), (2.0, 0.0, 0.0)), [[1.0, 5.0], [3.0, 5.0]]).tolist()
    [[0.0, -5.0], [0.0, 0.0]]
    """
    x = np.atleast_2d(np.asarray(points, float))[:, 0]
    if not (len(traction) > 0 and isinstance(traction[0], tuple)):
        return np.broadcast_to(np.asarray(traction, float), (len(x), 2)).copy()
    table = np.asarray(traction, float)
    return np.column_stack([np.interp(x, table[:, 0], table[:, k]) for k in (1, 2)])


def along(side, points):
    """Coordinate along edge ``side`` of points (P, 2) [m]: x on top and bottom, y on
    left and right."""
    return np.asarray(points)[..., 0 if side in ("top", "bottom") else 1]


@dataclass(frozen=True)
class Boundary:
    """The named edges: the rectangle's four (in :data:`EDGES` order) or a mesh's boundary
    groups (in :attr:`soilwater.geometry.mesh.Mesh.groups` order); ``boundary.top`` is the
    edge named ``top``."""

    edges: tuple[tuple[str, Edge], ...]

    def __getattr__(self, name):
        if not name.startswith("__") and name != "edges":
            for key, edge in self.edges:
                if key == name:
                    return edge
        raise AttributeError(name)

    def items(self):
        """``(name, Edge)`` pairs in the boundary's order."""
        return self.edges

    def segments(self):
        """``(edge name, Segment)`` pairs of every named segment, edges in EDGES order."""
        return tuple((name, seg) for name, edge in self.items() for seg in edge.segments)

    @property
    def drained(self):
        """True if p_w = 0 is imposed anywhere on the boundary (an edge or a segment)."""
        return any(edge.drained for _, edge in self.items()) or any(
            seg.water == "drained" for _, seg in self.segments())
