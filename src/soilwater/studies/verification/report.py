"""The verification sections: the problems, the EFG core (shape functions, background
cells, patch test, cantilever convergence) and the stress paths of the unconfined
compression and simple shear (Figs. 4 and 6)."""

from pathlib import Path

from soilwater.studies.harness import tables
from soilwater.studies.harness.tables import below_noise, marked
from soilwater.studies.verification import figures as core_figures
from soilwater.studies.verification import path_figures, study

NAME = "verification"
#: Columns of the path summary that depend on the branch round-off chose.
BRANCH_PATHS = ("path_error", "err_max", "err_final")


def run(root, inputs):
    """The tables ``patch_test``, ``efg_convergence``, ``stress_paths`` and
    ``stress_paths_summary`` and the figures of :func:`figures`; returns them as
    ``{"patch", "convergence", "paths", "path summary"}``."""
    patch = study.patch_test()
    convergence = study.cantilever_convergence(corrections=("vci", "none"))
    paths = study.stress_paths()
    summary = study.path_summary(paths)
    for table, stem in ((patch, "patch_test"), (convergence, "efg_convergence"),
                        (paths, "stress_paths"), (summary, "stress_paths_summary")):
        tables.write(table, root / "tables" / stem)
    data = {"patch": patch, "convergence": convergence, "paths": paths,
            "path summary": summary}
    figures(root, data)
    return data


def figures(root, data):
    """The figures ``problems``, ``shape_functions``, ``cells`` (drawn from the built-in
    cases, no run), ``efg_convergence``, ``fig4_stress_paths``, ``fig4_path_errors`` and
    ``fig6_err`` under ``root/figures``, from :func:`run`'s data; returns their paths."""
    folder = Path(root) / "figures"
    convergence, paths = data["convergence"], data["paths"]
    return [core_figures.problems(folder / "problems.png"),
            core_figures.shape_functions(folder / "shape_functions.png"),
            core_figures.background_cells(folder / "cells.png"),
            core_figures.efg_convergence(convergence[convergence.correction == "vci"],
                                         folder / "efg_convergence.png"),
            path_figures.stress_paths(paths, folder / "fig4_stress_paths.png"),
            path_figures.path_errors(paths, folder / "fig4_path_errors.png"),
            path_figures.err_history(paths, folder / "fig6_err.png")]


def section(data):
    """The sections' markdown lines."""
    patch = data["patch"].set_index(["cells", "correction"])
    conv = data["convergence"]
    q_rates = conv[(conv.weight == "Q") & (conv.cells == "delaunay")
                   & (conv.correction == "vci")].rate.dropna()
    uc = data["path summary"].set_index(["case", "run"]).loc["unconfined-compression"]
    return [
        "## The problems (Figs. 3 and 8)",
        "",
        "![problems](figures/problems.png)",
        "",
        "Unconfined compression: a quarter specimen, frictionless base, top moved with "
        "the constant stretching D22 of the driver test, undrained (k = 0, all edges "
        "impermeable), initial effective stress held by a negative pore pressure. Soil "
        "column: rollers on the sides, fixed base, an instantaneous load on the drained "
        "top.",
        "",
        "## EFG core: shape functions (Fig. 7), background cells (Figs. 3, 5), patch test",
        "",
        "![shape functions](figures/shape_functions.png)",
        "",
        "E-B (c = 0.25) is nearly interpolating at the paper's density; at twice the "
        "density with the same support radius it is not.",
        "",
        "![cells](figures/cells.png)",
        "",
        "Patch test (linear field imposed by penalty): with plain Gauss quadrature (the "
        "paper's scheme) the Delaunay cells miss by "
        f"{patch.loc[('delaunay', 'none'), 'displacement']:.1e} in displacement and "
        f"{patch.loc[('delaunay', 'none'), 'stress']:.1e} in stress; with variationally "
        "consistent test gradients (VCI, our default) by "
        f"{patch.loc[('delaunay', 'vci'), 'displacement']:.1e} and "
        f"{patch.loc[('delaunay', 'vci'), 'stress']:.1e} (the penalty's floor); "
        "smoothed nodal integration passes it with or without VCI ("
        f"{patch.loc[('nodal', 'none'), 'stress']:.1e} in stress without). "
        "Cantilever energy-norm convergence rates for Q on Delaunay cells: "
        + ", ".join(f"{r:.2f}" for r in q_rates) + ".",
        "",
        "![convergence](figures/efg_convergence.png)",
        "",
        "## Unconfined compression and simple shear (Figs. 4 and 6)",
        "",
        "![fig4](figures/fig4_stress_paths.png)",
        "![fig4 path errors](figures/fig4_path_errors.png)",
        "![fig6](figures/fig6_err.png)",
        "",
        "Largest distance of the averaged path from the driver (over p'0) and ERR "
        "(paper eq. 1), before the discrete onset of the loss of uniqueness (`onset`, "
        "axial strain; below) and over the whole run; † marks numbers that depend on the "
        "branch round-off chose past the onset (they differ between CPUs and linear "
        "solvers):",
        "",
        tables.to_markdown(marked(below_noise(data["path summary"]), BRANCH_PATHS),
                           floatfmt="{:.3g}"),
        "The path error before the onset, "
        f"{uc.loc['EFG, Delaunay cells', 'path_error_before']:.3g} p'0 for EFG and "
        f"{uc.loc['FEM Taylor-Hood (fem-th)', 'path_error_before']:.3g} for fem-th, is "
        "the first-order time error of the return mapping (100 steps), the same for "
        "every method with consistent quadrature.",
    ]
