"""Validation of ``[boundary]``: the four edges (or a mesh's boundary groups), their
named segments and the supports.

:func:`read_boundary` reads the section into a :class:`~soilwater.case.boundary.Boundary`
and refuses conflicting corners, more than one rigid plate and a body free to move
rigidly; :func:`require_coupled_footings` and :func:`require_segments_on_nodes` check the
boundary against the rest of the case. Every refusal is one
:class:`~soilwater.errors.InputError` line naming the key and the fix.
"""

import re
from dataclasses import replace

import numpy as np

from soilwater.case.boundary import (EDGES, KINDS, SEGMENT_KINDS, SEGMENT_TOLERANCE, WATER,
                                     Boundary, Edge, Segment)
from soilwater.case.entries import check_keys, number, pair, section, string
from soilwater.case.schema import KEYS, expand_displacement
from soilwater.errors import InputError, require

_RESTRAINED = ("fixed", "prescribed", "exact")
_CORNERS = (("left", "bottom"), ("left", "top"), ("right", "bottom"), ("right", "top"))


def read_boundary(table, loading, geometry):
    if geometry.mesh is not None:
        return _mesh_boundary(table, loading, geometry.mesh)
    check_keys(table, EDGES, "boundary", "edge")
    for side in EDGES:
        require(side in table, f"boundary: edge {side!r} is missing: add [boundary.{side}] "
                "(every edge of the rectangle exactly once)")
    length = {"left": geometry.height, "right": geometry.height,
              "bottom": geometry.width, "top": geometry.width}
    boundary = Boundary(tuple((side, _edge(section(table, side), side, loading,
                                           length[side])) for side in EDGES))
    corner = {("left", "bottom"): (0.0, 0.0), ("left", "top"): (geometry.height, 0.0),
              ("right", "bottom"): (0.0, geometry.width),
              ("right", "top"): (geometry.height, geometry.width)}
    for a, b in _CORNERS:
        (ka,), _, _ = getattr(boundary, a).at([corner[a, b][0]])
        (kb,), _, _ = getattr(boundary, b).at([corner[a, b][1]])
        for f, comp in enumerate(("ux", "uy")):
            kinds = {str(ka[f]), str(kb[f])}
            require(len(kinds - {"free"}) <= 1, f"boundary.{a}.{comp} and boundary.{b}."
                    f"{comp} conflict at their corner ({' vs '.join(sorted(kinds))}; a "
                    "segment reaching the corner counts there): make them agree or set "
                    "one free")
    plates = [f"boundary.{side}" for side, edge in boundary.items() if edge.uy == "rigid"]
    plates += [f"boundary.{side}.{seg.name}" for side, seg in boundary.segments()
               if seg.load_controlled]
    require(len(plates) <= 1, f"{' and '.join(plates)}: at most one rigid plate or "
            "load-controlled footing (force) per case: give the others a settlement_rate")
    _require_supports(boundary, length)
    return boundary


def _require_supports(boundary, length):
    """Refuse a body free to move rigidly: x and y translation and rotation must be stopped.

    ``fixed``, ``prescribed`` and ``exact`` restrain a component, and so does a
    velocity-controlled footing (:class:`~soilwater.case.boundary.Segment`) its uy; a
    ``rigid`` plate (or a load-controlled footing) lets its edge settle. It would stop
    rotation, but never decides: the uy that stops y translation is on a horizontal edge
    (stopping rotation too) or on a vertical one, which may not meet the plate's edge with another kind.
    """
    kinds = {side: edge.kinds(length[side]) for side, edge in boundary.items()}
    ux = {side for side, (kx, _) in kinds.items() if kx & set(_RESTRAINED)}
    uy = {side for side, (_, ky) in kinds.items() if ky & {*_RESTRAINED, "footing"}}
    kinds = '"fixed", "prescribed" or "exact"'
    require(ux, "boundary: the body is not supported along x (no edge restrains ux): set "
            f"an edge's ux to {kinds}, e.g. boundary.left.ux = \"fixed\"")
    require(uy, "boundary: the body is not supported along y (no edge restrains uy; a "
            f"rigid plate carries a load): set an edge's uy to {kinds}, e.g. "
            "boundary.bottom.uy = \"fixed\"")
    require(ux & {"left", "right"} or uy & {"bottom", "top"}
            or {"bottom", "top"} <= ux or {"left", "right"} <= uy,
            "boundary: the body is not supported against rotation: restrain ux on the left "
            "or right edge or uy on the top or bottom edge (e.g. boundary.left.ux = "
            "\"fixed\")")


def _mesh_boundary(table, loading, mesh):
    """The boundary groups of a mesh: ``[boundary.NAME]`` for any of its physical curves
    on the boundary, the others free, impermeable and unloaded; no named segments (a
    group is its own, :func:`_group`), no rigid plate but rigid footings, at most one of
    them load-controlled; supported along x, y and against rotation. A physical curve inside the domain
    (:attr:`~soilwater.geometry.mesh.Mesh.interior`) takes no ``[boundary.NAME]``."""
    inner = [name for name in table if name in mesh.interior]
    if inner:
        raise InputError(f"boundary.{inner[0]}: {inner[0]!r} is an interior curve of "
                         "geometry.mesh (between regions, not on the outline), so it "
                         f"cannot carry a boundary condition: remove [boundary.{inner[0]}] "
                         f"(the boundary groups are {', '.join(mesh.groups)})")
    check_keys(table, mesh.groups, "boundary", "boundary group (physical curve of "
               "geometry.mesh)")
    ends = mesh.points[np.stack([mesh.loop, np.roll(mesh.loop, -1)])]
    edges = []
    for k, name in enumerate(mesh.groups):
        spec = dict(section(table, name, {}))
        where = f"boundary.{name}"
        for key, value in spec.items():
            require(not isinstance(value, dict), f"{where}.{key}: named segments are for "
                    "the rectangle's edges: give that part of the boundary its own physical "
                    "curve in the mesh")
        d = np.ptp(ends[:, mesh.group == k].reshape(-1, 2), axis=0)
        if "displacement" in spec:
            require("ux" not in spec and "uy" not in spec,
                    f"{where}: give either displacement or ux/uy, not both")
            normal = "ux" if d[0] == 0 else "uy" if d[1] == 0 else None
            spec.update(expand_displacement(spec.pop("displacement"), name, normal))
        require("rigid" not in (spec.get("ux"), spec.get("uy")), f"{where}: 'rigid' "
                "applies to a rectangle's top or bottom edge: use \"footing\" (a rigid "
                "footing on the group), fixed or prescribed")
        edges.append((name, _group(spec, name, loading, mesh.group_length(name))))
    boundary = Boundary(tuple(edges))
    plates = [f"boundary.{name}" for name, seg in boundary.segments() if seg.load_controlled]
    require(len(plates) <= 1, f"{' and '.join(plates)}: at most one load-controlled "
            "footing (force) per case: give the others a settlement_rate")
    restrained = [[name for name, edge in edges
                   if edge.kinds(np.inf)[f] & {*_RESTRAINED, "footing"}]
                  for f in range(2)]
    for comp, names, axis in zip(("ux", "uy"), restrained, ("x", "y")):
        require(names, f"boundary: the body is not supported along {axis} (no boundary "
                f"group restrains {comp}): set a group's {comp} to \"fixed\", e.g. "
                f"boundary.{mesh.groups[0]}.{comp} = \"fixed\"")
    spread = [np.ptp(ends[:, np.isin(mesh.group, [mesh.groups.index(n) for n in names])]
                     .reshape(-1, 2)[:, 1 - f]) for f, names in enumerate(restrained)]
    require(max(spread) > 0, "boundary: the body is not supported against rotation (ux "
            "is restrained only along one horizontal line and uy only along one vertical "
            "line): restrain ux on a group that spans a height, or uy on one that spans a "
            "width")
    return boundary


def _group(spec, name, loading, length):
    """A mesh's boundary group ``[boundary.NAME]``: an :class:`~soilwater.case.boundary.
    Edge`, which a footing (``uy = "footing"``), a ``prescribed`` component or a traction
    makes one :attr:`~soilwater.case.boundary.Segment.whole` segment named for the group
    (its ``settlement@NAME`` and ``pressure@NAME`` columns)."""
    footing = {key: spec.pop(key) for key in ("settlement_rate", "force") if key in spec}
    if spec.get("uy") == "footing" or footing:
        where = f"boundary.{name}"
        if spec.get("uy") != "footing":
            raise InputError(f"{where}.{next(iter(footing))} applies to a footing only: set "
                             "uy = \"footing\" or remove it")
        seg = _segment({"ux": spec.get("ux", "free"), "uy": spec.pop("uy"), **footing},
                       name, name, loading, length, whole=True)
        edge = _edge(spec, name, loading, length)
        require(edge.traction != "exact" and edge.largest_traction == 0, f"{where}.traction:"
                " a footing carries no traction (its force or settlement_rate loads it): "
                "remove traction")
        return replace(edge, segments=(seg,))
    edge = _edge(spec, name, loading, length)
    if edge.traction != "exact" and ("prescribed" in (edge.ux, edge.uy)
                                     or edge.largest_traction > 0):
        return replace(edge, segments=(Segment(name, -np.inf, np.inf, edge.ux, edge.uy,
                                               traction=edge.traction),))
    return edge


def _edge(table, side, loading, length):
    where = f"boundary.{side}"
    segments = {k: v for k, v in table.items() if isinstance(v, dict)}
    table = {k: v for k, v in table.items() if k not in segments}
    for key in table:
        require(key in KEYS["edge"], f"{where}: unknown key {key!r}: allowed are "
                f"{', '.join(KEYS['edge'])}, or a named segment [{where}.NAME]")
    if "displacement" in table:
        require("ux" not in table and "uy" not in table,
                f"{where}: give either displacement or ux/uy, not both")
        table.update(expand_displacement(table.pop("displacement"), side))
    edge = Edge(ux=string(table, "ux", where, "free", KINDS),
                uy=string(table, "uy", where, "free", KINDS),
                traction=_traction(table.get("traction", (0.0, 0.0)), f"{where}.traction"),
                water=string(table, "water", where, "impermeable", WATER))
    require(edge.ux != "rigid" and (edge.uy != "rigid" or side in ("top", "bottom")),
            f"{where}: 'rigid' applies to uy of the top or bottom edge only")
    values = (np.abs(np.asarray(edge.traction, float)[:, 1:]).max(axis=0) if edge.profiled
              else np.broadcast_to(np.asarray(edge.traction, object), 2))
    for comp, t in zip(("ux", "uy"), values):
        kind = getattr(edge, comp)
        require(kind != "prescribed" or np.any(loading.L),
                f"{where}.{comp} = 'prescribed' needs a non-zero "
                "loading.velocity_gradient: set it, or use 'fixed'")
        require(edge.traction == "exact" or t == 0 or kind in ("free", "rigid"),
                f"{where}.traction acts on {comp}, "
                f"which is {kind!r}: set that traction component to 0 or {comp} free")
    parsed = tuple(_segment(spec, name, side, loading, length)
                   for name, spec in segments.items())
    spans = sorted((seg.start, seg.end, seg.name) for seg in parsed)
    for (_, end, a), (start, _, b) in zip(spans, spans[1:]):
        require(start > end, f"{where}.{a} and {where}.{b} overlap ({where}.{b}.from = "
                f"{start:g} <= {where}.{a}.to = {end:g}): make the segments disjoint")
    return replace(edge, segments=parsed)


def _segment(table, name, side, loading, length, whole=False):
    """A named segment ``[boundary.<side>.<name>]``, or with ``whole`` a mesh's whole
    boundary group ``name`` that is a footing (:class:`~soilwater.case.boundary.Segment`)."""
    where = f"boundary.{side}" if whole else f"boundary.{side}.{name}"
    if whole:
        start, end = -np.inf, np.inf
    else:
        require(re.fullmatch(r"[A-Za-z0-9_-]+", name) and name not in KEYS["edge"],
                f"{where}: use letters, digits, _ and - in segment names (they become "
                f"column names), other than the edge's keys {', '.join(KEYS['edge'])}")
        check_keys(table, KEYS["segment"], where)
        start, end = number(table, "from", where), number(table, "to", where)
        along = "x" if side in ("top", "bottom") else "y"
        require(0 <= start < end <= length, f"{where}: from = {start:g} and to = {end:g} "
                f"must satisfy 0 <= from < to <= {length:g} (m along {along}, the edge's "
                "length): put the segment on the edge")
    seg = Segment(name=name, start=start, end=end,
                  ux=string(table, "ux", where, "free", SEGMENT_KINDS["ux"]),
                  uy=string(table, "uy", where, "free", SEGMENT_KINDS["uy"]),
                  water=string(table, "water", where, None, WATER) if "water" in table
                  else None,
                  settlement_rate=(number(table, "settlement_rate", where)
                                   if "settlement_rate" in table else None),
                  force=number(table, "force", where) if "force" in table else None)
    given = [key for key in ("settlement_rate", "force") if key in table]
    if seg.footing:
        require(whole or side in ("top", "bottom"), f"{where}.uy = 'footing' applies to "
                "the top or bottom edge only: move the segment there")
        require(len(given) == 1, f"{where}.uy = 'footing' needs exactly one of "
                f"settlement_rate (m/s, velocity control) or force (kN/m, load control), "
                f"not {' and '.join(given) or 'neither'}: keep one")
    else:
        require(not given, f"{where}.{given[0] if given else ''} applies to a footing "
                "only: set uy = \"footing\" or remove it")
    for comp in ("ux", "uy"):
        require(getattr(seg, comp) != "prescribed" or np.any(loading.L),
                f"{where}.{comp} = 'prescribed' needs a non-zero "
                "loading.velocity_gradient: set it, or use 'fixed'")
    return seg


def require_coupled_footings(case):
    footings = [f"boundary.{side}" + ("" if seg.whole else f".{seg.name}")
                for side, seg in case.boundary.segments() if seg.footing]
    require(not footings or case.analysis == "coupled", f"{footings[0] if footings else ''}"
            ": a footing needs analysis = \"coupled\" (the static solver has none)")


def require_segments_on_nodes(case):
    """Refuse a segment end between two grid nodes of its edge: the FEM reference would
    impose the segment's kinds only up to the last node inside it, a shorter footing."""
    x, y = case.grid_lines()
    tol = SEGMENT_TOLERANCE * min(case.spacing)
    for side, seg in case.boundary.segments():
        if seg.whole:
            continue
        line, axis = (x, "x") if side in ("top", "bottom") else (y, "y")
        for key, end in (("from", seg.start), ("to", seg.end)):
            k = np.searchsorted(line, end - tol)
            require(abs(line[min(k, len(line) - 1)] - end) <= tol,
                    f"boundary.{side}.{seg.name}.{key} = {end:g} lies between the grid nodes "
                    f"at {axis} = {line[k - 1]:.6g} and {line[k]:.6g} m: put segment ends on "
                    "grid nodes (change it, discretisation.n" + axis + " or " + axis + ")")


def _traction(value, where):
    """``[tx, ty]``, ``"exact"`` (from the case's exact solution) or a profile ``[[x, tx,
    ty], ...]`` (:class:`~soilwater.case.boundary.Edge`)."""
    if value == "exact":
        return "exact"
    if not (isinstance(value, (list, tuple)) and value
            and isinstance(value[0], (list, tuple))):
        return pair(value, where)
    form = (f"{where} = {value!r}: give [tx, ty] or a profile [[x, tx, ty], ...] of rows "
            "with increasing x (m), piecewise linear in the initial x")
    require(all(isinstance(row, (list, tuple)) and len(row) == 3 for row in value), form)
    rows = tuple(tuple(number({"v": v}, "v", where) for v in row) for row in value)
    require(len(rows) >= 2 and all(b[0] > a[0] for a, b in zip(rows, rows[1:])), form)
    return rows
