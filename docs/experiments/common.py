"""What the experiment scripts of ``docs/experiments/`` share.

* :func:`solve`: a coupled run, each step's Newton system solved with the
  :class:`soilwater.linalg.layout.Layout` an experiment passes (:func:`replaced`), traced,
  or watched step by step, composed from the solvers' own pieces instead of patching
  them; :func:`bench_step`, one step of the bench case so;
* :func:`first_system` and :func:`first_tangent`: the Newton system and tangent of a
  run's first step, :func:`scaled_tangent` as the Krylov back-end sees it;
* :func:`step_row`, :func:`whole_run`, :func:`compare_runs` and :func:`agreement`: what
  the scripts print of a step or a run;
* :func:`scoped`: a module constant set for a ``with`` block and restored, for the few
  knobs the library takes no argument for;
* argument helpers (:func:`count`, :func:`run_spec`, :func:`parser`, :func:`parsed`).

The scripts import it from their own folder: run them as ``python
docs/experiments/<script>.py``.
"""

import argparse
import dataclasses
import resource
import time
from contextlib import contextmanager
from functools import partial

import numpy as np
import scipy.sparse as sp

import soilwater.efg.solver as efg
import soilwater.fem.solver as fem
from soilwater.case.loader import load_case
from soilwater.efg.discretisation import background_cells, discretise, min_rcond
from soilwater.efg.model import Model as EFGModel
from soilwater.efg.system import System as EFGSystem
from soilwater.errors import ConvergenceError, InputError
from soilwater.fem.model import Model as FEMModel
from soilwater.fem.remesh import remesh
from soilwater.fem.system import System as FEMSystem
from soilwater.fem.system import discretise as fem_discretise
from soilwater.linalg.backends import linear_solver
from soilwater.linalg.krylov import _permuted
from soilwater.nonlinear.history import TIMERS, timed
from soilwater.nonlinear.march import run
from soilwater.nonlinear.newton import newton
from soilwater.studies.bench.plan import compression

#: Seconds after which a step run in its own process is stopped.
LIMIT = 400.0
#: The whole runs of ``krylov_runs.py`` and ``direct_single.py``: (case, method, EFG's
#: essential conditions, EFG's stabilisation), None where the case's own.
RUNS = (("unconfined-compression", "efg", "nitsche", None),
        ("unconfined-compression", "efg", "penalty", None),
        ("unconfined-compression", "fem-th", None, None),
        ("unconfined-compression", "fem-p1p1-stab", None, None),
        ("terzaghi", "efg", "nitsche", None))
#: What :func:`step_row` reports of a step, and the summary entries or timers it reads.
STEP = {"step": "total_s", "assembly": "assembly_s", "solve": "solve_s",
        "constitutive": "material_s", "iterations": "newton_iterations",
        "linear_iterations": "linear_iterations", "factorisations": "factorisations",
        "single_factorisations": "single_factorisations"}


def count(text):
    """A node or item count from the command line: a whole number, ``1e4`` allowed."""
    try:
        value = float(text)
    except ValueError:
        value = np.nan
    if not (np.isfinite(value) and value == round(value) and value >= 1):
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number such as 3000 "
                                         "or 1e4")
    return int(value)


def run_spec(text):
    """``case:method[:essential[:stabilisation]]``, e.g. ``terzaghi:efg:nitsche``, as a
    tuple (EFG's essential conditions and stabilisation None where not given)."""
    parts = text.split(":")
    if not 2 <= len(parts) <= 4 or not all(parts):
        raise argparse.ArgumentTypeError(f"{text!r}: use case:method[:essential"
                                         "[:stabilisation]], e.g. terzaghi:efg:nitsche")
    return tuple(parts + [None] * (4 - len(parts)))


def parser(doc, overrides=False):
    """An argument parser described by a script's module docstring (its first line);
    with ``overrides``, ``--set KEY=VALUE`` (repeatable) for the case overrides of its
    whole runs (``args.overrides``)."""
    made = argparse.ArgumentParser(description=doc.strip().splitlines()[0])
    if overrides:
        made.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                          dest="overrides", help="case override of every whole run, e.g. "
                          "time.end=0.4 (repeatable)")
    return made


@contextmanager
def parsed(made, argv):
    """The arguments of ``argv`` (None: the command line); bad input inside the block
    (an :class:`soilwater.errors.InputError`, e.g. a bad ``--set``) ends the script with
    one line, as argparse's own errors do."""
    args = made.parse_args(argv)
    try:
        yield args
    except InputError as err:
        made.exit(2, f"{made.prog}: error: {err}\n")


def case_of(spec, overrides=()):
    """The case of a :func:`run_spec` with ``overrides``, and its method."""
    name, method, essential, stabilisation = spec
    efg = [f'efg.essential="{essential}"'] if essential else []
    efg += [f'efg.stabilisation="{stabilisation}"'] if stabilisation else []
    return load_case(name, *efg, overrides=overrides), method


@contextmanager
def scoped(owner, name, value):
    """``owner.name`` (a module constant or a class attribute) set to ``value`` inside the
    ``with`` block and restored after: only for a knob the library takes no argument
    for."""
    kept = getattr(owner, name)
    setattr(owner, name, value)
    try:
        yield
    finally:
        setattr(owner, name, kept)


def _parts(case, method):
    """``(model, initial state, system, finish, row, snapshot)`` of the solver of
    ``method``: ``system(model, state, t0, t1, timings)`` builds a step's Newton system
    (and its discretisation), ``finish(model, system, disc, t1, timings)`` the state after
    it, as :mod:`soilwater.efg.solver` and :mod:`soilwater.fem.solver` do."""
    if method == "efg":
        model = EFGModel.build(case)
        return (model, efg._initial_points(model), _efg_system, _efg_finish,
                efg._history_row, efg._snapshot)
    model = FEMModel.build(case, method)
    return (model, fem._initial_state(model), _fem_system, _fem_finish, fem._history_row,
            fem._snapshot)


def _efg_system(model, points, t0, t1, timings, load=None):
    disc = discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                      timings, points.cells)
    return EFGSystem(model, points, disc, t0, t1, timings, load), disc


def _efg_finish(model, system, disc, t1, timings, load=None):
    done = system.finish()
    with timed(timings, "cells_s"):
        done.cells = background_cells(model, done.nodes)
    done.rcond = min_rcond(disc)
    if model.case.diagnostics.uniqueness:
        done.uniqueness = efg._uniqueness(model, disc, system.domain_tangent(), system.n)
    return done


def _fem_system(model, current, t0, t1, timings, load=None):
    disc = fem_discretise(model, current.topology, current.vertices, t1, timings, load)
    return FEMSystem(model, current, disc, t0, t1, timings, load), disc


def _fem_finish(model, system, disc, t1, timings, load=None):
    return remesh(model, system.finish(), t1, timings, load)


def solve(case, method, layout=None, system=None, on_step=None, snapshots=None):
    """Run ``case`` with ``method`` (``"efg"`` or an FEM pair), as
    :func:`soilwater.efg.solver.solve` and :func:`soilwater.fem.solver.solve` do; with no
    argument but those, it is their run.

    Parameters
    ----------
    layout : callable, optional
        ``layout(Layout) -> Layout``: the layout each step's tangents are solved with,
        from the one the discretisation chose (e.g. ``partial(dataclasses.replace,
        smoother="schwarz")``).
    system : callable, optional
        ``system(newton_system) -> object``: what Newton iterates on (``residual``,
        ``tangent``, ``layout``, ``advance``), e.g. a tracer around the step's system.
    on_step : callable, optional
        ``on_step(model, state, t0, t1)`` before each step; it may raise to end the run.
    snapshots : list, optional
        Every snapshot the run takes is appended to it, those of a run that fails too.

    Returns
    -------
    soilwater.results.Result
        A composed run's summary holds the march's and Newton's counts and the timers,
        not the solver's own entries (penalty factors, element counts).
    """
    if all(given is None for given in (layout, system, on_step, snapshots)):
        return _library_solve(case, method)
    model, state, build, finish, row, snapshot = _parts(case, method)

    def step(current, t0, t1, stats, load):
        if on_step is not None:
            on_step(model, current, t0, t1)
        newton_system, disc = build(model, current, t0, t1, stats["timings"], load)
        if layout is not None:
            newton_system.layout = layout(newton_system.layout)
        iterations, residual = newton(newton_system if system is None
                                      else system(newton_system), stats)
        return (finish(model, newton_system, disc, t1, stats["timings"], load), iterations,
                residual)

    def kept(current, t):
        taken = snapshot(model, current, t)
        if snapshots is not None:
            snapshots.append(taken)
        return taken

    return run(case, method, {}, state, step, partial(row, model), kept, {},
               progress=False)


def _library_solve(case, method):
    if method == "efg":
        return efg.solve(case, progress=False)
    return fem.solve(case, method, progress=False)


def first_system(case, method="efg"):
    """The Newton system of the first step of ``case`` run with ``method``, and the
    timings its construction added to."""
    model, state, build, *_ = _parts(case, method)
    t0, t1 = case.times()[:2]
    timings = dict.fromkeys(TIMERS, 0.0)
    return build(model, state, t0, t1, timings)[0], timings


def first_tangent(nodes, krylov=False, method="efg"):
    """The first Newton tangent of one bench step (:func:`compression`, Cam-clay; EFG's
    ``krylov``: Nitsche's conditions and the perturbation stabilisation) of ``method``,
    the one Newton factorises first, and its layout."""
    system, _ = first_system(compression(nodes, krylov=krylov), method)
    system.residual()                       # the material's tangent at the iterate
    return system.tangent(), system.layout


def scaled_tangent(K, precondition, unknowns):
    """The tangent ``K`` on the first ``unknowns`` unknowns of the order of the Krylov
    ``precondition`` (:class:`soilwater.linalg.krylov.Krylov`), rows scaled as it scales
    them."""
    permuted = _permuted(sp.csr_matrix(K), precondition.order)
    return sp.csr_matrix(sp.diags(precondition.row) @ permuted)[:unknowns, :unknowns]


def peak_mb():
    """The process's peak resident memory [MB = 10^6 bytes] (Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e6


def step_row(result, **labels):
    """The ``labels`` and :data:`STEP` of a one-step ``result`` (times [s], counts) with
    the process's peak memory ``peak_mb``."""
    summary = result.summary
    values = {key: summary["timings"][name] if name.endswith("_s") else summary[name]
              for key, name in STEP.items()}
    return {**labels, **values, "peak_mb": peak_mb()}


def bench_step(method, nodes, solver, layout=None):
    """One step of the bench case as the Krylov sizes run it (:func:`compression`,
    Cam-clay, EFG with Nitsche's conditions and the perturbation) with ``method`` on the
    back-end ``solver``, its tangents solved with ``layout`` (:func:`solve`): its
    :func:`step_row`."""
    case = compression(nodes, krylov=True)
    with linear_solver(solver):
        result = solve(case, method, layout=layout)
    return step_row(result, method=method, nodes=len(case.nodes()), solver=solver)


def printed(label, row, keys, status="ok", digits=2):
    """Print ``label``, ``status`` and the ``keys`` of ``row`` (rounded), or ``row`` as
    it came back when the run did not finish."""
    shown = ({k: round(float(row[k]), digits) for k in keys} if status == "ok" else row)
    print(label, status, shown, flush=True)


def whole_run(label, case, method, layout=None):
    """Run ``case`` and print its time and counts; the row (``failed``: the error, or
    None), with its history."""
    tic = time.perf_counter()
    try:
        result = solve(case, method, layout=layout)
    except ConvergenceError as err:
        print(f"{label}: failed after {time.perf_counter() - tic:.1f} s: {err}", flush=True)
        return {"label": label, "failed": str(err), "history": None}
    s = result.summary
    row = {"label": label, "failed": None, "seconds": time.perf_counter() - tic,
           "newton": s["newton_iterations"], "factorisations": s["factorisations"],
           "single": s["single_factorisations"], "fgmres": s["linear_iterations"],
           "cutbacks": s["cutbacks"], "history": result.history}
    print(f"{label}: {row['seconds']:.1f} s, Newton {row['newton']}, factorisations "
          f"{row['factorisations']} ({row['single']} single), FGMRES {row['fgmres']}, "
          f"cut-backs {row['cutbacks']}", flush=True)
    return row


def compare_runs(runs, variants, overrides=()):
    """Each of ``runs`` (:func:`run_spec` tuples) under each of the two ``variants``
    (name: ``(linear solver, layout)``, as :func:`solve` takes them), printed
    (:func:`whole_run`); when both complete, their :func:`agreement`, printed.

    Returns
    -------
    list of dict
        The rows of :func:`whole_run` with ``run`` and ``variant``; a row per pair that
        completed, ``variant`` ``"agreement"``, with the differences.
    """
    rows = []
    for spec in runs:
        case, method = case_of(spec, overrides)
        label = " ".join(str(part) for part in spec if part)
        done = []
        for variant, (solver, layout) in variants.items():
            with linear_solver(solver):
                row = whole_run(f"{label} {variant}", case, method, layout)
            rows.append({**row, "run": spec, "variant": variant})
            done += [row["history"]] if row["failed"] is None else []
        if len(done) == 2:
            differences = agreement(*done)
            print("  agreement", differences, flush=True)
            rows.append({"run": spec, "variant": "agreement", **differences})
    return rows


def agreement(a, b):
    """The largest difference of p, q and the settlement between two histories, relative
    to the largest magnitude of each in ``a``."""
    return {c: float(np.abs(a[c] - b[c]).max() / max(np.abs(a[c]).max(), 1e-30))
            for c in ("p", "q", "settlement")}


def replaced(**changes):
    """``layout -> dataclasses.replace(layout, **changes)``, for :func:`solve`."""
    return partial(dataclasses.replace, **changes)
