"""Pictures of the strip-footing runs: the deformed configurations
coloured by shear strain and the excess pore pressure (the animations are
:mod:`soilwater.studies.footing.gif`).

Every picture is drawn from :class:`soilwater.results.Result` objects of the built-in
``strip-footing`` case (or a variant with one footing segment on the top edge), from the
node positions and nodal fields of their snapshots; the shear strain is
:mod:`soilwater.studies.harness.deformation`'s ``eps_s`` on a triangulation of the initial
nodes. The views show the window of :mod:`soilwater.studies.footing.view`. Files are
written whole or not at all (:func:`written`: a temporary file renamed into place).
"""

import os
import tempfile
import textwrap
from contextlib import contextmanager
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.colors import Normalize
from matplotlib.ticker import MaxNLocator
from matplotlib.tri import Triangulation

from soilwater.studies.harness import deformation
from soilwater.studies.footing.study import DENSITIES
from soilwater.studies.footing.view import STRAIN_LABEL, RunView, strain_norm, window_top
from soilwater.studies.harness.footing import CASE, PLAIN
from soilwater.studies.harness.grids import refined
from soilwater.studies.harness.runs import solved
from soilwater.geometry.quality import DISTORTED

#: Spacings per B at the footing of the runs the report draws: the built-in case's.
CORE = DENSITIES[len(DENSITIES) // 2]
#: Distance from the footing's edge [B] within which :func:`measures` takes the largest
#: eps_s ("under the footing edge").
EDGE_RADIUS = 0.5
#: Percentiles of the excess pore pressures in view that the contour levels span;
#: values beyond take the end colours (the titles give the full range).
LEVEL_PERCENTILES = (1.0, 99.0)
PRESSURE_LABEL = "excess pore pressure p_w - p_w0 [kPa], compression positive"


def runs(core=CORE, methods=PLAIN):
    """The footing study's runs of each method with ``core`` spacings per B at the
    footing (through the cached runner: the runs of :func:`soilwater.studies.footing.study.curves`
    are reused). The default, :data:`soilwater.studies.harness.footing.PLAIN`, leaves out re-meshed
    Taylor-Hood: its pictures and GIF would carry the name of its method, ``fem-th``,
    and the elements drawn would be its initial mesh's, not the re-meshed ones.

    Returns
    -------
    list of soilwater.results.Result
    """
    return solved([(CASE, (*refined(core), *extra), method)
                   for method, extra in methods.values()])


@contextmanager
def written(path):
    """A temporary path beside ``path`` (same suffix), renamed to ``path`` when the
    block succeeds and removed when it fails."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.",
                               suffix=path.suffix)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o644)  # mkstemp's 0o600 is for the temporary name only
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


def _panels(count, title):
    """A figure of ``count`` panels side by side under ``title`` (wrapped to fit)."""
    size = 3.7 * count + 1.1
    fig, axes = plt.subplots(1, count, figsize=(size, 5.1), sharey=True,
                             layout="compressed", squeeze=False)
    fig.suptitle(textwrap.fill(title, int(12 * size)), fontsize=11)
    return fig, axes[0]


def _save(fig, path):
    try:
        with written(path) as tmp:
            fig.savefig(tmp, dpi=150)
    finally:
        plt.close(fig)
    return Path(path)


def deformed_figure(results, path):
    """``path`` (PNG): each run's final level side by side, coloured by eps_s on one
    scale (EFG nodes, FEM elements with the distorted ones outlined), the footing drawn.

    Parameters
    ----------
    results : list of soilwater.results.Result
        Strip-footing runs (EFG: point cloud, FEM: snapshots with cells).
    path : str or Path

    Returns
    -------
    Path
    """
    runs = [RunView(r) for r in results]
    norm, top = strain_norm(runs), window_top(runs)
    fig, axes = _panels(len(runs), "Strip footing at its last level: EFG nodes and FEM "
                        "elements coloured by shear strain")
    for ax, run in zip(axes, runs):
        mappable, show = run.strain_view(ax, norm)
        counts = show(run.final)
        run.window(ax, top)
        s, p = run.loads(run.final)
        ax.set_title(f"{run.label}\nsettlement {s / run.B:.2f} B, pressure {p:.3g} kPa",
                     fontsize=10)
        if counts is not None:
            ax.text(0.97, 0.03, f"red: smallest angle < {DISTORTED:.2g} of its start, "
                    f"{counts[0]} elements\nmagenta: inverted, {counts[1]}",
                    transform=ax.transAxes, ha="right", va="bottom", fontsize=8,
                    bbox={"facecolor": "white", "alpha": 0.85, "edgecolor": "none"})
    for ax in axes[1:]:
        ax.set_ylabel("")
    fig.colorbar(mappable, ax=axes.tolist(), shrink=0.8, label=STRAIN_LABEL)
    return _save(fig, path)


def _pressure_levels(runs, fields):
    """Contour levels over :data:`LEVEL_PERCENTILES` of the nodal values in view, and a
    colour scale centred on zero (white)."""
    pooled = np.concatenate([field[run.in_view(run.result.snapshots[run.final].points)]
                             for run, field in zip(runs, fields)])
    low, high = np.percentile(pooled, LEVEL_PERCENTILES)
    levels = MaxNLocator(16).tick_values(low, high)
    reach = np.abs(levels).max()
    return levels, Normalize(-reach, reach)


def pore_pressure_figure(results, path):
    """``path`` (PNG): excess pore pressure p_w - p_w0 [kPa, compression positive] at
    each run's final level, filled contours on the deformed configuration (the
    triangulation of :func:`soilwater.studies.harness.deformation.triangulation` on the current node
    positions), the same levels in every panel (:func:`_pressure_levels`).

    Returns
    -------
    Path
    """
    runs = [RunView(r) for r in results]
    fields = [run.excess_pressure(run.final) for run in runs]
    levels, norm = _pressure_levels(runs, fields)
    top = window_top(runs)
    fig, axes = _panels(len(runs), "Strip footing at its last level: excess pore "
                        "pressure on the deformed configuration (levels: percentiles "
                        "{:g} to {:g} in view)".format(*LEVEL_PERCENTILES))
    for ax, run, field in zip(axes, runs, fields):
        points = run.result.snapshots[run.final].points
        filled = ax.tricontourf(Triangulation(*points.T, run.triangles), field,
                                levels=levels, cmap="RdBu_r", norm=norm, extend="both")
        run.footing(ax, run.final)
        run.window(ax, top)
        seen = field[run.in_view(points)]
        ax.set_title(f"{run.label}, settlement {run.loads(run.final)[0] / run.B:.2f} B\n"
                     f"in view {seen.min():.3g} to {seen.max():.3g} kPa", fontsize=10)
    for ax in axes[1:]:
        ax.set_ylabel("")
    fig.colorbar(filled, ax=axes.tolist(), shrink=0.8, label=PRESSURE_LABEL)
    return _save(fig, path)


def measures(results):
    """What the pictures show, measured per run.

    Returns
    -------
    pandas.DataFrame
        One row per run: ``method``, ``nodes``, ``reached`` (last settlement over B),
        ``eps_s_edge`` (largest triangle eps_s at the last level within
        :data:`EDGE_RADIUS` B of the footing's edge, by initial centroid),
        ``distorted`` and ``inverted`` (FEM elements at the last level with a smallest
        angle below :data:`soilwater.geometry.quality.DISTORTED` of its undeformed value / not above
        0; empty for EFG), ``dp_min``, ``dp_max`` (excess pore pressure in view at the
        last level [kPa], compression positive).
    """
    rows = []
    for run in map(RunView, results):
        edge = np.array([run.segment.end, run.surface])
        near = (np.linalg.norm(run.initial[run.triangles].mean(1) - edge, axis=1)
                <= EDGE_RADIUS * run.B)
        last = run.result.snapshots[run.final].points
        seen = run.excess_pressure(run.final)[run.in_view(last)]
        row = {"method": run.label, "nodes": len(run.initial),
               "reached": run.loads(run.final)[0] / run.B,
               "eps_s_edge": float(np.nanmax(run.strain(run.final)[near])),
               "distorted": "", "inverted": "",
               "dp_min": float(seen.min()), "dp_max": float(seen.max())}
        if not run.cloud:
            last = deformation.smallest_angles(run.result.snapshots[-1:], run.triangles)[0]
            row.update(distorted=int((last < DISTORTED * run.angle0).sum()),
                       inverted=int((last <= 0).sum()))
        rows.append(row)
    return pd.DataFrame(rows)
