"""The runs of ``make bench``: one coupled step per forked child, and shape functions alone.

Each run of :func:`soilwater.studies.bench.plan.plan` is one step in its own forked
child process (:func:`in_child`), so its peak resident memory is its own and a run that
is stopped, killed or fails is a row with its status. Times are the solvers' phase
timers [s], memory in MB = 10^6 bytes.
"""

import multiprocessing
import multiprocessing.connection
import resource
import time

import numpy as np
import pandas as pd
import skfem

from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.quadrature import delaunay_cells
from soilwater.efg.settings import DEFAULT_SCALE
from soilwater.linalg.backends import backend, linear_solver
from soilwater.studies.bench.plan import (MATERIALS, METHODS, SIZES, compression, direct,
                                          plan, usable)
from soilwater.studies.harness.machine import best_of

#: Phase: its timer in ``summary["timings"]`` (:data:`soilwater.nonlinear.history.TIMERS`).
PHASES = {"shape functions": "shape_functions_s", "cells": "cells_s",
          "assembly": "assembly_s", "solve": "solve_s", "constitutive": "material_s",
          "step": "total_s"}
#: Columns of a row of :func:`steps`, in order.
COLUMNS = ("method", "material", "nodes", "solver", "efg", "status", "dofs",
           "iterations", "linear_iterations", "factorisations", "symmetric_factorisations",
           "single_factorisations",
           "perturbed_pivots", "factor_flops", *PHASES, "factor_gflops_lb", "peak_mb",
           "kb_per_node", "wall_s", "limit_s")


def one_step(method, nodes, material, solver=None, ready=None):
    """Run one step under the linear back-end ``solver`` (None: :func:`backend`'s), EFG
    as the Krylov back-end needs it if ``ready`` (None: on ``"krylov"`` only;
    :func:`compression`).

    Returns
    -------
    dict
        The :data:`COLUMNS` but ``factor_gflops_lb``: phase times [s]; counts (Newton
        ``iterations`` summed over the step; ``linear_iterations``, the Krylov
        iterations, and ``factor_flops``, the floating-point operations of all the run's
        factorisations, where the back-end reports them in ``result.summary``, else
        NaN); ``peak_mb``, the process's peak resident memory [MB = 10^6 bytes] and
        ``kb_per_node`` [10^3 bytes per node]. A count the back-end does not report
        (an iterative one need not factorise) is NaN.
    """
    import soilwater.efg.solver
    import soilwater.fem.solver

    with linear_solver(solver):
        name = backend() if solver is None else solver
        case = compression(nodes, material, krylov=name == "krylov" if ready is None
                           else ready)
        tic = time.perf_counter()
        result = (soilwater.efg.solver.solve(case, progress=False) if method == "efg"
                  else soilwater.fem.solver.solve(case, method, progress=False))
        wall = time.perf_counter() - tic
    summary = result.summary
    row = {"method": method, "material": material, "nodes": len(case.nodes()),
           "solver": name,
           "efg": _conditions(case, method),
           "status": "ok", "dofs": summary["dofs"],
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


def _conditions(case, method):
    """The ``efg`` column: EFG's essential conditions and stabilisation, "-" for FEM."""
    return f"{case.efg.essential}, {case.efg.stabilisation}" if method == "efg" else "-"


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


def steps(sizes=SIZES, methods=METHODS, materials=MATERIALS, limit=None, progress=print):
    """One step of every run of :func:`plan`, each in its own child (:func:`in_child`).

    A run still going after its limit (``limit`` seconds, or :func:`time_limit` when
    None) is stopped; one whose child dies, raises, or whose back-end is not available
    here (:func:`usable`) is kept too, as a row of NaN times with its ``status``, so one
    pathological run cannot hold the benchmark. ``factor_gflops_lb`` = ``factor_flops``
    / solve time [GF/s]: the solve time includes the analysis and the back-solves, so it
    is a lower bound of the factorisation's rate.

    Returns
    -------
    pandas.DataFrame
        One row per run, the :data:`COLUMNS` (``limit_s``: the run's time limit [s]).
    """
    runs = plan(sizes, methods, materials)
    for method in methods:                       # compile numba kernels, load MKL
        one_step(method, 200, "cam-clay", direct())
    if any(run[3] == "krylov" for run in runs) and usable("krylov"):
        one_step(methods[0], 200, "cam-clay", "krylov")          # load pyamg
    rows = []
    for nodes, material, method, solver, seconds, ready in runs:
        seconds = seconds if limit is None else limit
        if usable(solver):
            row, status = in_child(one_step, method, nodes, material, solver, ready,
                                   timeout=seconds)
        else:
            row, status = None, f"{solver} not available"
        if status != "ok":
            case = compression(nodes, krylov=ready)
            row = {"method": method, "material": material, "nodes": len(case.nodes()),
                   "solver": solver, "efg": _conditions(case, method), "status": status,
                   **(row or {})}
            if row.get("peak_mb") is not None:
                row["kb_per_node"] = row["peak_mb"] * 1e3 / row["nodes"]
                status += f", peak {row['peak_mb']:.0f} MB"
            progress(f"{method:13s} {material:8s} {row['nodes']:7d} nodes, {solver:7s}: "
                     f"{status}")
        else:
            progress(f"{method:13s} {material:8s} {row['nodes']:7d} nodes, {solver:7s}: "
                     f"step {row['step']:8.2f} s, {row['iterations']} iterations, peak "
                     f"{row['peak_mb']:6.0f} MB ({row['kb_per_node']:.0f} kB/node)")
        rows.append({**row, "limit_s": seconds})
    table = pd.DataFrame(rows).reindex(columns=list(COLUMNS))
    table["factor_gflops_lb"] = table.factor_flops / table.solve / 1e9
    return table


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
