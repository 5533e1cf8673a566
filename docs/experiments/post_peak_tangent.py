"""Past the peak: is the tangent right, and what does the preconditioner make of it?

Quoted by ``docs/studies/krylov.rst`` ("Past the peak the homogeneous solution is
unstable, and the solver picks the branch"). The case of ``post_peak_branches.py``
(:data:`post_peak_branches.GRID`) run on PARDISO (``--solver``) up to the steps that end
at ``--times``; each such step at its start and after one and two exact Newton
corrections. Central differences of the residual, ``(R(x + h v) - R(x - h v)) / 2h`` for
each ``--steps`` h, against ``K v``: the relative error in the displacement and the
pressure rows, along the Newton correction and along random displacement and pressure
directions (scaled as the step's first correction). On the tangent's displacement
block, scaled as :class:`soilwater.linalg.krylov.Krylov` scales it: its negative
eigenvalues, and FGMRES iterations to 1e-8 on ``-R`` with the tangent's own
preconditioner, with the preconditioner of the step's first tangent (what the Krylov
back-end keeps through a step), and with the displacement block solved exactly.

``python docs/experiments/post_peak_tangent.py --times 2 8 11.6 14 18.4`` (the defaults;
about 3 minutes on 2 cores).
"""

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.efg.discretisation import discretise
from soilwater.efg.system import System
from soilwater.errors import ConvergenceError
from soilwater.linalg.backends import linear_solver
from soilwater.linalg.krylov import MAX_ITERATIONS, Krylov
from soilwater.nonlinear.history import TIMERS

from common import parsed, parser, scaled_tangent, solve
from post_peak_branches import case


class _Reached(Exception):
    """Raised to end the run once every wanted step has started."""


def starts(study, times, solver):
    """``(model, points, t0, t1)`` at the start of the steps of ``study`` run on
    ``solver`` that end at ``times`` (those the run reaches)."""
    taken = []

    def capture(model, points, t0, t1):
        if any(abs(t1 - t) < 1e-9 for t in times):
            taken.append((model, points, t0, t1))
            if len(taken) == len(times):
                raise _Reached

    with linear_solver(solver):
        try:
            solve(study, "efg", on_step=capture)
        except _Reached:
            pass
    return taken


def difference(system, K, v, h, n):
    """Central difference of the residual along ``v`` against ``K v``: the relative
    errors of the displacement and the pressure rows. The system is left at its
    iterate."""
    values = []
    for step in (h * v, -2 * h * v):
        system.advance(step)
        values.append(system.residual()[0])
    system.advance(h * v)
    error, Kv = (values[0] - values[1]) / (2 * h) - K @ v, K @ v
    rows = slice(0, 2 * n), slice(2 * n, 3 * n)
    return tuple(float(np.linalg.norm(error[r]) / max(np.linalg.norm(Kv[r]), 1e-300))
                 for r in rows)


def iterations(krylov, R):
    """FGMRES iterations of one solve to 1e-8, or how it failed."""
    before = krylov.iterations
    try:
        krylov.solve(-R, rtol=1e-8)
    except ConvergenceError:
        return f"failed after {krylov.iterations - before}"
    done = krylov.iterations - before
    return f"{done}" + (" (unfinished)" if done >= MAX_ITERATIONS else "")


def preconditioners(K, R, layout, first):
    """The scaled displacement block's eigenvalues' extremes and negative count, and
    FGMRES iterations to 1e-8 with three preconditioners."""
    own = Krylov(K, layout)
    nu = own.sizes[0]
    A = scaled_tangent(K, own, nu).toarray()
    eigenvalues = np.linalg.eigvalsh((A + A.T) / 2)
    first.adopt(K)
    counts = {"own": iterations(own, R), "step's first": iterations(first, R)}
    own.amg_u = spla.splu(sp.csc_matrix(A)).solve
    counts["exact A"] = iterations(own, R)
    return {"negative": int(np.sum(eigenvalues < 0)), "of": nu,
            "smallest": float(eigenvalues.min()), "largest": float(eigenvalues.max()),
            "fgmres": counts}


def study_step(model, points, t0, t1, steps, rng):
    """The step's three iterates: one row each (``residual``, ``differences``: direction
    -> h -> (u, p) relative errors, ``preconditioners``)."""
    timings = dict.fromkeys(TIMERS, 0.0)
    disc = discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                      timings, points.cells)
    system = System(model, points, disc, t0, t1, timings)
    first, scale, rows = None, None, []
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
        row = {"time": t1, "iterate": iterate, "residual": residual, "differences": {}}
        for name, v in directions.items():
            row["differences"][name] = {h: difference(system, K, v, h, n) for h in steps}
            print(f"  {name:8s}", "; ".join(f"h {h:.0e}: u {u:.1e}, p {p:.1e}" for h, (u, p)
                                            in row["differences"][name].items()))
        row["preconditioners"] = found = preconditioners(K, R, system.layout, first)
        print(f"  A: {found['negative']} negative eigenvalues of {found['of']} (smallest "
              f"{found['smallest']:.1e}, largest {found['largest']:.1e}); FGMRES to 1e-8: "
              + ", ".join(f"{k} {v}" for k, v in found["fgmres"].items()), flush=True)
        rows.append(row)
        system.advance(dx)
    return rows


def main(argv=None):
    """Study the steps; return one row per step and iterate (:func:`study_step`)."""
    made = parser(__doc__, overrides=True)
    made.add_argument("--times", nargs="+", type=float, default=[2.0, 8.0, 11.6, 14.0, 18.4],
                      help="ends of the steps studied [s]")
    made.add_argument("--steps", nargs="+", type=float, default=[1e-3, 1e-4, 1e-5],
                      help="finite-difference steps h")
    made.add_argument("--solver", default="pardiso", choices=["pardiso", "superlu"],
                      help="the direct solver of the run up to those steps")
    rows, rng = [], np.random.default_rng(0)
    with parsed(made, argv) as args:
        for model, points, t0, t1 in starts(case(args.overrides), args.times,
                                                 args.solver):
            rows += study_step(model, points, t0, t1, args.steps, rng)
    return rows


if __name__ == "__main__":
    main()
