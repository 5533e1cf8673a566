"""The TOML schema of a case: sections, keys, defaults, load-time bounds and overrides.

A case is a TOML file (or a built-in name, see
:func:`soilwater.case.loader.builtin_cases`) read by :func:`soilwater.case.loader.load_case`;
:func:`soilwater.case.validation.case_from_dict` checks it against this schema and builds
the :class:`soilwater.case.model.Case` the solvers read. This module holds the schema's
documentation and constants (the sections and their keys, the bounds) and the edits of a
raw case dict (:func:`apply_override`, :func:`expand_displacement`). Units are those of the
case (kPa, m, s in the built-in cases).

Conventions: x to the right, y up, origin at the lower-left corner of the rectangle;
stress and traction are tension positive (a traction ``[0, -1]`` on the top edge is a
compressive load); pore water pressure p_w is compression positive;
``sigma = sigma' - alpha p_w I``. Gravity (``[gravity]``) acts along -y; p_w is then the
pore pressure in excess of hydrostatic, the water table at or above the top.

Schema (every case has the same one; unknown keys are an error)::

    name = "my-case"                  # default: the file's stem
    description = "one line"
    analysis = "coupled"              # "coupled" (Biot u-p, default) or "static" (dry,
                                      # one load step, no pore pressure)

    [geometry]
    shape = "rectangle"               # or "mesh" (the default with mesh)
    width = 3.0                       # m, along x, in [1e-6, 1e6]
    height = 4.0                      # m, along y, in [1e-6, 1e6]
    # mesh = "slope.msh"              # instead of width and height: a gmsh mesh (.msh,
                                      # read by meshio) or geometry (.geo, meshed by the
                                      # optional gmsh package), relative to the case
                                      # file; 3-node triangles, one boundary loop, the
                                      # bounding box's lower-left corner at the origin;
                                      # its physical curves are the boundary groups of
                                      # [boundary.NAME] (every boundary facet in one),
                                      # its physical surfaces the material regions; no
                                      # [discretisation] (the mesh's vertices are the
                                      # nodes); soilwater.geometry.mesh

    [discretisation]
    nx = 7                            # grid nodes along x (>= 2): spacing width/(nx-1)
    ny = 9                            # grid nodes along y (>= 2): spacing height/(ny-1)
    layout = "grid+centres"           # "grid" (default) or grid plus one node per cell centre
                                      # (spacing aspect hx/hy of every cell in [1e-3, 1e3])
    # x = [[1.0, 16], [20.0, 24, 30.0]] # instead of nx: the grid lines along x in pieces
                                      # [to (m), spacings, ratio]: from the previous
                                      # piece's end (or 0) to "to" (increasing, the last
                                      # at the width), the last spacing "ratio" times the
                                      # first (default 1, in [1e-3, 1e3]), geometric in
                                      # between; y (instead of ny) likewise, bottom to
                                      # top; square EFG cells need a regular grid
    jitter = 0.0                      # interior nodes moved at random by up to this
                                      # fraction of the smallest spacing (0 <= jitter < 0.25)
    seed = 0                          # seed of the jitter (numpy default_rng)

    [material]                        # soilwater.material.presets.material_from_spec, plus fluid
                                      # keys:
    preset = "table1"                 # optional: start from the paper's Table 1
    model = "original"                # "original", "modified" or "elastic"
    # lambda = 0.11                   # Cam-clay: lambda, kappa (slopes of v against
    # kappa = 0.04                    # ln p'; or Cc, Cr, per decade: Cc = lambda ln 10),
    # M = 1.42                        # M, nu, e0, p0 [kPa] (the initial state:
    # nu = 0.333                      # e0 at p'0), ocr (default 1), G (default from nu),
                                      # e_ref and sigma_v_ref [kPa] (the oedometer's
                                      # anchor of the compression line: e_ref on the
                                      # normally consolidated 1-D line at sigma'_v =
                                      # sigma_v_ref; with them e0 and p0 are optional,
                                      # p0 = sigma_v_ref and e0 on the line);
    # e0 = 0.83                       # elastic: E [kPa] (or mv [1/kPa], the
    # p0 = 3.0                        # oedometric compressibility 1/(constrained
                                      # modulus): a constant-m_v skeleton), nu, p0
                                      # (default 0), e0 (default 1); a missing key is
                                      # named
    permeability = 0.0                # k [m/s] >= 0 (Darcy: q = -(k/gamma_w) grad p_w)
    gamma_w = 9.81                    # unit weight of water [kN/m3] > 0
    biot_alpha = 1.0                  # Biot coefficient in (0, 1]
    storage = 0.0                     # S = 1/M_biot [1/kPa] >= 0
    permeability_law = "constant"     # or "taylor": k = k_ref 10^((e - e_k)/C_k),
                                      # "kozeny-carman": k = k_ref (e^3/(1+e)) /
                                      # (e_k^3/(1+e_k)), or "xie-leo": k = k_ref
                                      # ((1+e)/(1+e_k))^2; k_ref = permeability
    permeability_e = 1.2              # e_k > 0 (required by taylor, kozeny-carman and
                                      # xie-leo, refused by constant)
    permeability_ck = 0.5             # C_k > 0 (required by taylor, refused otherwise)
    specific_gravity = 2.65           # Gs of the solids > 1: the saturated unit weight
                                      # (Gs + e) gamma_w / (1 + e); only with [gravity]

    [material.crust]                  # optional, on a mesh: the physical surface "crust"
    lambda = 0.1                      # gets [material]'s skeleton with these keys
    permeability = 1e-8               # changed (a table with model or preset starts
                                      # afresh) and its own permeability; the water and
                                      # Gs stay [material]'s (soilwater.case.regions)

    [gravity]                         # optional
    g = 9.81                          # m/s2 >= 0 along -y (default 0: weightless); the
                                      # buoyant weight (Gs - 1) gamma_w (g / 9.81) / (1 + e)
                                      # loads the skeleton (biot_alpha must be 1)

    [initial]                         # optional
    pore_pressure = "balance"         # a number (default 0) or "balance": p_w0 = -p'0/alpha,
                                      # total stress zero; sigma'0 = -p'0 I (material p0);
                                      # a number with a geostatic start, 0 with a
                                      # gravity start
    stress = "uniform"                # or "geostatic": sigma'v from the buoyant weight
                                      # under the surcharge, sigma'h = k0 sigma'v, e from
                                      # the compression line (soilwater.physics.geostatic;
                                      # a level top only); or "gravity" (needs [gravity],
                                      # any top, e.g. a slope): the uniform state takes
                                      # its self-weight drained before t = 0, the run
                                      # starts on the configuration it settled to with
                                      # u = 0 and p_w = 0 (soilwater.nonlinear.gravity_start)
    surcharge = 10.0                  # geostatic: kPa >= 0 on the top, in equilibrium at
                                      # t = 0 (> 0 for Cam-clay: p' > 0 at the top)
    k0 = "nc"                         # geostatic: in (0, 1], or "nc" (the material's
                                      # normally consolidated value)
    ocr = 1.0                         # geostatic: vertical overconsolidation ratio >= 1
    increments = 10                   # gravity: equal steps of the self-weight, in
                                      # [1, 1000] (default 10; a step that fails is halved)

    [boundary.left]                   # each of left, right, bottom, top exactly once;
                                      # on a mesh, any of its boundary groups (the others
                                      # free, impermeable, unloaded), no segments, no
                                      # rigid, roller on vertical or horizontal groups;
                                      # a group may be a footing (uy = "footing" with
                                      # settlement_rate or force, as a segment below)
    ux = "fixed"                      # "free" (default), "fixed", "prescribed", "rigid"
    uy = "free"
    # displacement = "roller"         # shorthand instead of ux/uy: "roller" (normal
                                      # component fixed), "fixed" or "free"
    traction = [0.0, 0.0]             # total traction [kPa] x load factor (default zero),
                                      # or a profile [[x, tx, ty], ...] piecewise linear
                                      # in the initial x (increasing; constant beyond)
    water = "impermeable"             # or "drained" (p_w = 0); drained wins at a corner

    [boundary.top.footing]            # optional named segments of an edge (any name of
    from = 0.0                        # letters, digits, _, -): m along the edge in the
    to = 1.0                          # initial configuration (x on top and bottom, y on
                                      # left and right), 0 <= from < to <= edge length;
                                      # disjoint segments; no traction of their own
    ux = "fixed"                      # "free" (default), "fixed" or "prescribed"
    uy = "footing"                    # the same, or "footing" (top or bottom edge only)
    settlement_rate = 0.01            # footing: m/s, positive down (velocity control), or
    # force = 50.0                    # kN/m, compression positive, x load factor (load
                                      # control; at most one per case, none with a
                                      # rigid edge); exactly one of the two
    # water = "drained"               # default: the edge's water condition

    [loading]                         # optional
    velocity_gradient = [[0.0, 0.0], [0.0, -0.01]]   # L [1/s], constant (default zero)
    load = 1.0                        # a factor from t = 0+ (step load, the default) or
                                      # [[t0, f0], [t1, f1], ...] piecewise linear

    [time]                            # every time in seconds or "NUMBER UNIT", UNIT
                                      # s, min, h, d (day, days), yr (year, years) of
                                      # 365.25 d: "60 yr", "1e6 s" (loading.load too)
    end = 20.0                        # s
    steps = 100                       # equal steps, or instead: dt0, growth, dt_max
    output = [1.0, "0.5 min"]         # optional: fields are written at t = 0 and at
                                      # these times only, each made a time level (a
                                      # history row exactly there); default: every level
    on_failure = "error"              # a step that fails after every halving ends the
                                      # run with an error and no result; "stop": the
                                      # result ends at the last converged level, and
                                      # its summary says where and why it stopped

    [probes]                          # optional: name = [x, y] inside the domain;
    centre = [1.5, 2.0]               # history columns p_w@centre [kPa] and ux@centre,
                                      # uy@centre [m] (the probe moves with the soil)

    [exact]                           # optional: a closed form of soilwater.references.closed_forms
    solution = "timoshenko-beam"      # boundary data for "exact" edges, error reference
    P = 1000.0                        # ... and the solution's parameters

    [diagnostics]                     # optional, both solvers
    uniqueness = false                # per step, the smallest eigenvalue of the tangent
                                      # restricted to the undrained constraint
                                      # (soilwater.diagnostics.bifurcation; history
                                      # column "uniqueness")

    [efg]                             # optional meshless settings (defaults shown)
    weight_u = "quartic"              # MLS weight of u: quartic (Q), cubic or exp:C with
                                      # 1e-3 <= C <= 1e3 (E-A = exp:0.5, E-B = exp:0.25)
    scale_u = 1.3                     # support = scale x distance to the 8th nearest node,
                                      # 1 <= scale <= 1000
    weight_p = "quartic"              # the same for the pore pressure p_w
    scale_p = 1.3
    integration = "gauss"             # where the material state lives: "gauss" (Gauss
                                      # points of Delaunay triangles moved with the
                                      # nodes), "paper" (nodes, MLS-interpolated to cells
                                      # rebuilt each step: the paper's) or "nodal"
                                      # (the nodes: stabilised conforming nodal
                                      # integration on median-dual cells)
    rebuild_quality = 0.3             # "nodal" and "gauss" re-triangulate below this
                                      # cell quality
    cells = "delaunay"                # background cells: delaunay or squares ("paper")
    order = 2                         # Gauss order (squares: per direction; triangles:
                                      # degree, at most 19)
    essential = "nitsche"             # essential conditions: "nitsche" or "penalty"
                                      # (soilwater.efg.essential.nitsche: consistent,
                                      # no factor to choose, a matrix on the
                                      # stiffness's scale)
    penalty = 1e6                     # penalty factor relative to the stiffness scale
                                      # (essential = "penalty")
    correction = "vci"                # consistent test gradients (soilwater.efg.vci) or "none"
    stabilisation = "perturbation"    # or "none"; "perturbation": the flow-equation term
                                      # -h^2/(4M) int grad(p - p_n) . grad(q) of
                                      # fem-p1p1-stab on the MLS pressure; or
                                      # "projection": -(1/G) int (dp - Pi dp)(q - Pi q),
                                      # Pi the mean over each background cell
    stabilisation_factor = 1.0        # multiplies that h^2/(4M) or 1/G, 0 < f <= 1000

    [fem]                             # optional FEM reference settings (defaults shown)
    remesh = "never"                  # or "delaunay": after a converged step whose worst
                                      # element's quality (soilwater.geometry.quality.cell_quality)
                                      # is below remesh_quality, re-triangulate the
                                      # current vertices (Delaunay inside the current
                                      # boundary) and transfer the state (triangle
                                      # pairs: fem-th, fem-p1p1, fem-p1p1-stab)
    remesh_quality = 0.3              # in (0, 1]; 1 re-triangulates after every step

Boundary kinds of a displacement component:

* ``free``: natural; the edge's traction component acts there.
* ``fixed``: zero displacement.
* ``prescribed``: velocity ``v = L x`` at the node's current position, L from
  ``loading.velocity_gradient`` (which must then be non-zero).
* ``exact``: displacement from the case's ``[exact]`` solution; ``traction = "exact"``
  likewise takes the traction ``sigma n`` from it.
* ``rigid`` (``uy`` of the top or bottom edge only): the whole edge settles by one unknown
  uniform vertical displacement (a frictionless rigid plate, Mandel's problem) whose total
  force is ``traction[1] x load factor x (initial edge length)`` per unit thickness.

* ``footing`` (``uy`` of a named segment of the top or bottom edge, or of a mesh's
  boundary group): a rigid strip footing, the segment's (group's) uy moving as one
  body; ``settlement_rate`` imposes uy = -rate x t on it, ``force`` lets it settle by
  one unknown whose total force is ``-force x load factor`` (the ``rigid`` plate's
  machinery). With ``ux = "fixed"`` it
  is rough (no sideways motion), with ``ux = "free"`` smooth. Coupled analyses only.

A named segment overrides its edge's kinds (and, if given, its water condition) where
the initial coordinate along the edge lies in ``[from, to]`` (within 1e-9 of the
smallest spacing): at the EFG boundary Gauss points and the FEM DOFs there; the rest of
the edge keeps the edge's conditions, its traction included. Each segment adds the
history columns ``settlement@NAME`` (m, positive down: the footing's settlement, or the
mean downward displacement of a segment that is no footing) and ``pressure@NAME``
(kPa, compression positive: the vertical force the boundary exerts on the soil there, in
excess of the initial state, over the current width; see
:func:`soilwater.nonlinear.history.segment_columns`).

On a mesh, a boundary group that is a footing, has a ``prescribed`` component or
carries a traction adds the same two columns under its own name: ``settlement@NAME`` the
footing's settlement or the mean downward displacement of its vertices, ``pressure@NAME``
the reaction over the current distance between its end vertices plus the applied ``-ty``
(times the load factor, mean over its vertices).

At a corner both edges' conditions apply (a segment that reaches the corner counts
there); two different non-free kinds on the same
component of a corner are an error. Tractions are loads in excess of the initial state,
which is taken as in equilibrium.

Every number must be finite. Load-time bounds (:func:`soilwater.case.validation.case_from_dict`
refuses a case outside them, naming the key, so that ``soilwater show`` fails wherever
``run`` would):

* ``geometry.width`` and ``height`` in [1e-6, 1e6] m, and the grid spacing aspect
  ``hx/hy = (width/(nx-1)) / (height/(ny-1))`` in [1e-3, 1e3]: bounds against absurd
  input (a width of 1e300 overflows the EFG's cell search, inf breaks both solvers).
  Within them a stretched plain grid still needs a larger EFG scale factor, about a
  quarter of the aspect (long over short spacing) beyond an aspect of 4; the solver
  reports that, naming the scale factor's key.
* The displacement must be restrained against the three rigid motions: some edge's ``ux``
  and some edge's ``uy`` ``fixed``, ``prescribed`` or ``exact`` (a ``rigid`` plate is
  load-controlled and stops no translation), and rotation stopped by ``ux`` restrained on
  the left or right edge, ``uy`` on the top or bottom edge, or ``ux`` on both the top and
  bottom (``uy`` on both the left and right).
* ``efg.scale_u`` and ``scale_p`` in [1, 1000]: below 1 a node's support stops short of
  its 8th nearest node, the distance that defines it, and whether each point still sees
  3 non-collinear nodes depends on the layout (on the built-in cases and their variants
  the smallest working factor ranges from 0.69 to 0.90, with condition numbers down to
  1e-7, and stretched grids need more); above 1000 the supports cover the body many times
  over and the moment matrices' conditioning, falling as 1/scale^2, nears the MLS
  safeguard (reached near 1e4 to 1e5).
* ``efg.weight_u`` and ``weight_p``: :func:`soilwater.efg.settings.weight_form` (outside
  1e-3 <= C <= 1e3 the exponential weight underflows to a spike or, above, equals its
  limit ``1 - r^2`` to 1e-6 while its formula loses digits and divides by zero near
  C = 1e8).
* ``efg.order`` an integer >= 1, at most 19 with Delaunay cells (the highest triangle
  rule of scikit-fem).

Time stepping: ``steps`` gives equal steps; otherwise ``t_1 = dt0`` and
``t_{n+1} = t_n + min((growth - 1) t_n, dt_max)`` (time levels grow geometrically until the
step reaches ``dt_max``), the last step cut to land on ``end``. This is MOOSE's Terzaghi
stepping (``dt = min(0.5 t, 0.1)``, peer-data case A): 118 steps to t = 10.

:func:`soilwater.case.loader.load_case` also takes overrides ``"section.key=value"`` (value in
TOML syntax, a bare word is read as a string; :func:`apply_override`), e.g.
``material.permeability=1e-6`` or ``boundary.top.water="drained"``. Setting
``time.steps`` drops the geometric keys (and the reverse), setting ``discretisation.nx``
drops ``discretisation.x`` (and the reverse; likewise ``ny`` and ``y``); setting an edge's
``displacement`` replaces its ``ux`` and ``uy``.
"""

import tomllib

from soilwater.errors import require

SECTIONS = ("geometry", "discretisation", "material", "initial", "gravity", "boundary",
            "loading", "time", "probes", "exact", "diagnostics", "efg", "fem")
"""The sections of a case, besides the top-level keys ``name``, ``description`` and
``analysis``."""
KEYS = {
    "geometry": ("shape", "width", "height", "mesh"),
    "discretisation": ("nx", "ny", "x", "y", "layout", "jitter", "seed"),
    "diagnostics": ("uniqueness",),
    "initial": ("pore_pressure", "stress", "surcharge", "k0", "ocr", "increments"),
    "gravity": ("g",),
    "edge": ("ux", "uy", "displacement", "traction", "water"),
    "segment": ("from", "to", "ux", "uy", "water", "settlement_rate", "force"),
    "loading": ("velocity_gradient", "load"),
    "time": ("end", "steps", "dt0", "growth", "dt_max", "output", "on_failure"),
    "efg": ("weight_u", "scale_u", "weight_p", "scale_p", "integration", "rebuild_quality",
            "cells", "order", "essential",
            "penalty", "correction", "stabilisation", "stabilisation_factor"),
    "fem": ("remesh", "remesh_quality"),
}
"""The keys each section accepts (``edge``: each ``[boundary.<side>]``, which also takes
named segments as sub-tables; ``segment``: each ``[boundary.<side>.<name>]``). ``[material]``,
``[probes]`` and ``[exact]`` take the keys of the material, the probe names and the
solution's parameters."""
GEOMETRIC = ("dt0", "growth", "dt_max")
"""The keys of geometric time stepping (instead of ``time.steps``)."""
LENGTHS = (1e-6, 1e6)
"""Accepted range of ``geometry.width`` and ``height`` [m]."""
ASPECTS = (1e-3, 1e3)
"""Accepted range of the grid spacing aspect ``hx/hy``."""
GRADINGS = (1e-3, 1e3)
"""Accepted range of the ratio of a grid piece (``discretisation.x``, ``y``: last spacing
over first)."""
SCALES = (1.0, 1e3)
"""Accepted range of the MLS support scale factors ``efg.scale_u`` and ``scale_p``."""
MAX_TRIANGLE_ORDER = 19
"""Highest degree of scikit-fem's triangle rules (``efg.order`` with Delaunay cells)."""
MAX_INCREMENTS = 1000
"""Most increments of a gravity start's self-weight (``initial.increments``)."""
_NORMAL = {"left": "ux", "right": "ux", "bottom": "uy", "top": "uy"}


def _key_path(key):
    """The parts of a dotted key: split at the dots, or read as a TOML dotted key when it
    quotes a part (``boundary."a.b".water``); ``[]`` for a malformed one."""
    if '"' not in key and "'" not in key:
        return [part.strip() for part in key.split(".")]
    try:
        table = tomllib.loads(f"{key} = 0")
    except tomllib.TOMLDecodeError:
        return []
    path = []
    while isinstance(table, dict) and len(table) == 1:
        (part, table), = table.items()
        path.append(part)
    return path


def apply_override(data, text):
    """Set ``section.key[.key]=value`` in a raw case dict, in place.

    Parameters
    ----------
    data : dict
        The case in TOML layout, not yet validated.
    text : str
        ``section.key=value`` with the value in TOML syntax (a bare word is read as a
        string), e.g. ``material.permeability=1e-6`` or ``boundary.top.water=drained``;
        a part holding a dot is quoted as in TOML (``boundary."a.b".water=drained``).
        Setting ``time.steps`` drops the geometric keys (and the reverse), setting
        ``discretisation.nx`` drops ``discretisation.x`` (and the reverse, likewise for y);
        setting an edge's ``displacement`` replaces its ``ux`` and ``uy``, and setting ``ux`` or
        ``uy`` of an edge given by ``displacement`` expands the shorthand first; setting
        ``material.model`` (or a region's) drops the skeleton keys the new model does not
        take (``lambda`` ... for ``elastic``, ``E`` and ``mv`` for Cam-clay), so that a
        resolved case (:meth:`soilwater.case.model.Case.replace`) can change its model and
        is then told which keys the new one needs.

    Raises
    ------
    TypeError
        ``text`` is not a string.
    InputError
        A malformed override, or one that descends into a value.

    Examples
    --------
    >>> data = {"time": {"end": 1.0, "dt0": 0.1, "growth": 1.5, "dt_max": 0.5}}
    >>> apply_override(data, "time.steps=10")
    >>> data
    {'time': {'end': 1.0, 'steps': 10}}
    >>> data = {}
    >>> apply_override(data, 'boundary."a.b".water=drained')   # a group named a.b
    >>> data
    {'boundary': {'a.b': {'water': 'drained'}}}
    """
    if not isinstance(text, str):
        raise TypeError(f"an override must be a string 'section.key=value', e.g. "
                        f"\"material.permeability=1e-6\", not {type(text).__name__}")
    key, sep, value = text.partition("=")
    path = _key_path(key) if sep else []
    require(sep and path and all(path), f"override {text!r}: write section.key=value, "
            "e.g. material.permeability=1e-6 (quote a name holding a dot: "
            "boundary.\"a.b\".water=drained)")
    try:
        value = tomllib.loads(f"v = {value}")["v"]
    except (tomllib.TOMLDecodeError, ValueError):    # ValueError: an integer too long
        value = value.strip()
    require(value != {}, f"override {text!r} sets an empty table, which would drop every "
            f"key of {key.strip()}: set its keys one at a time, e.g. {key.strip()}.KEY=VALUE")
    table = data
    for depth, part in enumerate(path[:-1]):
        table = table.setdefault(part, {})
        require(isinstance(table, dict), f"override {text!r}: "
                f"{'.'.join(path[:depth + 1])} is a value, not a section")
    last = path[-1]
    for other in _replaced_keys(path, value):
        table.pop(other, None)
    if len(path) == 3 and last in ("ux", "uy") and "displacement" in table:
        table.update(expand_displacement(table.pop("displacement"), path[1]))
    table[last] = value


def _replaced_keys(path, value):
    """Keys that an override of ``path`` with ``value`` replaces (the other way of saying
    the same, or another model's parameters)."""
    if path[0] == "material" and path[-1] == "model" and len(path) <= 3:
        from soilwater.material.presets import model_keys

        other = "original" if value == "elastic" else "elastic"
        return tuple(model_keys(other) - model_keys(value))
    if path[0] == "time" and path[-1] == "steps":
        return GEOMETRIC
    if path[0] == "time" and path[-1] in GEOMETRIC:
        return ("steps",)
    if path[0] == "discretisation" and path[-1] in ("nx", "ny", "x", "y"):
        return ({"nx": "x", "ny": "y", "x": "nx", "y": "ny"}[path[-1]],)
    if path[0] == "boundary" and path[-1] == "displacement":
        return ("ux", "uy")
    return ()


def expand_displacement(value, side, normal=None):
    """The ``displacement`` shorthand of edge ``side`` as ``{"ux": ..., "uy": ...}``.

    ``roller`` fixes the edge's normal component (``ux`` on the left and right edges,
    ``uy`` on the bottom and top; ``normal``, ``"ux"`` or ``"uy"``, on a mesh's boundary
    group) and frees the other; ``fixed`` and ``free`` set both.

    Examples
    --------
    >>> expand_displacement("roller", "bottom")
    {'ux': 'free', 'uy': 'fixed'}
    """
    require(value in ("roller", "fixed", "free"), f"boundary.{side}.displacement = "
            f"{value!r} is unknown: use roller, fixed or free (or set ux and uy)")
    if value == "roller":
        normal = normal or _NORMAL.get(side)
        require(normal is not None, f"boundary.{side}.displacement = \"roller\" needs a "
                "vertical or horizontal boundary group (a roller fixes the component "
                "normal to it): set ux and uy instead")
        return {"ux": "free", "uy": "free", normal: "fixed"}
    return {"ux": value, "uy": value}
