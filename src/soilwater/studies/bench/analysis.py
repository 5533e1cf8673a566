"""The analysis of the bench's rows: ratios, growth exponents, factorisation rates, targets.

Every function reads the table of :func:`soilwater.studies.bench.runs.steps` (one row per
run, times [s], memory [MB]) and returns a table; a value whose run did not complete is
NaN, and a target on it is "not measured" (:func:`verdict`), never met.
"""

import numpy as np
import pandas as pd

from soilwater.studies.bench.plan import MATERIALS, METHODS
from soilwater.studies.bench.runs import COUNTS, PHASES
from soilwater.studies.harness.machine import ram_gb

def exponent(nodes, seconds, within=None):
    """Least-squares slope of log(time) against log(nodes): the growth exponent.

    Parameters
    ----------
    nodes, seconds : array_like
        Node counts and times [s]; NaN or non-positive times (runs that did not
        complete) are left out.
    within : (float, float), optional
        Fit only node counts from ``within[0] / 1.1`` to ``1.1 * within[1]`` (a grid's
        count is within 10 % of the size asked for).

    Returns
    -------
    float
        The slope; NaN with fewer than two points.

    Examples
    --------
    >>> round(exponent([1e3, 1e4, 1e5], [1.0, 10.0, 1000.0], within=(1e3, 1e4)), 12)
    1.0
    """
    nodes, seconds = np.asarray(nodes, float), np.asarray(seconds, float)
    keep = seconds > 0
    if within is not None:
        keep &= (nodes >= within[0] / 1.1) & (nodes <= 1.1 * within[1])
    if keep.sum() < 2:
        return np.nan
    return float(np.polyfit(np.log(nodes[keep]), np.log(seconds[keep]), 1)[0])


def verdict(measured, limit):
    """``"yes"`` where ``measured <= limit``, ``"**no**"`` where not, ``"not measured"``
    where ``measured`` is NaN (its run did not complete): never "yes" without a value.

    Examples
    --------
    >>> verdict([1.0, 3.0, np.nan], 2.0).tolist()
    ['yes', '**no**', 'not measured']
    """
    measured = np.asarray(measured, float)
    return np.where(np.isnan(measured), "not measured",
                    np.where(measured <= limit, "yes", "**no**"))


def pick(table, method, material, nodes, solver=None, integration=None):
    """The row of ``method`` and ``material`` at the size ``nodes`` asked for (its grid's
    count within 10 %), on ``solver`` and with EFG's scheme ``integration`` (None: the
    first such run), or None if there was no such run."""
    rows = table[(table.method == method) & (table.material == material)
                 & np.isclose(table.nodes, nodes, rtol=0.1)]
    if solver is not None:
        rows = rows[rows.solver == solver]
    if integration is not None:
        rows = rows[rows.integration == integration]
    return rows.iloc[0] if len(rows) else None


def fastest(rows):
    """The completed row of ``rows`` with the shortest step, else the first row (its
    status says why); None for no rows.

    Examples
    --------
    >>> rows = pd.DataFrame({"solver": ["pardiso", "krylov"], "status": ["ok", "ok"],
    ...                      "step": [40.0, 35.0]})
    >>> fastest(rows).solver
    'krylov'
    """
    if not len(rows):
        return None
    done = rows[rows.status == "ok"]
    return done.loc[done.step.idxmin()] if len(done) else rows.iloc[0]


def at(x, xs, ys):
    """Log-log interpolation of the measured ``(xs, ys)`` at ``x`` (NaN outside)."""
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    if not xs.min() <= x <= xs.max():
        return np.nan
    return float(np.exp(np.interp(np.log(x), np.log(xs), np.log(ys))))


def pairs(table, against=METHODS[1:]):
    """Every EFG row with each FEM run of ``against`` at equal nodes (same grid), the same
    material and the same linear solver (the first such run of each method): ``(efg,
    fem)`` rows, in the table's order."""
    for _, group in table.groupby(["material", "nodes", "solver"], sort=False):
        by = group.drop_duplicates("method").set_index("method")
        for _, efg in group[group.method == "efg"].iterrows():
            yield from ((efg, by.loc[fem]) for fem in against if fem in by.index)


def ratios(table):
    """EFG / FEM per phase, and per count of :data:`~soilwater.studies.bench.runs.COUNTS`,
    at equal nodes (same grid) on the same linear solver, for each material, size,
    solver, EFG scheme (``integration``) and EFG's conditions (``efg``)."""
    rows = [{"material": efg.material, "nodes": efg.nodes, "solver": efg.solver,
             "integration": efg.integration, "efg": efg["efg"], "against": fem.name,
             **{column: efg[column] / fem[column] for column in (*COUNTS, *PHASES)}}
            for efg, fem in pairs(table)]
    return pd.DataFrame(rows, columns=["material", "nodes", "solver", "integration", "efg",
                                       "against", *COUNTS, *PHASES])


#: The FEM pair each EFG scheme is measured against in :func:`schemes`.
AGAINST = "fem-p1p1-stab"


def schemes(table):
    """Each EFG scheme against :data:`AGAINST` at equal nodes, same material and linear
    solver: the size of both discretisations and EFG / FEM per phase.

    Returns
    -------
    pandas.DataFrame
        Per EFG row: material, nodes, solver, ``integration``, ``efg`` (conditions),
        ``status``, EFG's ``points_per_node`` and ``entries_per_row``
        (:func:`~soilwater.studies.bench.runs.counts`), the same of :data:`AGAINST`
        (``fem_points_per_node``, ``fem_entries_per_row``), EFG's ``step_s`` [s] and
        EFG / FEM per phase (NaN where either run did not complete).
    """
    rows = [{"material": efg.material, "nodes": efg.nodes, "solver": efg.solver,
             "integration": efg.integration, "efg": efg["efg"], "status": efg.status,
             **{column: efg[column] for column in COUNTS},
             **{f"fem_{column}": fem[column] for column in COUNTS}, "step_s": efg.step,
             **{phase: efg[phase] / fem[phase] for phase in PHASES}}
            for efg, fem in pairs(table, (AGAINST,))]
    return pd.DataFrame(rows, columns=["material", "nodes", "solver", "integration", "efg",
                                       "status", *COUNTS,
                                       *(f"fem_{column}" for column in COUNTS), "step_s",
                                       *PHASES])


def exponents(table):
    """Growth exponent of every phase, per method, EFG scheme, material and linear
    solver, fitted on the runs that completed (``from`` and ``to``: the node counts of the
    fit)."""
    rows = []
    ok = table[table.status == "ok"]
    keys = ["method", "integration", "material", "solver", "efg"]
    for values, group in ok.groupby(keys, sort=False):
        row = {**dict(zip(keys, values, strict=True)), "from": group.nodes.min(),
               "to": group.nodes.max()}
        for phase in PHASES:
            row[phase] = exponent(group.nodes, group[phase])
        rows.append(row)
    return pd.DataFrame(rows, columns=[*keys, "from", "to", *PHASES])


def rates(table, yardstick):
    """The factorisation rate of every run that reported its flops, against dgemm.

    Parameters
    ----------
    table : pandas.DataFrame
        The rows of :func:`~soilwater.studies.bench.runs.steps`.
    yardstick : dict
        :func:`~soilwater.studies.harness.machine.dgemm`'s rates [GF/s].

    Returns
    -------
    pandas.DataFrame
        Method, EFG's scheme, material, nodes, solver, EFG's conditions,
        ``single_factorisations``, ``factor_flops``, ``solve`` [s], ``factor_gflops_lb``
        [GF/s] and its fractions of MKL's and NumPy's dgemm rates (a single-precision
        factorisation's rate is compared with double's dgemm too, so its fraction
        overstates).
    """
    done = table[table.factor_flops.notna() & (table.status == "ok")]
    return done[["method", "integration", "material", "nodes", "solver", "efg",
                 "single_factorisations", "factor_flops", "solve", "factor_gflops_lb"]].assign(
        of_mkl_dgemm=done.factor_gflops_lb / yardstick["mkl_gflops"],
        of_numpy_dgemm=done.factor_gflops_lb / yardstick["numpy_gflops"])


def phase_targets(table, shapes, growth):
    """The speed targets per phase, EFG against FEM: measured value, target and verdict,
    one row each.

    A "whole step / fem-p1p1" row whose fem-p1p1 run was stopped compares with its time
    limit: an upper bound of the ratio; EFG is taken on fem-p1p1's solver, once per
    scheme. Assembly per tangent and growth exponents are of the direct solver's runs.
    """
    rows = []
    ok = table[table.status == "ok"]
    if len(shapes):
        largest = shapes.iloc[-1]
        for basis in ("P2", "P1"):
            rows.append((f"shape functions / CellBasis({basis}), same points",
                         f"{int(largest.nodes)} nodes, {int(largest.points)} points",
                         largest.efg_s / largest[f"{basis}_s"], 1.5))
    factorised = ok[(ok.solver != "krylov") & (ok.factorisations > 0)]
    for material in MATERIALS:
        efg = factorised[(factorised.method == "efg") & (factorised.material == material)]
        th = factorised[(factorised.method == "fem-th") & (factorised.material == material)]
        for _, row in efg.iterrows():
            fem = at(row.dofs, th.dofs, th.assembly / th.factorisations) if len(th) else np.nan
            if fem == fem:
                rows.append((f"assembly per tangent / fem-th at equal DOFs ({material})",
                             f"{row.nodes} nodes, {int(row.dofs)} DOFs; "
                             f"{row.integration}; {row.efg}",
                             row.assembly / row.factorisations / fem, 2.0))
        for nodes in (10_000, 100_000):
            f = pick(table, "fem-p1p1", material, nodes)
            for scheme in dict.fromkeys(table.integration[table.method == "efg"]):
                e = None if f is None else pick(table, "efg", material, nodes, f.solver,
                                                scheme)
                if e is None:
                    continue
                stopped = f.status.startswith("stopped")
                rows.append((f"whole step / fem-p1p1 at equal nodes ({material})",
                             f"{e.nodes} nodes, {scheme}"
                             + (f" (fem-p1p1 {f.status}: an upper bound)" if stopped else ""),
                             e.step / (f.limit_s if stopped else f.step), 3.0))
    direct = growth[(growth.method == "efg") & (growth.solver != "krylov")]
    for _, row in direct.iterrows():
        for phase in PHASES:
            if phase != "solve":
                rows.append((f"growth exponent, EFG {phase} ({row.material})",
                             f"{row['from']} to {row['to']} nodes, {row.solver}; "
                             f"{row.integration}; {row.efg}",
                             row[phase], 1.2))
    frame = pd.DataFrame(rows, columns=["target", "where", "measured", "limit"])
    frame["met"] = verdict(frame.measured, frame.limit)
    return frame


#: The reference EFG Cam-clay step at 10^5 nodes [s], measured on :data:`BASELINE_CPU`:
#: the first scale target is half of it.
BASELINE_STEP = 32.1
BASELINE_CPU = "AMD EPYC, 2 cores"
#: Memory of the target machine [GB = 10^9 bytes]: 24 GiB.
MACHINE_GB = 24 * 2**30 / 1e9

def scale_targets(table, machine_name="this machine"):
    """The targets at scale (EFG Cam-clay step and memory at 10^5 and 10^6 nodes, its
    growth, EFG against the stabilised P1-P1): measured value, target and verdict, one
    row each.

    A target whose run did not complete is "not measured" (:func:`verdict`), with the
    run's status, and where it bounds the value, the bound, in ``where``. Each EFG
    scheme (``integration``) is judged on its own runs. The 10^5-node step and memory
    are given per run there; the growth exponent per scheme on the faster solver at each
    size (:func:`fastest`) and per solver; each scheme and fem-p1p1-stab are compared at
    equal nodes, each on its faster solver there.

    Parameters
    ----------
    table : pandas.DataFrame
        The rows of :func:`~soilwater.studies.bench.runs.steps`.
    machine_name : str
        Where the runs were measured (:func:`soilwater.studies.harness.machine.cpu`), for
        the first target's baseline.
    """
    rows = []
    efg = table[(table.method == "efg") & (table.material == "cam-clay")]

    def at_size(nodes, column, scale, what, limit, note=""):
        there = efg[np.isclose(efg.nodes, nodes, rtol=0.1)]
        if not len(there):
            size = f"{nodes:.0e}".replace("e+0", "e")
            rows.append((what, f"no run at {size} nodes", np.nan, limit))
        for _, row in there.iterrows():
            done, peak = row.status == "ok", row.get("peak_mb", np.nan)
            until = f" (peak {peak / 1e3:.2f} GB until then)" if peak == peak else ""
            rows.append((what, f"{row.nodes} nodes, {row.solver}; {row.integration}; "
                         f"{row.efg}"
                         + ("" if done else f", {row.status}{until}") + note,
                         row[column] * scale if done else np.nan, limit))

    at_size(100_000, "step", 1.0, "EFG Cam-clay step at 1e5 nodes [s]", 0.5 * BASELINE_STEP,
            f", measured on {machine_name}; limit 0.5 x {BASELINE_STEP} s, the reference step "
            f"on {BASELINE_CPU}, not in this run (the CPU may differ)")
    at_size(100_000, "peak_mb", 1e-3, "EFG Cam-clay peak memory at 1e5 nodes [GB]", 3.0)
    at_size(1_000_000, "step", 1.0, "EFG Cam-clay step at 1e6 nodes [s]", 600.0)
    at_size(1_000_000, "peak_mb", 1e-3, "EFG Cam-clay peak memory at 1e6 nodes [GB]",
            MACHINE_GB, f"; limit 24 GiB; this machine has {ram_gb():.1f} GB")

    for scheme, scheme_runs in efg.groupby("integration", sort=False):
        faster = pd.DataFrame([fastest(group) for _, group in scheme_runs.groupby("nodes")],
                              columns=efg.columns)
        series = {"faster solver at each size": faster,
                  **{f"{solver}; {conditions}": runs for (solver, conditions), runs
                     in scheme_runs.groupby(["solver", "efg"], sort=False)}}
        for name, runs in series.items():
            rows.append((f"EFG Cam-clay step growth exponent, 1e4 to 1e6 nodes ({scheme}: "
                         f"{name})", *_growth(runs), 1.15))

    stab = table[table.method == "fem-p1p1-stab"]
    for (material, nodes, scheme), group in table[table.method == "efg"].groupby(
            ["material", "nodes", "integration"], sort=False):
        e = fastest(group)
        f = fastest(stab[(stab.material == material) & (stab.nodes == nodes)])
        if f is None:
            continue
        where = (f"{nodes} nodes, efg {scheme} {e.solver} ({e.efg}), fem-p1p1-stab "
                 f"{f.solver}")
        if e.status == "ok" and f.status == "ok":
            ratio = e.step / f.step
        else:
            ratio = np.nan
            for name, row in (("efg", e), ("fem-p1p1-stab", f)):
                if row.status != "ok":
                    where += f"; {name} {row.status}"
            if e.status == "ok" and f.status.startswith("stopped"):
                where += f": ratio < {e.step / f.limit_s:.3g}"
            elif f.status == "ok" and e.status.startswith("stopped"):
                where += f": ratio > {e.limit_s / f.step:.3g}"
        rows.append((f"EFG step / fem-p1p1-stab step at equal nodes ({material})", where,
                     ratio, 2.0))
    frame = pd.DataFrame(rows, columns=["target", "where", "measured", "limit"])
    frame["met"] = verdict(frame.measured, frame.limit)
    return frame


def _growth(runs):
    """``(where, exponent)`` of the steps of ``runs`` from 10^4 to 10^6 nodes; the exponent
    is NaN unless both ends completed (``where`` then gives the partial fit)."""
    fit = exponent(runs.nodes, runs.step, within=(1e4, 1e6))
    done = runs[(runs.status == "ok") & (runs.nodes >= 1e4 / 1.1) & (runs.nodes <= 1.1e6)]
    whole = all(((np.isclose(done.nodes, n, rtol=0.1)).any() for n in (1e4, 1e6)))
    where = (f"{done.nodes.min()} to {done.nodes.max()} nodes, "
             f"{', '.join(dict.fromkeys(done.solver))}" if len(done) > 1
             else "fewer than two sizes completed")
    if not whole and fit == fit:
        where += f" only (fit {fit:.2f}): 1e4 or 1e6 did not complete or was not run"
    return where, fit if whole else np.nan
