"""The soil column's pore-pressure stability: the paper's Table 2 as a sweep of the nodes
in a support, the built-in column at several first steps and skeletons, triangle rules,
the stabilisations' factors and the pressure profiles after the first step.

Each function runs the built-in ``soil-column`` case over a sweep of settings through the
cached runner and returns a DataFrame; the tests assert on these tables and the report
writes them.
"""

import itertools

import numpy as np
import pandas as pd

from soilwater.case.loader import load_case
from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.quadrature import background
from soilwater.efg.statics import solve
from soilwater.studies.harness.metrics import (axis_profile, column_pollution, rating,
                                               terzaghi_errors)
from soilwater.studies.harness.runs import FEM_METHODS, solved
from soilwater.studies.harness.quick import pick


#: Weight combinations of the paper's Table 2 for (u, p_w), and E-B/E-B.
COMBINATIONS = {"Q/Q": ("quartic", "quartic"), "E-A/E-A": ("exp:0.5", "exp:0.5"),
                "E-A/E-B": ("exp:0.5", "exp:0.25"), "E-B/E-B": ("exp:0.25", "exp:0.25")}


#: The paper's Table 2 symbols, from its lowest to its highest density of nodes in a
#: support (× bad, △ better, ○ good); E-B/E-B is not in the paper.
PAPER_TABLE2 = {"Q/Q": "× → ×", "E-A/E-A": "△ → △", "E-A/E-B": "△ → ○", "E-B/E-B": ""}


#: Support scale factors of the Table 2 sweep (u and p_w alike).
TABLE2_SCALES = (1.3, 1.6, 2.0, 2.5, 3.0)


def table2(scales=TABLE2_SCALES, combinations=COMBINATIONS, permeabilities=(0.0, 1e-5),
           grid=(5, 41), dt=10.0, method="efg-paper"):
    """The paper's Table 2 as a sweep that varies one factor: the nodes in a support.

    Every weight combination at every scale factor (u and p_w alike) on one grid with
    one first step ``dt`` [s] (``h^2 / (c_v dt)`` = 30 at k = 1e-5 on 5 x 41 nodes), so
    the grid aspect and the ratio stay fixed while the supports grow, solved by
    ``method`` (the paper's configuration ``efg-paper``, or ``efg``). Interior pollution and its rating as in
    :func:`soilwater.studies.harness.metrics.column_pollution`.

    Returns
    -------
    pandas.DataFrame
        ``permeability, weights, scale, nodes_per_support`` (:func:`nodes_per_support`),
        ``overshoot, interior, rating`` and ``paper`` (:data:`PAPER_TABLE2`).
    """
    nx, ny = grid
    settings = list(itertools.product(permeabilities, combinations.items(), scales))
    results = solved([("soil-column", (
        f"material.permeability={k}", f"discretisation.nx={nx}", f"discretisation.ny={ny}",
        "time.steps=1", f"time.end={dt!r}", f"efg.weight_u={wu}", f"efg.weight_p={wp}",
        f"efg.scale_u={scale}", f"efg.scale_p={scale}"), method)
        for k, (_, (wu, wp)), scale in settings])
    rows = []
    for (k, (label, _), scale), result in zip(settings, results):
        rows.append({"permeability": k, "weights": label, "scale": scale,
                     "nodes_per_support": nodes_per_support(result.case),
                     **_pollution(result), "paper": PAPER_TABLE2.get(label, "")})
    return pd.DataFrame(rows)


def _scaled_step(base, ny):
    """The column's first step on ``ny`` nodes along it, scaled with h^2 from the built-in
    ``base`` (so ``h^2 / (c_v dt)`` stays that of the built-in column) [s]."""
    h = base.geometry.height / (ny - 1)
    return float(base.times()[1]) * (h / base.spacing[1]) ** 2


def _pollution(result):
    """``overshoot``, ``interior`` and ``rating`` of a column run's first step
    (:func:`soilwater.studies.harness.metrics.column_pollution`)."""
    overshoot, interior = column_pollution(result, 1)
    return {"overshoot": overshoot, "interior": interior, "rating": rating(interior)}


def nodes_per_support(case):
    """Mean number of nodes whose p_w support covers an integration point of the case's
    background cells (initial configuration): the paper's "density of nodal points
    within a support"."""
    s, nodes = case.efg, case.nodes()
    quad = background(case, nodes, case.boundary_loop(), s)
    phi = ShapeFunctions.build(nodes, quad.points, s.weight_p, s.scale_p).phi
    return float(np.diff(phi.indptr).mean())


#: Nodes per side of the inf-sup tests (:func:`soilwater.diagnostics.pairs.measure`).
INFSUP_SIZES = pick((5, 9, 17, 33), (5, 9, 17))
#: The stabilisation factors tried.
FACTORS = pick((1, 2, 4, 8), (1, 4))


def stabilisation_factors(kinds=("perturbation", "projection"), factors=FACTORS,
                          grids=((3, 21), (5, 41), (9, 81))):
    """EFG Q/Q with each pressure stabilisation times ``efg.stabilisation_factor``: the
    undrained (k = 0) column's first-step interior pollution per grid (first step scaled
    with h^2, as in :func:`column_stability`), Terzaghi's error for t >= 0.1 (5 x 41
    nodes) and the inf-sup test with v = 0 (:func:`soilwater.diagnostics.pairs.measure`).

    Returns
    -------
    pandas.DataFrame
        ``stabilisation``, ``factor``, ``interior_NxM`` per grid, ``terzaghi``, ``beta``
        (n = 33) and ``slope`` (:func:`soilwater.diagnostics.pairs.slopes`).
    """
    from soilwater.diagnostics import pairs as infsup

    base = load_case("soil-column")
    rows = []
    for kind, factor in itertools.product(kinds, factors):
        o = (f"efg.stabilisation={kind}", f"efg.stabilisation_factor={factor}")
        specs = [("soil-column", ("material.permeability=0.0", f"discretisation.nx={nx}",
                                  f"discretisation.ny={ny}", "time.steps=1",
                                  f"time.end={_scaled_step(base, ny)!r}",
                                  *o)) for nx, ny in grids]
        specs.append(("terzaghi", ("discretisation.nx=5", "discretisation.ny=41", *o)))
        *columns, terzaghi = solved(specs)
        test = infsup.measure(["efg"], INFSUP_SIZES, boundaries=["dirichlet"], overrides=o)
        fit = infsup.slopes(test).iloc[0]
        rows.append({"stabilisation": kind, "factor": factor,
                     **{f"interior_{nx}x{ny}": _pollution(r)["interior"]
                        for (nx, ny), r in zip(grids, columns)},
                     "terzaghi": terzaghi_errors(terzaghi)["max_error_load_after_0.1"],
                     "beta": test.beta.iloc[-1], "slope": fit.slope})
    return pd.DataFrame(rows)


#: The stabilised EFG's goal: an undrained first-step interior pollution on 5 x 41 nodes
#: below this fraction of the load.
TARGET = 0.02


def target_infsup(factors, target=TARGET, sizes=pick((9, 17, 33, 65), (9, 17, 33))):
    """The inf-sup test with v = 0 one refinement further (n = 65), for the smallest
    factor of each stabilisation that meets ``target`` in :func:`stabilisation_factors`
    (``factors``): whether its beta, still falling at n = 33, levels off.

    Returns
    -------
    pandas.DataFrame
        ``stabilisation, factor, n, beta, zero_modes`` and the group's ``slope`` and
        ``stable`` (:func:`soilwater.diagnostics.pairs.slopes`); empty when no factor meets it.
    """
    from soilwater.diagnostics import pairs as infsup

    tables = []
    for kind, part in factors[factors["interior_5x41"] < target].groupby("stabilisation"):
        factor = part.factor.min()
        test = infsup.measure(["efg"], sizes, boundaries=["dirichlet"], overrides=(
            f"efg.stabilisation={kind}", f"efg.stabilisation_factor={factor}"))
        fit = infsup.slopes(test).iloc[0]
        tables.append(test[["n", "beta", "zero_modes"]].assign(
            stabilisation=kind, factor=factor, slope=fit.slope, stable=fit.stable))
    columns = ["stabilisation", "factor", "n", "beta", "zero_modes", "slope", "stable"]
    return pd.concat(tables)[columns] if tables else pd.DataFrame(columns=columns)


def quadrature_orders(orders=pick((2, 4, 6), (2, 4)), combinations=COMBINATIONS):
    """Does a weight need a higher triangle rule? Each weight combination at each
    Delaunay rule degree (``efg.order``, VCI on): the column's first-step interior
    pollution (5 x 41 nodes, k = 0 and 1e-5), Terzaghi's error for t >= 0.1 (5 x 41),
    the patch test's displacement error and the cantilever's energy error (u's weight).
    No pressure stabilisation: the rule's effect on the weights alone; the static cases
    with the paper's penalty (Nitsche passes the patch test to round-off on any rule).

    Returns
    -------
    pandas.DataFrame
        ``weights, order, interior_k0, interior_k1e-5, terzaghi, patch, cantilever``.
    """
    column = ("discretisation.nx=5", "discretisation.ny=41", "time.steps=1", "time.end=10.0")
    settings = list(itertools.product(combinations.items(), orders))
    specs = []
    for (_, (wu, wp)), order in settings:
        o = (f"efg.weight_u={wu}", f"efg.weight_p={wp}", f"efg.order={order}",
             "efg.stabilisation=none")
        specs += [("soil-column", ("material.permeability=0.0", *column, *o)),
                  ("soil-column", ("material.permeability=1e-05", *column, *o)),
                  ("terzaghi", ("discretisation.nx=5", "discretisation.ny=41", *o))]
    results = iter(solved(specs))
    rows = []
    for (label, (wu, _)), order in settings:
        undrained, seeping, terzaghi = next(results), next(results), next(results)
        static = [f"efg.weight_u={wu}", f"efg.order={order}", "efg.essential=penalty"]
        rows.append({"weights": label, "order": order,
                     "interior_k0": column_pollution(undrained, 1)[1],
                     "interior_k1e-5": column_pollution(seeping, 1)[1],
                     "terzaghi": terzaghi_errors(terzaghi)["max_error_load_after_0.1"],
                     "patch": solve(load_case("patch-test", static)).summary["errors"][
                         "displacement"],
                     "cantilever": solve(load_case("cantilever", static)).summary["errors"][
                         "energy"]})
    return pd.DataFrame(rows)


#: Methods of the column stability table: FEM pairs and EFG settings (overrides): the
#: recommended configuration (``efg Q/Q, perturbation``), the same without pressure
#: stabilisation (with Q/Q and with the paper's E-A/E-B) and with the projection.
STABILITY_METHODS = {"fem-th": ("fem-th", ()), "fem-p1p1": ("fem-p1p1", ()),
                     "fem-p1p1-stab": ("fem-p1p1-stab", ()),
                     "efg Q/Q": ("efg", ("efg.stabilisation=none",)),
                     "efg E-A/E-B": ("efg", ("efg.stabilisation=none", "efg.weight_u=exp:0.5",
                                             "efg.weight_p=exp:0.25")),
                     "efg Q/Q, perturbation": ("efg", ("efg.stabilisation=perturbation",)),
                     "efg Q/Q, projection": ("efg", ("efg.stabilisation=projection",))}


def column_stability(permeabilities=(0.0, 1e-5), grids=((3, 21), (5, 41), (9, 81)),
                     methods=STABILITY_METHODS):
    """First-step pore-pressure stability of the soil column, boundary layer and interior
    apart (:func:`soilwater.studies.harness.metrics.column_pollution`), under refinement at
    the built-in column's ratio: the first step scales with h^2 (40 s at 3 x 21 nodes), so
    ``h^2 / (c_v dt)`` stays 30 at k = 1e-5.

    Returns
    -------
    pandas.DataFrame
        ``permeability, nodes, h, dt, method, overshoot, interior, rating``.
    """
    base = load_case("soil-column")
    settings = list(itertools.product(permeabilities, grids, methods.items()))
    specs = []
    for k, (nx, ny), (_, (method, extra)) in settings:
        dt = _scaled_step(base, ny)
        specs.append(("soil-column", (f"material.permeability={k}", f"discretisation.nx={nx}",
                                      f"discretisation.ny={ny}", "time.steps=1",
                                      f"time.end={dt!r}", *extra), method))
    rows = []
    for (k, (nx, ny), (label, _)), result in zip(settings, solved(specs)):
        rows.append({"permeability": k, "nodes": f"{nx}x{ny}", "h": result.case.spacing[1],
                     "dt": float(result.case.times()[1]), "method": label,
                     **_pollution(result)})
    return pd.DataFrame(rows)


def column_ratios(ratios=(3, 30, 300), methods=STABILITY_METHODS):
    """First-step pore-pressure stability of the built-in column (3 x 21 nodes,
    k = 1e-5) at first steps with these ``h^2 / (c_v dt)``.

    Returns
    -------
    pandas.DataFrame
        ``ratio, dt, method, overshoot, interior, rating``
        (:func:`soilwater.studies.harness.metrics.column_pollution`).
    """
    base = load_case("soil-column")
    dts = [float(base.times()[1] * stability_number(base) / ratio) for ratio in ratios]
    settings = list(itertools.product(zip(ratios, dts), methods.items()))
    results = solved([("soil-column", (f"time.end={dt!r}", "time.steps=1", *extra),
                         method) for (_, dt), (_, (method, extra)) in settings])
    rows = []
    for ((ratio, dt), (label, _)), result in zip(settings, results):
        rows.append({"ratio": ratio, "dt": dt, "method": label, **_pollution(result)})
    return pd.DataFrame(rows)


def column_skeletons(methods=STABILITY_METHODS, permeabilities=(0.0, 1e-5), grid=(5, 41),
                     dt=10.0):
    """The column's first step with the Cam-clay skeleton and with a linear elastic one
    of the same initial moduli (``material.model = "elastic"`` on the preset): how much
    of the pollution the clay's yielding adds.

    Returns
    -------
    pandas.DataFrame
        ``permeability, skeleton, method, overshoot, interior, rating``.
    """
    nx, ny = grid
    skeletons = {"Cam-clay": (), "elastic": ("material.model=elastic",)}
    settings = list(itertools.product(permeabilities, skeletons.items(), methods.items()))
    results = solved([("soil-column", (
        f"material.permeability={k}", f"discretisation.nx={nx}", f"discretisation.ny={ny}",
        "time.steps=1", f"time.end={dt!r}", *skeleton, *extra), method)
        for k, (_, skeleton), (_, (method, extra)) in settings])
    rows = []
    for (k, (skeleton, _), (label, _)), result in zip(settings, results):
        rows.append({"permeability": k, "skeleton": skeleton, "method": label,
                     **_pollution(result)})
    return pd.DataFrame(rows)


def stability_number(case):
    """``h^2 / (c_v dt0)`` of a column: h the vertical nodal spacing, c_v = mobility x
    (K + 4G/3) at the initial state, dt0 the first step."""
    modulus = case.material().constrained_modulus()
    dt0 = case.times()[1]
    return float(case.spacing[1] ** 2 / (case.fluid.mobility * modulus * dt0))


#: Runs of the column figure: label -> (method, overrides), at the built-in first step:
#: the paper's weight pairs in the paper's configuration, the recommended EFG and FEM.
COLUMN_RUNS = {**{f"EFG paper {label}": ("efg-paper", (f"efg.weight_u={u}",
                                                        f"efg.weight_p={p}"))
                  for label, (u, p) in COMBINATIONS.items()},
               "EFG recommended": ("efg", ()),
               **{method: (method, ()) for method in FEM_METHODS}}


def column_profiles(runs=COLUMN_RUNS):
    """Pore pressure along the soil column's axis after the first step, every run.

    Returns
    -------
    pandas.DataFrame
        ``run, y`` (current height, m), ``p_w`` over the load, and ``reference``: the
        Terzaghi series with the initial constrained modulus (indicative: Cam-clay
        yields under the load, so its consolidation is slower).
    """
    from soilwater.references.closed_forms import terzaghi

    results = solved([("soil-column", ("time.end=40.0",) + overrides, method)
                        for method, overrides in runs.values()])
    frames = []
    for label, result in zip(runs, results):
        case = result.case
        y, p = axis_profile(result, 1)
        load = -case.boundary.top.traction[1]
        fluid = case.fluid
        reference, _ = terzaghi(y, case.times()[1], load, case.geometry.height,
                                case.material().constrained_modulus(), fluid.biot_alpha,
                                fluid.storage, fluid.mobility)
        frames.append(pd.DataFrame({"run": label, "y": y, "p_w": p / load,
                                    "reference": reference / load}))
    return pd.concat(frames, ignore_index=True)
