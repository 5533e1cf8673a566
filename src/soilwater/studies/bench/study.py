"""``make bench``: speed and scale as ratios against scikit-fem in the same run.

Three measurements, all on this machine in one command (never timed tests):

1. **dgemm**, the yardstick of the factorisation's rate: ``C = A B`` of two
   3000 x 3000 float64 matrices through NumPy's BLAS and through MKL's ``cblas_dgemm``
   (the library PARDISO runs on), GF/s = 2 n^3 / best time. OpenBLAS reads
   ``OPENBLAS_CORETYPE`` and ``OPENBLAS_L2_SIZE`` when NumPy loads it, so ``make bench``
   unsets both for this command only (``env -u`` in the Makefile); the run records the
   kernel it got.
2. **One coupled step** of the unconfined-compression geometry (grid layout, 3 x 4 m, one
   step of 0.2 % axial strain) at about 10^3, 3 x 10^3, ..., 10^6 nodes
   (:data:`~soilwater.studies.bench.plan.SIZES`) for ``efg``, ``fem-p1p1``, ``fem-th``
   and ``fem-p1p1-stab`` on the same vertices, with the Cam-clay skeleton of the case and
   with a linear elastic one, EFG once per integration scheme (``efg.integration`` =
   paper, gauss, nodal: :data:`~soilwater.studies.bench.plan.SCHEMES`) wherever it runs.
   The rule that bounds the whole run: from 3 x 10^5 nodes
   (:data:`~soilwater.studies.bench.plan.LARGE_FROM`) only ``efg`` and ``fem-p1p1-stab``
   with Cam-clay run, and a run is stopped after 900 s there, 240 s below
   (:func:`~soilwater.studies.bench.plan.time_limit`); there ``nodal`` is skipped
   (:data:`~soilwater.studies.bench.plan.SKIPS`), so the large runs take at most
   6 x 900 s (4 x 900 s, and 28 minutes in all on 2 cores, before the schemes). The
   linear solver is chosen by size (:func:`~soilwater.studies.bench.plan.solver_for`):
   the direct one, PARDISO where ``pypardiso`` is installed, else SuperLU, below
   3 x 10^5 nodes
   (:data:`~soilwater.studies.bench.plan.KRYLOV_FROM`), and
   ``soilwater.linalg.backends.linear_solver("krylov")`` from there, where EFG runs with
   Nitsche's conditions and the perturbation stabilisation, as the Krylov back-end needs
   (:func:`~soilwater.studies.bench.plan.compression`; the ``efg`` column says which).
   From 10^4 nodes (:data:`~soilwater.studies.bench.plan.BOTH_FROM`) EFG and
   ``fem-p1p1-stab`` also run on Krylov below 3 x 10^5, with either skeleton, so the
   scale targets take each on its faster solver, measured, and on PARDISO EFG runs a
   second time with Nitsche's conditions and the perturbation: PARDISO factorises such a
   tangent (and fem-th's) in single precision (``soilwater.linalg.layout.Layout.single``;
   the ``single_factorisations`` column). The solvers' own phase timers
   (:data:`soilwater.nonlinear.history.TIMERS`) give shape functions (FEM: basis
   construction), background cells (FEM: moving the mesh), assembly of the tangent, linear
   solve (analysis, factorisations and back-substitutions), constitutive update, and the
   whole step; each row adds the solver, Newton and Krylov iterations, the flops of the
   factorisations and their rate (a lower bound: flops / solve time), and peak memory per
   node, and the size of the step's discretisation: integration points per node and
   stored entries per row of its first Newton tangent
   (:func:`~soilwater.studies.bench.runs.counts`). Each EFG scheme is set against
   ``fem-p1p1-stab`` at equal nodes (:func:`~soilwater.studies.bench.analysis.schemes`).
   Each run is a forked child process, so its peak resident memory is its own; a run
   stopped, killed (out of memory) or failed, or whose solver is not available here, is a
   row with its status, and so is a run the plan skips, with the plan's reason.
3. **Shape functions alone** up to 10^5 nodes: MLS values and gradients against
   scikit-fem's ``CellBasis`` construction (P1 and P2) at the same quadrature points
   (3 per triangle of the Delaunay triangulation of the nodes).

Writes ``reports/bench.md`` (the targets at scale and per phase, factorisation rate
against dgemm, the schemes against fem-p1p1-stab, ratios, growth exponents, memory),
``reports/tables/bench.csv`` (every run) and ``reports/figures/bench.png``. The jobs have
their own modules: :mod:`~soilwater.studies.bench.plan` (which runs),
:mod:`~soilwater.studies.bench.runs` (the forked steps, the discretisations' sizes and
shape functions), :mod:`soilwater.studies.harness.machine` (dgemm
and the machine), :mod:`~soilwater.studies.bench.analysis` (ratios, exponents, targets)
and :mod:`~soilwater.studies.bench.report` (Markdown, CSV, figure).
"""

import os
import time

import numpy as np

from soilwater.studies.bench.analysis import exponents, phase_targets, scale_targets
from soilwater.studies.bench.plan import SHAPES_UP_TO, SIZES
from soilwater.studies.bench.report import write
from soilwater.studies.bench.runs import in_child, shape_functions, steps
from soilwater.studies.harness.machine import DGEMM_N, cpu, dgemm


def run(path="reports/bench.md", sizes=SIZES):
    """Run the benchmarks, write the Markdown, CSV and figure, and print the targets.

    The dgemm yardstick (:func:`~soilwater.studies.harness.machine.dgemm`, in its own
    child), then one step of every run of :func:`~soilwater.studies.bench.plan.plan`
    (:func:`~soilwater.studies.bench.runs.steps`), then shape functions alone up to
    :data:`~soilwater.studies.bench.plan.SHAPES_UP_TO` nodes
    (:func:`~soilwater.studies.bench.runs.shape_functions`); the report is
    :func:`soilwater.studies.bench.report.write`'s.

    Returns
    -------
    pandas.DataFrame
        The rows of :func:`~soilwater.studies.bench.runs.steps`.
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
    phases = phase_targets(table, shapes, growth)
    scale = scale_targets(table, cpu())
    write(path, table, shapes, growth, phases, scale, yardstick, tic)
    print(to_markdown(scale, "{:.3g}"))
    print(to_markdown(phases, "{:.3g}"))
    return table
