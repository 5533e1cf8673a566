"""Verification tables of the EFG solvers: patch test, cantilever convergence, the paper's
unconfined compression and soil column, Terzaghi and Mandel.

Each function runs the built-in case over a sweep of settings and returns a DataFrame;
the tests assert on these tables and the report writes them.
"""

import itertools

import numpy as np
import pandas as pd

from soilwater.studies.harness.metrics import (axis_profile, column_pollution, mandel_errors,
                                 moose_errors, rating, terzaghi_errors)
from soilwater.studies.harness import runner
from soilwater.studies.peers.study import moose_terzaghi
from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.quadrature import background
from soilwater.efg.statics import solve
from soilwater.references.closed_forms import undrained_pressure
from soilwater.diagnostics.bifurcation import onset
from soilwater.material.driver import run_test
from soilwater.errors import SoilwaterError
from soilwater.case.loader import load_case

#: The paper's weights: quartic (Q), exponential c = 0.5 (E-A) and c = 0.25 (E-B).
WEIGHTS = {"Q": "quartic", "E-A": "exp:0.5", "E-B": "exp:0.25"}
CELLS = ("delaunay", "squares")


def patch_test(corrections=("vci", "none"), cells=CELLS):
    """Relative errors of the linear patch test for each cell type and correction."""
    rows = []
    for cell, correction in itertools.product(cells, corrections):
        result = solve(load_case("patch-test", [f"efg.cells={cell}",
                                                f"efg.correction={correction}"]))
        rows.append({"cells": cell, "correction": correction,
                     "order": result.options["order"], **result.summary["errors"]})
    return pd.DataFrame(rows)


def cantilever_convergence(levels=((13, 4), (25, 7), (49, 13), (97, 25)),
                           weights=WEIGHTS, cells=CELLS, corrections=("vci",)):
    """Energy-norm error of the Timoshenko cantilever under refinement.

    Returns
    -------
    pandas.DataFrame
        One row per (weight, cells, correction, level): ``h`` (nodal spacing along x), ``nodes``,
        the three relative errors and ``rate``, the energy-norm convergence rate
        ``d ln(error) / d ln(h)`` against the previous level (empty on the first).
    """
    rows = []
    for (label, weight), cell, correction in itertools.product(weights.items(), cells,
                                                               corrections):
        previous = None
        for nx, ny in levels:
            case = load_case("cantilever", [f"discretisation.nx={nx}",
                                            f"discretisation.ny={ny}",
                                            f"efg.weight_u={weight}", f"efg.cells={cell}",
                                            f"efg.correction={correction}"])
            errors = solve(case).summary["errors"]
            h = case.spacing[0]
            rate = (np.log(previous[1] / errors["energy"]) / np.log(previous[0] / h)
                    if previous else np.nan)
            rows.append({"weight": label, "cells": cell, "correction": correction,
                         "nx": nx, "ny": ny, "h": h, "nodes": nx * ny, **errors,
                         "rate": rate})
            previous = (h, errors["energy"])
    return pd.DataFrame(rows)


#: The runs of the paper's Figs. 4 and 6: label -> (method, overrides).
PATH_RUNS = {
    "EFG, Delaunay cells": ("efg", ("efg.cells=delaunay",)),
    "EFG, square cells": ("efg", ("efg.cells=squares",)),
    "EFG, Delaunay, plain Gauss": ("efg", ("efg.cells=delaunay", "efg.correction=none")),
    "EFG, squares, plain Gauss": ("efg", ("efg.cells=squares", "efg.correction=none")),
    "FEM Taylor-Hood (fem-th)": ("fem-th", ()),
    "FEM P1/P1 (fem-p1p1)": ("fem-p1p1", ()),
}
#: The paper's two homogeneous tests and the driver test with the same stretching.
PATH_CASES = {"unconfined-compression": "undrained-plane-strain",
              "simple-shear": "undrained-simple-shear"}


def stress_paths(cases=tuple(PATH_CASES), runs=PATH_RUNS):
    """Each run of each case beside the stress-point driver, per step (paper Figs. 4, 6).

    The unconfined compression runs record the uniqueness indicator
    (``diagnostics.uniqueness``).

    Returns
    -------
    pandas.DataFrame
        Long format: ``case, run, time, strain`` (axial, or shear for simple shear),
        ``p, q`` (p', q over p'0), ``err`` (paper eq. 1, NaN where undefined),
        ``uniqueness`` (NaN where not recorded) and the driver's ``p_driver, q_driver`` at
        the same strain.
    """
    settings = list(itertools.product(cases, runs.items()))
    results = solved([(case, overrides + UNIQUENESS.get(case, ()), method)
                        for case, (_, (method, overrides)) in settings])
    frames = []
    for (case, (label, _)), result in zip(settings, results):
        history, clay = result.history, result.case.material()
        strain = history["gamma" if case == "simple-shear" else "eps_a"]
        driver = run_test(clay, PATH_CASES[case], float(strain.max()), 2000)
        frames.append(pd.DataFrame({
            "case": case, "run": label, "time": history.time, "strain": strain,
            "p": history.p / clay.p0, "q": history.q / clay.p0,
            "err": history.err.astype(float),
            "uniqueness": history.get("uniqueness", np.nan),
            "p_driver": np.interp(strain, driver.eps_a, driver.p) / clay.p0,
            "q_driver": np.interp(strain, driver.eps_a, driver.q) / clay.p0}))
    return pd.concat(frames, ignore_index=True)


#: Extra overrides per case of :func:`stress_paths`: the indicator where it is reported.
UNIQUENESS = {"unconfined-compression": ("diagnostics.uniqueness=true",)}


def path_summary(table):
    """Path error (over p'0) and ERR per case and run, before the discrete onset of the
    loss of uniqueness (comparable between methods; the whole run where the indicator
    stays positive or is not recorded) and over the whole run (branch-dependent past the
    onset: round-off chooses the branch)."""
    gap = np.maximum(np.abs(table.p - table.p_driver), np.abs(table.q - table.q_driver))
    rows = []
    for (case, run), g in table.assign(path_error=gap).groupby(["case", "run"], sort=False):
        start = onset(g.strain, g.uniqueness) if g.uniqueness.notna().all() else np.nan
        before = g[g.strain < start] if np.isfinite(start) else g
        rows.append({"case": case, "run": run, "onset": start,
                     "path_error_before": before.path_error.max(),
                     "err_before": before.err.max(), "path_error": g.path_error.max(),
                     "err_max": g.err.max(), "err_final": g.err.iloc[-1]})
    return pd.DataFrame(rows)


#: Weight combinations of the paper's Table 2 for (u, p_w), and E-B/E-B.
COMBINATIONS = {"Q/Q": ("quartic", "quartic"), "E-A/E-A": ("exp:0.5", "exp:0.5"),
                "E-A/E-B": ("exp:0.5", "exp:0.25"), "E-B/E-B": ("exp:0.25", "exp:0.25")}
#: The paper's Table 2 symbols, from its lowest to its highest density of nodes in a
#: support (× bad, △ better, ○ good); E-B/E-B is not in the paper.
PAPER_TABLE2 = {"Q/Q": "× → ×", "E-A/E-A": "△ → △", "E-A/E-B": "△ → ○", "E-B/E-B": ""}
#: Support scale factors of the Table 2 sweep (u and p_w alike).
TABLE2_SCALES = (1.3, 1.6, 2.0, 2.5, 3.0)


def table2(scales=TABLE2_SCALES, combinations=COMBINATIONS, permeabilities=(0.0, 1e-5),
           grid=(5, 41), dt=10.0):
    """The paper's Table 2 as a sweep that varies one factor: the nodes in a support.

    Every weight combination at every scale factor (u and p_w alike) on one grid with
    one first step ``dt`` [s] (``h^2 / (c_v dt)`` = 30 at k = 1e-5 on 5 x 41 nodes), so
    the grid aspect and the ratio stay fixed while the supports grow. Interior pollution
    and its rating as in :func:`soilwater.studies.harness.metrics.column_pollution`.

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
        f"efg.scale_u={scale}", f"efg.scale_p={scale}"))
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


def stabilisation_factors(kinds=("perturbation", "projection"), factors=(1, 2, 4, 8),
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
        test = infsup.measure(["efg"], boundaries=["dirichlet"], overrides=o)
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


def target_infsup(factors, target=TARGET, sizes=(9, 17, 33, 65)):
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


def quadrature_orders(orders=(2, 4, 6), combinations=COMBINATIONS):
    """Does a weight need a higher triangle rule? Each weight combination at each
    Delaunay rule degree (``efg.order``, VCI on): the column's first-step interior
    pollution (5 x 41 nodes, k = 0 and 1e-5), Terzaghi's error for t >= 0.1 (5 x 41),
    the patch test's displacement error and the cantilever's energy error (u's weight).

    Returns
    -------
    pandas.DataFrame
        ``weights, order, interior_k0, interior_k1e-5, terzaghi, patch, cantilever``.
    """
    column = ("discretisation.nx=5", "discretisation.ny=41", "time.steps=1", "time.end=10.0")
    settings = list(itertools.product(combinations.items(), orders))
    specs = []
    for (_, (wu, wp)), order in settings:
        o = (f"efg.weight_u={wu}", f"efg.weight_p={wp}", f"efg.order={order}")
        specs += [("soil-column", ("material.permeability=0.0", *column, *o)),
                  ("soil-column", ("material.permeability=1e-05", *column, *o)),
                  ("terzaghi", ("discretisation.nx=5", "discretisation.ny=41", *o))]
    results = iter(solved(specs))
    rows = []
    for (label, (wu, _)), order in settings:
        undrained, seeping, terzaghi = next(results), next(results), next(results)
        static = [f"efg.weight_u={wu}", f"efg.order={order}"]
        rows.append({"weights": label, "order": order,
                     "interior_k0": column_pollution(undrained, 1)[1],
                     "interior_k1e-5": column_pollution(seeping, 1)[1],
                     "terzaghi": terzaghi_errors(terzaghi)["max_error_load_after_0.1"],
                     "patch": solve(load_case("patch-test", static)).summary["errors"][
                         "displacement"],
                     "cantilever": solve(load_case("cantilever", static)).summary["errors"][
                         "energy"]})
    return pd.DataFrame(rows)


#: The scikit-fem reference methods.
FEM_METHODS = ("fem-th", "fem-p1p1", "fem-p1p1-stab", "fem-q1q1", "fem-q2q1")


#: Methods of the column stability table: FEM pairs and EFG settings (overrides).
STABILITY_METHODS = {"fem-th": ("fem-th", ()), "fem-p1p1": ("fem-p1p1", ()),
                     "fem-p1p1-stab": ("fem-p1p1-stab", ()), "efg Q/Q": ("efg", ()),
                     "efg E-A/E-B": ("efg", ("efg.weight_u=exp:0.5", "efg.weight_p=exp:0.25")),
                     "efg Q/Q, perturbation": ("efg", ("efg.stabilisation=perturbation",)),
                     "efg Q/Q, projection": ("efg", ("efg.stabilisation=projection",))}


def column_stability(permeabilities=(0.0, 1e-5), grids=((3, 21), (5, 41), (9, 81)),
                     methods=STABILITY_METHODS):
    """First-step pore-pressure stability of the soil column, boundary layer and interior
    apart (:func:`soilwater.studies.harness.metrics.column_pollution`), under refinement at the built-in
    column's ratio: the first step scales with h^2 (40 s at 3 x 21 nodes), so
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


def fem_terzaghi(methods=FEM_METHODS, moose=None):
    """Terzaghi with every FEM pair on MOOSE's steps, and on steps capped at 0.01.

    Returns
    -------
    pandas.DataFrame
        ``method, steps`` (``moose`` or ``dt<=0.01``), the errors of
        :func:`soilwater.studies.harness.metrics.terzaghi_errors` and, on MOOSE's steps with ``moose``
        given, those of :func:`soilwater.studies.harness.metrics.moose_errors`.
    """
    steps = {"moose": (), "dt<=0.01": ("time.dt_max=0.01", "time.end=2.0")}
    settings = list(itertools.product(steps, methods))
    results = solved([("terzaghi", steps[label], method) for label, method in settings])
    rows = []
    for (label, method), result in zip(settings, results):
        errors = terzaghi_errors(result)
        row = {"method": method, "steps": label,
               "error_p0_after_0.1": max(v for k, v in errors["window_errors"].items()
                                         if not k.startswith(("0 ", "0.01 "))),
               "settlement_after_0.1": errors["settlement_error_after_0.1"],
               "overshoot": errors["overshoot"]}
        if moose is not None and label == "moose":
            row.update({f"moose_{k}": v for k, v in moose_errors(result, moose).items()})
        rows.append(row)
    return pd.DataFrame(rows)


def solved(specs):
    """Results of ``(case, overrides[, method])`` runs (method default ``efg``) through
    the parallel, cached runner.

    Raises
    ------
    SoilwaterError
        If any run failed (a verification table needs them all).
    """
    outcomes = runner.run([runner.Job(spec[0], spec[2] if len(spec) > 2 else "efg",
                                      tuple(spec[1])) for spec in specs], progress=False)
    failed = [o for o in outcomes if not o.ok]
    if failed:
        raise SoilwaterError(f"{len(failed)} verification run(s) failed, first: "
                             f"{failed[0].job.case} {' '.join(failed[0].job.overrides)}: "
                             f"{failed[0].error}")
    return [o.result for o in outcomes]


def stability_number(case):
    """``h^2 / (c_v dt0)`` of a column: h the vertical nodal spacing, c_v = mobility x
    (K + 4G/3) at the initial state, dt0 the first step."""
    modulus = case.material().constrained_modulus()
    dt0 = case.times()[1]
    return float(case.spacing[1] ** 2 / (case.fluid.mobility * modulus * dt0))


def consolidation():
    """Terzaghi (5 x 41 nodes) and Mandel errors of the EFG solver (default settings)."""
    terzaghi, mandel = solved([("terzaghi", ("discretisation.nx=5", "discretisation.ny=41")),
                                 ("mandel", ())])
    terzaghi, mandel = terzaghi_errors(terzaghi), mandel_errors(mandel)
    rows = [("terzaghi", f"max abs(p - p_exact) / p0, {w}", v)
            for w, v in terzaghi.pop("window_errors").items()]
    rows += [("terzaghi", k, v) for k, v in terzaghi.items()]
    rows += [("mandel", k, v) for k, v in mandel.items()]
    return pd.DataFrame(rows, columns=["case", "metric", "value"])


#: Runs of the column figure: label -> (method, overrides), at the built-in first step.
COLUMN_RUNS = {**{f"EFG {label}": ("efg", (f"efg.weight_u={u}", f"efg.weight_p={p}"))
                  for label, (u, p) in COMBINATIONS.items()},
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


def consolidation_histories():
    """Terzaghi and Mandel pore pressures of EFG and FEM beside the closed forms.

    Returns
    -------
    terzaghi : pandas.DataFrame
        ``run, time, y, p`` (p over the undrained p0) at the probes p0..p9, for EFG
        (5 x 41 nodes), fem-q1q1 and fem-th (MOOSE's 2 x 11 vertices) and MOOSE's file.
    mandel : pandas.DataFrame
        ``run, time, p_centre, p_exact`` (over F/(2a)) for EFG, fem-th and fem-q1q1.
    """
    runs = {"EFG (5 x 41 nodes)": ("efg", ("discretisation.nx=5", "discretisation.ny=41")),
            "fem-q1q1": ("fem-q1q1", ()), "fem-th": ("fem-th", ())}
    terzaghi_runs = solved([("terzaghi", o, m) for m, o in runs.values()])
    mandel_runs = solved([("mandel", (), m) for m in ("efg", "fem-th", "fem-q1q1")])
    frames = []
    for label, result in zip(runs, terzaghi_runs):
        case, h = result.case, result.history
        p0 = _terzaghi_p0(case)
        for k in range(10):
            frames.append(pd.DataFrame({"run": label, "time": h.time, "y": float(k),
                                        "p": h[f"p_w@p{k}"] / p0}))
    moose, case = moose_terzaghi(), terzaghi_runs[1].case
    p0_unit_load = _terzaghi_p0(case) / -case.boundary.top.traction[1]  # MOOSE's load is 1
    frames += [pd.DataFrame({"run": "MOOSE Q1/Q1 (peer)", "time": moose.time, "y": float(k),
                             "p": moose[f"p{k}"] / p0_unit_load}) for k in range(10)]
    mandel_frames = []
    for label, result in zip(("EFG", "fem-th", "fem-q1q1"), mandel_runs):
        case, h = result.case, result.history
        force, a = -case.plate_force(case.times()[-1]), case.geometry.width
        mandel_frames.append(pd.DataFrame({"run": label, "time": h.time,
                                           "p_centre": h["p_w@centre"] / (force / (2 * a)),
                                           "p_exact": mandel_centre(h.time, case)}))
    return pd.concat(frames, ignore_index=True), pd.concat(mandel_frames, ignore_index=True)


def mandel_centre(times, case=None):
    """Mandel's closed-form centre pressure over F/(2a) at ``times`` [s] (built-in
    ``mandel`` case unless another is given): drawn on a grid of its own, it shows no
    kinks of the solvers' time levels."""
    from soilwater.references.closed_forms import mandel

    case = case or load_case("mandel")
    material, a = case.material(), case.geometry.width
    force = -case.plate_force(case.times()[-1])
    exact = [mandel([0.0], t, force, a, material.G, material.nu, case.fluid.mobility)[0]
             for t in np.asarray(times, float)]
    return np.array(exact) / (force / (2 * a))


def _terzaghi_p0(case):
    """Undrained pore pressure of the Terzaghi column under its load."""
    fluid = case.fluid
    return undrained_pressure(-case.boundary.top.traction[1],
                              case.material().constrained_modulus(), fluid.biot_alpha,
                              fluid.storage)
