"""Newton's iterations on the Krylov back-end per forcing cap, and modified and full Newton.

Quoted by ``docs/studies/krylov.rst`` (the Krylov back-end's inexact Newton). The bench
step (:func:`soilwater.studies.bench.plan.compression`, EFG with Nitsche's conditions and
the perturbation stabilisation) on the Krylov back-end with each largest forcing (the
step's :attr:`soilwater.linalg.layout.Layout.forcing`, EFG's
:data:`soilwater.efg.system.FORCING` by default): the scaled residuals and the step's
FGMRES iterations. Then, beside them, modified Newton on Krylov
(:attr:`soilwater.linalg.krylov.Krylov.current` off: the step's first tangent kept while
it contracts the residual tenfold, as PARDISO's factorisation is) and full Newton on
PARDISO (:data:`soilwater.linalg.layout.CONTRACTION` 0: the current tangent factorised at
every iteration; in double precision, since with no contraction asked a single factor's
refinement would stop at once and redo it in double). Neither switch is an argument of
the library: each is set for its run only (:func:`common.scoped`).

``python docs/experiments/krylov_newton.py --nodes 3000 --forcings 1e-2 1e-4 1e-5 1e-6``
(the defaults; under a minute on 2 cores).
"""

import argparse
import time

import soilwater.linalg.layout
from soilwater.errors import ConvergenceError
from soilwater.linalg.backends import linear_solver
from soilwater.linalg.krylov import Krylov
from soilwater.studies.bench.plan import compression

from common import count, parsed, parser, replaced, scoped, solve


class Traced:
    """A Newton system that prints its scaled residuals and each tangent it assembles,
    and keeps them (``residuals``, ``tangents``)."""

    def __init__(self, system):
        self.system, self.layout = system, system.layout
        self.residuals, self.tangents = [], 0

    def residual(self):
        R, scaled = self.system.residual()
        self.residuals.append(scaled)
        print(f"    residual {scaled:.3e}", flush=True)
        return R, scaled

    def tangent(self):
        self.tangents += 1
        print("    tangent assembled", flush=True)
        return self.system.tangent()

    def advance(self, dx):
        self.system.advance(dx)


def forcing(text):
    """A forcing cap from the command line: a relative residual in (0, 1)."""
    value = float(text)
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"{text!r}: use a relative residual in (0, 1)")
    return value


def traced_step(label, nodes, solver, layout=None):
    """The bench step on ``solver``, traced; its row: ``residuals`` (scaled),
    ``tangents``, FGMRES iterations (``fgmres``), ``seconds`` and ``failed``."""
    print(f"{nodes} nodes, {label}:", flush=True)
    traces = []

    def trace(system):
        traces.append(Traced(system))
        return traces[-1]

    row, tic = {"label": label, "failed": None, "fgmres": None}, time.perf_counter()
    with linear_solver(solver):
        try:
            summary = solve(compression(nodes, krylov=True), "efg", layout=layout,
                            system=trace).summary
            row["fgmres"] = summary["linear_iterations"]
        except ConvergenceError as err:
            row["failed"] = str(err)
            print(f"    failed: {err}", flush=True)
    row.update(seconds=time.perf_counter() - tic,
               residuals=[r for t in traces for r in t.residuals],
               tangents=sum(t.tangents for t in traces))
    print(f"    FGMRES iterations {row['fgmres']}, step {row['seconds']:.1f} s", flush=True)
    return row


def main(argv=None):
    """Run the traced steps; return their rows (:func:`traced_step`)."""
    made = parser(__doc__)
    made.add_argument("--nodes", type=count, default=3_000, help="requested node count")
    made.add_argument("--forcings", nargs="+", type=forcing, default=[1e-2, 1e-4, 1e-5, 1e-6],
                      help="largest forcings of the Krylov runs, each in (0, 1)")
    made.add_argument("--direct", default="pardiso", choices=["pardiso", "superlu"],
                      help="the direct solver of the full-Newton run")
    with parsed(made, argv) as args:
        rows = [traced_step(f"krylov, largest forcing {forcing:g}", args.nodes, "krylov",
                            replaced(forcing=forcing)) for forcing in args.forcings]
        with scoped(Krylov, "current", False):
            rows.append(traced_step("krylov, modified Newton", args.nodes, "krylov"))
        with scoped(soilwater.linalg.layout, "CONTRACTION", 0.0):
            rows.append(traced_step(f"{args.direct}, full Newton", args.nodes, args.direct,
                                    replaced(single=False)))
    return rows


if __name__ == "__main__":
    main()
