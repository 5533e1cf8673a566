"""The writers of ``make bench``: the Markdown report, the CSV of every run and the figure.

:func:`write` takes what :func:`soilwater.studies.bench.study.run` measured and writes
``<root>/bench.md``, ``<root>/tables/bench.csv`` and ``<root>/figures/bench.png``.
"""

import os
import platform
import time

import numpy as np
import skfem

from soilwater.studies.bench.analysis import AGAINST, rates, ratios, schemes
from soilwater.studies.bench.plan import (BOTH_FROM, KRYLOV_FROM, LARGE_FROM, LARGE_MATERIALS,
                                          LARGE_METHODS, LARGE_TIME_LIMIT, METHODS, SCHEMES,
                                          TIME_LIMIT, direct)
from soilwater.studies.bench.runs import COUNTS, PHASES
from soilwater.studies.harness import figures
from soilwater.studies.harness.machine import cpu, ram_gb


def machine():
    """One line naming the machine, its memory, the solvers and the main versions."""
    import numba
    import scipy

    return (f"{cpu()}, {os.cpu_count()} cores, {ram_gb():.1f} GB; linear solver {direct()} "
            f"below {KRYLOV_FROM} nodes, krylov from there (and from {BOTH_FROM} for "
            f"{', '.join(LARGE_METHODS)}); Python "
            f"{platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, "
            f"scikit-fem {skfem.__version__}, numba {numba.__version__}")


def figure(table, path):
    """Log-log time against nodes, one panel per phase: a colour per FEM method and per
    EFG scheme; Cam-clay solid with circles, elastic dashed with squares (diamonds for EFG
    with Nitsche's conditions and the perturbation); a line per solver, filled markers on
    the direct one, open ones on the iterative one (``krylov``); in the step panel, a run
    stopped at its time limit is a triangle at that limit (its time is longer). Runs that
    died or did not run are not drawn (the tables list them)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, axes = plt.subplots(2, 3, figsize=(12, 7), sharex=True, constrained_layout=True)
    colours = dict(zip([*METHODS[1:], *(f"efg {scheme}" for scheme in SCHEMES)],
                       ("C1", "C2", "C3", "C0", "C4", "C5"), strict=True))
    named = table.assign(curve=np.where(table.method == "efg",
                                        "efg " + table.integration, table.method))
    ok = named[named.status == "ok"]
    for ax, phase in zip(axes.ravel(), PHASES, strict=True):
        for (curve, material, efg), group in ok.groupby(["curve", "material", "efg"],
                                                        sort=False):
            if not group[phase].notna().any():
                continue
            colour = colours[curve]
            marker = ("D" if efg.startswith("nitsche") else "o") if material == "cam-clay" \
                else ("d" if efg.startswith("nitsche") else "s")
            label = f"{curve}, {material}" + (f" ({efg})" if efg != "-" else "")
            for krylov, part in group.groupby(group.solver == "krylov"):
                ax.loglog(part.nodes, part[phase], ("-" if material == "cam-clay" else "--")
                          + marker, color=colour, ms=4, mfc="none" if krylov else colour,
                          label=label)
                label = None
        if phase == "step":
            stopped = named[named.status.str.startswith("stopped")]
            for curve, group in stopped.groupby("curve"):
                ax.loglog(group.nodes, group.limit_s, "^", color=colours[curve], ms=7,
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
    figures.save(fig, path, dpi=120)


def write(path, table, shapes, growth, phases, scale, yardstick, tic):
    """Write the Markdown report at ``path``, ``tables/bench.csv`` and
    ``figures/bench.png`` beside it.

    Parameters
    ----------
    path : str
        The Markdown file; its folder gets ``tables/`` and ``figures/``.
    table : pandas.DataFrame
        The rows of :func:`soilwater.studies.bench.runs.steps`.
    shapes : pandas.DataFrame
        :func:`soilwater.studies.bench.runs.shape_functions`' rows.
    growth, phases, scale : pandas.DataFrame
        :func:`~soilwater.studies.bench.analysis.exponents`,
        :func:`~soilwater.studies.bench.analysis.phase_targets` and
        :func:`~soilwater.studies.bench.analysis.scale_targets` of the rows.
    yardstick : dict
        :func:`soilwater.studies.harness.machine.dgemm`'s rates [GF/s].
    tic : float
        ``time.perf_counter()`` at the start of the run: the report gives its length.
    """
    from soilwater.studies.harness.tables import to_markdown

    root = os.path.dirname(path) or "."
    table.to_csv(os.path.join(root, "tables", "bench.csv"), index=False)
    figure(table, os.path.join(root, "figures", "bench.png"))
    largest = table[table.nodes == table.nodes.max()]
    memory = ", ".join(f"{r.method} {r.integration} {r.material} "
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
        f"EFG runs once per integration scheme ({', '.join(SCHEMES)}; the "
        "`integration` column, - for FEM) wherever it runs. "
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
        "the interpreter and libraries included. `points_per_node` is the domain's "
        "integration points (the material points) per node of the grid and "
        "`entries_per_row` the stored entries of the step's first Newton tangent per row "
        "(nnz over the unknowns the linear solver gets), both read off the solver's own "
        "step objects in a child of their own, once per size, method and scheme. A run "
        "the plan skips is a row whose status says why.", "",
        "## Targets at scale (EFG step, memory and growth to 10^6 nodes)", "",
        "A target whose run did not complete is \"not measured\"; `where` gives the "
        "run's status and, when it bounds the value, the bound.", "",
        to_markdown(scale, "{:.3g}"),
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
        "## Targets per phase (EFG against FEM)", "", to_markdown(phases, "{:.3g}"),
        f"## EFG schemes against {AGAINST} at equal nodes", "",
        f"Per EFG run: its scheme's size ({', '.join(COUNTS)}; `fem_...` the same of "
        f"{AGAINST}), its step [s] and EFG / {AGAINST} per phase, on the same grid, "
        "material and linear solver (- where either run did not complete).", "",
        to_markdown(schemes(table), "{:.3g}"),
        "## Phase times [s]", "",
        to_markdown(table[["method", "integration", "material", "nodes", "solver", "efg",
                           "status", *COUNTS, *PHASES]], "{:.3g}"),
        "## Counts, memory and rates", "",
        "Newton `iterations` summed over the step, `linear_iterations` the Krylov "
        "iterations (- where the back-end reports none), `factor_flops` as above, "
        "`limit_s` the run's time limit [s].", "",
        to_markdown(table[["method", "integration", "material", "nodes", "solver", "efg",
                           "dofs", "iterations",
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
