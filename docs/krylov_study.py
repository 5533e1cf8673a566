"""The measured numbers of the Krylov back-end against PARDISO, README "Speed".

``python docs/krylov_study.py [nodes ...]`` (default 1e4 3e4; about 12 minutes on 2
cores): one step of ``make bench``'s case (:func:`soilwater.studies.bench.plan.compression` with
``krylov=True``: EFG with Nitsche's conditions and the perturbation stabilisation, which
the Krylov back-end needs) on both back-ends, each in its own forked process, stopped
after 400 s. Prints the step time, Newton and FGMRES iterations, solve time and peak
memory.

``python docs/krylov_study.py --runs`` (about 5 minutes): whole runs of the built-in cases
on both back-ends; prints Newton, FGMRES and cut-back counts, and the largest difference
of p, q and the settlement relative to their range, or the failure.

``python docs/krylov_study.py --symmetric [nodes ...]`` (default 1e4 1e5; about 6
minutes): the first tangent of the bench case's step (EFG with the penalty, as ``make
bench`` runs it on PARDISO, and with Nitsche's conditions and the perturbation) factorised
as LU of ``K`` and as PARDISO's LDL^T of ``sym(K)``; prints how far ``K`` is from
symmetric (whole and displacement block), their times and flops, one back-solve of each,
and FGMRES on ``K`` preconditioned by the LDL^T (rows scaled as Newton scales them) to
1e-4, 1e-8 and 1e-10: iterations, time and the largest difference from the LU solution
relative to its largest entry.

``python docs/krylov_study.py --orderings [nodes ...]`` (default 3e3 1e4; about 3
minutes): SuperLU's factorisation of the first tangent of the bench step of EFG, fem-th,
fem-q2q1 and fem-p1p1-stab with scipy's default column ordering (COLAMD) and with
``soilwater.linalg.direct.SUPERLU_ORDERING``: time and the factor's entries.

``python docs/krylov_study.py --single [nodes ...]`` (default 3e4 1e5; about 20 minutes):
PARDISO's factorisation of the first tangent of the bench step as the Krylov sizes run it
(Nitsche, stabilised) in double and in single precision: time, flops, perturbed pivots,
the factor's memory (``iparm(17)``) and the scaled residual after each refinement of one
solve; one whole step of EFG (so conditioned), fem-th and fem-p1p1-stab with each, each
in its own forked process (step and solve time, Newton iterations, factorisations, peak
memory); then whole runs of the built-in cases (as ``--runs``, and EFG's with the
perturbation too) with each: Newton iterations, factorisations, cut-backs, and the
largest difference of p, q and the settlement relative to their range. Single precision
is forced on every discretisation that suits an iterative solver
(``soilwater.linalg.layout.Layout.iterative``), whether it asks for it (``Layout.single``) or not.

``python docs/krylov_study.py --newton [nodes] [forcing ...]`` (default 3e3 nodes,
forcings 1e-2 1e-4 1e-5 1e-6; under a minute): the Newton iterations of the bench step on the
Krylov back-end with each largest forcing (``soilwater.efg.system.FORCING``): the scaled
residuals and the step's FGMRES iterations; then modified Newton on Krylov
(``soilwater.linalg.krylov.Krylov.current = False``: the step's first tangent kept while it
contracts the residual tenfold, as PARDISO's factorisation is) and full Newton on PARDISO
(the current tangent factorised at every iteration) beside them.

``python docs/krylov_study.py --unstabilised [nodes]`` (default 3e3; under a minute): the
bench step on the Krylov back-end with EFG's pressure stabilisation ``"none"`` and
``"perturbation"``: Newton and FGMRES iterations, or the failure.

``python docs/krylov_study.py --memory [nodes]`` (default 3e4; a few minutes): where the
memory of one Krylov step of the bench case goes: the process's resident and peak memory
[MB] before the step, when the first tangent is assembled, after its preconditioner is
built, and after the step.

``python docs/krylov_study.py --smoother [nodes ...]`` (default 1e4 3e4; about 10
minutes): one Krylov step of the bench case per method (EFG and the stable FEM pairs)
with each finest-level AMG smoother (``soilwater.linalg.layout.Layout.smoother``): step and solve
time, Newton and FGMRES iterations. Then whole unconfined-compression runs of fem-th and
fem-q2q1 (on the grid without centres) with each smoother: time, Newton and FGMRES
iterations, cut-backs.

``python docs/krylov_study.py --overlap [nodes] [overlap ...]`` (default 3e4 nodes,
overlaps 0.25 0.5 1.01; a few minutes): the Schwarz subdomains' growth
(``soilwater.linalg.krylov_schwarz.OVERLAP``; above 1 no unknown joins a neighbouring aggregate) against cost,
on the first tangent of the bench step as the Krylov sizes run it: the preconditioner's
build time and kept inverses [MB], and FGMRES on a random right-hand side to 1e-8:
iterations and time.

``python docs/krylov_study.py --strength [theta ...]`` (default 0 0.01 0.02; about 15
minutes): per strength-of-connection threshold of the AMG hierarchies
(``soilwater.linalg.layout.Layout.strength``, set for every discretisation alike), one Krylov step
of the bench case at 3e4 and 1e5 nodes (step and solve time, Newton and FGMRES
iterations, peak memory) and whole unconfined-compression runs of fem-th and
fem-p1p1-stab on Krylov (time, Newton and FGMRES iterations, cut-backs, or the failure).

``python docs/krylov_study.py --threads [nodes ...]`` (default 1e5; a few minutes): one
Krylov step of the bench case with ``SOILWATER_THREADS=1`` and with every core
(:mod:`soilwater.linalg.threads`): step, assembly, solve and constitutive times, Newton and FGMRES
iterations.

``python docs/krylov_study.py --schur [nodes ...]`` (default 3e3 1e4; about 5 minutes):
which block of the Krylov preconditioner limits it. On the first tangent of the bench
step as the Krylov sizes run it, the displacement-pressure rows scaled and ordered as
:class:`soilwater.linalg.krylov.Krylov` does, FGMRES (restart 60) to 1e-8 on a random right-hand side,
preconditioned block triangular with the displacement block solved by one AMG V-cycle
(pyamg's default Gauss-Seidel smoother or the back-end's Schwarz) or exactly (SuperLU),
and the pressure block by the fixed-stress ``D - s M_p/M`` with the lumped or the
consistent mass, the SIMPLE ``D - C diag(A)^-1 B``, or (up to 4000 pressures) the true
Schur complement ``D - C A^-1 B``, each exactly or through AMG.

``python docs/krylov_study.py --spectral [nodes ...]`` (default 1e5; about a minute): pyamg's
estimate of the spectral radius of ``D^-1 S`` that weighs its Jacobi prolongation smoother,
on the displacement block of the bench step's first tangent (scaled and in node blocks as
:class:`soilwater.linalg.krylov.Krylov` builds it), Arnoldi run by run (15 products each, restarted
until the relative error is below 0.01): the restart vector's type, time, estimate and
error, as pyamg restarts (from the complex Ritz vector) and from its real part.

``python docs/krylov_study.py --faults [nodes ...]`` (default 1e5; a few minutes, Linux):
one Krylov step of the bench case per size, with transparent huge pages as the system
has them and off for the process (``prctl``): step time, user and system CPU time, and
the minor page faults of the step and of its preconditioner builds (with huge pages off
each is 4 kB of freshly touched memory).
"""

import dataclasses
import itertools
import sys
import time
from contextlib import contextmanager
from functools import partial

import numpy as np

from soilwater.studies.bench.plan import compression
from soilwater.studies.bench.runs import in_child, one_step
from soilwater.errors import ConvergenceError
from soilwater.linalg.backends import linear_solver
from soilwater.case.loader import load_case

LIMIT = 400.0
#: (case, method, efg.essential) of ``--runs``.
RUNS = (("unconfined-compression", "efg", "nitsche"),
        ("unconfined-compression", "efg", "penalty"),
        ("unconfined-compression", "fem-th", None),
        ("unconfined-compression", "fem-p1p1-stab", None),
        ("terzaghi", "efg", "nitsche"))


def stabilised(nodes, material="cam-clay", krylov=False):
    """The bench case as the Krylov sizes run it, for both back-ends alike."""
    return compression(nodes, material, krylov=True)


def steps(sizes):
    """One step per size and back-end."""
    import soilwater.studies.bench.runs

    soilwater.studies.bench.runs.compression = stabilised
    for nodes in sizes:
        for solver in ("pardiso", "krylov"):
            row, status = in_child(one_step, "efg", nodes, "cam-clay", solver,
                                   timeout=LIMIT)
            keys = ("step", "iterations", "linear_iterations", "solve", "peak_mb")
            print(f"{nodes:8d} {solver:8s} {status}",
                  {k: round(row[k], 2) for k in keys} if status == "ok" else row,
                  flush=True)


def runs(variants=None, cases=RUNS):
    """Whole runs of ``cases`` (:data:`RUNS`; an optional fourth entry is EFG's
    stabilisation) under each of ``variants`` (name: a function returning a context
    manager; default: on PARDISO and on the Krylov back-end)."""
    import soilwater.efg.solver
    import soilwater.fem.solver

    variants = variants or {solver: partial(linear_solver, solver)
                            for solver in ("pardiso", "krylov")}
    for name, method, essential, *stabilisation in cases:
        case = load_case(name)
        if essential:
            case = dataclasses.replace(case, efg=dataclasses.replace(
                case.efg, essential=essential, stabilisation=(stabilisation or
                                                              [case.efg.stabilisation])[0]))
        histories, label = {}, " ".join([name, method, str(essential), *stabilisation])
        for variant, within in variants.items():
            with within():
                tic = time.perf_counter()
                try:
                    result = (soilwater.efg.solver.solve(case, progress=False) if method == "efg"
                              else soilwater.fem.solver.solve(case, method, progress=False))
                except ConvergenceError as err:
                    print(f"{label} {variant}: failed: {err}", flush=True)
                    continue
                s = result.summary
                histories[variant] = result.history
                print(f"{label} {variant}: "
                      f"{time.perf_counter() - tic:.1f} s, Newton {s['newton_iterations']}, "
                      f"factorisations {s['factorisations']} "
                      f"({s['single_factorisations']} single), "
                      f"FGMRES {s['linear_iterations']}, cut-backs {s['cutbacks']}",
                      flush=True)
        if len(histories) == 2:
            a, b = histories.values()
            print("  agreement", {c: float(np.abs(a[c] - b[c]).max()
                                           / max(np.abs(a[c]).max(), 1e-30))
                                  for c in ("p", "q", "settlement")}, flush=True)


#: The methods of ``--smoother``.
SMOOTHED = ("efg", "fem-p1p1-stab", "fem-q2q1", "fem-th")


def _laid_out(changes, fn, *args):
    """``fn(*args)`` with the ``changes`` (:class:`soilwater.linalg.layout.Layout` fields) made to
    the layout of every Krylov preconditioner."""
    import soilwater.linalg.krylov

    build = soilwater.linalg.krylov.Krylov.__init__

    def forced(self, K, layout):
        build(self, K, dataclasses.replace(layout, **changes))

    soilwater.linalg.krylov.Krylov.__init__ = forced
    try:
        return fn(*args)
    finally:
        soilwater.linalg.krylov.Krylov.__init__ = build


def overlaps(nodes, shares):
    """Build and solve time, inverses and iterations of the preconditioner per overlap."""
    import soilwater.linalg.krylov_schwarz
    from soilwater.linalg.krylov import Krylov

    K, layout = first_tangent(nodes, krylov=True)
    b = np.random.default_rng(0).standard_normal(K.shape[0])
    kept, build = [], soilwater.linalg.krylov_schwarz.Schwarz.__init__

    def measured(self, *args):
        build(self, *args)
        kept.append(self.inverses.nbytes)

    soilwater.linalg.krylov_schwarz.Schwarz.__init__, default = measured, soilwater.linalg.krylov_schwarz.OVERLAP
    try:
        for share in shares:
            soilwater.linalg.krylov_schwarz.OVERLAP, kept[:] = share, []
            tic = time.perf_counter()
            solver = Krylov(K, layout)
            built = time.perf_counter() - tic
            solver.solve(b, rtol=1e-8)
            print(f"{nodes} nodes, overlap {share}: build {built:.1f} s, inverses "
                  f"{sum(kept) / 1e6:.0f} MB, FGMRES {solver.iterations} iterations, "
                  f"{time.perf_counter() - tic - built:.1f} s", flush=True)
    finally:
        soilwater.linalg.krylov_schwarz.Schwarz.__init__, soilwater.linalg.krylov_schwarz.OVERLAP = build, default


def strengths(thetas):
    """Bench steps and whole FEM runs on Krylov per strength threshold."""
    import soilwater.fem.solver

    for theta in thetas:
        for nodes in (30_000, 100_000):
            row, status = in_child(_laid_out, {"strength": theta}, one_step, "efg", nodes,
                                   "cam-clay", "krylov", timeout=LIMIT)
            keys = ("step", "solve", "iterations", "linear_iterations", "peak_mb")
            print(f"theta {theta} {nodes:8d} {status}",
                  {k: round(row[k], 1) for k in keys} if status == "ok" else row,
                  flush=True)
        for method in ("fem-th", "fem-p1p1-stab"):
            tic = time.perf_counter()
            with linear_solver("krylov"):
                try:
                    s = _laid_out({"strength": theta}, soilwater.fem.solver.solve,
                                  load_case("unconfined-compression"), method,
                                  False).summary
                except ConvergenceError as err:
                    print(f"theta {theta} unconfined-compression {method}: failed: {err}",
                          flush=True)
                    continue
            print(f"theta {theta} unconfined-compression {method}: "
                  f"{time.perf_counter() - tic:.0f} s, Newton {s['newton_iterations']}, "
                  f"FGMRES {s['linear_iterations']}, cut-backs {s['cutbacks']}",
                  flush=True)


def smoothers(sizes):
    """One Krylov step per method, size and smoother; :func:`whole_runs`."""
    for nodes in sizes:
        for method in SMOOTHED:
            for smoother in ("gauss_seidel", "schwarz"):
                row, status = in_child(_laid_out, {"smoother": smoother}, one_step, method,
                                       nodes, "cam-clay", "krylov", timeout=LIMIT)
                keys = ("step", "solve", "iterations", "linear_iterations")
                print(f"{nodes:8d} {method:14s} {smoother:12s} {status}",
                      {k: round(row[k], 1) for k in keys} if status == "ok" else row,
                      flush=True)
    whole_runs()


def whole_runs():
    """Unconfined compression with the quadratic FEM pairs, each smoother (quadrilaterals
    on the case's grid without centres)."""
    import soilwater.fem.solver

    for method, overrides in (("fem-th", []), ("fem-q2q1", ["discretisation.layout=grid"])):
        case = load_case("unconfined-compression", overrides)
        for smoother in ("gauss_seidel", "schwarz"):
            tic = time.perf_counter()
            with linear_solver("krylov"):
                try:
                    s = _laid_out({"smoother": smoother}, soilwater.fem.solver.solve, case,
                                  method, False).summary
                    print(f"unconfined-compression {method} {smoother}: "
                          f"{time.perf_counter() - tic:.0f} s, Newton "
                          f"{s['newton_iterations']}, FGMRES {s['linear_iterations']}, "
                          f"cut-backs {s['cutbacks']}", flush=True)
                except ConvergenceError as err:
                    print(f"unconfined-compression {method} {smoother}: failed: {err}",
                          flush=True)


@contextmanager
def _factorising(wrap):
    """``soilwater.nonlinear.newton.factorise`` replaced by ``wrap(original)`` inside the block."""
    import soilwater.nonlinear.newton

    original = soilwater.nonlinear.newton.factorise
    soilwater.nonlinear.newton.factorise = wrap(original)
    try:
        yield
    finally:
        soilwater.nonlinear.newton.factorise = original


class _Captured(Exception):
    """The first tangent of a step, and its layout."""


def threads(sizes):
    """One Krylov step per size on one thread and on every core."""
    from soilwater.linalg.threads import CORES, using

    for nodes in sizes:
        for count in (1, CORES):
            with using(count):
                row, status = in_child(one_step, "efg", nodes, "cam-clay", "krylov",
                                       timeout=LIMIT)
            keys = ("step", "assembly", "solve", "constitutive", "iterations",
                    "linear_iterations")
            print(f"{nodes:8d} threads {count} {status}",
                  {k: round(row[k], 2) for k in keys} if status == "ok" else row,
                  flush=True)


def first_tangent(nodes, krylov=False, method="efg", solver="pardiso"):
    """The first Newton tangent of one bench step (Cam-clay; EFG's ``krylov``: with
    Nitsche's conditions and the perturbation stabilisation) of ``method`` on the
    back-end ``solver``, and its layout."""
    import soilwater.efg.solver
    import soilwater.fem.solver

    def capture(original):
        def captured(K, layout=None, symmetric=False):
            raise _Captured(K, layout)
        return captured

    try:
        with _factorising(capture), linear_solver(solver):
            case = compression(nodes, krylov=krylov)
            (soilwater.efg.solver.solve(case, progress=False) if method == "efg"
             else soilwater.fem.solver.solve(case, method, progress=False))
    except _Captured as captured:
        return captured.args
    raise RuntimeError("the step did not factorise")


def orderings(sizes, methods=("efg", "fem-th", "fem-q2q1", "fem-p1p1-stab")):
    """SuperLU's factorisation of each method's first bench tangent (Cam-clay; EFG as
    ``make bench`` runs it on a direct solver) with scipy's default column ordering,
    COLAMD, and with :data:`soilwater.linalg.direct.SUPERLU_ORDERING`: time and fill."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from soilwater.linalg.direct import SUPERLU_ORDERING

    for nodes, method in itertools.product(sizes, methods):
        K = sp.csc_matrix(first_tangent(nodes, method=method, solver="superlu")[0])
        for ordering in ("COLAMD", SUPERLU_ORDERING):
            tic = time.perf_counter()
            lu = spla.splu(K, permc_spec=ordering)
            print(f"{method} {nodes} nodes, {K.shape[0]} unknowns, {ordering}: "
                  f"{time.perf_counter() - tic:.2f} s, L + U {lu.L.nnz + lu.U.nnz:.3g} "
                  "entries", flush=True)


def symmetric(sizes):
    """LU of K against LDL^T of sym(K) as FGMRES's preconditioner, per size, on the
    penalty tangent and on the Nitsche one (with the perturbation stabilisation)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from pyamg.krylov import fgmres

    from soilwater.linalg.pardiso import _Pardiso

    for nodes, nitsche in itertools.product(sizes, (False, True)):
        K, layout = first_tangent(nodes, krylov=nitsche)
        K = sp.csr_matrix(K)
        u = np.flatnonzero(np.asarray(layout.fields) < 2)
        Kuu = K[u][:, u]
        print(f"{nodes} nodes, {'Nitsche' if nitsche else 'penalty'}, {K.shape[0]} unknowns, "
              f"||K - K^T|| / ||K|| = {spla.norm(K - K.T) / spla.norm(K):.1e} "
              f"(displacement block {spla.norm(Kuu - Kuu.T) / spla.norm(Kuu):.1e})",
              flush=True)
        b = np.random.default_rng(0).standard_normal(K.shape[0]) * layout.scales
        solves, solutions = {}, {}
        for name, sym in (("LU of K", False), ("LDL^T of sym(K)", True)):
            tic = time.perf_counter()
            solves[name] = _Pardiso(K, layout.groups, sym)
            built = time.perf_counter() - tic
            tic = time.perf_counter()
            solutions[name] = solves[name].solve(b)
            print(f"  {name}: factorisation {built:.1f} s, {solves[name].flops:.2e} flops, "
                  f"{solves[name].perturbed_pivots} perturbed pivots; back-solve "
                  f"{time.perf_counter() - tic:.2f} s", flush=True)
        exact, ldlt = solutions["LU of K"], solves["LDL^T of sym(K)"]
        row = 1 / layout.scales
        A = spla.LinearOperator(K.shape, lambda x: row * (K @ x))
        M = spla.LinearOperator(K.shape, lambda r: ldlt.solve(r / row))
        for rtol in (1e-4, 1e-8, 1e-10):
            residuals, tic = [], time.perf_counter()
            x, _ = fgmres(A, row * b, M=M, tol=rtol, restart=60, maxiter=1,
                          residuals=residuals)
            print(f"  FGMRES to {rtol:.0e}: {len(residuals) - 1} iterations, "
                  f"{time.perf_counter() - tic:.2f} s, difference from LU "
                  f"{np.abs(x - exact).max() / np.abs(exact).max():.1e}", flush=True)


class _Traced:
    """A Newton system that prints its scaled residuals and each tangent it assembles."""

    def __init__(self, system):
        self.system, self.layout = system, system.layout

    def residual(self):
        R, scaled = self.system.residual()
        print(f"    residual {scaled:.3e}", flush=True)
        return R, scaled

    def tangent(self):
        print("    tangent assembled", flush=True)
        return self.system.tangent()

    def advance(self, dx):
        self.system.advance(dx)


def newton_iterations(nodes, forcings):
    """The Newton residuals of one bench step per largest forcing, modified Newton on
    Krylov, and full Newton on PARDISO."""
    import soilwater.efg.solver
    import soilwater.efg.system
    import soilwater.nonlinear.newton
    import soilwater.linalg.krylov

    original = soilwater.efg.solver.newton, soilwater.efg.system.FORCING, soilwater.nonlinear.newton.must_refactorise

    def traced(system, stats):
        before, tic = stats["linear_iterations"], time.perf_counter()
        try:
            return original[0](_Traced(system), stats)
        finally:
            print(f"    FGMRES iterations {stats['linear_iterations'] - before}, Newton "
                  f"{time.perf_counter() - tic:.1f} s", flush=True)

    def run(solver):
        with linear_solver(solver):
            try:
                soilwater.efg.solver.solve(compression(nodes, krylov=True), progress=False)
            except ConvergenceError as err:
                print(f"    failed: {err}", flush=True)

    soilwater.efg.solver.newton = traced
    try:
        for forcing in forcings:
            soilwater.efg.system.FORCING = forcing
            print(f"{nodes} nodes, krylov, largest forcing {forcing:g}:", flush=True)
            run("krylov")
        soilwater.efg.system.FORCING, soilwater.linalg.krylov.Krylov.current = original[1], False
        print(f"{nodes} nodes, krylov, modified Newton:", flush=True)
        run("krylov")
        soilwater.linalg.krylov.Krylov.current = True
        soilwater.nonlinear.newton.must_refactorise = lambda *args: True
        print(f"{nodes} nodes, pardiso, full Newton:", flush=True)
        run("pardiso")
    finally:
        soilwater.efg.solver.newton, soilwater.efg.system.FORCING, soilwater.nonlinear.newton.must_refactorise = original
        soilwater.linalg.krylov.Krylov.current = True


def unstabilised(nodes):
    """The bench step on the Krylov back-end without and with EFG's stabilisation."""
    import soilwater.efg.solver

    for kind in ("none", "perturbation"):
        case = compression(nodes, krylov=True)
        case = dataclasses.replace(case, efg=dataclasses.replace(case.efg, stabilisation=kind))
        with linear_solver("krylov"):
            try:
                s = soilwater.efg.solver.solve(case, progress=False).summary
                print(f"{nodes} nodes, stabilisation {kind}: Newton {s['newton_iterations']}, "
                      f"FGMRES {s['linear_iterations']}, cut-backs {s['cutbacks']}", flush=True)
            except ConvergenceError as err:
                print(f"{nodes} nodes, stabilisation {kind}: failed: {err}", flush=True)


def _memory(label):
    """Print the process's resident and peak memory [MB] (Linux ``/proc``)."""
    with open("/proc/self/status") as fh:
        kb = {line.split(":")[0]: float(line.split()[1]) for line in fh
              if line.startswith(("VmRSS", "VmHWM"))}
    print(f"  {label:40s} resident {kb['VmRSS'] * 1.024e-3:8.0f} MB, peak "
          f"{kb['VmHWM'] * 1.024e-3:8.0f} MB", flush=True)


def _faulting_step(nodes, huge_pages):
    """One Krylov step (child process): step [s], user and system CPU [s], minor faults
    of the step and of its preconditioner builds."""
    import ctypes
    import resource

    if not huge_pages:                                # PR_SET_THP_DISABLE
        ctypes.CDLL(None, use_errno=True).prctl(41, 1, 0, 0, 0)
    built = [0]

    def count(original):
        def counted(K, layout=None, symmetric=False):
            before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
            solver = original(K, layout, symmetric)
            built[0] += resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
            return solver
        return counted

    before = resource.getrusage(resource.RUSAGE_SELF)
    with _factorising(count):
        row = one_step("efg", nodes, "cam-clay", "krylov")
    after = resource.getrusage(resource.RUSAGE_SELF)
    return (row["step"], after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime,
            after.ru_minflt - before.ru_minflt, built[0])


def faults(sizes):
    """Page faults and system time of one Krylov step per size, huge pages on and off."""
    one_step("efg", 200, "cam-clay", "krylov")        # numba's caches, outside the runs
    for nodes in sizes:
        for huge_pages in (True, False):
            out, status = in_child(_faulting_step, nodes, huge_pages, timeout=LIMIT)
            label = f"{nodes} nodes, huge pages {'as set' if huge_pages else 'off'}"
            if status != "ok":
                print(f"{label}: {status}", flush=True)
                continue
            step, user, system, step_faults, build_faults = out
            fresh = ("" if huge_pages else f"; {step_faults * 4096e-9:.1f} and "
                     f"{build_faults * 4096e-9:.1f} GB of fresh memory")
            print(f"{label}: step {step:.1f} s, user {user:.1f} s, system {system:.1f} s, "
                  f"faults {step_faults:.3g} (builds {build_faults:.3g}{fresh})", flush=True)


def memory(nodes):
    """Resident and peak memory around the first preconditioner of a Krylov step."""
    import soilwater.efg.solver

    def watch(original):
        def watched(K, layout=None, symmetric=False):
            _memory(f"tangent assembled ({K.nnz:.2e} entries)")
            solver = original(K, layout, symmetric)
            _memory("preconditioner built")
            return solver
        return watched

    case = compression(nodes, krylov=True)
    print(f"{len(case.nodes())} nodes, krylov:", flush=True)
    _memory("before the step")
    with _factorising(watch), linear_solver("krylov"):
        soilwater.efg.solver.solve(case, progress=False)
    _memory("after the step")


@contextmanager
def _precision(single):
    """PARDISO inside the block, factorising the tangent of every discretisation that
    suits an iterative solver (:attr:`soilwater.linalg.layout.Layout.iterative`) in single precision
    (whether its :attr:`soilwater.linalg.layout.Layout.single` asks for it or not), or every tangent
    in double."""
    import soilwater.linalg.backends

    def wrap(original):
        def factorised(K, layout=None, symmetric=False):
            if layout is not None:
                layout = dataclasses.replace(layout, single=single and layout.iterative)
            return original(K, layout, symmetric)
        return factorised

    kept, soilwater.linalg.backends.SINGLE = soilwater.linalg.backends.SINGLE, True
    try:
        with _factorising(wrap), linear_solver("pardiso"):
            yield
    finally:
        soilwater.linalg.backends.SINGLE = kept


def _single_step(method, nodes, single):
    """One bench step (:func:`stabilised`) of ``method`` on PARDISO, in single precision
    or double."""
    import soilwater.studies.bench.runs

    soilwater.studies.bench.runs.compression = stabilised
    with _precision(single):
        return one_step(method, nodes, "cam-clay", "pardiso")


def single(sizes):
    """PARDISO's factorisation of the bench step's first tangent (Nitsche, stabilised) in
    double and in single precision and the refinement of one solve, one bench step of
    three methods with each, and whole runs of :data:`RUNS` (and EFG's with the
    perturbation) with each."""
    import scipy.sparse as sp

    from soilwater.linalg.pardiso import _Pardiso

    for nodes in sizes:
        K, layout = first_tangent(nodes, krylov=True)
        K = sp.csr_matrix(K)
        b = np.random.default_rng(0).standard_normal(K.shape[0]) * layout.scales
        print(f"{nodes} nodes, {K.shape[0]} unknowns", flush=True)
        for scales in (None, layout.scales):
            tic = time.perf_counter()
            lu = _Pardiso(K, layout.groups, scales=scales)
            built = time.perf_counter() - tic
            name = "single" if lu.single else "double"
            tic, history = time.perf_counter(), []
            if lu.single:
                lu._refined(b, history)
            else:
                history.append(np.linalg.norm((b - K @ lu.solve(b)) / layout.scales)
                               / np.linalg.norm(b / layout.scales))
            print(f"  {name}: analysis and factorisation {built:.1f} s, "
                  f"{lu.flops:.2e} flops, {lu.perturbed_pivots} perturbed pivots, factor "
                  f"{lu.solver.get_iparm(17) / 1e3:.0f} MB (iparm 17); "
                  f"{'refinements' if lu.single else 'back-solve'} "
                  f"{(time.perf_counter() - tic) / len(history):.2f} s each, scaled "
                  f"residual after each", " ".join(f"{h:.1e}" for h in history), flush=True)
            del lu
        for method in ("efg", "fem-th", "fem-p1p1-stab"):
            for precision in (False, True):
                row, status = in_child(_single_step, method, nodes, precision,
                                       timeout=LIMIT)
                keys = ("step", "solve", "iterations", "factorisations",
                        "single_factorisations", "peak_mb")
                print(f"  {method} step, {'single' if precision else 'double'}: {status}",
                      {k: round(float(row[k]), 2) for k in keys} if status == "ok" else row,
                      flush=True)
    runs({"double": partial(_precision, False), "single": partial(_precision, True)},
         RUNS + (("unconfined-compression", "efg", "nitsche", "perturbation"),
                 ("terzaghi", "efg", "nitsche", "perturbation")))


def scaled_tangent(K, precondition, count):
    """The tangent ``K`` on the first ``count`` unknowns of the order of the Krylov
    ``precondition``, rows scaled as it scales them."""
    import scipy.sparse as sp

    from soilwater.linalg.krylov import _permuted

    permuted = _permuted(sp.csr_matrix(K), precondition.order)
    return sp.csr_matrix(sp.diags(precondition.row) @ permuted)[:count, :count]


def spectral(sizes):
    """pyamg's restarted Arnoldi estimate of rho(D^-1 S), run by run, per size."""
    import scipy.sparse as sp
    from pyamg.util.linalg import _approximate_eigenvalues
    from pyamg.util.utils import get_diagonal, scale_rows

    from soilwater.linalg.krylov import Krylov

    for nodes in sizes:
        K, layout = first_tangent(nodes, krylov=True)
        precondition = Krylov(K, layout)              # its displacement order and scales
        S = sp.bsr_matrix(scaled_tangent(K, precondition, precondition.sizes[0]),
                          blocksize=(2, 2))
        scaled = scale_rows(S, get_diagonal(S, inv=True), copy=True)      # as pyamg does
        for restart in ("complex", "real"):
            np.random.seed(0)
            v0 = np.random.rand(S.shape[0], 1)
            for run in range(6):
                tic = time.perf_counter()
                vectors, values, H, V, _ = _approximate_eigenvalues(
                    scaled, 15, False, initial_guess=v0 / np.linalg.norm(v0))
                top = np.abs(values).argmax()
                error = abs(H[len(values), len(values) - 1] * vectors[-1, top] / values[top])
                print(f"{nodes} nodes, {restart} restarts, run {run}: vector "
                      f"{V[0].dtype}, {time.perf_counter() - tic:.2f} s, rho "
                      f"{abs(values[top]):.5f}, relative error {error:.2g}", flush=True)
                if error < 0.01:
                    break
                v0 = np.hstack(V[:-1]) @ vectors[:, top].reshape(-1, 1)
                if restart == "real":             # the Ritz vector's phase removed
                    v0 = np.real(v0 * np.exp(-1j * np.angle(v0[np.abs(v0).argmax()])))


def schur(sizes):
    """FGMRES iterations with each displacement and pressure block solve, per size."""
    import scipy.linalg
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from pyamg.krylov import fgmres

    from soilwater.linalg.krylov import RESTART, Krylov
    from soilwater.linalg.krylov_amg import amg, rigid_modes

    for nodes in sizes:
        K, layout = first_tangent(nodes, krylov=True)
        precondition = Krylov(K, layout)
        nu, n_p = precondition.sizes
        order = precondition.order[:nu + n_p]
        row = precondition.row[:nu + n_p]
        scaled = scaled_tangent(K, precondition, nu + n_p)
        A, B = scaled[:nu, :nu], scaled[:nu, nu:]
        C, D = scaled[nu:, :nu], scaled[nu:, nu:]
        s = -precondition.sign_p
        mass = sp.csr_matrix(sp.diags(row[nu:]) @ layout.mass_matrix()[order[nu:]][:, order[nu:]]
                             / layout.modulus)
        lumped = sp.diags(np.asarray(mass.sum(axis=1)).ravel())
        consistent = sp.csr_matrix(D - s * mass)

        def exact(M):
            return spla.splu(sp.csc_matrix(M)).solve

        modes = rigid_modes(layout.locations[order[:nu]], layout.fields[order[:nu]])
        displacements = {
            "AMG, Gauss-Seidel": amg(A, "gauss_seidel", layout.strength, modes, 2),
            "AMG, Schwarz": precondition.amg_u,
            "exact": exact(A)}
        pressures = {"fixed-stress lumped, exact": exact(D - s * lumped),
                     "SIMPLE, exact": exact(D - C @ sp.diags(1 / A.diagonal()) @ B),
                     "fixed-stress, AMG Gauss-Seidel": (
                         lambda r, t=-s,
                         cycle=amg(-s * consistent, "gauss_seidel", layout.strength):
                         t * cycle(r)),
                     "fixed-stress, AMG Schwarz": (
                         lambda r, t=-s, cycle=amg(-s * consistent, "schwarz", layout.strength):
                         t * cycle(r)),
                     "fixed-stress, exact": exact(consistent)}
        if n_p <= 4000:
            true = scipy.linalg.lu_factor(D.toarray() - C @ exact(A)(B.toarray()))
            pressures["true Schur, exact"] = lambda r: scipy.linalg.lu_solve(true, r)
        b = np.random.default_rng(0).standard_normal(nu + n_p)
        print(f"{nodes} nodes: {nu} displacements, {n_p} pressures", flush=True)
        for a_name, solve_A in displacements.items():
            for p_name, solve_S in pressures.items():
                def apply(r, solve_A=solve_A, solve_S=solve_S):
                    y_p = solve_S(r[nu:])
                    return np.concatenate([solve_A(r[:nu] - B @ y_p), y_p])

                residuals, tic = [], time.perf_counter()
                fgmres(scaled, b, M=spla.LinearOperator(scaled.shape, apply, dtype=float),
                       tol=1e-8, restart=RESTART, maxiter=10, residuals=residuals)
                print(f"  A {a_name:17s} S {p_name:30s}: {len(residuals) - 1:4d} "
                      f"iterations, {time.perf_counter() - tic:5.1f} s", flush=True)


if __name__ == "__main__":
    if sys.argv[1:] == ["--runs"]:
        runs()
    elif sys.argv[1:2] == ["--newton"]:
        arguments = [float(a) for a in sys.argv[2:]]
        newton_iterations(int(arguments[0]) if arguments else 3_000,
                          arguments[1:] or [1e-2, 1e-4, 1e-5, 1e-6])
    elif sys.argv[1:2] == ["--unstabilised"]:
        unstabilised(int(float(sys.argv[2])) if sys.argv[2:] else 3_000)
    elif sys.argv[1:2] == ["--memory"]:
        memory(int(float(sys.argv[2])) if sys.argv[2:] else 30_000)
    elif sys.argv[1:2] == ["--overlap"]:
        arguments = [float(a) for a in sys.argv[2:]]
        overlaps(int(arguments[0]) if arguments else 30_000, arguments[1:] or [0.25, 0.5, 1.01])
    elif sys.argv[1:2] == ["--smoother"]:
        smoothers([int(float(n)) for n in sys.argv[2:]] or [10_000, 30_000])
    elif sys.argv[1:2] == ["--strength"]:
        strengths([float(t) for t in sys.argv[2:]] or [0.0, 0.01, 0.02])
    elif sys.argv[1:2] == ["--threads"]:
        threads([int(float(n)) for n in sys.argv[2:]] or [100_000])
    elif sys.argv[1:2] == ["--schur"]:
        schur([int(float(n)) for n in sys.argv[2:]] or [3_000, 10_000])
    elif sys.argv[1:2] == ["--faults"]:
        faults([int(float(n)) for n in sys.argv[2:]] or [100_000])
    elif sys.argv[1:2] == ["--spectral"]:
        spectral([int(float(n)) for n in sys.argv[2:]] or [100_000])
    elif sys.argv[1:2] == ["--single"]:
        single([int(float(n)) for n in sys.argv[2:]] or [30_000, 100_000])
    elif sys.argv[1:2] == ["--orderings"]:
        orderings([int(float(n)) for n in sys.argv[2:]] or [3_000, 10_000])
    elif sys.argv[1:2] == ["--symmetric"]:
        symmetric([int(float(n)) for n in sys.argv[2:]] or [10_000, 100_000])
    else:
        steps([int(float(n)) for n in sys.argv[1:]] or [10_000, 30_000])
