"""Validation: a plain dict in TOML layout to a :class:`soilwater.case.model.Case`, one
reader per section.

:func:`case_from_dict` checks every entry against the schema of :mod:`soilwater.case.schema`
(keys, types, finite numbers, bounds) and the sections against each other, and refuses a
bad one with an :class:`~soilwater.errors.InputError` of one line naming the key and the
fix. The entry readers are in :mod:`soilwater.case.entries`, the ``[boundary]`` readers and
the supports against rigid motion in :mod:`soilwater.case.boundary_validation`.
"""

import re

import numpy as np

from soilwater.case.boundary_validation import (read_boundary, require_coupled_footings,
                                                require_segments_on_nodes)
from soilwater.case.entries import check_keys, integer, number, pair, section, string
from soilwater.case.domain import read_geometry
from soilwater.case.regions import read_regions
from soilwater.case.grid import LAYOUTS, MESH, Discretisation
from soilwater.case.model import (ANALYSES, GRAVITY_INCREMENTS, STRESS_STARTS, Case,
                                  Diagnostics, Gravity, Initial, Probe)
from soilwater.case.schema import (ASPECTS, GRADINGS, KEYS, MAX_INCREMENTS,
                                   MAX_TRIANGLE_ORDER, SCALES, SECTIONS)
from soilwater.case.time_validation import read_loading, read_time
from soilwater.efg.settings import (CELLS, CORRECTIONS, DEFAULT_SCALE, ESSENTIAL,
                                    INTEGRATIONS, STABILISATIONS, EFGSettings, Weight)
from soilwater.errors import InputError, require
from soilwater.material.camclay import MAX_OCR
from soilwater.fem.settings import REMESH, FEMSettings
from soilwater.material.fluid import PERMEABILITY_LAWS, Fluid
from soilwater.material.presets import FLUID_KEYS, material_from_spec, parameters
from soilwater.references.closed_forms import exact_solution


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
    check_keys(data, ("name", "description", "analysis") + SECTIONS, "case", "section")
    geometry = read_geometry(section(data, "geometry"))
    material_spec, fluid = _material(section(data, "material"))
    regions = read_regions(section(data, "material"), fluid, geometry)
    probes = _probes(section(data, "probes", {}), geometry)
    loading = read_loading(section(data, "loading", {}))
    case = Case(
        name=string(data, "name", "case", "case"),
        description=string(data, "description", "case", ""),
        analysis=string(data, "analysis", "case", "coupled", ANALYSES),
        geometry=geometry,
        discretisation=_discretisation(section(data, "discretisation", {}), geometry),
        material_spec=material_spec, fluid=fluid, regions=regions,
        initial=_initial(section(data, "initial", {})),
        boundary=read_boundary(section(data, "boundary"), loading, geometry),
        loading=loading,
        time=read_time(section(data, "time")),
        probes=probes,
        exact=_exact(section(data, "exact", {})),
        efg=_efg(section(data, "efg", {})),
        diagnostics=_diagnostics(section(data, "diagnostics", {})),
        fem=_fem(section(data, "fem", {})),
        gravity=_gravity(section(data, "gravity", {})),
    )
    _require_aspect(case)
    _require_exact_if_used(case)
    require_coupled_footings(case)
    require_segments_on_nodes(case)
    _require_weight(case)
    require(not case.regions or case.analysis == "coupled", "material regions need analysis "
            "= \"coupled\" (the static solver takes one elastic material)")
    require("specific_gravity" not in section(data, "material") or case.gravity.g > 0,
            "material.specific_gravity has no effect without gravity: add [gravity] with "
            "g = 9.81 for a layer under its own weight, or remove the key")
    case.times()
    return case


def _discretisation(table, geometry):
    if geometry.mesh is not None:
        require(not table, f"discretisation.{next(iter(table), '')}: a case on a mesh takes "
                "its nodes from geometry.mesh: remove [discretisation] (refine the mesh "
                "instead)")
        return Discretisation(nx=0, ny=0, layout=MESH)
    require(table, "discretisation is missing: add [discretisation] with nx and ny")
    check_keys(table, KEYS["discretisation"], "discretisation")
    counts, pieces = {}, {}
    for axis, length in (("x", geometry.width), ("y", geometry.height)):
        key = f"n{axis}"
        require(not (table.get(axis) and key in table), f"discretisation: give {key} or "
                f"{axis} (the grid in pieces), not both: remove one of them")
        if table.get(axis):
            pieces[axis] = _pieces(table[axis], f"discretisation.{axis}", length)
            counts[key] = 1 + sum(count for _, count, _ in pieces[axis])
        else:
            counts[key] = integer(table, key, "discretisation")
            require(counts[key] >= 2, f"discretisation.{key} = {counts[key]} must be at "
                    f"least 2 (nodes along {axis})")
    jitter = number(table, "jitter", "discretisation", 0.0)
    require(0 <= jitter < 0.25, f"discretisation.jitter = {jitter} must lie in [0, 0.25) "
            "(a fraction of the smallest nodal spacing)")
    seed = table.get("seed", 0)
    require(isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0,
            f"discretisation.seed = {seed!r} must be a non-negative integer")
    return Discretisation(**counts,
                          layout=string(table, "layout", "discretisation", "grid", LAYOUTS),
                          jitter=jitter, seed=seed, **pieces)


def _pieces(value, where, length):
    """Grid pieces ``[[to, spacings(, ratio)], ...]`` along an edge of ``length`` [m] as a
    tuple of ``(to, spacings, ratio)`` (:class:`soilwater.case.grid.Discretisation`)."""
    form = (f"{where} = {value!r} must be a list of pieces [to, spacings] or [to, spacings, "
            f"ratio]: to in m, increasing to {length:g}, spacings an integer >= 1, ratio "
            f"(last spacing over first) in [{GRADINGS[0]:g}, {GRADINGS[1]:g}]")
    require(isinstance(value, (list, tuple)) and all(
        isinstance(p, (list, tuple)) and len(p) in (2, 3) for p in value), form)
    out, start = [], 0.0
    for piece in value:
        to = number({"v": piece[0]}, "v", where)
        spacings, ratio = piece[1], (number({"v": piece[2]}, "v", where)
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
    if d.layout == MESH:
        require(case.efg.cells != "squares", "efg.cells = 'squares' needs a regular grid, "
                "not geometry.mesh: use efg.cells = 'delaunay'")
        return
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
    check_keys(table, KEYS["diagnostics"], "diagnostics")
    value = table.get("uniqueness", False)
    require(isinstance(value, bool), f"diagnostics.uniqueness = {value!r} must be true or "
            "false")
    return Diagnostics(uniqueness=value)


def _material(table):
    """Split ``[material]`` into the skeleton spec (validated by building it) and Fluid."""
    spec = {}
    for key in table:
        if key in FLUID_KEYS or isinstance(table[key], dict):
            continue
        spec[key] = (string(table, key, "material", None) if key in ("model", "preset")
                     else number(table, key, "material"))
    spec = parameters(material_from_spec(spec))
    law = string(table, "permeability_law", "material", "constant", PERMEABILITY_LAWS)
    fluid = Fluid(**{key: number(table, key, "material")
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
             "kozeny-carman": ("permeability_e",), "xie-leo": ("permeability_e",)}[law]
    for key in needs:
        require(getattr(fluid, key) is not None and getattr(fluid, key) > 0,
                f"material.{key} = {getattr(fluid, key)} must be set and positive for "
                f"permeability_law = {law!r}")
    idle = [key for key in ("permeability_e", "permeability_ck")
            if key in table and key not in needs]
    require(not idle, f"material.{', '.join(idle)} has no effect with permeability_law = "
            f"{law!r}: remove it, or choose a law that uses it (taylor; permeability_e also "
            "kozeny-carman, xie-leo)")
    return tuple(sorted(spec.items())), fluid


def _gravity(table):
    check_keys(table, KEYS["gravity"], "gravity")
    g = number(table, "g", "gravity", 0.0)
    require(g >= 0, f"gravity.g = {g} must be >= 0 (m/s2, acting along -y)")
    return Gravity(g)


def _initial(table):
    moved = [key for key in ("e_ref", "sigma_v_ref") if key in table]
    require(not moved, f"initial.{', '.join(moved)}: the compression line's anchor is the "
            "material's: set material.e_ref and material.sigma_v_ref")
    check_keys(table, KEYS["initial"], "initial")
    value = table.get("pore_pressure", 0.0)
    if value != "balance":
        require(not isinstance(value, str), f"initial.pore_pressure = {value!r} must be a "
                "number or \"balance\"")
        value = number(table, "pore_pressure", "initial", 0.0)
    start = string(table, "stress", "initial", "uniform", STRESS_STARTS)
    geostatic = ("surcharge", "k0", "ocr")
    if start != "geostatic":
        given = [key for key in geostatic if key in table]
        require(not given, f"initial.{', '.join(given)} only apply to initial.stress = "
                "\"geostatic\": set it, or remove them")
    if start != "gravity":
        require("increments" not in table, "initial.increments only applies to "
                "initial.stress = \"gravity\": set it, or remove the key")
    if start == "uniform":
        return Initial(value)
    if start == "gravity":
        require(value == 0, f"initial.pore_pressure = {value!r}: a gravity start has no "
                "excess pore pressure (its self-weight is switched on drained): remove it")
        increments = integer(table, "increments", "initial") if "increments" in table \
            else GRAVITY_INCREMENTS
        require(1 <= increments <= MAX_INCREMENTS, f"initial.increments = {increments} "
                f"must lie in [1, {MAX_INCREMENTS}] (equal steps of the self-weight)")
        return Initial(stress=start, increments=increments)
    require(value != "balance", "initial.pore_pressure = \"balance\" sets the total stress "
            "to zero, which a geostatic start does not have: give a number (default 0)")
    k0 = table.get("k0", "nc")
    if k0 != "nc":
        require(not isinstance(k0, str), f"initial.k0 = {k0!r} must be a number in (0, 1] "
                "or \"nc\"")
        k0 = number(table, "k0", "initial")
        require(0 < k0 <= 1, f"initial.k0 = {k0} must lie in (0, 1] (or \"nc\": the "
                "material's normally consolidated value)")
    surcharge = number(table, "surcharge", "initial", 0.0)
    require(surcharge >= 0, f"initial.surcharge = {surcharge} must be >= 0 (kPa, "
            "compression positive)")
    ocr = number(table, "ocr", "initial", 1.0)
    require(1 <= ocr <= MAX_OCR, f"initial.ocr = {ocr} must lie in [1, {MAX_OCR:g}] (no "
            "soil is more overconsolidated)")
    return Initial(value, start, surcharge, k0, ocr)


def _require_weight(case):
    """Gravity needs alpha = 1 (p_w in excess of hydrostatic, buoyancy of the skeleton);
    a geostatic Cam-clay start needs a surcharge (p' > 0 at the top)."""
    if case.gravity.g > 0:
        require(case.fluid.biot_alpha == 1, f"material.biot_alpha = "
                f"{case.fluid.biot_alpha} must be 1 with gravity: the skeleton carries its "
                "buoyant weight, which holds for incompressible grains")
    if case.initial.stress == "gravity":
        require(case.analysis == "coupled", "initial.stress = \"gravity\" needs analysis "
                "= \"coupled\"")
        require(case.gravity.g > 0, "initial.stress = \"gravity\" switches on the "
                "self-weight: add [gravity] with g = 9.81, or start \"uniform\"")
    if case.initial.stress == "geostatic":
        require(case.analysis == "coupled", "initial.stress = \"geostatic\" needs analysis "
                "= \"coupled\"")
        mesh = case.geometry.mesh
        if mesh is not None:
            up = mesh.loop[mesh.surface()]
            low = mesh.points[up[np.argmin(mesh.points[up, 1])]]
            require(low[1] >= case.geometry.height * (1 - 1e-9), "initial.stress = "
                    "\"geostatic\" takes the depth below a level ground surface, and the "
                    f"mesh's surface falls to y = {low[1]:g} m at x = {low[0]:g} m (its top "
                    f"is at {case.geometry.height:g} m): use initial.stress = \"gravity\" "
                    "(the self-weight switched on drained before t = 0)")
        plastic = case.material().plastic
        require(case.initial.surcharge > 0 or not plastic,
                "initial.surcharge must be > 0 with a Cam-clay geostatic start: p' would be "
                "0 at the top surface (use e.g. 1 kPa)")
        require(plastic or case.initial.ocr == 1, "initial.ocr describes a compression "
                "line, which a linear elastic skeleton does not have: remove it (its void "
                "ratio is material.e0)")


def _exact(table):
    """``[exact]``: ``solution`` (see :data:`soilwater.references.closed_forms.SOLUTIONS`)
    and its parameters."""
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
    check_keys(table, KEYS["efg"], "efg")
    defaults = EFGSettings()
    order = table.get("order", defaults.order)
    require(isinstance(order, int) and not isinstance(order, bool) and order >= 1,
            f"efg.order = {order!r} must be an integer >= 1")
    values = {"weight_u": string(table, "weight_u", "efg", str(defaults.weight_u)),
              "scale_u": number(table, "scale_u", "efg", defaults.scale_u),
              "weight_p": string(table, "weight_p", "efg", str(defaults.weight_p)),
              "scale_p": number(table, "scale_p", "efg", defaults.scale_p),
              "integration": string(table, "integration", "efg", defaults.integration,
                                    INTEGRATIONS),
              "rebuild_quality": number(table, "rebuild_quality", "efg",
                                        defaults.rebuild_quality),
              "cells": string(table, "cells", "efg", defaults.cells, CELLS),
              "order": order,
              "essential": string(table, "essential", "efg", defaults.essential,
                                   ESSENTIAL),
              "penalty": number(table, "penalty", "efg", defaults.penalty),
              "correction": string(table, "correction", "efg", defaults.correction,
                                    CORRECTIONS),
              "stabilisation": string(table, "stabilisation", "efg",
                                       defaults.stabilisation, STABILISATIONS),
              "stabilisation_factor": number(table, "stabilisation_factor", "efg",
                                              defaults.stabilisation_factor)}
    require(0 < values["rebuild_quality"] < 1,
            f"efg.rebuild_quality = {values['rebuild_quality']:g} must lie between 0 and 1 "
            f"(a cell quality), e.g. {defaults.rebuild_quality:g}")
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
    check_keys(table, KEYS["fem"], "fem")
    defaults = FEMSettings()
    quality = number(table, "remesh_quality", "fem", defaults.remesh_quality)
    require(0 < quality <= 1, f"fem.remesh_quality = {quality:g} must lie in (0, 1] (the "
            "worst element's shape quality below which the mesh is re-triangulated: 1 "
            f"equilateral, 0 degenerate): use e.g. {defaults.remesh_quality:g}")
    return FEMSettings(remesh=string(table, "remesh", "fem", defaults.remesh, REMESH),
                       remesh_quality=quality)


def _extent(geometry):
    """The domain in words, for an error message."""
    if geometry.mesh is not None:
        return f"the mesh {geometry.mesh.path}"
    return f"[0, {geometry.width:g}] x [0, {geometry.height:g}]"


def _probes(table, geometry):
    probes = []
    for name, point in table.items():
        require(re.fullmatch(r"[A-Za-z0-9_-]+", name), f"probes.{name}: use letters, "
                "digits, _ and - in probe names (they become column names)")
        x, y = pair(point, f"probes.{name}")
        tol = 1e-9 * max(geometry.width, geometry.height)
        require(geometry.inside([(x, y)], tol)[0], f"probes.{name} = [{x}, {y}] lies "
                f"outside the domain ({_extent(geometry)}): move it inside")
        probes.append(Probe(name, (x, y)))
    return tuple(probes)
