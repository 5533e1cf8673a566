"""Fixed-mesh against re-meshed FEM on the strip footing (issue 15, item 5): a helper for
the report.

Each FEM pair runs the built-in ``strip-footing`` on grids of n x n nodes pushed to
``END`` (over B; twice the case's 0.5 B, to see where the fixed mesh degrades), once on
its fixed mesh and once with ``fem.remesh = "delaunay"`` at the default threshold
(:data:`soil.settings.REMESH_QUALITY`), through the cached runner.
"""

import numpy as np
import pandas as pd

from comparisons.footing import CASE, GRIDS, width
from comparisons.verification import _results
from soil.analytical import PRANDTL, undrained_strength
from soil.problems import load_case

#: The pairs compared (the triangle pairs of the footing study).
METHODS = ("fem-p1p1-stab", "fem-th")
#: Settlement the runs are pushed to [B], and its steps (the case's 0.5 B in 100 steps:
#: the same step).
END, STEPS = 1.0, 200
#: Settlements at which the pressure is reported [B].
AT = (0.1, 0.5)


def table(methods=METHODS, grids=GRIDS, end=END, steps=STEPS):
    """One row per method, grid and mesh (``fixed`` or ``remeshed``).

    Returns
    -------
    pandas.DataFrame
        ``method, nodes, mesh, reached`` (the last converged settlement over B),
        ``min_quality`` (the worst element over the run, :func:`soil.quality.cell_quality`),
        ``remeshes``, ``refused``, ``quality_after_remesh`` (the worst element right
        after a re-meshing, over the run; empty without one), ``run_time`` [s],
        ``iterations_per_step`` (Newton), ``iterations_after_remesh`` (mean over the
        steps that follow a re-meshing), ``remesh_residual`` (the largest scaled
        equilibrium residual of a carried state, in units of the Newton tolerance's
        scales), ``at_0.1B`` and ``at_0.5B`` (pressure over ``(2 + pi) s_u``),
        ``stopped`` (why a run ended early, else empty).
    """
    case = load_case(CASE)
    B, s_u = width(case), undrained_strength(case.material())
    load = (f"time.end={end * B / _rate(case)!r}", f"time.steps={steps}")
    specs, labels = [], []
    for method in methods:
        for n in grids:
            grid = (f"discretisation.nx={n}", f"discretisation.ny={n}")
            for mesh, extra in (("fixed", ()), ("remeshed", ("fem.remesh=delaunay",))):
                specs.append((CASE, (*grid, *load, *extra), method))
                labels.append((method, f"{n}x{n}", mesh))
    rows = []
    for (method, nodes, mesh), result in zip(labels, _results(specs)):
        h, summary = result.history, result.summary
        s = h["settlement@footing"].to_numpy() / B
        p = h["pressure@footing"].to_numpy() / (PRANDTL * s_u)
        count = h["remeshes"].to_numpy() if "remeshes" in h else np.zeros(len(h), int)
        grew = np.flatnonzero(np.diff(np.r_[0, count]) > 0)
        after = grew[grew + 1 < len(h)] + 1
        rows.append({
            "method": method, "nodes": nodes, "mesh": mesh, "reached": s[-1],
            "min_quality": h.min_quality.min(), "remeshes": int(count[-1]),
            "refused": int(h["remesh_refused"].iloc[-1]) if "remesh_refused" in h else 0,
            "quality_after_remesh": h.min_quality.to_numpy()[grew].min() if len(grew)
            else "",
            "run_time": summary["timings"]["total_s"],
            "iterations_per_step": h.iterations.sum() / len(h),
            "iterations_after_remesh": h.iterations.to_numpy()[after].mean() if len(after)
            else "",
            "remesh_residual": h.remesh_residual.to_numpy()[grew].max() if len(grew)
            else "",
            **{f"at_{a:g}B": float(np.interp(a, s, p)) if s[-1] >= a else "" for a in AT},
            "stopped": summary["stopped"] or ""})
    return pd.DataFrame(rows)


def _rate(case):
    """The footing's settlement rate [m/s]."""
    (_, footing), = case.boundary.segments()
    return footing.settlement_rate
