"""Verification tables of the static EFG core: patch test and cantilever convergence.

Each function runs the built-in case over a sweep of settings and returns a DataFrame;
the tests assert on these tables and the report writes them.
"""

import itertools

import numpy as np
import pandas as pd

from efg.statics import solve
from soil.problems import load_case

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
            rows.append({"weight": label, "cells": cell, "correction": correction, "nx": nx, "ny": ny, "h": h,
                         "nodes": nx * ny, **errors, "rate": rate})
            previous = (h, errors["energy"])
    return pd.DataFrame(rows)
