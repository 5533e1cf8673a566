"""Penalty against Nitsche's method (``efg.essential``): accuracy and what a Krylov solver
sees.

* :func:`accuracy`: the verification cases with either method, each with its error
  against the closed form (patch test, cantilever, Terzaghi, Mandel, unconfined
  compression, simple shear; the strip footing against fem-th);
* :func:`confined`: how near singular the undrained simple shear's tangent is with
  either method, with and without the pressure stabilisation;
* :func:`eigenvalue_strips`: Nitsche's eigenvalue bound on strips of 0 to 3 neighbour
  rings against the whole domain's (:func:`soilwater.efg.essential.nitsche.largest_eigenvalue`);
* :func:`conditioning`: the first Newton tangent of a case at a few thousand nodes, its
  displacement block's diagonal span and condition estimate, and restarted GMRES with
  Jacobi or incomplete LU preconditioners: the relative residual it reaches against the
  error of its solution measured against the direct solve.

``python -m soilwater.studies.essential.study`` prints the tables (measured: 5 min for the
conditioning, 10 min for the accuracy on 2 cores). ``make report`` writes
:func:`accuracy` and :func:`confined` with its :func:`section` (its coupled runs go
through the cached runner); how far the footing gets with either method is
:mod:`soilwater.studies.footing.reach`.
"""

import itertools
from functools import cache

import numpy as np
import pandas as pd
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.studies.harness import tables
from soilwater.studies.harness.metrics import mandel_errors, path_error, terzaghi_errors
from soilwater.studies.harness.runs import solved
from soilwater.efg.essential import nitsche
from soilwater.efg import quadrature
from soilwater.efg import solver
from soilwater.efg.discretisation import discretise
from soilwater.efg.system import System
from soilwater.efg import statics
from soilwater.efg.boundary import boundary_points, segment_edges
from soilwater.efg.mls import ShapeFunctions
from soilwater.nonlinear.history import TIMERS
from soilwater.case.loader import load_case

METHODS = ("penalty", "nitsche")
#: The strip footing's first 0.05 B of settlement in 10 steps (undrained; it ends at
#: about 0.6 of Prandtl's pressure).
FOOTING = ["time.end=5", "time.steps=10"]


def accuracy(methods=METHODS):
    """Errors of every verification case with each method.

    Returns
    -------
    pandas.DataFrame
        ``case, setting, method, metric, value``: the patch test's and the cantilever's
        relative errors (displacement, stress, energy; :func:`soilwater.efg.statics.error_norms`)
        per cell type and gradient correction, and per refinement for the cantilever;
        Terzaghi's (5 x 41 nodes) :func:`soilwater.studies.harness.metrics.terzaghi_errors`, Mandel's
        :func:`soilwater.studies.harness.metrics.mandel_errors`, the unconfined compression's path error
        over p'0 and largest ERR, the simple shear's path error (:data:`COUPLED`), the strip
        footing's pressure against fem-th's (:data:`FOOTING`); each coupled run's Newton
        iterations and run time [s] (``run_time_s``, as the run measured it; the runs are
        cached).
    """
    rows = []
    for method, cells, correction in itertools.product(methods, ("delaunay", "squares"),
                                                       ("vci", "none")):
        o = [f"efg.essential={method}", f"efg.cells={cells}", f"efg.correction={correction}"]
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


def eigenvalue_strips(levels=((13, 4), (25, 7), (49, 13), (97, 25)), rings=(0, 1, 2, 3)):
    """The cantilever's eigenvalue bound lambda (times h/M) on strips of ``rings``
    neighbour rings and on the whole domain (``exact``), per refinement.

    Returns
    -------
    pandas.DataFrame
        ``nodes``, ``rings_R`` per ring count and ``exact``: ``lambda h / M``
        (dimensionless; M the P-wave modulus, h the smallest spacing).
    """
    rows = []
    for nx, ny in levels:
        case = load_case("cantilever", [f"discretisation.nx={nx}", f"discretisation.ny={ny}"])
        domain, boundary = _static_bound(case)
        scale = min(case.spacing) / case.material().constrained_modulus()
        row = {"nodes": nx * ny}
        for r in (*rings, None):
            row["exact" if r is None else f"rings_{r}"] = scale * nitsche.largest_eigenvalue(
                domain, boundary, rings=r)
        rows.append(row)
    return pd.DataFrame(rows)


def _static_bound(case):
    """``(domain, boundary)`` arguments of :func:`soilwater.efg.essential.nitsche.largest_eigenvalue` for a
    static case's elastic operator and constrained components."""
    s, material = case.efg, case.material()
    nodes, loop = case.nodes(), case.boundary_loop()
    quad = quadrature.background(case, nodes, loop, s)
    shape = ShapeFunctions.build(nodes, quad.points, s.weight_u, s.scale_u)
    bp = boundary_points(nodes, loop, segment_edges(nodes, loop, case.geometry))
    shape_b = ShapeFunctions.build(nodes, bp.points, s.weight_u, s.scale_u)
    constrained, *_ = statics.boundary_data(case, bp, case.exact_solution())
    K, G = material.moduli()
    D_b, D = (nitsche.gradient_operator(nitsche.isotropic(np.full(m, K), np.full(m, G)))
              for m in (len(bp.weights), len(quad.weights)))
    return ((shape, quad.weights, D),
            (shape_b, bp.weights, nitsche.flux_operator(bp, constrained, D_b)))


#: Cases of :func:`conditioning`, a few thousand nodes each: the consolidating column
#: (rollers, fixed base, drained top) and the unconfined compression (prescribed top).
CONDITIONING_CASES = {
    "terzaghi": ("discretisation.nx=21", "discretisation.ny=101"),
    "unconfined-compression": ("discretisation.layout=grid", "discretisation.nx=41",
                               "discretisation.ny=55"),
}
#: Preconditioners of :func:`conditioning`: label -> factory of ``M ~ K^-1`` from K.
PRECONDITIONERS = {
    "jacobi": lambda K: spla.LinearOperator(K.shape, matvec=lambda x: x / K.diagonal(),
                                            dtype=float),
    "ilu 1e-2": lambda K: _ilu(K, drop_tol=1e-2, fill_factor=5),
    "ilu 1e-4": lambda K: _ilu(K, drop_tol=1e-4, fill_factor=10),
}
#: The systems of :func:`conditioning` and their preconditioners: the whole first Newton
#: system (a saddle point when undrained: no Jacobi) and its displacement block alone
#: with the displacement rows of the residual (the block an AMG cycle would precondition).
SYSTEMS = {"coupled": ("ilu 1e-4",), "u block": ("jacobi", "ilu 1e-2", "ilu 1e-4")}


def conditioning(cases=CONDITIONING_CASES, methods=METHODS, rtols=(1e-3, 1e-6, 1e-9),
                 systems=SYSTEMS, restart=50, maxiter=20):
    """What a Krylov solver sees on the first Newton system of each case.

    Returns
    -------
    summary : pandas.DataFrame
        ``case, method, dofs, diagonal_span`` (largest over smallest ``|K_ii|`` of the
        displacement block), ``condition`` (1-norm estimate of the displacement block,
        :func:`scipy.sparse.linalg.onenormest` of it and of its inverse) and
        ``factor_h_over_M``, the displacement condition's factor (``alpha_u`` or
        ``beta_u``) over ``M/h``.
    krylov : pandas.DataFrame
        ``case, method, system, preconditioner, rtol``, GMRES ``iterations`` (inner,
        restart ``restart``, at most ``maxiter`` restarts), the reached ``residual``
        ``|K x - b| / |b|``, ``error_u`` (max ``|u - u*|`` over max ``|u*|``, u* the
        direct solve), ``error_p`` (the same for p_w, coupled system only) and
        ``converged``.
    """
    summary, krylov = [], []
    for (name, overrides), method in itertools.product(cases.items(), methods):
        K, R, n, factor = captured(name, overrides + (f"efg.essential={method}",))
        Kuu = K[:2 * n, :2 * n].tocsc()
        d = np.abs(Kuu.diagonal())
        summary.append({"case": name, "method": method, "dofs": K.shape[0],
                        "diagonal_span": d.max() / d.min(),
                        "condition": _condition(Kuu), "factor_h_over_M": factor})
        for system, labels in systems.items():
            A, b = (K, -R) if system == "coupled" else (Kuu, -R[:2 * n])
            exact = spla.spsolve(A.tocsc(), b)
            for label, rtol in itertools.product(labels, rtols):
                krylov.append({"case": name, "method": method, "system": system,
                               "preconditioner": label, "rtol": rtol,
                               **_gmres(A, b, n, exact, PRECONDITIONERS[label](A), rtol,
                                        restart, maxiter)})
    return pd.DataFrame(summary), pd.DataFrame(krylov)


def confined(methods=METHODS, stabilisations=("none", "perturbation"), small=1e-6):
    """The singular values of the first Newton tangent of the undrained simple shear
    (every edge prescribed, k = 0: the pore pressure is defined up to the constant
    that the mean-pressure multiplier pins), per method and ``efg.stabilisation``.

    Returns
    -------
    pandas.DataFrame
        ``method, stabilisation``, ``condition`` (largest over smallest singular value of
        the tangent with rows and columns scaled by ``|K_ii|^(-1/2)``), ``below`` (how many
        are under ``small`` times the largest), ``smallest`` (the smallest over the
        largest) and ``spread``, max - min of the nodal pore pressure [kPa] after 10
        steps to gamma = 0.06 (exact: uniform, so 0).
    """
    rows = []
    for method, stabilisation in itertools.product(methods, stabilisations):
        overrides = (f"efg.essential={method}", f"efg.stabilisation={stabilisation}")
        K, _, _, _ = captured("simple-shear", overrides)
        run, = solved([("simple-shear", ["time.end=6", "time.steps=10", *overrides])])
        p = run.snapshots[-1].point_data["p_w"]
        d = np.abs(K.diagonal())
        scale = 1 / np.sqrt(np.where(d > 0, d, 1.0))
        values = np.linalg.svd((sp.diags(scale) @ K @ sp.diags(scale)).toarray(),
                               compute_uv=False)
        rows.append({"method": method, "stabilisation": stabilisation,
                     "condition": values[0] / values[-1],
                     "below": int((values < small * values[0]).sum()),
                     "smallest": values[-1] / values[0], "spread": p.max() - p.min()})
    return pd.DataFrame(rows)


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
    :func:`confined` (markdown lines)."""
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
        "Every verification case run with `efg.essential = \"penalty\"` (the paper's and "
        "the default) and `\"nitsche\"` (Nitsche's symmetric method, its stabilisation "
        "from a local eigenvalue bound): the patch test and the cantilever (relative "
        "errors against the exact solutions, per cell type and gradient correction, and "
        "per refinement), Terzaghi (5 x 41 nodes), Mandel, the unconfined compression "
        "(path error over p'0, largest ERR and the strain reached), the undrained simple "
        "shear (`" + " ".join(COUPLED["simple-shear"]) + "`: without the stabilisation "
        "its tangent is near singular, below, and Nitsche's run depends on the linear "
        "solver) and the strip footing's first "
        "0.05 B in 10 steps against fem-th's pressure; each coupled run's Newton "
        f"iterations and run time [s]. Errors below {ROUNDOFF:g} are round-off and "
        "written as the bound; † marks the branch-dependent runs.",
        "",
        tables.to_markdown(shown),
        "",
        "Nitsche's error is no larger than the penalty's in "
        f"{len(errors) - len(worse)} of {len(errors)} error rows"
        + ("." if worse.empty else "; larger in " + "; ".join(
            f"{r.case} ({r.setting}) {r.metric}: {r.nitsche:.3g} against {r.penalty:.3g}"
            for r in worse.itertuples()) + ".") + " How far each gets on the strip "
        "footing is the footing section's `efg+nitsche` rows.",
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


def _ilu(K, **options):
    """scipy's incomplete LU of K as a LinearOperator."""
    ilu = spla.spilu(sp.csc_matrix(K), **options)
    return spla.LinearOperator(K.shape, matvec=ilu.solve, dtype=float)


def captured(name, overrides):
    """The first Newton system of a case's first step (the tangent the solver factorises).

    Returns
    -------
    K : scipy.sparse.csr_matrix
        The tangent, unknowns ``[du, p_w, plate?, pin?]``.
    R : ndarray
        The residual at the start of the step.
    n : int
        Nodes.
    factor : float
        The displacement condition's factor over ``M/h``: ``alpha_u`` (penalty) or
        ``beta_u`` (Nitsche).
    """
    case = load_case(name, list(overrides))
    model = solver.Model.build(case)
    points = solver._initial_points(model)
    timings = dict.fromkeys(TIMERS, 0.0)
    disc = discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                              timings)
    system = System(model, points, disc, *case.times()[:2], timings)
    R, _ = system.residual()
    factor = system._factors[0] * model.scales.h / model.scales.modulus
    return sp.csr_matrix(system.tangent()), R, system.n, factor


def _condition(A):
    """1-norm condition estimate of a sparse square matrix (its inverse by SuperLU)."""
    lu = spla.splu(A)
    inverse = spla.LinearOperator(A.shape, matvec=lu.solve, rmatvec=lambda x: lu.solve(x, "T"),
                                  dtype=float)
    return float(spla.onenormest(A) * spla.onenormest(inverse))


def _gmres(A, b, n, exact, M, rtol, restart, maxiter):
    """One preconditioned GMRES solve of ``A x = b`` and its errors (:func:`conditioning`):
    the first 2n unknowns are the displacement's, the next n (if any) p_w's."""
    count = [0]

    def inner(_):
        count[0] += 1

    x, info = spla.gmres(A, b, rtol=rtol, restart=restart, maxiter=maxiter, M=M,
                         callback=inner, callback_type="pr_norm")
    u, u_star = x[:2 * n], exact[:2 * n]
    p, p_star = x[2 * n:3 * n], exact[2 * n:3 * n]
    return {"iterations": count[0],
            "residual": float(np.linalg.norm(A @ x - b) / np.linalg.norm(b)),
            "error_u": float(np.abs(u - u_star).max() / np.abs(u_star).max()),
            "error_p": (float(np.abs(p - p_star).max() / np.abs(p_star).max())
                        if len(p) and np.abs(p_star).max() > 0 else np.nan),
            "converged": info == 0}


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
