"""``make bench``: speed and scale as ratios against scikit-fem in the same run.

Three measurements, all on this machine in one command (never timed tests):

1. **dgemm**, the yardstick of the factorisation's rate (issue 17): ``C = A B`` of two
   3000 x 3000 float64 matrices through NumPy's BLAS and through MKL's ``cblas_dgemm``
   (the library PARDISO runs on), GF/s = 2 n^3 / best time. OpenBLAS reads
   ``OPENBLAS_CORETYPE`` and ``OPENBLAS_L2_SIZE`` when NumPy loads it, so ``make bench``
   unsets both for this command only (``env -u`` in the Makefile); the run records the
   kernel it got.
2. **One coupled step** of the unconfined-compression geometry (grid layout, 3 x 4 m, one
   step of 0.2 % axial strain) at about 10^3, 3 x 10^3, ..., 10^6 nodes (:data:`SIZES`)
   for ``efg``, ``fem-p1p1``, ``fem-th`` and ``fem-p1p1-stab`` on the same vertices, with
   the Cam-clay skeleton of the case and with a linear elastic one. The rule that bounds
   the whole run (28 minutes on 2 cores, the four large runs at most 4 x 900 s of it):
   from 3 x 10^5 nodes (:data:`LARGE_FROM`) only ``efg`` and ``fem-p1p1-stab`` with
   Cam-clay run, and a run is stopped after 900 s there, 240 s below
   (:func:`time_limit`). The linear solver is chosen by size (:func:`solver_for`): the direct
   one, PARDISO where ``pypardiso`` is installed, else SuperLU, below 3 x 10^5 nodes
   (:data:`KRYLOV_FROM`), and ``soilwater.linalg.backends.linear_solver("krylov")`` from there, where
   EFG runs with Nitsche's conditions and the perturbation stabilisation, as the Krylov
   back-end needs (:func:`compression`; the ``efg`` column says which). From 10^4 nodes
   (:data:`BOTH_FROM`) EFG and ``fem-p1p1-stab`` also run on Krylov below 3 x 10^5,
   with either skeleton, so issue 17's targets take each on its faster solver, measured,
   and on PARDISO EFG runs a second time with Nitsche's conditions and the perturbation:
   PARDISO factorises such a tangent (and fem-th's) in single precision
   (``soilwater.linalg.backends.Layout.single``; the ``single_factorisations`` column). The
   solvers' own phase timers (:data:`soilwater.nonlinear.coupling.TIMERS`) give shape functions (FEM:
   basis construction), background cells (FEM: moving the mesh), assembly of the
   tangent, linear solve (analysis, factorisations and back-substitutions), constitutive
   update, and the whole step; each row adds the solver, Newton and Krylov iterations,
   the flops of the factorisations and their rate (a lower bound: flops / solve time),
   and peak memory per node. Each run is a forked child process, so its peak resident
   memory is its own; a run stopped, killed (out of memory) or failed, or whose solver
   is not available here, is a row with its status.
3. **Shape functions alone** up to 10^5 nodes: MLS values and gradients against
   scikit-fem's ``CellBasis`` construction (P1 and P2) at the same quadrature points
   (3 per triangle of the Delaunay triangulation of the nodes).

Writes ``reports/bench.md`` (targets of issues 17 and 7, factorisation rate against
dgemm, ratios, growth exponents, memory), ``reports/tables/bench.csv`` (every run) and
``reports/figures/bench.png``.
"""

import ctypes
import dataclasses
import multiprocessing
import multiprocessing.connection
import os
import platform
import resource
import time

import numpy as np
import pandas as pd
import skfem

from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.quadrature import delaunay_cells
from soilwater.linalg import backends as linear
from soilwater.errors import InputError
from soilwater.linalg.backends import available, backend, linear_solver
from soilwater.case.loader import load_case
from soilwater.efg.settings import DEFAULT_SCALE

#: Requested node counts of the default run.
SIZES = (1_000, 3_000, 10_000, 30_000, 100_000, 300_000, 1_000_000)
#: Smallest node count ``--sizes`` accepts (the grid has at least 10 x 13 nodes).
MIN_SIZE = 100
METHODS = ("efg", "fem-p1p1", "fem-th", "fem-p1p1-stab")
MATERIALS = ("cam-clay", "elastic")
#: From this many (requested) nodes only :data:`LARGE_METHODS` with
#: :data:`LARGE_MATERIALS` run, under :data:`LARGE_TIME_LIMIT`: issue 17's comparison,
#: within the run time of the module docstring.
LARGE_FROM = 300_000
LARGE_METHODS = ("efg", "fem-p1p1-stab")
LARGE_MATERIALS = ("cam-clay",)
#: From this many (requested) nodes the tangents are solved by the iterative back-end
#: ``soilwater.linalg.backends.linear_solver("krylov")``; below, by the direct one (:func:`direct`):
#: where the default back-end turns iterative (:data:`soilwater.linalg.backends.KRYLOV_FROM` unknowns,
#: three per node).
KRYLOV_FROM = linear.KRYLOV_FROM // 3
#: From this many (requested) nodes up to :data:`KRYLOV_FROM`, :data:`LARGE_METHODS` run
#: on both back-ends, with every material: issue 17's targets take each method on its
#: faster one, measured, and the Krylov path's growth spans 10^4 to 10^6.
BOTH_FROM = 10_000
#: Seconds after which one run below :data:`LARGE_FROM` nodes is stopped (recorded, not
#: timed); :data:`LARGE_TIME_LIMIT` from there.
TIME_LIMIT = 240.0
LARGE_TIME_LIMIT = 900.0
#: Largest (requested) size of the shape-function comparison (issue 7's); beyond it the
#: MLS build would take minutes and gigabytes in the bench's own process.
SHAPES_UP_TO = 100_000
#: Order of the dgemm of :func:`dgemm` (3 x 72 MB of matrices, about a second).
DGEMM_N = 3000
#: OpenBLAS reads these when it loads and picks its kernels and blocking from them;
#: ``make bench`` runs with both unset (``env -u``), so NumPy's BLAS uses the kernels of
#: this CPU. :func:`numpy_blas` records what the run saw.
OPENBLAS_VARIABLES = ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE")
#: Linear elastic skeleton of the elastic runs (kPa), at the case's p'0.
ELASTIC = (("model", "elastic"), ("E", 200.0), ("nu", 0.3), ("p0", 3.0))
#: Phase: its timer in ``summary["timings"]`` (:data:`soilwater.nonlinear.coupling.TIMERS`).
PHASES = {"shape functions": "shape_functions_s", "cells": "cells_s",
          "assembly": "assembly_s", "solve": "solve_s", "constitutive": "material_s",
          "step": "total_s"}


def parse_sizes(text):
    """The node counts of ``--sizes``: comma-separated whole numbers, ``1e6`` allowed.

    Raises
    ------
    InputError
        One line naming the entry that is not a node count of at least :data:`MIN_SIZE`.

    Examples
    --------
    >>> parse_sizes("1000, 3e5,1e6")
    [1000, 300000, 1000000]
    """
    sizes = []
    for part in text.split(","):
        try:
            value = float(part)
        except ValueError:
            value = np.nan
        if not (np.isfinite(value) and value == round(value) and value >= MIN_SIZE):
            raise InputError(f"--sizes {text!r}: {part.strip()!r} is not a node count; use "
                             f"whole numbers of at least {MIN_SIZE}, e.g. 1000,3000,1e5")
        sizes.append(int(value))
    return sizes


def compression(nodes, material="cam-clay", krylov=False):
    """The benchmark case: unconfined compression on a grid of about ``nodes`` nodes.

    Parameters
    ----------
    nodes : int
        Wanted node count; the grid is (3k + 1) x (4k + 1) with square spacing.
    material : {"cam-clay", "elastic"}
        The case's Cam-clay (Table 1) or the linear elastic :data:`ELASTIC`.
    krylov : bool
        EFG as the Krylov back-end needs it: Nitsche's essential conditions (a penalty's
        diagonal spans 1e6, so a small residual says nothing of the error) and the
        perturbation stabilisation (the case is undrained: without it the pressure Schur
        complement of equal-order MLS is near singular and FGMRES stalls).

    Examples
    --------
    >>> len(compression(1000).nodes())
    1036
    """
    k = max(1, round(np.sqrt(nodes / 12)))
    case = load_case("unconfined-compression", [
        f"discretisation.nx={3 * k + 1}", f"discretisation.ny={4 * k + 1}",
        "discretisation.layout=grid", "time.steps=1", "time.end=0.2",
        *(['efg.essential="nitsche"', 'efg.stabilisation="perturbation"'] if krylov
          else [])])
    if material == "elastic":
        case = dataclasses.replace(case, material_spec=ELASTIC)
    return case


def direct():
    """The direct back-end of the bench: ``"pardiso"`` where ``pypardiso`` imports, else
    ``"superlu"`` (whatever ``SOILWATER_LINEAR_SOLVER`` says)."""
    return "pardiso" if available("pardiso") else "superlu"


def solver_for(nodes):
    """The linear solver of a run of ``nodes`` requested nodes: :func:`direct` below
    :data:`KRYLOV_FROM`, ``"krylov"`` from there.

    Examples
    --------
    >>> solver_for(KRYLOV_FROM)
    'krylov'
    """
    return "krylov" if nodes >= KRYLOV_FROM else direct()


def time_limit(nodes):
    """Seconds after which a run of ``nodes`` requested nodes is stopped."""
    return LARGE_TIME_LIMIT if nodes >= LARGE_FROM else TIME_LIMIT


def usable(solver):
    """True if ``soilwater.linalg.backends.linear_solver(solver)`` accepts the back-end here (a
    back-end it does not know, or PARDISO without pypardiso, raises InputError).

    Examples
    --------
    >>> usable("superlu"), usable("no-such-solver")
    (True, False)
    """
    try:
        with linear_solver(solver):
            return True
    except InputError:
        return False


def plan(sizes=SIZES, methods=METHODS, materials=MATERIALS):
    """The runs of :func:`steps`: ``(nodes, material, method, solver, limit, ready)`` per
    run, sizes in the given order; from :data:`LARGE_FROM` nodes only
    :data:`LARGE_METHODS` with :data:`LARGE_MATERIALS`; from :data:`BOTH_FROM` to
    :data:`KRYLOV_FROM` :data:`LARGE_METHODS` run on the direct back-end and then on
    ``"krylov"``, and on PARDISO EFG runs a second time as the Krylov back-end needs it
    (``ready``, :func:`compression`'s ``krylov``), where PARDISO factorises it in single
    precision (:attr:`soilwater.linalg.backends.Layout.single`). ``ready`` is True for every Krylov
    run.

    Examples
    --------
    >>> [run[:4] for run in plan([1_000_000], ("efg", "fem-th"))]
    [(1000000, 'cam-clay', 'efg', 'krylov')]
    >>> [run[3] for run in plan([BOTH_FROM], ("efg",), ("elastic",))][-1:]
    ['krylov']
    """
    runs = []
    for nodes in sizes:
        for material in materials:
            for method in methods:
                if nodes >= LARGE_FROM and not (method in LARGE_METHODS
                                                and material in LARGE_MATERIALS):
                    continue
                default = solver_for(nodes)
                solvers = [(default, default == "krylov")]
                if method in LARGE_METHODS and BOTH_FROM <= nodes < KRYLOV_FROM:
                    if method == "efg" and direct() == "pardiso":
                        solvers.append(("pardiso", True))
                    solvers.append(("krylov", True))
                runs += [(nodes, material, method, solver, time_limit(nodes), ready)
                         for solver, ready in solvers]
    return runs


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


def best_of(fn, repeat=3):
    """Best wall time [s] of ``repeat`` calls after one warm-up call."""
    fn()
    times = []
    for _ in range(repeat):
        tic = time.perf_counter()
        fn()
        times.append(time.perf_counter() - tic)
    return min(times)


def numpy_blas():
    """One line naming NumPy's BLAS: build name and version, and, read from the loaded
    OpenBLAS, its kernel (core) and threads, with the ``OPENBLAS_*`` variables it read."""
    blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
    text = f"{blas.get('name', 'unknown')} {blas.get('version', '')}".strip()
    library = _loaded("openblas")
    if library is not None:
        core = _call(library, ("scipy_openblas_get_corename64_", "openblas_get_corename64_",
                               "openblas_get_corename"), ctypes.c_char_p)
        threads = _call(library, ("scipy_openblas_get_num_threads64_",
                                  "openblas_get_num_threads64_", "openblas_get_num_threads"),
                        ctypes.c_int)
        text += f", core {core.decode() if core else 'unknown'}, {threads} threads"
    return text + "; " + ", ".join(f"{name} {os.environ.get(name, 'unset')}"
                                   for name in OPENBLAS_VARIABLES)


def _loaded(word, prefer="numpy"):
    """Path of a shared library loaded in this process whose file name has ``word``, one
    whose path has ``prefer`` first (SciPy loads an OpenBLAS of its own); None if none."""
    try:
        with open("/proc/self/maps") as fh:
            paths = [line.split()[-1] for line in fh]
    except OSError:
        return None
    paths = [path for path in paths if word in os.path.basename(path).lower()]
    return next((path for path in paths if prefer in path), paths[0] if paths else None)


def _call(path, names, restype):
    """The first function of ``names`` that the library ``path`` exports, called without
    arguments; None if it exports none."""
    library = ctypes.CDLL(path)
    for name in names:
        function = getattr(library, name, None)
        if function is not None:
            function.restype = restype
            return function()
    return None


def dgemm(n=DGEMM_N, repeat=3):
    """The machine's dense matrix product rate, the yardstick of the factorisation's.

    ``C = A B`` of two ``n x n`` float64 matrices, best of ``repeat`` after a warm-up,
    through NumPy's BLAS and through MKL's ``cblas_dgemm`` (the library PARDISO runs on,
    where ``pypardiso`` is installed), on all the threads each library uses.

    Returns
    -------
    dict
        ``n``; ``numpy_gflops`` and ``mkl_gflops``: ``2 n^3 / t`` [GF/s = 10^9 flop/s]
        (NaN without MKL); ``numpy_blas`` (:func:`numpy_blas`) and ``mkl`` (version and
        threads).

    Examples
    --------
    >>> rates = dgemm(200, repeat=1)
    >>> bool(rates["numpy_gflops"] > 0)
    True
    """
    rng = np.random.default_rng(0)
    a, b = rng.random((n, n)), rng.random((n, n))
    rates = {"n": n, "numpy_gflops": 2.0 * n**3 / best_of(lambda: a @ b, repeat) / 1e9,
             "numpy_blas": numpy_blas(), "mkl_gflops": np.nan, "mkl": "not installed"}
    if available("pardiso"):
        import pypardiso

        mkl = pypardiso.PyPardisoSolver().libmkl            # the library PARDISO calls
        c, double = np.empty((n, n)), ctypes.POINTER(ctypes.c_double)
        row_major, no_transpose = 101, 111                   # CBLAS enumerations

        def product():
            mkl.cblas_dgemm(row_major, no_transpose, no_transpose, n, n, n,
                            ctypes.c_double(1.0), a.ctypes.data_as(double), n,
                            b.ctypes.data_as(double), n, ctypes.c_double(0.0),
                            c.ctypes.data_as(double), n)

        rates["mkl_gflops"] = 2.0 * n**3 / best_of(product, repeat) / 1e9
        if not np.allclose(c[:, :4], a @ b[:, :4]):
            raise RuntimeError("MKL's dgemm through ctypes gave a wrong product")
        version = ctypes.create_string_buffer(256)
        mkl.MKL_Get_Version_String(version, len(version))
        mkl.MKL_Get_Max_Threads.restype = ctypes.c_int
        rates["mkl"] = f"{version.value.decode()}, {mkl.MKL_Get_Max_Threads()} threads"
    return rates


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


def pick(table, method, material, nodes, solver=None):
    """The row of ``method`` and ``material`` at the size ``nodes`` asked for (its grid's
    count within 10 %), on ``solver`` (None: the first such run), or None if there was
    no such run."""
    rows = table[(table.method == method) & (table.material == material)
                 & np.isclose(table.nodes, nodes, rtol=0.1)]
    if solver is not None:
        rows = rows[rows.solver == solver]
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


def ratios(table):
    """EFG / FEM per phase at equal nodes (same grid) on the same linear solver, for each
    material, size, solver and EFG's conditions (``efg``)."""
    rows = []
    for (material, nodes, solver), group in table.groupby(["material", "nodes", "solver"],
                                                          sort=False):
        by = group.drop_duplicates("method").set_index("method")
        for _, efg in group[group.method == "efg"].iterrows():
            for fem in METHODS[1:]:
                if fem not in by.index:
                    continue
                row = {"material": material, "nodes": nodes, "solver": solver,
                       "efg": efg["efg"], "against": fem}
                for phase in PHASES:
                    row[phase] = efg[phase] / by.loc[fem, phase]
                rows.append(row)
    return pd.DataFrame(rows)


def exponents(table):
    """Growth exponent of every phase, per method, material and linear solver, fitted on
    the runs that completed (``from`` and ``to``: the node counts of the fit)."""
    rows = []
    ok = table[table.status == "ok"]
    for (method, material, solver, efg), group in ok.groupby(
            ["method", "material", "solver", "efg"], sort=False):
        row = {"method": method, "material": material, "solver": solver, "efg": efg,
               "from": group.nodes.min(), "to": group.nodes.max()}
        for phase in PHASES:
            row[phase] = exponent(group.nodes, group[phase])
        rows.append(row)
    return pd.DataFrame(rows, columns=["method", "material", "solver", "efg", "from", "to",
                                       *PHASES])


def targets(table, shapes, growth):
    """Issue 7's speed targets: measured value, target and verdict, one row each.

    A "whole step / fem-p1p1" row whose fem-p1p1 run was stopped compares with its time
    limit: an upper bound of the ratio; EFG is taken on fem-p1p1's solver. Assembly per
    tangent and growth exponents are of the direct solver's runs.
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
                             f"{row.nodes} nodes, {int(row.dofs)} DOFs; {row.efg}",
                             row.assembly / row.factorisations / fem, 2.0))
        for nodes in (10_000, 100_000):
            f = pick(table, "fem-p1p1", material, nodes)
            e = None if f is None else pick(table, "efg", material, nodes, f.solver)
            if e is not None:
                stopped = f.status.startswith("stopped")
                rows.append((f"whole step / fem-p1p1 at equal nodes ({material})",
                             f"{e.nodes} nodes" + (f" (fem-p1p1 {f.status}: an upper bound)"
                                                   if stopped else ""),
                             e.step / (f.limit_s if stopped else f.step), 3.0))
    direct = growth[(growth.method == "efg") & (growth.solver != "krylov")]
    for _, row in direct.iterrows():
        for phase in PHASES:
            if phase != "solve":
                rows.append((f"growth exponent, EFG {phase} ({row.material})",
                             f"{row['from']} to {row['to']} nodes, {row.solver}; {row.efg}",
                             row[phase], 1.2))
    frame = pd.DataFrame(rows, columns=["target", "where", "measured", "limit"])
    frame["met"] = verdict(frame.measured, frame.limit)
    return frame


#: Issue 17's EFG Cam-clay step at 10^5 nodes [s], measured on its CPU
#: (:data:`BASELINE_CPU`): its first target is half of it.
BASELINE_STEP = 32.1
BASELINE_CPU = "AMD EPYC, 2 cores"
#: Memory of issue 17's one machine [GB = 10^9 bytes]: 24 GiB.
MACHINE_GB = 24 * 2**30 / 1e9


def issue17_targets(table, machine_name="this machine"):
    """Issue 17's targets: measured value, target and verdict, one row each.

    A target whose run did not complete is "not measured" (:func:`verdict`), with the
    run's status, and where it bounds the value, the bound, in ``where``. The 10^5-node
    step and memory are given per solver that ran there; the growth exponent on the
    faster solver at each size (:func:`fastest`) and per solver; EFG and fem-p1p1-stab
    are compared at equal nodes, each on its faster solver there.

    Parameters
    ----------
    table : pandas.DataFrame
        The rows of :func:`steps`.
    machine_name : str
        Where the runs were measured (:func:`cpu`), for the first target's baseline.
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
            rows.append((what, f"{row.nodes} nodes, {row.solver}; {row.efg}"
                         + ("" if done else f", {row.status}{until}") + note,
                         row[column] * scale if done else np.nan, limit))

    at_size(100_000, "step", 1.0, "EFG Cam-clay step at 1e5 nodes [s]", 0.5 * BASELINE_STEP,
            f", measured on {machine_name}; limit 0.5 x {BASELINE_STEP} s, issue 17's step "
            f"on its {BASELINE_CPU}, not in this run (the CPU may differ)")
    at_size(100_000, "peak_mb", 1e-3, "EFG Cam-clay peak memory at 1e5 nodes [GB]", 3.0)
    at_size(1_000_000, "step", 1.0, "EFG Cam-clay step at 1e6 nodes [s]", 600.0)
    at_size(1_000_000, "peak_mb", 1e-3, "EFG Cam-clay peak memory at 1e6 nodes [GB]",
            MACHINE_GB, f"; limit 24 GiB; this machine has {ram_gb():.1f} GB")

    faster = pd.DataFrame([fastest(group) for _, group in efg.groupby("nodes")],
                          columns=efg.columns)
    series = {"faster solver at each size": faster,
              **{f"{solver}; {conditions}": runs for (solver, conditions), runs
                 in efg.groupby(["solver", "efg"], sort=False)}}
    for name, runs in series.items():
        rows.append((f"EFG Cam-clay step growth exponent, 1e4 to 1e6 nodes ({name})",
                     *_growth(runs), 1.15))

    stab = table[table.method == "fem-p1p1-stab"]
    for (material, nodes), group in table[table.method == "efg"].groupby(
            ["material", "nodes"], sort=False):
        e = fastest(group)
        f = fastest(stab[(stab.material == material) & (stab.nodes == nodes)])
        if f is None:
            continue
        where = f"{nodes} nodes, efg {e.solver} ({e.efg}), fem-p1p1-stab {f.solver}"
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


def figure(table, path):
    """Log-log time against nodes, one panel per phase: Cam-clay solid with circles,
    elastic dashed with squares; a line per solver, filled markers on the direct one, open
    ones on the iterative one (``krylov``); in the step panel, a run stopped at its time limit is a
    triangle at that limit (its time is longer). Runs that died or did not run are not
    drawn (the tables list them)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, axes = plt.subplots(2, 3, figsize=(12, 7), sharex=True, constrained_layout=True)
    colours = dict(zip(METHODS, ("C0", "C1", "C2", "C3"), strict=True))
    ok = table[table.status == "ok"]
    for ax, phase in zip(axes.ravel(), PHASES, strict=True):
        for (method, material, efg), group in ok.groupby(["method", "material", "efg"],
                                                         sort=False):
            if not group[phase].notna().any():
                continue
            colour = "C4" if efg.startswith("nitsche") else colours[method]
            marker = "o" if material == "cam-clay" else "s"
            label = f"{method}, {material}" + (f" ({efg})" if efg != "-" else "")
            for krylov, part in group.groupby(group.solver == "krylov"):
                ax.loglog(part.nodes, part[phase], ("-" if material == "cam-clay" else "--")
                          + marker, color=colour, ms=4, mfc="none" if krylov else colour,
                          label=label)
                label = None
        if phase == "step":
            stopped = table[table.status.str.startswith("stopped")]
            for method, group in stopped.groupby("method"):
                ax.loglog(group.nodes, group.limit_s, "^", color=colours[method], ms=7,
                          mfc="none")
        reference = ok[ok.method == "efg"][phase].min()
        if reference == reference:
            n = np.array([ok.nodes.min(), ok.nodes.max()], float)
            ax.loglog(n, reference * (n / n[0]) ** 1.2, ":", color="grey", label="N^1.2")
        ax.set_title(phase)
        ax.set_xlabel("nodes")
        ax.set_ylabel("time [s]")
        ax.grid(True, which="both", alpha=0.3)
    handles, _ = axes[0, 0].get_legend_handles_labels()
    handles += [Line2D([], [], marker="o", ls="none", color="k", ms=4, label="direct solver"),
                Line2D([], [], marker="o", ls="none", color="k", ms=4, mfc="none",
                       label="krylov"),
                Line2D([], [], marker="^", ls="none", color="k", ms=7, mfc="none",
                       label="stopped at its limit (step)")]
    axes[0, 0].legend(handles=handles, fontsize=7)
    fig.suptitle("One step of unconfined compression (0.2 % strain): phase times")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def cpu():
    """The CPU model (``model name`` of /proc/cpuinfo, else what platform knows)."""
    try:
        with open("/proc/cpuinfo") as fh:
            return next(line.split(":", 1)[1].strip() for line in fh
                        if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def ram_gb():
    """This machine's physical memory [GB = 10^9 bytes]."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9


def machine():
    """One line naming the machine, its memory, the solvers and the main versions."""
    import numba
    import scipy

    return (f"{cpu()}, {os.cpu_count()} cores, {ram_gb():.1f} GB; linear solver {direct()} "
            f"below {KRYLOV_FROM} nodes, krylov from there (and from {BOTH_FROM} for "
            f"{', '.join(LARGE_METHODS)}); Python "
            f"{platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, "
            f"scikit-fem {skfem.__version__}, numba {numba.__version__}")


def rates(table, yardstick):
    """The factorisation rate of every run that reported its flops, against dgemm.

    Parameters
    ----------
    table : pandas.DataFrame
        The rows of :func:`steps`.
    yardstick : dict
        :func:`dgemm`'s rates [GF/s].

    Returns
    -------
    pandas.DataFrame
        Method, material, nodes, solver, EFG's conditions, ``single_factorisations``,
        ``factor_flops``, ``solve`` [s], ``factor_gflops_lb`` [GF/s] and its fractions of
        MKL's and NumPy's dgemm rates (a single-precision factorisation's rate is
        compared with double's dgemm too, so its fraction overstates).
    """
    done = table[table.factor_flops.notna() & (table.status == "ok")]
    return done[["method", "material", "nodes", "solver", "efg", "single_factorisations",
                 "factor_flops", "solve", "factor_gflops_lb"]].assign(
        of_mkl_dgemm=done.factor_gflops_lb / yardstick["mkl_gflops"],
        of_numpy_dgemm=done.factor_gflops_lb / yardstick["numpy_gflops"])


def run(path="reports/bench.md", sizes=SIZES):
    """Run the benchmarks, write the Markdown, CSV and figure, and print the targets.

    The dgemm yardstick (:func:`dgemm`, in its own child), then one step of every run of
    :func:`plan` (:func:`steps`), then shape functions alone up to :data:`SHAPES_UP_TO`
    nodes (:func:`shape_functions`).
    """
    from soilwater.studies.harness.tables import to_markdown

    root = os.path.dirname(path) or "."
    os.makedirs(os.path.join(root, "tables"), exist_ok=True)
    os.makedirs(os.path.join(root, "figures"), exist_ok=True)
    tic = time.perf_counter()
    yardstick, status = in_child(dgemm, DGEMM_N, timeout=600)
    if yardstick is None:
        yardstick = {"n": DGEMM_N, "numpy_gflops": np.nan, "mkl_gflops": np.nan,
                     "numpy_blas": f"dgemm {status}", "mkl": f"dgemm {status}"}
    print(f"dgemm n = {DGEMM_N}: NumPy {yardstick['numpy_gflops']:.1f} GF/s "
          f"({yardstick['numpy_blas']}); MKL {yardstick['mkl_gflops']:.1f} GF/s")
    table = steps(sizes)
    shapes = shape_functions([nodes for nodes in sizes if nodes <= SHAPES_UP_TO])
    growth = exponents(table)
    goals = targets(table, shapes, growth)
    goals17 = issue17_targets(table, cpu())
    table.to_csv(os.path.join(root, "tables", "bench.csv"), index=False)
    figure(table, os.path.join(root, "figures", "bench.png"))
    largest = table[table.nodes == table.nodes.max()]
    memory = ", ".join(f"{r.method} {r.material} "
                       + (f"{r.peak_mb:.0f} MB ({r.kb_per_node:.0f} kB/node)"
                          if r.status == "ok" else r.status)
                       for r in largest.itertuples())
    shapes = shapes.assign(over_P1=shapes.efg_s / shapes.P1_s,
                           over_P2=shapes.efg_s / shapes.P2_s)
    measured = rates(table, yardstick)
    seconds = time.perf_counter() - tic
    text = "\n".join([
        "# Benchmarks (`make bench`)", "",
        f"Measured in one run of {seconds:.0f} s on {machine()}. "
        "One step of the unconfined-compression geometry (grid layout, 0.2 % axial "
        "strain) per method, material and size, each in its own forked process. "
        f"From {LARGE_FROM} nodes only {' and '.join(LARGE_METHODS)} run, with "
        f"{' and '.join(LARGE_MATERIALS)}. The linear solver is chosen by size: "
        f"{direct()} below {KRYLOV_FROM} nodes, the iterative back-end (krylov) from "
        f"there; from {BOTH_FROM} nodes {' and '.join(LARGE_METHODS)} also run on "
        f"krylov below {KRYLOV_FROM}, with either material, and on {direct()} EFG runs "
        "a second time as Krylov needs it. Each "
        "row names its solver, and the `efg` column EFG's essential conditions and "
        "stabilisation (the Krylov back-end needs Nitsche's and the perturbation). "
        "PARDISO factorises the tangents of such EFG and of fem-th in single precision "
        "and refines in double (`single_factorisations`). A run "
        "is stopped after "
        f"{TIME_LIMIT:.0f} s ({LARGE_TIME_LIMIT:.0f} s from {LARGE_FROM} nodes). "
        "Times are the solvers' phase timers [s]; the step includes everything the "
        "solver does in it (shape functions or bases, cells, every Newton iteration). "
        "EFG assembly includes building the sparse pattern of the step. Memory is the "
        "whole process's peak resident set [MB = 10^6 bytes; kB = 10^3 bytes per node], "
        "the interpreter and libraries included.", "",
        "## Targets (issue 17)", "",
        "A target whose run did not complete is \"not measured\"; `where` gives the "
        "run's status and, when it bounds the value, the bound.", "",
        to_markdown(goals17, "{:.3g}"),
        "## Factorisation rate against dgemm", "",
        f"dgemm of two {yardstick['n']} x {yardstick['n']} float64 matrices, best of 3, "
        f"in this run: NumPy's BLAS ({yardstick['numpy_blas']}) "
        f"{yardstick['numpy_gflops']:.1f} GF/s; MKL ({yardstick['mkl']}), the library "
        f"PARDISO factorises with, {yardstick['mkl_gflops']:.1f} GF/s. PARDISO's rate is "
        "compared with MKL's dgemm (NumPy's for reference). `factor_gflops_lb` is the "
        "floating-point operations of all the run's factorisations (the back-end's count, "
        "`factor_flops`) divided by the solve time, which also holds the analysis "
        "(ordering) and the back-solves: a lower bound of the factorisation's rate "
        "[GF/s = 10^9 flop/s]. A run with `single_factorisations` factorised in single "
        "precision, whose arithmetic runs at about twice dgemm's rate: its fractions "
        "overstate.", "",
        to_markdown(measured, "{:.3g}") if len(measured) else
        "No run reported `factor_flops` (`result.summary` has no count from its linear "
        "back-end): the factorisation rate is not measured.\n",
        "## Targets (issue 7)", "", to_markdown(goals, "{:.3g}"),
        "## Phase times [s]", "",
        to_markdown(table[["method", "material", "nodes", "solver", "efg", "status",
                           *PHASES]], "{:.3g}"),
        "## Counts, memory and rates", "",
        "Newton `iterations` summed over the step, `linear_iterations` the Krylov "
        "iterations (- where the back-end reports none), `factor_flops` as above, "
        "`limit_s` the run's time limit [s].", "",
        to_markdown(table[["method", "material", "nodes", "solver", "efg", "dofs",
                           "iterations",
                           "linear_iterations", "factorisations",
                           "symmetric_factorisations", "single_factorisations",
                           "perturbed_pivots", "factor_flops",
                           "factor_gflops_lb", "peak_mb", "kb_per_node", "limit_s"]],
                    "{:.3g}"),
        "## EFG / FEM at equal nodes", "", to_markdown(ratios(table), "{:.3g}"),
        "## Growth exponents (least squares of log time on log nodes, completed runs)", "",
        to_markdown(growth, "{:.2f}"),
        "## Shape functions alone: MLS against CellBasis at the same points [s]", "",
        to_markdown(shapes, "{:.3g}"),
        f"Peak resident memory at {largest.nodes.max()} nodes (whole process): {memory}.",
        "", "![bench](figures/bench.png)", ""])
    with open(path, "w") as fh:
        fh.write(text)
    print(to_markdown(goals17, "{:.3g}"))
    print(to_markdown(goals, "{:.3g}"))
    return table
