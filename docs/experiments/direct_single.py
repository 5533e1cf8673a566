"""PARDISO's factorisation in single precision against double, on tangents, steps and runs.

Quoted by ``docs/studies/direct.rst`` ("Single precision"). Per size, PARDISO's
factorisation of the first tangent of the bench step as the Krylov sizes run it (EFG,
Nitsche, stabilised) in double and in single precision: time, flops, perturbed pivots,
the factor's memory (``iparm(17)``) and the scaled residual after each refinement of one
solve. Then one bench step of each of ``--methods`` with each precision, each in its own
forked process (step and solve time, Newton iterations, factorisations, peak memory);
then whole runs (as ``krylov_runs.py``, and EFG's with the perturbation) with each:
Newton iterations, factorisations, cut-backs, and the largest difference of p, q and the
settlement relative to their range. Single precision is forced on every discretisation
that suits an iterative solver (:attr:`soilwater.linalg.layout.Layout.iterative`),
whether it asks for it (:attr:`soilwater.linalg.layout.Layout.single`) or not, through
the layout each step's tangents are solved with (:func:`common.solve`). Needs pypardiso.

``python docs/experiments/direct_single.py [nodes ...]`` (default 3e4 1e5; about 20
minutes on 2 cores).
"""

import dataclasses
import time

import numpy as np
import scipy.sparse as sp

from soilwater.errors import InputError
from soilwater.linalg import backends
from soilwater.linalg.pardiso import _Pardiso
from soilwater.studies.bench.runs import in_child

from common import (LIMIT, RUNS, bench_step, compare_runs, count, first_tangent, parsed,
                    parser, printed, run_spec)

#: The whole runs: :data:`common.RUNS` and EFG's with the perturbation.
SINGLE_RUNS = RUNS + (("unconfined-compression", "efg", "nitsche", "perturbation"),
                      ("terzaghi", "efg", "nitsche", "perturbation"))
KEYS = ("step", "solve", "iterations", "factorisations", "single_factorisations",
        "peak_mb")


def precision(single):
    """``layout -> layout`` factorised in single precision if ``single`` and the
    discretisation suits an iterative solver, else in double."""
    def laid_out(layout):
        return dataclasses.replace(layout, single=single and layout.iterative)
    return laid_out


def factorisations(nodes):
    """PARDISO's double and single factorisation of the first bench tangent, and the
    scaled residual of one solve after each refinement; one row each."""
    K, layout = first_tangent(nodes, krylov=True)
    K = sp.csr_matrix(K)
    b = np.random.default_rng(0).standard_normal(K.shape[0]) * layout.scales
    print(f"{nodes} nodes, {K.shape[0]} unknowns", flush=True)
    rows = []
    for scales in (None, layout.scales):
        tic = time.perf_counter()
        lu = _Pardiso(K, layout.groups, scales=scales)
        built = time.perf_counter() - tic
        tic, history = time.perf_counter(), []
        if lu.single:
            lu._refined(b, history)
        else:
            history.append(np.linalg.norm((b - K @ lu.solve(b)) / layout.scales)
                           / np.linalg.norm(b / layout.scales))
        row = {"nodes": nodes, "precision": "single" if lu.single else "double",
               "factorisation": built, "flops": lu.flops, "residuals": history,
               "factor_mb": lu.solver.get_iparm(17) / 1e3,
               "each": (time.perf_counter() - tic) / len(history)}
        print(f"  {row['precision']}: analysis and factorisation {built:.1f} s, "
              f"{lu.flops:.2e} flops, {lu.perturbed_pivots} perturbed pivots, factor "
              f"{row['factor_mb']:.0f} MB (iparm 17); "
              f"{'refinements' if lu.single else 'back-solve'} {row['each']:.2f} s each, "
              "scaled residual after each", " ".join(f"{h:.1e}" for h in history),
              flush=True)
        rows.append(row)
        del lu
    return rows


def main(argv=None):
    """Measure; return the rows of the factorisations (``residuals``), the steps
    (``status``) and the whole runs (:func:`common.compare_runs`), in that order."""
    made = parser(__doc__, overrides=True)
    made.add_argument("sizes", nargs="*", type=count, default=[30_000, 100_000],
                      help="requested node counts")
    made.add_argument("--methods", nargs="*", default=["efg", "fem-th", "fem-p1p1-stab"],
                      help="methods of the bench steps")
    made.add_argument("--run", action="append", type=run_spec, dest="runs",
                      metavar="CASE:METHOD[:ESSENTIAL[:STABILISATION]]",
                      help="a whole run (repeatable; default: the seven of SINGLE_RUNS)")
    made.add_argument("--limit", type=float, default=LIMIT, help="seconds per step")
    rows = []
    with parsed(made, argv) as args:
        if not backends.SINGLE:
            raise InputError("soilwater.linalg.backends.SINGLE is off: PARDISO factorises "
                             "in double only; set it back to True for this study")
        for nodes in args.sizes:
            rows += factorisations(nodes)
            for method in args.methods:
                for single in (False, True):
                    name = "single" if single else "double"
                    row, status = in_child(bench_step, method, nodes, "pardiso",
                                           precision(single), timeout=args.limit)
                    printed(f"  {method} step, {name}:", row, KEYS, status)
                    rows.append({**(row or {}), "precision": name, "status": status})
        variants = {"double": ("pardiso", precision(False)),
                    "single": ("pardiso", precision(True))}
        rows += compare_runs(args.runs or SINGLE_RUNS, variants, args.overrides)
    return rows


if __name__ == "__main__":
    main()
