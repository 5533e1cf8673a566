"""Verification tables of the EFG solvers: patch test, cantilever convergence and the
paper's unconfined compression and simple shear (Figs. 4 and 6).

Each function runs the built-in case over a sweep of settings and returns a DataFrame;
the tests assert on these tables and the report writes them.
"""

import itertools

import numpy as np
import pandas as pd

from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.runs import PATH_RUNS, UNIQUENESS, solved
from soilwater.efg.statics import solve
from soilwater.diagnostics.bifurcation import onset
from soilwater.material.driver import run_test
from soilwater.case.loader import load_case

#: The paper's weights: quartic (Q), exponential c = 0.5 (E-A) and c = 0.25 (E-B).
WEIGHTS = {"Q": "quartic", "E-A": "exp:0.5", "E-B": "exp:0.25"}
#: The integration cells of the EFG core's tables: Delaunay triangles of the nodes (the
#: cells of ``gauss``, and of ``paper`` with ``efg.cells = "delaunay"``: one solve, the
#: same cells), the paper's squares, and the smoothing cells of nodal integration.
CELLS = {"delaunay": ("efg.integration=gauss",),
         "squares": ("efg.integration=paper", "efg.cells=squares"),
         "nodal": ("efg.integration=nodal",)}
#: The essential conditions of these tables: the paper's penalty (Nitsche's are the
#: essential-conditions study's).
ESSENTIAL = "efg.essential=penalty"


def patch_test(corrections=("vci", "none"), cells=tuple(CELLS)):
    """Relative errors of the linear patch test for each of :data:`CELLS` and correction."""
    rows = []
    for cell, correction in itertools.product(cells, corrections):
        result = solve(load_case("patch-test", [*CELLS[cell], ESSENTIAL,
                                                f"efg.correction={correction}"]))
        rows.append({"cells": cell, "correction": correction,
                     "order": result.options["order"], **result.summary["errors"]})
    return pd.DataFrame(rows)


#: The cantilever's refinement levels (nodes along x and y).
LEVELS = pick(((13, 4), (25, 7), (49, 13), (97, 25)), ((13, 4), (25, 7), (49, 13)))


def cantilever_convergence(levels=LEVELS,
                           weights=WEIGHTS, cells=("delaunay", "squares"),
                           corrections=("vci",)):
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
                                            f"efg.weight_u={weight}", *CELLS[cell],
                                            ESSENTIAL, f"efg.correction={correction}"])
            errors = solve(case).summary["errors"]
            h = case.spacing[0]
            rate = (np.log(previous[1] / errors["energy"]) / np.log(previous[0] / h)
                    if previous else np.nan)
            rows.append({"weight": label, "cells": cell, "correction": correction,
                         "nx": nx, "ny": ny, "h": h, "nodes": nx * ny, **errors,
                         "rate": rate})
            previous = (h, errors["energy"])
    return pd.DataFrame(rows)


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


