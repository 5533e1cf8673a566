"""The run template of both coupled solvers: the march through the case's time levels.

The EFG and FEM solvers differ only in how they discretise a step (shape functions or
bases, cells, assembly, essential conditions); the run around the step is here:

* :func:`run`: timers, the march, the summary every result carries;
* :func:`march`: the case's time levels, a failing level halved up to :data:`MAX_CUTS`
  times; a level that starts with a jump of the load (a step load at t = 0) spreads the
  jump over its halves.

The step itself is Newton's method (:mod:`soilwater.nonlinear.newton`); its history rows
are :mod:`soilwater.nonlinear.history`'s.
"""

import time

import numpy as np
import pandas as pd
from soilwater.errors import ConvergenceError
from soilwater.linalg.backends import identity
from soilwater.nonlinear.history import TIMERS
from soilwater.nonlinear.newton import TOLERANCE, new_counts
from soilwater.nonlinear.progress import Progress
from soilwater.results import Result

#: Halvings of a failing time step before the run stops.
MAX_CUTS = 6


def run(case, method, options, current, step, row, snapshot, summary, progress=True):
    """The run template of both coupled solvers: march, time, summarise.

    Parameters
    ----------
    case : Case
    method : str
        ``efg`` or an FEM pair; it names the result and the progress bar.
    options : dict
        The method's settings, stored with the result.
    current : object
        The solver's state at t = 0.
    step : callable
        ``step(current, t0, t1, stats, load) -> (current, iterations, residual)`` with
        ``load`` the load factor at t1 (:func:`march`), adding to
        ``stats["timings"]`` (keys :data:`soilwater.nonlinear.history.TIMERS`) and the
        counts of :func:`soilwater.nonlinear.newton.newton`.
    row, snapshot : callable
        As in :func:`march`.
    summary : dict
        The method's own summary entries (unknowns, penalties, ...).

    Returns
    -------
    Result
        Its summary holds ``steps``, ``tolerance``, ``linear_solver`` (the back-end of the
        last factorisation, :func:`soilwater.linalg.backends.backend`'s without one),
        ``summary``, the statistics of :func:`march`, the counts of
        :func:`soilwater.nonlinear.newton.newton` (``factorisations``,
        ``symmetric_factorisations``, ``single_factorisations``, ``perturbed_pivots``,
        ``factor_flops``, ``linear_iterations``) and ``timings``.
    """
    stats = {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)}
    tic = time.perf_counter()
    history, snapshots = march(case, current,
                               lambda c, t0, t1, load: step(c, t0, t1, stats, load),
                               row, snapshot, stats, progress, desc=f"{method} {case.name}")
    stats["timings"]["total_s"] = time.perf_counter() - tic
    return Result(case, method, options, history, snapshots,
                  {"steps": len(history), "tolerance": TOLERANCE,
                   "linear_solver": identity(), **summary, **stats})


def march(case, current, step, row, snapshot, stats, progress=True, desc=""):
    """Advance through the case's time levels; cut a failing level back.

    Parameters
    ----------
    case : Case
    current : object
        The solver's state at t = 0.
    step : callable
        ``step(current, t0, t1, load) -> (current, iterations, residual)``, ``load`` the
        load factor at t1 (``case.loading.factor(t1)``, but see Notes); raises
        :class:`ConvergenceError` (or ``FloatingPointError``) when it fails.
    row : callable
        ``row(current, t, dt, info) -> dict``: the history row of a converged level.
    snapshot : callable
        ``snapshot(current, t) -> Snapshot``.
    stats : dict
        Updated in place: ``newton_iterations``, ``cutbacks``, ``max_residual``,
        ``stopped`` (with ``time.on_failure = "stop"``: None, or where and why the run
        ended before ``time.end``) and, when
        the rows carry the uniqueness indicator (``diagnostics.uniqueness``),
        ``uniqueness_onset_step``: the first step (from 1) whose indicator is not
        positive, None if there is none.
    progress : bool
        Show the march's progress (:class:`soilwater.nonlinear.progress.Progress`: a bar
        on a terminal, plain lines on standard error without one).
    desc : str
        What runs, for the progress.

    Returns
    -------
    history : pandas.DataFrame
        One row per level; an ``err`` column that is undefined throughout is left empty.
    snapshots : list of Snapshot
        At t = 0 and after every level (only at ``time.output``'s when the case gives
        them).

    Notes
    -----
    A level that fails is cut into 2, 4, ... 2^MAX_CUTS equal sub-steps. A jump of the
    load factor at the level's start (:meth:`soilwater.case.timeline.Loading.jump`: a step
    load at t = 0) is then applied in equal parts, one per sub-step, instead of all in
    the first: the step load becomes a ramp over the first level, which changes the
    drainage during that level by O(dt), the order of the time integration. A short
    first level (``time.dt0``) keeps the first response close to the undrained one.
    """
    stats.update({"newton_iterations": 0, "cutbacks": 0, "max_residual": 0.0,
                  "stopped": None})
    times = case.times()
    rows, snapshots = [], [snapshot(current, 0.0)]
    shown = Progress(len(times) - 1, desc, enabled=progress)
    try:
        for t0, t1 in zip(times[:-1], times[1:]):
            try:
                current, info = _advance(current, step, t0, t1, stats, case)
            except ConvergenceError as err:
                if case.time.on_failure != "stop" or not rows:
                    raise
                stats["stopped"] = f"at t = {t0:g} s: {err}"
                break
            rows.append(row(current, t1, t1 - t0, info))
            if case.time.writes(t1):
                snapshots.append(snapshot(current, t1))
            shown.update(t1, stats)
    finally:
        shown.close()
    history = pd.DataFrame(rows)
    if "err" in history and history["err"].isna().all():
        history["err"] = None
    if "uniqueness" in history:
        lost = np.flatnonzero(history["uniqueness"].to_numpy() <= 0)
        stats["uniqueness_onset_step"] = int(lost[0]) + 1 if len(lost) else None
    return history, snapshots


def _advance(current, step, t0, t1, stats, case):
    """One time level, halved while it fails (up to MAX_CUTS times); a jump of the load
    at t0 spread over the halves."""
    loading = case.loading
    dt, jump = t1 - t0, loading.jump(t0)
    for cut in range(MAX_CUTS + 1):
        n = 2**cut
        try:
            trial, iterations, residuals = current, 0, []
            krylov = stats.get("linear_iterations", 0)
            for k in range(1, n + 1):
                t, end = t0 + (k - 1) * dt / n, (t0 + k * dt / n) if k < n else t1
                load = float(loading.factor(end)) - jump * (n - k) / n
                with np.errstate(all="ignore"):  # failures end in ConvergenceError
                    trial, its, res = step(trial, t, end, load)
                iterations += its
                residuals.append(res)
            stats["cutbacks"] += cut
            stats["newton_iterations"] += iterations
            stats["max_residual"] = max(stats["max_residual"], *residuals)
            return trial, {"iterations": iterations, "residual": max(residuals),
                           "substeps": n,
                           "linear_iterations": stats.get("linear_iterations", 0) - krylov}
        except (ConvergenceError, FloatingPointError) as err:
            reason = err
    raise ConvergenceError(f"step t = {t0:g} -> {t1:g} s failed after {MAX_CUTS} halvings "
                           f"of the time step ({reason}): {_advice(case, t0, t1, reason)}")


def _advice(case, t0, t1, reason):
    """What to do about the level ``t0 -> t1`` that failed after every halving, from why
    (``reason``, the last failure) and when it failed.

    * A load or stress larger than the initial P-wave modulus (strains of order one): the
      input's size or units (a modulus past :data:`soilwater.physics.scales.RANGE` times
      the loads is refused before the run).
    * An element or cell that inverts: the mesh cannot follow the deformation.
    * A step load on a drained boundary whose smallest sub-step drains a skin thinner than
      the node spacing, ``sqrt(c_v dt) < h`` (``c_v`` from the initial P-wave modulus and
      the permeability): a soft soil compresses at once in that skin, which a fixed
      discretisation cannot follow, the less the shorter the step. This is the nonlinear
      face of the minimum time step of consolidation, about ``h^2 / (6 c_v)`` for linear
      elements (Vermeer and Verruijt 1981): longer first steps or a ramped load help.
    * A load that grows over the level: it may exceed what the soil can carry.

    Every message ends by naming ``time.on_failure = "stop"``, which keeps the levels that
    converged.
    """
    from soilwater.physics.scales import Scales

    loading = case.loading
    scales = Scales.of(case, case.material())
    skin = (float(np.sqrt(case.fluid.mobility * scales.modulus * (t1 - t0) / 2**MAX_CUTS))
            if loading.jump(t0) and case.boundary.drained else None)
    if scales.stress > scales.modulus:
        cause = (f"the largest load or stress ({scales.stress:.3g}) exceeds the soil's "
                 f"initial P-wave modulus ({scales.modulus:.3g}, the case's units): "
                 "strains of order one at once; check the loads' and moduli's size and "
                 "units")
    elif "invert" in str(reason):
        cause = ("the deformation is more than the mesh can follow here: stop earlier, "
                 "refine where it distorts, or re-mesh (fem.remesh = \"delaunay\" for the "
                 "triangle pairs)")
    elif skin is not None and skin < scales.h:
        cause = (f"the step load drains a skin of about {skin:.2g} m in the shortest "
                 f"sub-step, thinner than the node spacing ({scales.h:.2g} m), and shorter "
                 "steps make it thinner (the minimum time step of consolidation, about "
                 "h^2 / (6 c_v)): lengthen the first steps (time.dt0, e.g. 10 or 100 "
                 "times), refine the nodes at the drained boundary, or ramp the load "
                 "over a first interval (loading.load = [[0, 0], [t1, 1]])")
    elif loading.jump(t0) or float(loading.factor(t1)) > float(loading.factor(t0)):
        cause = (f"the load grows to {float(loading.factor(t1)):.4g} x the tractions "
                 "and footing loads over this step: check that it does not exceed "
                 "what the soil can carry (a footing's bearing capacity), then "
                 "reduce the load steps or the loading rate")
    else:
        cause = ("reduce the time steps or the loading rate, or check the boundary "
                 "conditions and material")
    keep = ("" if case.time.on_failure == "stop" else
            "; time.on_failure = \"stop\" keeps the levels that converged")
    return cause + keep
