"""What both coupled solvers share: the run, the Newton step and the history it records.

The EFG and FEM solvers differ only in how they discretise a step (shape functions or
bases, cells, assembly, essential conditions); everything around that is here:

* :class:`Scales`: the residual scales a step converges against
  and the rule that pins the mean pore pressure of a confined undrained body;
* :func:`run`: the run template (timers, the march, the summary every result carries);
* :func:`march`: the case's time levels, a failing level halved up to :data:`MAX_CUTS`
  times;
* :func:`newton`: Newton's method on one step, reusing a factorisation while it
  contracts (:func:`soilwater.linalg.backends.must_refactorise`);
* :func:`material_update`: kinematics and the material's return mapping at the points;
* :func:`history_row`: the columns of a history row.
"""

import time
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import pandas as pd
from tqdm import tqdm

from soilwater.errors import ConvergenceError
from soilwater.physics.geostatic import buoyant_weight, initial_state
from soilwater.material.kinematics import determinant, invariants, inverse, strain_increment
from soilwater.linalg.backends import FORCING_MAX, factorise, forcing, identity, must_refactorise
from soilwater.geometry.quality import cell_quality
from soilwater.results import Result

#: Newton tolerance on the scaled residuals (see :class:`Scales`).
TOLERANCE = 1e-8
MAX_ITERATIONS = 25
#: Whether the first factorisation of a step is the symmetric one of ``sym(K)``
#: (:func:`soilwater.linalg.backends.factorise`; every refactorisation is of ``K``). Off: the tangents
#: are not symmetric enough for it to pay (README, "Speed").
SYMMETRIC_FIRST = False
#: Halvings of a Newton correction whose iterate the material cannot take.
BACKTRACKS = 4
#: Halvings of a failing time step before the run stops.
MAX_CUTS = 6
#: Phase timers of a run [s], ``summary["timings"]`` of both methods (plus ``total_s``):
#: background cells or mesh geometry, shape functions or bases, assembly of the tangent
#: (and of sparsity patterns), factorisations and back-solves, material updates.
TIMERS = ("cells_s", "shape_functions_s", "assembly_s", "solve_s", "material_s")


@dataclass(frozen=True)
class Scales:
    """Constants of a coupled run, from the case's initial state.

    Attributes
    ----------
    stress : float
        Stress scale: the largest initial effective stress, edge traction, footing stress
        (:func:`_footing_stresses`) or buoyant weight of the height [kPa].
    modulus : float
        P-wave modulus ``K + 4G/3`` of the initial state, the median over the nodes [kPa].
    h : float
        Smallest nodal spacing [m].
    pin_pressure : bool
        True for a confined body (no free or rigid component, no drained edge) with
        incompressible constituents: its pore pressure is defined up to a constant, and
        the solvers pin the mean change to zero.
    shear : float
        Shear modulus G of the initial state, the median over the nodes [kPa].

    Notes
    -----
    A step has converged when the displacement residual is below ``TOLERANCE x stress x
    h`` (force per unit thickness) and the continuity residual below ``TOLERANCE x
    stress x h^2 / modulus`` (volume per unit thickness).
    """

    stress: float
    modulus: float
    h: float
    pin_pressure: bool
    shear: float

    @classmethod
    def of(cls, case, material):
        effective, state = initial_state(case, material, case.nodes())
        edges = [edge for _, edge in case.boundary.items()]
        tractions = [abs(np.asarray(e.traction, float)).max() for e in edges
                     if e.traction != "exact"]
        p, _ = invariants(effective)
        modulus = float(np.median(material.constrained_modulus(p, state["v"])))
        free = any({"free", "rigid"} & (kx | ky) for kx, ky in
                   (edge.kinds(case.edge_length(side)) for side, edge in case.boundary.items()))
        drained = any(e.drained or any(s.water == "drained" for s in e.segments)
                      for e in edges)
        pin = case.fluid.storage == 0 and not free and not drained
        weight = buoyant_weight(case, state["v"]).max() * case.geometry.height
        return cls(max([abs(effective).max(), *tractions, weight,
                        *_footing_stresses(case, modulus), 1e-12]),
                   modulus, float(min(case.spacing)), pin,
                   float(np.median(material.moduli(p, state["v"])[1])))

    @property
    def perturbation(self):
        """``h^2 / (4 M)`` [m2/kPa]: the coefficient of the flow-equation perturbation
        ``-beta int grad(p - p_n) . grad(q)`` of Aguilar, Gaspar, Lisbona and Rodrigo
        (2008), with the initial P-wave modulus M and the smallest nodal spacing h."""
        return self.h**2 / (4 * self.modulus)

    @property
    def projection(self):
        """``1 / G`` [1/kPa]: the coefficient of the polynomial pressure projection
        ``-tau int (dp - Pi dp)(q - Pi q)`` (:func:`soilwater.physics.weakform.fluctuation`), the
        inverse viscosity of Dohrmann and Bochev (2004) read as the initial shear
        modulus of the skeleton."""
        return 1.0 / self.shear

    @property
    def force(self):
        """Residual scale of equilibrium [force per unit thickness]."""
        return self.stress * self.h

    @property
    def volume(self):
        """Residual scale of continuity [volume per unit thickness]."""
        return self.stress * self.h**2 / self.modulus


def _footing_stresses(case, modulus):
    """Stress scales of the footings [kPa]: ``force / (to - from)`` under load control,
    ``modulus x rate x time.end / height`` (the oedometric stress of the final
    settlement over the depth) under velocity control."""
    for _, seg in case.boundary.segments():
        if seg.load_controlled:
            yield abs(seg.force) / (seg.end - seg.start)
        elif seg.footing:
            yield modulus * abs(seg.settlement_rate) * case.time.end / case.geometry.height


@contextmanager
def timed(timings, key):
    """Add the wall time of the ``with`` block to ``timings[key]`` [s]."""
    tic = time.perf_counter()
    yield
    timings[key] += time.perf_counter() - tic


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
        ``step(current, t0, t1, stats) -> (current, iterations, residual)``, adding to
        ``stats["timings"]`` (keys :data:`TIMERS`) and the counts of :func:`newton`.
    row, snapshot : callable
        As in :func:`march`.
    summary : dict
        The method's own summary entries (unknowns, penalties, ...).

    Returns
    -------
    Result
        Its summary holds ``steps``, ``tolerance``, ``linear_solver`` (the back-end of
        the last factorisation, :func:`soilwater.linalg.backends.backend`'s without one), ``summary``, the
        statistics of :func:`march`, the counts of :func:`newton`
        (``factorisations``, ``symmetric_factorisations``, ``single_factorisations``,
        ``perturbed_pivots``, ``factor_flops``, ``linear_iterations``) and ``timings``.
    """
    stats = {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)}
    tic = time.perf_counter()
    history, snapshots = march(case, current, lambda c, t0, t1: step(c, t0, t1, stats),
                               row, snapshot, stats, progress, desc=f"{method} {case.name}")
    stats["timings"]["total_s"] = time.perf_counter() - tic
    return Result(case, method, options, history, snapshots,
                  {"steps": len(history), "tolerance": TOLERANCE,
                   "linear_solver": identity(), **summary, **stats})


def new_counts():
    """The factorisation counts :func:`newton` adds to, at zero."""
    return {"factorisations": 0, "symmetric_factorisations": 0, "single_factorisations": 0,
            "perturbed_pivots": 0,
            "factor_flops": 0.0, "linear_iterations": 0}


def newton(system, stats):
    """Newton's method on one step's nonlinear system.

    Modified Newton: a factorisation is kept while each iteration contracts the residual
    (:func:`soilwater.linalg.backends.must_refactorise`), and the current tangent is factorised
    otherwise. With :data:`SYMMETRIC_FIRST` (off by default) the first factorisation of
    the step is the symmetric one of ``sym(K) = (K + K^T) / 2`` (half the factor of
    ``K``'s on PARDISO), kept while it contracts like any other; once a factorisation
    stalls, the step refactorises the full unsymmetric ``K``. The corrections of
    ``sym(K)`` contract the residual at best by the spectral radius of
    ``sym(K)^-1 (K - K^T) / 2``, those of ``K`` by the change of the tangent over the
    step. SuperLU has no symmetric mode: every factorisation is of ``K``.

    With the Krylov back-end a "factorisation" is a preconditioner, and Newton is
    Newton: every iteration assembles the current tangent and hands it to the
    solver (:meth:`soilwater.linalg.krylov.Krylov.adopt`), which keeps the preconditioner of the
    step's first tangent. Each correction is solved inexactly, to the
    relative residual of :func:`soilwater.linalg.backends.forcing` (Eisenstat-Walker): loosely far from
    the solution, tightly near it, and at most the layout's
    :attr:`~soilwater.linalg.backends.Layout.forcing`.

    A correction whose iterate the material or the kinematics cannot take (a return
    mapping that fails, an inverted point) is halved, up to :data:`BACKTRACKS` times
    (:func:`_residual`), before the step fails: past a peak, full Newton's corrections
    can overshoot into such states.

    Parameters
    ----------
    system : object
        The step's unknowns and equations, with

        * ``residual() -> (R, scaled)``: the residual vector at the current iterate and
          its size in units of the tolerance's scales (:class:`Scales`);
        * ``tangent() -> K``: the sparse Jacobian of ``R`` at the current iterate;
        * ``layout``: what the unknowns are, a :class:`soilwater.linalg.backends.Layout` (or None);
        * ``advance(dx)``: add a correction to the unknowns.
    stats : dict
        Added to: ``factorisations`` (all of them), ``symmetric_factorisations`` (those of
        ``sym(K)``), ``single_factorisations`` (those in single precision, PARDISO),
        ``perturbed_pivots`` (summed over the factorisations; PARDISO's
        ``iparm(14)``), ``factor_flops`` (PARDISO's ``iparm(19)``, summed),
        ``linear_iterations`` (Krylov iterations) and ``timings`` (``assembly_s``,
        ``solve_s``); ``linear_solver`` set to the back-end of the last factorisation
        (:func:`soilwater.linalg.backends.identity`).

    Returns
    -------
    iterations : int
        Residual evaluations, the converged one included.
    residual : float
        The converged scaled residual (< :data:`TOLERANCE`).

    Raises
    ------
    ConvergenceError
        No convergence in :data:`MAX_ITERATIONS` iterations.
    FloatingPointError
        A residual that is not finite.

    Examples
    --------
    ``x^2 = 2`` from ``x = 1``; the first factorisation is reused while it contracts the
    residual tenfold per iteration:

    >>> import scipy.sparse as sp
    >>> class Root:
    ...     layout, x = None, np.array([1.0])
    ...     def residual(self):
    ...         return self.x**2 - 2, abs(self.x[0]**2 - 2)
    ...     def tangent(self):
    ...         return sp.csr_matrix(2 * self.x[None])
    ...     def advance(self, dx):
    ...         self.x = self.x + dx
    >>> root, stats = Root(), {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)}
    >>> iterations, residual = newton(root, stats)
    >>> round(float(root.x[0]), 8), stats["factorisations"], bool(residual < TOLERANCE)
    (1.41421356, 2, True)
    """
    cap = FORCING_MAX if system.layout is None else system.layout.forcing
    lu, previous, eta, dx = None, np.inf, cap, None
    for iteration in range(1, MAX_ITERATIONS + 1):
        R, residual = _residual(system, dx)
        if not np.isfinite(residual):
            raise FloatingPointError("the residual is not finite")
        if residual < TOLERANCE:
            return iteration, residual
        if iteration == MAX_ITERATIONS:
            raise ConvergenceError(f"Newton residual {residual:.2e} after {iteration} "
                                   "iterations")
        if must_refactorise(lu, residual, previous) or lu.current:
            first = lu is None
            if not first:
                lu.release()                # one tangent in memory at a time
            with timed(stats["timings"], "assembly_s"):
                K = system.tangent()
            if first or not lu.adopt(K):
                lu = None                   # and one factorisation
                with timed(stats["timings"], "solve_s"):
                    lu = factorise(K, system.layout, symmetric=SYMMETRIC_FIRST and first)
                _count(stats, lu)
            del K                           # the solver holds what it needs
        eta = forcing(residual, previous, eta, TOLERANCE, cap)
        previous, before = residual, (lu.iterations, lu.factorisations, lu.flops)
        with timed(stats["timings"], "solve_s"):
            dx = lu.solve(-R, rtol=eta)
        stats["linear_iterations"] += lu.iterations - before[0]
        stats["factorisations"] += lu.factorisations - before[1]    # redone in double
        stats["factor_flops"] += lu.flops - before[2]
        system.advance(dx)


def _residual(system, dx):
    """``system.residual()`` at the iterate, the last correction ``dx`` halved (up to
    :data:`BACKTRACKS` times) while the iterate is one the material or the kinematics
    cannot take (a :class:`ConvergenceError`: a return mapping that fails, an inverted
    point). If every halving fails, the full correction's error is raised."""
    try:
        return system.residual()
    except ConvergenceError as failure:
        if dx is None:
            raise
        for _ in range(BACKTRACKS):
            dx = dx / 2
            system.advance(-dx)
            try:
                return system.residual()
            except ConvergenceError:
                pass
        raise failure


def _count(stats, lu):
    """Add the factorisation ``lu`` to the counts of :func:`newton`, and name its
    back-end (``linear_solver``, :func:`soilwater.linalg.backends.identity`)."""
    stats["linear_solver"] = identity(lu.backend)
    stats["factorisations"] += lu.factorisations
    stats["symmetric_factorisations"] += lu.symmetric
    stats["single_factorisations"] += lu.single
    stats["perturbed_pivots"] += lu.perturbed_pivots
    stats["factor_flops"] += lu.flops


def material_update(material, stress, state, H, timings, where="an integration point"):
    """Kinematics and the material's return mapping over a step, at many points.

    Parameters
    ----------
    material : Material
    stress, state : ndarray (P, 4), dict
        Effective stress (tension positive) and material state at the start of the step.
    H : ndarray, shape (P, 2, 2)
        ``grad_n(du)``: the step's displacement gradient on the start-of-step
        configuration, ``H[p, i, j] = d du_i / d x_j``.
    timings : dict
        ``material_s`` is added to.
    where : str
        What a point is (``"a node"``, ``"a background cell"``), for the messages of a
        point that inverts or whose return mapping fails.

    Returns
    -------
    stress, state, tangent
        The material's update (:meth:`update`) with the strain and spin increments of
        :func:`soilwater.material.kinematics.strain_increment`.
    J : ndarray, shape (P,)
        ``det F``, ``F = I + H``.
    Finv : ndarray, shape (P, 2, 2)
    deps : ndarray, shape (P, 4)
        The strain increment (Voigt).

    Raises
    ------
    ConvergenceError
        Where ``J <= 0`` (the step inverts ``where``), or the material's update fails
        (its message, with ``where``).
    """
    F = np.eye(2) + H
    J = determinant(F)
    if not np.all(J > 0):
        raise ConvergenceError(f"{where} inverts (J = {J.min():.3g})")
    Finv = inverse(F)
    deps, dw = strain_increment(H, J)
    with timed(timings, "material_s"):
        try:
            stress, state, tangent = material.update(stress, state, deps, dw)
        except ConvergenceError as error:
            raise ConvergenceError(f"{error} (at {where})") from None
    return stress, state, tangent, J, Finv, deps


def history_row(case, t, dt, info, stress, stretching, top, top0, weights=None, probes=(),
                uniqueness=None, segments=(), cells=None, rcond=None):
    """One row of a coupled run's history.

    Parameters
    ----------
    case : Case
    t, dt : float
        The level's time and step [s].
    info : dict
        ``iterations``, ``substeps``, ``residual`` and ``linear_iterations`` of the level
        (:func:`march`); the Krylov iterations become a column where there were any.
    stress, stretching : ndarray, shape (P, 4)
        Effective stress (tension positive) and last stretching [1/s] at the material
        points.
    top, top0 : ndarray, shape (T, 2)
        Current and initial positions of the top edge's nodes [m].
    weights : ndarray, shape (P,), optional
        Weights of the domain averages (current volumes); equal weights by default.
    probes : iterable of (str, float)
        Probe name and its pore pressure [kPa].
    uniqueness : float, optional
        The :mod:`soilwater.diagnostics.bifurcation` indicator of the level, if asked for.
    segments : iterable of (Segment, ndarray, ndarray, float, float or None)
        Per named segment (:meth:`soilwater.case.model.Boundary.segments` order): the segment, the
        current and initial positions (K, 2) [m] of its boundary nodes, the vertical
        force the boundary exerts on the soil over it (reaction, per unit thickness, y
        up positive [kN/m]) and the plate unknown (uy [m]) of a load-controlled footing,
        else None.
    cells : ndarray, shape (C, V, 2), optional
        The current cells (FEM elements or EFG background cells), counter-clockwise in
        their undeformed state, V = 3 or 4 (:func:`soilwater.geometry.quality.cell_quality`).
    rcond : float, optional
        The smallest reciprocal condition number of the MLS moment matrix over the
        level's integration points (EFG).

    Returns
    -------
    dict
        ``time``, ``eps_a`` (:func:`axial_strain`), ``p`` and ``q`` (domain averages of
        p', q [kPa]), ``err`` (:func:`stretching_error`), ``gamma`` (mean horizontal
        displacement of the top over the height), ``settlement`` (mean
        downward displacement of the top edge's nodes [m]), ``dt``, ``iterations``, ``substeps``,
        ``residual``, ``p_w@NAME`` per probe, if given, ``uniqueness`` and per segment
        ``settlement@NAME`` and ``pressure@NAME`` (:func:`segment_columns`); with
        ``cells``, ``min_angle`` [degrees] and ``min_quality`` (the worst cell's
        :func:`soilwater.geometry.quality.cell_quality`), with ``rcond``, ``min_rcond``.
    """
    p, q = invariants(stress)
    quality = {}
    if cells is not None:
        angle, shape = cell_quality(cells)
        quality = {"min_angle": float(angle.min()), "min_quality": float(shape.min())}
    if rcond is not None:
        quality["min_rcond"] = float(rcond)
    contact = {}
    for seg, nodes, nodes0, reaction, plate in segments:
        contact.update(segment_columns(seg, t, nodes, nodes0, reaction, plate))
    return {"time": t, "eps_a": axial_strain(case, top[:, 1]),
            "p": np.average(p, weights=weights), "q": np.average(q, weights=weights),
            "err": stretching_error(case, stretching[:, 1], weights),
            "gamma": np.mean(top[:, 0] - top0[:, 0]) / case.geometry.height,
            "settlement": -float(np.mean(top[:, 1] - top0[:, 1])),
            "dt": dt, "iterations": info["iterations"], "substeps": info["substeps"],
            "residual": info["residual"], **{f"p_w@{name}": v for name, v in probes},
            **({"linear_iterations": info["linear_iterations"]}
               if info.get("linear_iterations") else {}),
            **({} if uniqueness is None else {"uniqueness": uniqueness}), **contact,
            **quality}


def segment_columns(segment, t, nodes, nodes0, reaction, plate=None):
    """``settlement@NAME`` [m, positive down] and ``pressure@NAME`` [kPa, compression
    positive] of one named segment at time t [s].

    The settlement is the footing's: ``settlement_rate x t`` under velocity control,
    ``-plate`` under load control; for a segment that is no footing, the mean downward
    displacement of its nodes. The pressure is the mean contact pressure, ``-reaction /
    width``, the current width being ``(to - from)`` times the stretch of the segment's
    nodes (the current over the initial distance between its two end nodes; 1 with
    fewer than two nodes).

    Examples
    --------
    >>> from soilwater.case.model import Segment
    >>> seg = Segment("f", 0.0, 1.0, uy="footing", settlement_rate=1e-3)
    >>> nodes0 = np.array([[0.0, 1.0], [1.0, 1.0]])
    >>> cols = segment_columns(seg, 2.0, nodes0 + [[0.0, -2e-3], [0.1, -2e-3]], nodes0, -5.5)
    >>> round(cols["settlement@f"], 12), round(cols["pressure@f"], 12)
    (0.002, 5.0)
    """
    nodes, nodes0 = np.asarray(nodes).reshape(-1, 2), np.asarray(nodes0).reshape(-1, 2)
    if segment.load_controlled:
        settlement = -plate
    elif segment.footing:
        settlement = segment.settlement_rate * t
    else:
        settlement = -float(np.mean(nodes[:, 1] - nodes0[:, 1])) if len(nodes) else 0.0
    stretch = 1.0
    if len(nodes0) > 1:
        order = np.argsort(nodes0[:, np.argmax(np.ptp(nodes0, axis=0))])
        ends, ends0 = nodes[order[[0, -1]]], nodes0[order[[0, -1]]]
        stretch = np.linalg.norm(ends[1] - ends[0]) / np.linalg.norm(ends0[1] - ends0[0])
    width = (segment.end - segment.start) * stretch
    return {f"settlement@{segment.name}": float(settlement),
            f"pressure@{segment.name}": float(-reaction / width)}


def march(case, current, step, row, snapshot, stats, progress=True, desc=""):
    """Advance through the case's time levels; cut a failing level back.

    Parameters
    ----------
    case : Case
    current : object
        The solver's state at t = 0.
    step : callable
        ``step(current, t0, t1) -> (current, iterations, residual)``; raises
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

    Returns
    -------
    history : pandas.DataFrame
        One row per level; an ``err`` column that is undefined throughout is left empty.
    snapshots : list of Snapshot
        At t = 0 and after every level.
    """
    stats.update({"newton_iterations": 0, "cutbacks": 0, "max_residual": 0.0,
                  "stopped": None})
    times = case.times()
    rows, snapshots = [], [snapshot(current, 0.0)]
    for t0, t1 in tqdm(list(zip(times[:-1], times[1:])), desc=desc, unit="step",
                       disable=not progress or None, leave=False):
        try:
            current, info = _advance(current, step, t0, t1, stats)
        except ConvergenceError as err:
            if case.time.on_failure != "stop" or not rows:
                raise
            stats["stopped"] = f"at t = {t0:g} s: {err}"
            break
        rows.append(row(current, t1, t1 - t0, info))
        snapshots.append(snapshot(current, t1))
    history = pd.DataFrame(rows)
    if "err" in history and history["err"].isna().all():
        history["err"] = None
    if "uniqueness" in history:
        lost = np.flatnonzero(history["uniqueness"].to_numpy() <= 0)
        stats["uniqueness_onset_step"] = int(lost[0]) + 1 if len(lost) else None
    return history, snapshots


def _advance(current, step, t0, t1, stats):
    """One time level, halved while it fails (up to MAX_CUTS times)."""
    dt = t1 - t0
    for cut in range(MAX_CUTS + 1):
        try:
            t, trial, iterations, residuals = t0, current, 0, []
            krylov = stats.get("linear_iterations", 0)
            for _ in range(2**cut):
                with np.errstate(all="ignore"):  # failures end in ConvergenceError
                    trial, its, res = step(trial, t, t + dt / 2**cut)
                t += dt / 2**cut
                iterations += its
                residuals.append(res)
            stats["cutbacks"] += cut
            stats["newton_iterations"] += iterations
            stats["max_residual"] = max(stats["max_residual"], *residuals)
            return trial, {"iterations": iterations, "residual": max(residuals),
                           "substeps": 2**cut,
                           "linear_iterations": stats.get("linear_iterations", 0) - krylov}
        except (ConvergenceError, FloatingPointError) as err:
            reason = err
    raise ConvergenceError(f"step t = {t0:g} -> {t1:g} s failed after {MAX_CUTS} halvings "
                           f"of the time step ({reason}): reduce time steps or loading "
                           "rate, or check the boundary conditions")


def axial_strain(case, heights):
    """``eps_a = -ln(h / H)``: logarithmic axial strain from current top heights [m]."""
    return float(-np.log(np.mean(heights) / case.geometry.height))


def stretching_error(case, d22, weights=None):
    """Paper eq. 1: mean over points of ``|(D22_exact - D22^I) / D22_exact|``.

    ``D22_exact`` is the case's prescribed ``L22``; NaN when it is zero (undefined).
    ``weights`` (e.g. quadrature volumes) turn the mean into a weighted one.
    """
    L22 = case.loading.L[1, 1]
    if L22 == 0:
        return np.nan
    return float(np.average(np.abs((L22 - d22) / L22), weights=weights))
