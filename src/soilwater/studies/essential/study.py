"""Penalty against Nitsche's method (``efg.essential``): accuracy and what a Krylov solver
sees.

* :func:`accuracy`: the verification cases with either method, each with its error
  against the closed form (patch test, cantilever, Terzaghi, Mandel, unconfined
  compression, simple shear; the strip footing against fem-th);
* :func:`section`: the report's section from :func:`accuracy` and
  :func:`soilwater.studies.essential.tangent.confined`;
* :mod:`soilwater.studies.essential.tangent`: how near singular the undrained simple
  shear's tangent is with either method, with and without the pressure stabilisation, and
  the first Newton tangent of a case at a few thousand nodes under restarted GMRES;
* :mod:`soilwater.studies.essential.strips`: Nitsche's eigenvalue bound on boundary strips
  against the whole domain's.

``python -m soilwater.studies.essential.study`` prints the tables (measured: 5 min for the
conditioning, 10 min for the accuracy on 2 cores). ``make report`` writes
:func:`accuracy` and :func:`~soilwater.studies.essential.tangent.confined` with its
:func:`section` (its coupled runs go through the cached runner); how far the footing gets
with either method is :mod:`soilwater.studies.footing.reach`.
"""

import itertools
from functools import cache

import numpy as np
import pandas as pd

from soilwater.studies.essential.strips import eigenvalue_strips
from soilwater.studies.essential.tangent import METHODS, conditioning, confined
from soilwater.studies.harness import tables
from soilwater.studies.harness.metrics import mandel_errors, path_error, terzaghi_errors
from soilwater.studies.harness.runs import solved
from soilwater.efg import statics
from soilwater.case.loader import load_case

#: The strip footing's first 0.05 B of settlement in 10 steps (undrained; it ends at
#: about 0.6 of Prandtl's pressure).
FOOTING = ["time.end=5", "time.steps=10"]


def accuracy(methods=METHODS):
    """Errors of every verification case with each method.

    Returns
    -------
    pandas.DataFrame
        ``case, setting, method, metric, value``: the patch test's and the cantilever's
        relative errors (displacement, stress, energy;
        :func:`soilwater.efg.statics.error_norms`) per cell type and gradient correction,
        and per refinement for the cantilever; Terzaghi's (5 x 41 nodes)
        :func:`soilwater.studies.harness.metrics.terzaghi_errors`, Mandel's
        :func:`soilwater.studies.harness.metrics.mandel_errors`, the unconfined
        compression's path error over p'0 and largest ERR, the simple shear's path error
        (:data:`COUPLED`), the strip footing's pressure against fem-th's
        (:data:`FOOTING`); each coupled run's Newton iterations and run time [s]
        (``run_time_s``, as the run measured it; the runs are cached).
    """
    rows = []
    for method, cells, correction in itertools.product(methods, ("delaunay", "squares"),
                                                       ("vci", "none")):
        o = [f"efg.essential={method}", f"efg.cells={cells}", f"efg.correction={correction}",
             *(("efg.integration=paper",) if cells == "squares" else ())]
        errors = statics.solve(load_case("patch-test", o)).summary["errors"]
        rows += [("patch-test", f"{cells}, {correction}", method, k, v)
                 for k, v in errors.items()]
    for method, (nx, ny) in itertools.product(methods, ((13, 4), (25, 7), (49, 13),
                                                         (97, 25))):
        o = [f"efg.essential={method}", f"discretisation.nx={nx}", f"discretisation.ny={ny}"]
        errors = statics.solve(load_case("cantilever", o)).summary["errors"]
        rows += [("cantilever", f"{nx} x {ny}", method, k, v) for k, v in errors.items()]
    for method in methods:
        rows += _coupled(method)
    return pd.DataFrame(rows, columns=["case", "setting", "method", "metric", "value"])


#: The coupled runs of :func:`accuracy` (case: overrides). The simple shear with the
#: pressure stabilisation: without it its undrained tangent is near singular with either
#: method (:func:`confined`) and Nitsche's run depends on the linear solver.
COUPLED = {"terzaghi": ["discretisation.nx=5", "discretisation.ny=41"], "mandel": [],
           "unconfined-compression": [],
           "simple-shear": ["time.steps=50", "efg.stabilisation=perturbation"],
           "strip-footing": FOOTING}


def _coupled(method):
    """Rows of :func:`accuracy` for the coupled cases (:data:`COUPLED`) with one method,
    through the cached runner."""
    rows = []
    results = solved([(name, overrides + [f"efg.essential={method}"])
                      for name, overrides in COUPLED.items()])
    for (name, overrides), result in zip(COUPLED.items(), results):
        if name == "terzaghi":
            errors = terzaghi_errors(result)
            errors.update(errors.pop("window_errors"))
        elif name == "mandel":
            errors = mandel_errors(result)
        elif name == "strip-footing":
            errors = {"pressure_vs_fem_th": _against_taylor_hood(result.history)}
        elif name == "simple-shear":
            errors = {"path_error": path_error(result.history, result.case.material(),
                                               "undrained-simple-shear")}
        else:
            history = result.history
            errors = {"path_error": path_error(history, result.case.material()),
                      "err_max": float(history.err.max()),
                      "eps_a_end": float(history.eps_a.iloc[-1])}
        errors.update({"newton_iterations": result.summary["newton_iterations"],
                       "run_time_s": result.summary["timings"]["total_s"]})
        setting = " ".join(overrides) or "built-in"
        rows += [(name, setting, method, k, float(v)) for k, v in errors.items()]
    return rows


def _against_taylor_hood(history):
    """Largest relative difference of the footing pressure of ``history`` from fem-th's
    on the same :data:`FOOTING` run (no closed form before the collapse load)."""
    pressure = history["pressure@footing"].to_numpy()
    return float(np.abs(pressure / _taylor_hood_pressure() - 1).max())


@cache
def _taylor_hood_pressure():
    """fem-th's footing pressure [kPa] per step of the :data:`FOOTING` run."""
    result, = solved([("strip-footing", FOOTING, "fem-th")])
    return result.history["pressure@footing"].to_numpy()


#: Metrics of :func:`accuracy` that count cost or reach, not error.
COST = ("newton_iterations", "run_time_s", "eps_a_end")
#: Relative errors below this are round-off (Nitsche passes the patch test to machine
#: precision): their digits differ between CPUs, so the report writes the bound.
ROUNDOFF = 1e-12
#: Cases of :func:`accuracy` whose runs pass the unconfined compression's loss of
#: uniqueness: their values depend on the branch the run takes (marked †).
BRANCHED = ("unconfined-compression",)


def section(accuracy, confined):
    """The report's section on the essential conditions from :func:`accuracy` and
    :func:`~soilwater.studies.essential.tangent.confined` (markdown lines)."""
    table = accuracy.assign(case=accuracy.case.map(
        lambda c: f"{c} †" if c in BRANCHED else c))
    wide = table.pivot_table(index=["case", "setting", "metric"], columns="method",
                             values="value", sort=False).reset_index()
    errors = wide[~wide.metric.isin(COST)]
    worse = errors[errors.nitsche > errors.penalty]
    shown = wide.assign(**{m: wide[m].map(lambda v: f"< {ROUNDOFF:g}" if v < ROUNDOFF
                                          else f"{v:.3g}") for m in METHODS})
    c = confined.set_index(["method", "stabilisation"])
    return [
        "## Essential conditions: penalty or Nitsche",
        "",
        "Every verification case run with `efg.essential = \"penalty\"` (the paper's) "
        "and `\"nitsche\"` (the recommended configuration's: Nitsche's symmetric method, "
        "its stabilisation "
        "from a local eigenvalue bound): the patch test and the cantilever (relative "
        "errors against the exact solutions, per cell type and gradient correction, and "
        "per refinement), Terzaghi (5 x 41 nodes), Mandel, the unconfined compression "
        "(path error over p'0, largest ERR and the strain reached), the undrained simple "
        "shear (`" + " ".join(COUPLED["simple-shear"]) + "`: without the stabilisation "
        "its tangent is near singular, below, and Nitsche's run depends on the linear "
        "solver) and the strip footing's first "
        "0.05 B in 10 steps against fem-th's pressure; each coupled run's Newton "
        "iterations and run time [s]. The other settings are the recommended "
        "configuration's (state at the Gauss points of Lagrangian cells, the pressure "
        "perturbation); the patch test's square cells are the paper's scheme's. Errors below"
        f" {ROUNDOFF:g} are round-off and "
        "written as the bound; † marks the branch-dependent runs.",
        "",
        tables.to_markdown(shown),
        "",
        "Nitsche's error is no larger than the penalty's in "
        f"{len(errors) - len(worse)} of {len(errors)} error rows"
        + ("." if worse.empty else "; larger in " + "; ".join(
            f"{r.case} ({r.setting}) {r.metric}: {r.nitsche:.3g} against {r.penalty:.3g}"
            for r in worse.itertuples()) + ".") + " How far each gets on the strip "
        "footing is the footing section's `efg` (Nitsche) and `efg-paper` (penalty) rows.",
        "",
        "How near singular the undrained simple shear's first tangent is (every edge "
        "prescribed, k = 0): its singular values with rows and columns scaled by "
        "|K_ii|^(-1/2), how many lie below 1e-6 of the largest, and the spread of the "
        "nodal pore pressure [kPa] after 10 steps to gamma = 0.06 (exact: 0; † where "
        "the tangent is near singular, its digits depend on the linear solver):",
        "",
        tables.to_markdown(confined.rename(columns={"spread": "spread †"}),
                           floatfmt="{:.2g}"),
        "",
        "Without the pressure stabilisation "
        f"{c.loc[('penalty', 'none'), 'below']} (penalty) and "
        f"{c.loc[('nitsche', 'none'), 'below']} (Nitsche) singular values lie below 1e-6 "
        "of the largest: the equal-order pressure's spurious modes, with either method; "
        f"with the perturbation {c.loc[('penalty', 'perturbation'), 'below']} and "
        f"{c.loc[('nitsche', 'perturbation'), 'below']}.",
        "",
    ]


def main():
    """Print the tables."""
    pd.set_option("display.width", 200)
    summary, krylov = conditioning()
    print("## Conditioning of the first Newton tangent\n")
    print(summary.to_string(index=False, float_format="{:.3g}".format))
    print("\n## GMRES + incomplete LU: residual reached against the error\n")
    print(krylov.to_string(index=False, float_format="{:.3g}".format))
    print("\n## Undrained simple shear, first tangent: scaled singular values\n")
    print(confined().to_string(index=False, float_format="{:.3g}".format))
    print("\n## Nitsche's eigenvalue bound on boundary strips (cantilever, lambda h / M)\n")
    print(eigenvalue_strips().to_string(index=False, float_format="{:.4g}".format))
    print("\n## Accuracy, penalty and Nitsche\n")
    table = accuracy().pivot_table(index=["case", "setting", "metric"], columns="method",
                                   values="value", sort=False)
    print(table.to_string(float_format="{:.3g}".format))


if __name__ == "__main__":
    main()
