"""The runs of ``make bench``: one coupled step per forked child, and shape functions alone.

Each run of :func:`soilwater.studies.bench.plan.plan` is one step in its own forked
child process (:func:`in_child`), so its peak resident memory is its own and a run that
is stopped, killed or fails is a row with its status. Times are the solvers' phase
timers [s], memory in MB = 10^6 bytes. The size of the step's discretisation
(:func:`counts`: integration points per node, stored tangent entries per row) is read in
a child of its own, once per size, method and scheme.
"""

import multiprocessing
import multiprocessing.connection
import resource
import time

import numpy as np
import pandas as pd
import scipy.sparse as sp
import skfem

from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.quadrature import delaunay_cells
from soilwater.efg.settings import DEFAULT_SCALE
from soilwater.linalg.backends import backend, linear_solver
from soilwater.nonlinear.history import TIMERS
from soilwater.studies.bench.plan import (MATERIALS, METHODS, SCHEMES, SIZES, compression,
                                          direct, plan, usable)
from soilwater.studies.harness.machine import best_of

#: Phase: its timer in ``summary["timings"]`` (:data:`soilwater.nonlinear.history.TIMERS`).
PHASES = {"shape functions": "shape_functions_s", "cells": "cells_s",
          "assembly": "assembly_s", "solve": "solve_s", "constitutive": "material_s",
          "step": "total_s"}
#: The size of a step's discretisation (:func:`counts`).
COUNTS = ("points_per_node", "entries_per_row")
#: Columns of a row of :func:`steps`, in order.
COLUMNS = ("method", "integration", "material", "nodes", "solver", "efg", "status", "dofs",
           *COUNTS, "iterations", "linear_iterations", "factorisations",
           "symmetric_factorisations", "single_factorisations",
           "perturbed_pivots", "factor_flops", *PHASES, "factor_gflops_lb", "peak_mb",
           "kb_per_node", "wall_s", "limit_s")


def one_step(method, nodes, material, solver=None, ready=None, integration="paper"):
    """Run one step under the linear back-end ``solver`` (None: :func:`backend`'s), EFG
    with the scheme ``integration`` and as the Krylov back-end needs it if ``ready``
    (None: on ``"krylov"`` only; :func:`compression`).

    Returns
    -------
    dict
        The :data:`COLUMNS` but :data:`COUNTS` and ``factor_gflops_lb``: phase times [s];
        counts (Newton ``iterations`` summed over the step; ``linear_iterations``, the
        Krylov iterations, and ``factor_flops``, the floating-point operations of all the
        run's factorisations, where the back-end reports them in ``result.summary``, else
        NaN); ``peak_mb``, the process's peak resident memory [MB = 10^6 bytes] and
        ``kb_per_node`` [10^3 bytes per node]. A count the back-end does not report
        (an iterative one need not factorise) is NaN.
    """
    import soilwater.efg.solver
    import soilwater.fem.solver

    with linear_solver(solver):
        name = backend() if solver is None else solver
        case = compression(nodes, material, krylov=name == "krylov" if ready is None
                           else ready, integration=integration)
        tic = time.perf_counter()
        result = (soilwater.efg.solver.solve(case, progress=False) if method == "efg"
                  else soilwater.fem.solver.solve(case, method, progress=False))
        wall = time.perf_counter() - tic
    summary = result.summary
    row = {**_names(case, method), "material": material, "nodes": len(case.nodes()),
           "solver": name, "status": "ok", "dofs": summary["dofs"],
           "iterations": int(result.history.iterations.sum()),
           "linear_iterations": float(summary.get("linear_iterations", np.nan)),
           "factorisations": summary.get("factorisations", np.nan),
           "symmetric_factorisations": summary.get("symmetric_factorisations", np.nan),
           "single_factorisations": summary.get("single_factorisations", np.nan),
           "perturbed_pivots": summary.get("perturbed_pivots", np.nan),
           "factor_flops": float(summary.get("factor_flops", np.nan)), "wall_s": wall}
    for phase, timer in PHASES.items():
        row[phase] = summary["timings"][timer]
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0   # bytes (Linux)
    row["peak_mb"], row["kb_per_node"] = peak / 1e6, peak / 1e3 / row["nodes"]
    return row


def _names(case, method):
    """The ``method``, ``integration`` and ``efg`` columns: EFG's scheme, and its
    essential conditions and stabilisation; "-" for FEM."""
    efg = method == "efg"
    return {"method": method, "integration": case.efg.integration if efg else "-",
            "efg": f"{case.efg.essential}, {case.efg.stabilisation}" if efg else "-"}


def counts(method, nodes, integration="paper", ready=False):
    """The size of the step's discretisation, read off the solvers' own step objects.

    The step of :func:`one_step` is the first of its case, on the initial configuration:
    its discretisation and first Newton tangent are built here as the solver builds them
    (:func:`soilwater.efg.discretisation.discretise` on the cells of the scheme, or
    :func:`soilwater.fem.system.discretise`, then the method's ``System``), without
    solving.

    Returns
    -------
    dict
        ``points_per_node``, the domain's integration points (the material points:
        Gauss points of the cells, the nodes for ``nodal``, the elements' quadrature
        points for FEM) per node of the grid; ``entries_per_row``, the stored entries
        of the first Newton tangent (``nnz``, explicit zeros of the pattern included)
        over its rows, the unknowns the linear solver gets (FEM: after eliminating the
        prescribed ones; a plate or pressure pin borders it).
    """
    case = compression(nodes, krylov=ready, integration=integration)
    timings = dict.fromkeys(TIMERS, 0.0)
    t0, t1 = case.times()[:2]
    if method == "efg":
        from soilwater.efg import solver
        from soilwater.efg.discretisation import discretise
        from soilwater.efg.system import System

        model = solver.Model.build(case)
        current = solver._initial_points(model)
        disc = discretise(model, current.nodes, np.vstack([current.nodes, current.probes]),
                          timings, current.cells)
        points = disc.w.size
    else:
        from soilwater.fem import solver
        from soilwater.fem.system import System, discretise

        model = solver.Model.build(case, method)
        current = solver._initial_state(model)
        disc = discretise(model, current.topology, current.vertices, t1, timings)
        points = disc.dx.size
    system = System(model, current, disc, t0, t1, timings)
    system.residual()
    K = sp.csr_matrix(system.tangent())
    return {"points_per_node": points / len(case.nodes()),
            "entries_per_row": K.nnz / K.shape[0]}


def in_child(fn, *args, timeout=None):
    """``fn(*args)`` in a forked child process, so its peak memory is its own.

    Parameters
    ----------
    fn : callable
        Called in the child; its value is sent back through a pipe (it must pickle).
    timeout : float, optional
        Seconds after which a child that has not answered is killed (None: no limit).

    Returns
    -------
    value : object or None
        ``fn(*args)``; for a child stopped after ``timeout``, ``{"peak_mb": M}``, its
        peak resident memory until then [MB = 10^6 bytes] (Linux ``/proc``; None where
        that cannot be read); None when it did not come back otherwise.
    status : str
        ``"ok"``; ``"stopped at T s"`` (killed after ``timeout``); ``"died (signal N)"``
        (killed by a signal: SIGKILL from the kernel's out-of-memory killer, a crash in
        a native library) or ``"died (exit N)"`` without an answer; ``"failed: ..."``
        (``fn`` raised; its first line). The parent waits on the pipe and the child's
        sentinel together, so a dead child is noticed at once, not after ``timeout``.

    Examples
    --------
    >>> in_child(pow, 2, 10)
    (1024, 'ok')
    >>> import os
    >>> in_child(os._exit, 3)
    (None, 'died (exit 3)')
    """
    context = multiprocessing.get_context("fork")
    reader, writer = context.Pipe(duplex=False)

    def answer():
        try:
            message = (fn(*args), "ok")
        except Exception as err:               # the run's own failure, told as a status
            lines = str(err).strip().splitlines() or [""]
            message = (None, f"failed: {type(err).__name__}: {lines[0]}".rstrip(": "))
        writer.send(message)

    child = context.Process(target=answer)
    child.start()
    writer.close()                             # the child holds the only writing end
    try:
        ready = multiprocessing.connection.wait([reader, child.sentinel], timeout)
        if reader in ready or reader.poll():
            try:
                return reader.recv()
            except (EOFError, OSError):        # died while sending, or before
                pass
        elif not ready:
            return {"peak_mb": _peak_mb(child.pid)}, f"stopped at {timeout:g} s"
        child.join()
        code = child.exitcode
        return None, (f"died (signal {-code})" if code < 0 else f"died (exit {code})")
    finally:
        child.kill()
        child.join()
        reader.close()


def _peak_mb(pid):
    """Peak resident memory of the live process ``pid`` [MB] (``VmHWM`` in Linux's
    ``/proc/pid/status``), or None where it cannot be read."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            kb = next(line.split()[1] for line in fh if line.startswith("VmHWM:"))
    except (OSError, StopIteration):
        return None
    return float(kb) * 1024 / 1e6


def steps(sizes=SIZES, methods=METHODS, materials=MATERIALS, limit=None, progress=print,
          schemes=SCHEMES):
    """One step of every run of :func:`plan`, each in its own child (:func:`in_child`).

    A run still going after its limit (``limit`` seconds, or :func:`time_limit` when
    None) is stopped; one whose child dies, raises, or whose back-end is not available
    here (:func:`usable`) is kept too, as a row of NaN times with its ``status``, so one
    pathological run cannot hold the benchmark; one the plan skips is a row whose
    status is ``"skipped: "`` and the plan's reason. ``factor_gflops_lb`` =
    ``factor_flops`` / solve time [GF/s]: the solve time includes the analysis and the
    back-solves, so it is a lower bound of the factorisation's rate. The :data:`COUNTS`
    are :func:`counts`', in a child of their own under the same limit, once per size,
    method and scheme (NaN where that child did not answer).

    Returns
    -------
    pandas.DataFrame
        One row per run, the :data:`COLUMNS` (``limit_s``: the run's time limit [s]).
    """
    runs = plan(sizes, methods, materials, schemes)
    for method in methods:                       # compile numba kernels, load MKL
        for scheme in (schemes if method == "efg" else ("paper",)):
            one_step(method, 200, "cam-clay", direct(), integration=scheme)
    if any(run.solver == "krylov" for run in runs) and usable("krylov"):
        one_step(methods[0], 200, "cam-clay", "krylov")          # load pyamg
    rows, counted = [], {}
    for run in runs:
        seconds = run.limit if limit is None else limit
        row, status = None, f"skipped: {run.skip}"
        if not run.skip and usable(run.solver):
            row, status = in_child(one_step, run.method, run.nodes, run.material, run.solver,
                                   run.ready, run.scheme, timeout=seconds)
        elif not run.skip:
            status = f"{run.solver} not available"
        key = (run.nodes, run.method, run.integration)
        if key not in counted and not run.skip:
            counted[key], _ = in_child(counts, run.method, run.nodes, run.scheme,
                                        run.ready, timeout=seconds)
        if status != "ok":
            case = compression(run.nodes, krylov=run.ready, integration=run.scheme)
            row = {**_names(case, run.method), "material": run.material,
                   "nodes": len(case.nodes()), "solver": run.solver, "status": status,
                   **(row or {})}
            if row.get("peak_mb") is not None:
                row["kb_per_node"] = row["peak_mb"] * 1e3 / row["nodes"]
                status += f", peak {row['peak_mb']:.0f} MB"
            progress(f"{_label(row)}: {status}")
        else:
            progress(f"{_label(row)}: step {row['step']:8.2f} s, {row['iterations']} "
                     f"iterations, peak {row['peak_mb']:6.0f} MB "
                     f"({row['kb_per_node']:.0f} kB/node)")
        rows.append({**row, **(counted.get(key) or {}), "limit_s": seconds})
    table = pd.DataFrame(rows).reindex(columns=list(COLUMNS))
    table["factor_gflops_lb"] = table.factor_flops / table.solve / 1e9
    return table


def _label(row):
    """Method, scheme, material, nodes and solver of a row, for the progress lines."""
    return (f"{row['method']:13s} {row['integration']:5s} {row['material']:8s} "
            f"{row['nodes']:7d} nodes, {row['solver']:7s}")


def shape_functions(sizes=SIZES, weight="quartic", scale=DEFAULT_SCALE):
    """MLS values + gradients against ``CellBasis`` construction at the same points.

    Returns
    -------
    pandas.DataFrame
        Per size: nodes, quadrature points, EFG time and P1 / P2 basis times [s].
    """
    rows = []
    for nodes in sizes:
        case = compression(nodes)
        x = case.nodes()
        quad = delaunay_cells(x, x[case.boundary_loop()], order=2)
        mesh = skfem.MeshTri(np.ascontiguousarray(x.T),
                             np.ascontiguousarray(quad.triangles.T))
        row = {"nodes": len(x), "points": len(quad.weights),
               "efg_s": best_of(lambda: ShapeFunctions.build(x, quad.points, weight, scale))}
        for name, element in (("P1", skfem.ElementTriP1()), ("P2", skfem.ElementTriP2())):
            row[f"{name}_s"] = best_of(
                lambda element=element: skfem.CellBasis(mesh, element, intorder=2))
        rows.append(row)
    return pd.DataFrame(rows, columns=["nodes", "points", "efg_s", "P1_s", "P2_s"])
