"""Unconfined compression past its peak on a refined grid: branches, tangent and
preconditioner (README, "Past the peak the homogeneous solution is unstable").

The case is the built-in unconfined compression on the 825-node grid of :data:`GRID`
(EFG, Nitsche's conditions, the perturbation stabilisation: what the Krylov back-end
runs). Its exact solution is homogeneous, and MLS with a linear basis reproduces a
homogeneous field on any layout, so the spread of q and p_w over the nodes measures how
far a run has left that solution.

``python docs/post_peak_study.py --branches`` (about 18 minutes on 2 cores): the case
with EFG three ways: PARDISO's modified Newton (the default), full Newton on PARDISO (the
current tangent factorised at every iteration, ``soilwater.linalg.layout.CONTRACTION = 0``) and the
Krylov back-end; then with fem-th and fem-p1p1-stab on the same nodes (PARDISO's
modified Newton). Prints time, Newton and FGMRES iterations, cut-backs and the largest
q, and every 2 s the spread (largest minus smallest) of q and of p_w over the nodes
relative to their mean magnitude (of a run that fails, up to its last level).

``python docs/post_peak_study.py --tangent [t ...]`` (default 2 8 11.6 14 18.4; about 3
minutes): the PARDISO run's steps ending at those times, at their start and after one and
two exact Newton corrections. Central differences of the residual, ``(R(x + h v) - R(x -
h v)) / 2h`` for h = 1e-3, 1e-4, 1e-5, against ``K v``: the relative error in the
displacement and the pressure rows, along the Newton correction and along random
displacement and pressure directions (scaled as the step's first correction). On the
tangent's displacement block, scaled as :class:`soilwater.linalg.krylov.Krylov` scales it: its
negative eigenvalues, and FGMRES iterations to 1e-8 on ``-R`` with the tangent's own
preconditioner, with the preconditioner of the step's first tangent (what the Krylov
back-end keeps through a step), and with the displacement block solved exactly.
"""

import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import soilwater.efg.solver
import soilwater.fem.solver
import soilwater.efg.discretisation
import soilwater.efg.system
import soilwater.linalg.layout
from soilwater.nonlinear.history import TIMERS
from soilwater.errors import ConvergenceError
from soilwater.linalg.krylov import MAX_ITERATIONS, Krylov
from soilwater.linalg.backends import linear_solver
from soilwater.case.loader import load_case

from krylov_study import scaled_tangent   # docs/, this script's folder

#: Grid k = 8 of the case's 3 x 4 m quarter: 25 x 33 nodes, spacing 0.125 m.
GRID = ["discretisation.nx=25", "discretisation.ny=33", "discretisation.layout=grid",
        'efg.essential="nitsche"', 'efg.stabilisation="perturbation"']


def case():
    """The study's case (:data:`GRID`)."""
    return load_case("unconfined-compression", GRID)


#: The runs of ``--branches``: method, linear solver, label, ``soilwater.linalg.layout.CONTRACTION``.
PATHS = (("efg", "pardiso", "modified Newton", soilwater.linalg.layout.CONTRACTION),
         ("efg", "pardiso", "full Newton", 0.0),
         ("efg", "krylov", "Newton", soilwater.linalg.layout.CONTRACTION),
         ("fem-th", "pardiso", "modified Newton", soilwater.linalg.layout.CONTRACTION),
         ("fem-p1p1-stab", "pardiso", "modified Newton", soilwater.linalg.layout.CONTRACTION))


def branches():
    """The case on the paths of :data:`PATHS`."""
    kept = soilwater.linalg.layout.CONTRACTION
    for method, solver, label, contraction in PATHS:
        soilwater.linalg.layout.CONTRACTION = contraction
        try:
            _branch(method, solver, label)
        finally:
            soilwater.linalg.layout.CONTRACTION = kept


def _branch(method, solver, label):
    name = f"{method} on {solver}, {label}"
    module = soilwater.efg.solver if method == "efg" else soilwater.fem.solver
    snapshots, snapshot = [], module._snapshot

    def kept(*args):                # the levels reached, a failed run's too
        snapshots.append(snapshot(*args))
        return snapshots[-1]

    module._snapshot = kept
    with linear_solver(solver):
        tic = time.perf_counter()
        try:
            result = (soilwater.efg.solver.solve(case(), progress=False) if method == "efg" else
                      soilwater.fem.solver.solve(case(), method, progress=False))
            s = result.summary
            print(f"{name}: {time.perf_counter() - tic:.0f} s, Newton "
                  f"{s['newton_iterations']}, FGMRES {s['linear_iterations']}, cut-backs "
                  f"{s['cutbacks']}, largest q {result.history.q.max():.6f} kPa", flush=True)
        except ConvergenceError as err:
            print(f"{name}: failed after {time.perf_counter() - tic:.0f} s: {err}")
        finally:
            module._snapshot = snapshot
    for snap in snapshots:
        if snap.time > 0 and abs(snap.time / 2 - round(snap.time / 2)) < 1e-9:
            q, p = snap.point_data["q"], snap.point_data["p_w"]
            print(f"  t = {snap.time:4.1f} s: spread of q {np.ptp(q) / np.abs(q).mean():.1e}"
                  f", of p_w {np.ptp(p) / np.abs(p).mean():.1e}", flush=True)


class _Reached(Exception):
    """Raised to stop the run at the step a study wants."""


def _steps(times):
    """``(model, points, t0, t1)`` at the start of the PARDISO run's steps that end at
    ``times``."""
    taken, step = [], soilwater.efg.solver._step

    def capture(model, points, t0, t1, stats):
        if any(abs(t1 - t) < 1e-9 for t in times):
            taken.append((model, points, t0, t1))
            if len(taken) == len(times):
                raise _Reached
        return step(model, points, t0, t1, stats)

    soilwater.efg.solver._step = capture
    try:
        with linear_solver("pardiso"):
            soilwater.efg.solver.solve(case(), progress=False)
    except _Reached:
        pass
    finally:
        soilwater.efg.solver._step = step
    return taken


def tangent(times):
    """``--tangent``: finite differences and preconditioners at ``times``."""
    rng = np.random.default_rng(0)
    for model, points, t0, t1 in _steps(times):
        timings = dict.fromkeys(TIMERS, 0.0)
        disc = soilwater.efg.discretisation.discretise(model, points.nodes,
                                      np.vstack([points.nodes, points.probes]), timings,
                                      points.cells)
        system = soilwater.efg.system.System(model, points, disc, t0, t1, timings)
        first, scale = None, None
        for iterate in range(3):
            R, residual = system.residual()
            K = system.tangent()
            dx = spla.spsolve(K.tocsc(), -R)
            n = system.n
            if scale is None:
                scale = np.abs(dx[:2 * n]).max(), np.abs(dx[2 * n:3 * n]).max()
                first = Krylov(K, system.layout)
            print(f"t = {t1:4.1f} s, iterate {iterate}, scaled residual {residual:.1e}")
            directions = {
                "Newton": dx * scale[0] / np.abs(dx[:2 * n]).max(),
                "random u": np.r_[scale[0] * rng.standard_normal(2 * n), 0 * dx[2 * n:]],
                "random p": np.r_[0 * dx[:2 * n], scale[1] * rng.standard_normal(n),
                                  0 * dx[3 * n:]]}
            for name, v in directions.items():
                print(f"  {name:8s}", "; ".join(_difference(system, K, v, h, n)
                                                for h in (1e-3, 1e-4, 1e-5)))
            print("  " + _preconditioners(K, R, system.layout, first), flush=True)
            system.advance(dx)


def _difference(system, K, v, h, n):
    """Central difference of the residual along ``v`` against ``K v``: the relative
    error of the displacement and the pressure rows. The system is left at its
    iterate."""
    values = []
    for step in (h * v, -2 * h * v):
        system.advance(step)
        values.append(system.residual()[0])
    system.advance(h * v)
    error, Kv = (values[0] - values[1]) / (2 * h) - K @ v, K @ v
    rows = slice(0, 2 * n), slice(2 * n, 3 * n)
    u, p = (np.linalg.norm(error[r]) / max(np.linalg.norm(Kv[r]), 1e-300) for r in rows)
    return f"h {h:.0e}: u {u:.1e}, p {p:.1e}"


def _preconditioners(K, R, layout, first):
    """Negative eigenvalues of the scaled displacement block, and FGMRES iterations to
    1e-8 with three preconditioners."""
    own = Krylov(K, layout)
    nu = own.sizes[0]
    A = scaled_tangent(K, own, nu).toarray()
    eigenvalues = np.linalg.eigvalsh((A + A.T) / 2)
    first.adopt(K)
    counts = {"own": _iterations(own, R), "step's first": _iterations(first, R)}
    own.amg_u = spla.splu(sp.csc_matrix(A)).solve
    counts["exact A"] = _iterations(own, R)
    return (f"A: {np.sum(eigenvalues < 0)} negative eigenvalues of {nu} (smallest "
            f"{eigenvalues.min():.1e}, largest {eigenvalues.max():.1e}); FGMRES to 1e-8: "
            + ", ".join(f"{k} {v}" for k, v in counts.items()))


def _iterations(krylov, R):
    before = krylov.iterations
    try:
        krylov.solve(-R, rtol=1e-8)
    except ConvergenceError:
        return f"failed after {krylov.iterations - before}"
    done = krylov.iterations - before
    return f"{done}" + (" (unfinished)" if done >= MAX_ITERATIONS else "")


if __name__ == "__main__":
    if sys.argv[1:] == ["--branches"]:
        branches()
    elif sys.argv[1:2] == ["--tangent"]:
        tangent([float(t) for t in sys.argv[2:]] or [2.0, 8.0, 11.6, 14.0, 18.4])
    else:
        sys.exit("usage: python docs/post_peak_study.py --branches | --tangent [t ...]")
