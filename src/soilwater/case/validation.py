"""Validation: a plain dict in TOML layout to a :class:`soilwater.case.model.Case`, one reader per
section.

:func:`case_from_dict` checks every entry against the schema of :mod:`soilwater.case.schema` (keys,
types, finite numbers, bounds, supports against rigid motion) and refuses a bad one with
an :class:`~soilwater.errors.InputError` of one line naming the key and the fix.
"""

import math
import re
from dataclasses import replace

import numpy as np

from soilwater.references.closed_forms import exact_solution
from soilwater.case.model import (ANALYSES, EDGES, KINDS, LAYOUTS, MAX_STEPS, ON_FAILURE,
                       PERMEABILITY_LAWS, SEGMENT_KINDS, SEGMENT_TOLERANCE, STRESS_STARTS,
                       WATER, Boundary, Case, Diagnostics, Discretisation, Edge, Fluid,
                       Geometry, Gravity, Initial, Loading, Probe, Segment, TimeStepping)
from soilwater.errors import InputError, require
from soilwater.material.presets import FLUID_KEYS, material_from_spec
from soilwater.case.schema import (ASPECTS, GEOMETRIC, GRADINGS, KEYS, LENGTHS, MAX_TRIANGLE_ORDER,
                         SCALES, SECTIONS, expand_displacement)
from soilwater.efg.settings import (CELLS, CORRECTIONS, DEFAULT_SCALE, ESSENTIAL,
                                    STABILISATIONS, EFGSettings, Weight)
from soilwater.fem.settings import REMESH, FEMSettings

_RESTRAINED = ("fixed", "prescribed", "exact")
_CORNERS = (("left", "bottom"), ("left", "top"), ("right", "bottom"), ("right", "top"))
_REQUIRED = object()


def case_from_dict(data):
    """Validate a plain dict in TOML layout and build the :class:`~soilwater.case.model.Case`.

    Parameters
    ----------
    data : dict
        The case as :mod:`soilwater.case.schema` lays it out (e.g. parsed TOML, or
        ``Case.to_dict()``); not modified.

    Returns
    -------
    Case

    Raises
    ------
    InputError
        On any bad or unknown entry, including material errors from
        :func:`soilwater.material.presets.material_from_spec`.
    """
    require(isinstance(data, dict), "a case must be a table of sections")
    _check_keys(data, ("name", "description", "analysis") + SECTIONS, "case", "section")
    geometry = _geometry(_section(data, "geometry"))
    material_spec, fluid = _material(_section(data, "material"))
    probes = _probes(_section(data, "probes", {}), geometry)
    loading = _loading(_section(data, "loading", {}))
    case = Case(
        name=_string(data, "name", "case", "case"),
        description=_string(data, "description", "case", ""),
        analysis=_string(data, "analysis", "case", "coupled", ANALYSES),
        geometry=geometry,
        discretisation=_discretisation(_section(data, "discretisation"), geometry),
        material_spec=material_spec, fluid=fluid,
        initial=_initial(_section(data, "initial", {})),
        boundary=_boundary(_section(data, "boundary"), loading, geometry),
        loading=loading,
        time=_time(_section(data, "time")),
        probes=probes,
        exact=_exact(_section(data, "exact", {})),
        efg=_efg(_section(data, "efg", {})),
        diagnostics=_diagnostics(_section(data, "diagnostics", {})),
        fem=_fem(_section(data, "fem", {})),
        gravity=_gravity(_section(data, "gravity", {})),
    )
    _require_aspect(case)
    _require_exact_if_used(case)
    _require_coupled_footings(case)
    _require_segments_on_nodes(case)
    _require_weight(case)
    case.times()
    return case


def _section(data, name, default=_REQUIRED):
    """``data[name]`` as a table; required unless a default is given."""
    require(name in data or default is not _REQUIRED,
            f"case: section [{name}] is missing: add it (see soilwater/case/schema.py)")
    table = data.get(name, default)
    require(isinstance(table, dict), f"{name} must be a section [{name}], not a value")
    return table


def _check_keys(table, allowed, where, what="key"):
    """Reject keys of ``table`` outside ``allowed``."""
    for key in table:
        require(key in allowed, f"{where}: unknown {what} {key!r}: "
                f"allowed are {', '.join(allowed)}")


def _number(table, key, where, default=_REQUIRED):
    """A finite float entry (ints accepted, bools not)."""
    require(key in table or default is not _REQUIRED, f"{where}.{key} is missing: set it")
    value = table.get(key, default)
    require(isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value), f"{where}.{key} = {value!r} must be a finite number")
    return float(value)


def _integer(table, key, where):
    """A required integer entry."""
    require(key in table, f"{where}.{key} is missing: set it")
    value = table[key]
    require(isinstance(value, int) and not isinstance(value, bool),
            f"{where}.{key} = {value!r} must be an integer")
    return value


def _string(table, key, where, default, choices=None):
    """A string entry, optionally one of ``choices``."""
    value = table.get(key, default)
    require(isinstance(value, str), f"{where}.{key} = {value!r} must be a string")
    if choices is not None:
        require(value in choices,
                f"{where}.{key} = {value!r} is unknown: use one of {', '.join(choices)}")
    return value


def _pair(value, where):
    """Two numbers ``[a, b]`` as a tuple of floats."""
    require(isinstance(value, (list, tuple)) and len(value) == 2,
            f"{where} = {value!r} must be a pair of numbers [a, b]")
    return tuple(_number({"v": v}, "v", where) for v in value)


def _geometry(table):
    _check_keys(table, KEYS["geometry"], "geometry")
    _string(table, "shape", "geometry", "rectangle", ("rectangle",))
    width, height = _number(table, "width", "geometry"), _number(table, "height", "geometry")
    for key, value in (("width", width), ("height", height)):
        require(LENGTHS[0] <= value <= LENGTHS[1], f"geometry.{key} = {value:g} must lie "
                f"in [{LENGTHS[0]:g}, {LENGTHS[1]:g}] m: give the size of the rectangle in m")
    return Geometry(width=width, height=height)


def _discretisation(table, geometry):
    _check_keys(table, KEYS["discretisation"], "discretisation")
    counts, pieces = {}, {}
    for axis, length in (("x", geometry.width), ("y", geometry.height)):
        key = f"n{axis}"
        require(not (table.get(axis) and key in table), f"discretisation: give {key} or "
                f"{axis} (the grid in pieces), not both: remove one of them")
        if table.get(axis):
            pieces[axis] = _pieces(table[axis], f"discretisation.{axis}", length)
            counts[key] = 1 + sum(count for _, count, _ in pieces[axis])
        else:
            counts[key] = _integer(table, key, "discretisation")
            require(counts[key] >= 2, f"discretisation.{key} = {counts[key]} must be at "
                    f"least 2 (nodes along {axis})")
    jitter = _number(table, "jitter", "discretisation", 0.0)
    require(0 <= jitter < 0.25, f"discretisation.jitter = {jitter} must lie in [0, 0.25) "
            "(a fraction of the smallest nodal spacing)")
    seed = table.get("seed", 0)
    require(isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0,
            f"discretisation.seed = {seed!r} must be a non-negative integer")
    return Discretisation(**counts,
                          layout=_string(table, "layout", "discretisation", "grid", LAYOUTS),
                          jitter=jitter, seed=seed, **pieces)


def _pieces(value, where, length):
    """Grid pieces ``[[to, spacings(, ratio)], ...]`` along an edge of ``length`` [m] as a
    tuple of ``(to, spacings, ratio)`` (:class:`soilwater.case.model.Discretisation`)."""
    form = (f"{where} = {value!r} must be a list of pieces [to, spacings] or [to, spacings, "
            f"ratio]: to in m, increasing to {length:g}, spacings an integer >= 1, ratio "
            f"(last spacing over first) in [{GRADINGS[0]:g}, {GRADINGS[1]:g}]")
    require(isinstance(value, (list, tuple)) and all(
        isinstance(p, (list, tuple)) and len(p) in (2, 3) for p in value), form)
    out, start = [], 0.0
    for piece in value:
        to = _number({"v": piece[0]}, "v", where)
        spacings, ratio = piece[1], (_number({"v": piece[2]}, "v", where)
                                     if len(piece) == 3 else 1.0)
        require(isinstance(spacings, int) and not isinstance(spacings, bool)
                and spacings >= 1 and to > start and GRADINGS[0] <= ratio <= GRADINGS[1],
                form)
        out.append((to, spacings, ratio))
        start = to
    require(abs(start - length) <= 1e-9 * length, f"{where}: the last piece ends at "
            f"{start:g} m, the edge is {length:g} m long: end it at {length:g}")
    out[-1] = (length, *out[-1][1:])
    return tuple(out)


def _require_aspect(case):
    """Refuse sliver cells: the spacing aspect hx/hy of every grid cell must lie in
    :data:`ASPECTS`; square background cells need a regular grid."""
    d = case.discretisation
    hx, hy = case.spacing
    hx_max, hy_max = (np.diff(line).max() if pieces else h for h, pieces, line
                      in zip(case.spacing, (d.x, d.y), case.grid_lines()))
    for a, b in ((hx, hy_max), (hx_max, hy)):
        require(ASPECTS[0] <= a / b <= ASPECTS[1], f"discretisation: the grid spacing aspect "
                f"hx/hy = {a:g}/{b:g} = {a / b:g} (spacing along x over spacing along y of "
                f"a cell) must lie in [{ASPECTS[0]:g}, {ASPECTS[1]:g}]: change "
                "discretisation.nx, ny, x or y")
    require(case.efg.cells != "squares" or d.regular, "efg.cells = 'squares' needs a "
            "regular grid, and discretisation.x or y lays it out in pieces: use efg.cells = "
            "'delaunay' or give discretisation.nx and ny instead")


def _diagnostics(table):
    _check_keys(table, KEYS["diagnostics"], "diagnostics")
    value = table.get("uniqueness", False)
    require(isinstance(value, bool), f"diagnostics.uniqueness = {value!r} must be true or "
            "false")
    return Diagnostics(uniqueness=value)


def _material(table):
    """Split ``[material]`` into the skeleton spec (validated by building it) and Fluid."""
    spec = {}
    for key in table:
        if key in FLUID_KEYS:
            continue
        spec[key] = (_string(table, key, "material", None) if key in ("model", "preset")
                     else _number(table, key, "material"))
    material_from_spec(spec)
    law = _string(table, "permeability_law", "material", "constant", PERMEABILITY_LAWS)
    fluid = Fluid(**{key: _number(table, key, "material")
                     for key in FLUID_KEYS if key in table and key != "permeability_law"},
                  permeability_law=law)
    require(fluid.permeability >= 0, f"material.permeability = {fluid.permeability} must "
            "be >= 0 (m/s; 0 means undrained)")
    require(fluid.gamma_w > 0, f"material.gamma_w = {fluid.gamma_w} must be positive")
    require(0 < fluid.biot_alpha <= 1,
            f"material.biot_alpha = {fluid.biot_alpha} must lie in (0, 1]")
    require(fluid.storage >= 0, f"material.storage = {fluid.storage} must be >= 0 "
            "(S = 1/M_biot; 0 for incompressible constituents)")
    require(fluid.specific_gravity > 1, f"material.specific_gravity = "
            f"{fluid.specific_gravity} must exceed 1 (solids heavier than water; 2.65 for "
            "quartz)")
    needs = {"constant": (), "taylor": ("permeability_e", "permeability_ck"),
             "kozeny-carman": ("permeability_e",)}[law]
    for key in needs:
        require(getattr(fluid, key) is not None and getattr(fluid, key) > 0,
                f"material.{key} = {getattr(fluid, key)} must be set and positive for "
                f"permeability_law = {law!r}")
    return tuple(sorted(spec.items())), fluid


def _gravity(table):
    _check_keys(table, KEYS["gravity"], "gravity")
    g = _number(table, "g", "gravity", 0.0)
    require(g >= 0, f"gravity.g = {g} must be >= 0 (m/s2, acting along -y)")
    return Gravity(g)


def _initial(table):
    _check_keys(table, KEYS["initial"], "initial")
    value = table.get("pore_pressure", 0.0)
    if value != "balance":
        require(not isinstance(value, str), f"initial.pore_pressure = {value!r} must be a "
                "number or \"balance\"")
        value = _number(table, "pore_pressure", "initial", 0.0)
    start = _string(table, "stress", "initial", "uniform", STRESS_STARTS)
    geostatic = ("surcharge", "k0", "e_ref", "sigma_v_ref", "ocr")
    if start == "uniform":
        given = [key for key in geostatic if key in table]
        require(not given, f"initial.{', '.join(given)} only apply to initial.stress = "
                "\"geostatic\": set it, or remove them")
        return Initial(value)
    require(value != "balance", "initial.pore_pressure = \"balance\" sets the total stress "
            "to zero, which a geostatic start does not have: give a number (default 0)")
    k0 = table.get("k0", "nc")
    if k0 != "nc":
        require(not isinstance(k0, str), f"initial.k0 = {k0!r} must be a number in (0, 1] "
                "or \"nc\"")
        k0 = _number(table, "k0", "initial")
        require(0 < k0 <= 1, f"initial.k0 = {k0} must lie in (0, 1] (or \"nc\": the "
                "material's normally consolidated value)")
    require(("e_ref" in table) == ("sigma_v_ref" in table), "initial.e_ref and "
            "initial.sigma_v_ref anchor the compression line together: set both or neither")
    e_ref = sigma_ref = None
    if "e_ref" in table:
        e_ref = _number(table, "e_ref", "initial")
        sigma_ref = _number(table, "sigma_v_ref", "initial")
        require(e_ref > 0, f"initial.e_ref = {e_ref} must be positive (a void ratio)")
        require(sigma_ref > 0, f"initial.sigma_v_ref = {sigma_ref} must be positive (kPa, "
                "compression positive)")
    surcharge = _number(table, "surcharge", "initial", 0.0)
    require(surcharge >= 0, f"initial.surcharge = {surcharge} must be >= 0 (kPa, "
            "compression positive)")
    ocr = _number(table, "ocr", "initial", 1.0)
    require(ocr >= 1, f"initial.ocr = {ocr} must be at least 1")
    return Initial(value, start, surcharge, k0, e_ref, sigma_ref, ocr)


def _require_weight(case):
    """Gravity needs alpha = 1 (p_w in excess of hydrostatic, buoyancy of the skeleton);
    a geostatic Cam-clay start needs a surcharge (p' > 0 at the top)."""
    if case.gravity.g > 0:
        require(case.fluid.biot_alpha == 1, f"material.biot_alpha = "
                f"{case.fluid.biot_alpha} must be 1 with gravity: the skeleton carries its "
                "buoyant weight, which holds for incompressible grains")
    if case.initial.stress == "geostatic":
        require(case.analysis == "coupled", "initial.stress = \"geostatic\" needs analysis "
                "= \"coupled\"")
        plastic = case.material().plastic
        require(case.initial.surcharge > 0 or not plastic,
                "initial.surcharge must be > 0 with a Cam-clay geostatic start: p' would be "
                "0 at the top surface (use e.g. 1 kPa)")
        given = [k for k in ("e_ref", "ocr") if getattr(case.initial, k) not in (None, 1.0)]
        require(plastic or not given, f"initial.{', '.join(given)} describe a compression "
                "line, which a linear elastic skeleton does not have: remove them (its "
                "void ratio is material.e0)")


def _boundary(table, loading, geometry):
    _check_keys(table, EDGES, "boundary", "edge")
    for side in EDGES:
        require(side in table, f"boundary: edge {side!r} is missing: add [boundary.{side}] "
                "(every edge of the rectangle exactly once)")
    length = {"left": geometry.height, "right": geometry.height,
              "bottom": geometry.width, "top": geometry.width}
    boundary = Boundary(**{side: _edge(_section(table, side), side, loading, length[side])
                           for side in EDGES})
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
    velocity-controlled footing (:class:`~soilwater.case.model.Segment`) its uy; a ``rigid`` plate
    (or a load-controlled footing) lets its edge settle. It would stop rotation, but never
    decides: the uy that stops y translation is on a horizontal edge (stopping rotation
    too) or on a vertical one, which may not meet the plate's edge with another kind.
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
    edge = Edge(ux=_string(table, "ux", where, "free", KINDS),
                uy=_string(table, "uy", where, "free", KINDS),
                traction=_traction(table.get("traction", (0.0, 0.0)), f"{where}.traction"),
                water=_string(table, "water", where, "impermeable", WATER))
    require(edge.ux != "rigid" and (edge.uy != "rigid" or side in ("top", "bottom")),
            f"{where}: 'rigid' applies to uy of the top or bottom edge only")
    for comp, t in zip(("ux", "uy"), np.broadcast_to(np.asarray(edge.traction, object), 2)):
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


def _segment(table, name, side, loading, length):
    """A named segment ``[boundary.<side>.<name>]`` (:class:`soilwater.case.model.Segment`)."""
    where = f"boundary.{side}.{name}"
    require(re.fullmatch(r"[A-Za-z0-9_-]+", name) and name not in KEYS["edge"],
            f"{where}: use letters, digits, _ and - in segment names (they become column "
            f"names), other than the edge's keys {', '.join(KEYS['edge'])}")
    _check_keys(table, KEYS["segment"], where)
    start, end = _number(table, "from", where), _number(table, "to", where)
    along = "x" if side in ("top", "bottom") else "y"
    require(0 <= start < end <= length, f"{where}: from = {start:g} and to = {end:g} must "
            f"satisfy 0 <= from < to <= {length:g} (m along {along}, the edge's length): "
            "put the segment on the edge")
    seg = Segment(name=name, start=start, end=end,
                  ux=_string(table, "ux", where, "free", SEGMENT_KINDS["ux"]),
                  uy=_string(table, "uy", where, "free", SEGMENT_KINDS["uy"]),
                  water=_string(table, "water", where, None, WATER) if "water" in table
                  else None,
                  settlement_rate=(_number(table, "settlement_rate", where)
                                   if "settlement_rate" in table else None),
                  force=_number(table, "force", where) if "force" in table else None)
    given = [key for key in ("settlement_rate", "force") if key in table]
    if seg.footing:
        require(side in ("top", "bottom"), f"{where}.uy = 'footing' applies to the top "
                "or bottom edge only: move the segment there")
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


def _require_coupled_footings(case):
    footings = [f"boundary.{side}.{seg.name}" for side, seg in case.boundary.segments()
                if seg.footing]
    require(not footings or case.analysis == "coupled", f"{footings[0] if footings else ''}"
            ": a footing needs analysis = \"coupled\" (the static solver has none)")


def _require_segments_on_nodes(case):
    """Refuse a segment end between two grid nodes of its edge: the FEM reference would
    impose the segment's kinds only up to the last node inside it, a shorter footing."""
    x, y = case.grid_lines()
    tol = SEGMENT_TOLERANCE * min(case.spacing)
    for side, seg in case.boundary.segments():
        line, axis = (x, "x") if side in ("top", "bottom") else (y, "y")
        for key, end in (("from", seg.start), ("to", seg.end)):
            k = np.searchsorted(line, end - tol)
            require(abs(line[min(k, len(line) - 1)] - end) <= tol,
                    f"boundary.{side}.{seg.name}.{key} = {end:g} lies between the grid nodes "
                    f"at {axis} = {line[k - 1]:.6g} and {line[k]:.6g} m: put segment ends on "
                    "grid nodes (change it, discretisation.n" + axis + " or " + axis + ")")


def _traction(value, where):
    """``[tx, ty]`` or ``"exact"`` (from the case's exact solution)."""
    return "exact" if value == "exact" else _pair(value, where)


def _exact(table):
    """``[exact]``: ``solution`` (see soilwater.references.closed_forms.SOLUTIONS) and its parameters."""
    if not table:
        return ()
    require("solution" in table, "exact: name the solution, e.g. solution = "
            "\"timoshenko-beam\" (see soilwater/references/closed_forms.py)")
    params = {k: v for k, v in table.items() if k != "solution"}
    try:
        exact_solution(table["solution"], **params)(np.zeros((1, 2)))
    except TypeError as err:
        raise InputError(f"exact: bad parameters for {table['solution']!r}: {err}") from None
    return tuple(sorted((k, _frozen(v)) for k, v in table.items()))


def _frozen(value):
    """Lists to tuples, recursively (hashable, comparable)."""
    return tuple(_frozen(v) for v in value) if isinstance(value, list) else value


def _require_exact_if_used(case):
    uses = [f"boundary.{name}" for name, edge in case.boundary.items()
            if "exact" in (edge.ux, edge.uy, edge.traction)]
    require(not uses or case.exact, f"{uses[0] if uses else ''} uses 'exact' but the case "
            "has no [exact] section: add one naming the solution")


def _efg(table):
    _check_keys(table, KEYS["efg"], "efg")
    defaults = EFGSettings()
    order = table.get("order", defaults.order)
    require(isinstance(order, int) and not isinstance(order, bool) and order >= 1,
            f"efg.order = {order!r} must be an integer >= 1")
    values = {"weight_u": _string(table, "weight_u", "efg", str(defaults.weight_u)),
              "scale_u": _number(table, "scale_u", "efg", defaults.scale_u),
              "weight_p": _string(table, "weight_p", "efg", str(defaults.weight_p)),
              "scale_p": _number(table, "scale_p", "efg", defaults.scale_p),
              "cells": _string(table, "cells", "efg", defaults.cells, CELLS),
              "order": order,
              "essential": _string(table, "essential", "efg", defaults.essential,
                                   ESSENTIAL),
              "penalty": _number(table, "penalty", "efg", defaults.penalty),
              "correction": _string(table, "correction", "efg", defaults.correction,
                                    CORRECTIONS),
              "stabilisation": _string(table, "stabilisation", "efg",
                                       defaults.stabilisation, STABILISATIONS),
              "stabilisation_factor": _number(table, "stabilisation_factor", "efg",
                                              defaults.stabilisation_factor)}
    require(values["cells"] != "delaunay" or order <= MAX_TRIANGLE_ORDER,
            f"efg.order = {order} must be at most {MAX_TRIANGLE_ORDER} with efg.cells = "
            "\"delaunay\" (the highest triangle rule): lower it or use efg.cells = "
            "\"squares\"")
    for field in ("u", "p"):
        key, scale = f"efg.scale_{field}", values[f"scale_{field}"]
        name = f"weight_{field}"
        values[name] = Weight.parse(values[name], f"efg.{name}")
        require(scale >= SCALES[0], f"{key} = {scale:g} must be >= {SCALES[0]:g} (each "
                "node's support must reach its 8th nearest node): increase the scale "
                f"factor, e.g. to {DEFAULT_SCALE:g}")
        require(scale <= SCALES[1], f"{key} = {scale:g} must be <= {SCALES[1]:g} (beyond, "
                "the MLS moment matrices approach singularity): use 1.2 to 2, e.g. "
                f"{DEFAULT_SCALE:g}")
    require(values["penalty"] > 0, f"efg.penalty = {values['penalty']:g} must be positive")
    factor = values["stabilisation_factor"]
    require(0 < factor <= 1e3, f"efg.stabilisation_factor = {factor:g} must be in (0, 1000] "
            "(it multiplies the stabilisation's coefficient, h^2/(4M) or 1/G; 1 is the "
            "published one)")
    return EFGSettings(**values)


def _fem(table):
    _check_keys(table, KEYS["fem"], "fem")
    defaults = FEMSettings()
    quality = _number(table, "remesh_quality", "fem", defaults.remesh_quality)
    require(0 < quality <= 1, f"fem.remesh_quality = {quality:g} must lie in (0, 1] (the "
            "worst element's shape quality below which the mesh is re-triangulated: 1 "
            f"equilateral, 0 degenerate): use e.g. {defaults.remesh_quality:g}")
    return FEMSettings(remesh=_string(table, "remesh", "fem", defaults.remesh, REMESH),
                       remesh_quality=quality)


def _loading(table):
    _check_keys(table, KEYS["loading"], "loading")
    L = table.get("velocity_gradient", ((0.0, 0.0), (0.0, 0.0)))
    require(isinstance(L, (list, tuple)) and len(L) == 2, "loading.velocity_gradient "
            "must be [[L11, L12], [L21, L22]] (1/s)")
    L = tuple(_pair(row, "loading.velocity_gradient row") for row in L)
    load = table.get("load", 1.0)
    if not isinstance(load, (list, tuple)):
        return Loading(L, _number(table, "load", "loading", 1.0))
    points = tuple(_pair(p, "loading.load point [t, factor]") for p in load)
    times = [t for t, _ in points]
    require(points and times[0] >= 0 and all(np.diff(times) > 0), "loading.load: give "
            "[t, factor] points with increasing times t >= 0, or one number (step load)")
    return Loading(L, points)


def _time(table):
    _check_keys(table, KEYS["time"], "time")
    end = _number(table, "end", "time")
    require(end > 0, f"time.end = {end} must be positive (s)")
    on_failure = _string(table, "on_failure", "time", "error", ON_FAILURE)
    if "steps" in table:
        require(not set(GEOMETRIC) & set(table), "time: give either steps or dt0, "
                "growth, dt_max, not both")
        steps = _integer(table, "steps", "time")
        require(1 <= steps <= MAX_STEPS, f"time.steps = {steps} must lie in 1..{MAX_STEPS}")
        return TimeStepping(end=end, steps=steps, on_failure=on_failure)
    require(set(GEOMETRIC) <= set(table), "time: give steps (equal steps) or all of dt0, "
            "growth, dt_max (geometric steps)")
    dt0, growth, dt_max = (_number(table, key, "time") for key in GEOMETRIC)
    require(0 < dt0 <= dt_max, f"time.dt0 = {dt0} must be positive and at most "
            f"time.dt_max = {dt_max}")
    require(growth > 1, f"time.growth = {growth} must exceed 1 (t_(n+1) = growth t_n)")
    return TimeStepping(end=end, dt0=dt0, growth=growth, dt_max=dt_max,
                        on_failure=on_failure)


def _probes(table, geometry):
    probes = []
    for name, point in table.items():
        require(re.fullmatch(r"[A-Za-z0-9_-]+", name), f"probes.{name}: use letters, "
                "digits, _ and - in probe names (they become column names)")
        x, y = _pair(point, f"probes.{name}")
        tol = 1e-9 * max(geometry.width, geometry.height)
        require(-tol <= x <= geometry.width + tol and -tol <= y <= geometry.height + tol,
                f"probes.{name} = [{x}, {y}] lies outside the domain [0, {geometry.width}]"
                f" x [0, {geometry.height}]: move it inside")
        probes.append(Probe(name, (x, y)))
    return tuple(probes)
