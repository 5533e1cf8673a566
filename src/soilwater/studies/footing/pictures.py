"""Pictures of the strip-footing runs: the deformed configurations
coloured by shear strain and the excess pore pressure (the animations are
:mod:`soilwater.studies.footing.gif`).

Every picture is drawn from :class:`soilwater.results.Result` objects of the built-in
``strip-footing`` case (or a variant with one footing segment on the top edge), from the
node positions and nodal fields of their snapshots; the shear strain is
:mod:`soilwater.studies.harness.deformation`'s ``eps_s`` on a triangulation of the initial
nodes. The views show the window of :mod:`soilwater.studies.footing.view`, every run
drawn alike on triangles. Files are written whole or not at all
(:func:`soilwater.studies.harness.figures.save`).
"""

import textwrap

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.colors import Normalize
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator
from matplotlib.tri import Triangulation

from soilwater.studies.harness import deformation, figures
from soilwater.studies.footing.study import DENSITIES
from soilwater.studies.footing.view import (CMAP, STRAIN_LABEL, STRAIN_PERCENTILE, RunView,
                                            final_strains, strain_extend, strain_norm,
                                            window_top)
from soilwater.studies.harness.footing import CASE, PLAIN, time_steps
from soilwater.studies.harness.grids import refined
from soilwater.studies.harness.runs import solved
from soilwater.case.loader import load_case
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
    steps = f"time.steps={time_steps(load_case(CASE))}"
    return solved([(CASE, (*refined(core), *extra, steps), method)
                   for method, extra in methods.values()])


def _panels(count, title):
    """A slide (:func:`soilwater.studies.harness.figures.slide`) of ``count`` panels side
    by side sharing their axes, under ``title`` (wrapped to fit)."""
    fig, axes = figures.slide(1, count, sharex=True, sharey=True, squeeze=False)
    fig.suptitle(textwrap.fill(title, 110))
    return fig, axes[0]


def _bare(axes):
    """Leave the axis labels to the outer panels (the panels share their axes)."""
    for ax in axes[1:]:
        ax.set_ylabel("")


def deformed_figure(results, path):
    """``path`` (PNG): each run's final level side by side, every triangle coloured by
    its eps_s on one linear scale (EFG and FEM alike: the Delaunay triangles of EFG's
    initial nodes, FEM's elements; the scale of :func:`~soilwater.studies.footing.view.
    strain_norm`, larger values in the top colour, said in the legend and marked by the
    colour bar's arrow), the distorted triangles outlined, the footing drawn;
    each panel's title gives the settlement, pressure and the counts of distorted and
    inverted triangles, the legend below says what the outlines mean.

    Parameters
    ----------
    results : list of soilwater.results.Result
        Strip-footing runs.
    path : str or Path

    Returns
    -------
    Path
    """
    runs = [RunView(r) for r in results]
    norm, top = strain_norm(runs), window_top(runs)
    with figures.style():
        fig, axes = _panels(len(runs), "Strip footing at its last level: EFG and FEM alike, "
                            "each triangle of the initial nodes coloured by its shear strain")
        for ax, run in zip(axes, runs):
            mappable, show = run.strain_view(ax, norm)
            distorted, inverted = show(run.final)
            run.window(ax, top)
            s, p = run.loads(run.final)
            ax.set_title(f"{run.label}\nsettlement {s / run.B:.2f} B, {p:.3g} kPa\n"
                         f"{distorted} distorted, {inverted} inverted", fontsize=12)
            ax.grid(False)
        _bare(axes)
        fig.colorbar(mappable, ax=axes.tolist(), shrink=0.8, label=STRAIN_LABEL,
                     extend=strain_extend(runs, norm))
        top_note = (f"colours end at {norm.vmax:.2g}, percentile {STRAIN_PERCENTILE:g} in "
                    f"view; the largest, {final_strains(runs).max():.2g}, in the top "
                    "colour (arrow)")
        fig.legend(handles=[
            Patch(facecolor="none", edgecolor="red", lw=1.5,
                  label=f"distorted: smallest angle below {DISTORTED:.2g} of its initial "
                        "value"),
            Patch(facecolor="magenta", label="inverted (turned inside out)"),
            Patch(facecolor="0.35", edgecolor="k", label="rigid footing"),
            Patch(facecolor=plt.get_cmap(CMAP)(1.0), label=top_note)],
            loc="outside lower center", ncol=2)
        return figures.save(fig, path)


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
    with figures.style():
        fig, axes = _panels(len(runs), "Strip footing at its last level: excess pore "
                            "pressure on the deformed configuration (colours span "
                            "percentiles {:g} to {:g} in view; beyond, the end "
                            "colours)".format(*LEVEL_PERCENTILES))
        for ax, run, field in zip(axes, runs, fields):
            points = run.result.snapshots[run.final].points
            filled = ax.tricontourf(Triangulation(*points.T, run.triangles), field,
                                    levels=levels, cmap=figures.DIVERGING, norm=norm,
                                    extend="both")
            run.footing(ax, run.final)
            run.window(ax, top)
            ax.grid(False)
            seen = field[run.in_view(points)]
            ax.set_title(f"{run.label}, settlement {run.loads(run.final)[0] / run.B:.2f} "
                         f"B\nin view {seen.min():.3g} to {seen.max():.3g} kPa",
                         fontsize=12)
        _bare(axes)
        fig.colorbar(filled, ax=axes.tolist(), shrink=0.8, label=PRESSURE_LABEL)
        return figures.save(fig, path)


def measures(results):
    """What the pictures show, measured per run.

    Returns
    -------
    pandas.DataFrame
        One row per run: ``method``, ``nodes``, ``reached`` (last settlement over B),
        ``eps_s_edge`` (largest triangle eps_s at the last level within
        :data:`EDGE_RADIUS` B of the footing's edge, by initial centroid),
        ``distorted`` and ``inverted`` (triangles at the last level with a smallest
        angle below :data:`soilwater.geometry.quality.DISTORTED` of its undeformed value /
        not above 0: FEM's elements, EFG's Delaunay triangles of its initial nodes),
        ``dp_min``, ``dp_max`` (excess pore pressure in view at the last level [kPa],
        compression positive).
    """
    rows = []
    for run in map(RunView, results):
        edge = np.array([run.segment.end, run.surface])
        near = (np.linalg.norm(run.initial[run.triangles].mean(1) - edge, axis=1)
                <= EDGE_RADIUS * run.B)
        last = run.result.snapshots[run.final].points
        seen = run.excess_pressure(run.final)[run.in_view(last)]
        angles = deformation.smallest_angles(run.result.snapshots[-1:], run.triangles)[0]
        rows.append({"method": run.label, "nodes": len(run.initial),
                     "reached": run.loads(run.final)[0] / run.B,
                     "eps_s_edge": float(np.nanmax(run.strain(run.final)[near])),
                     "distorted": int((angles < DISTORTED * run.angle0).sum()),
                     "inverted": int((angles <= 0).sum()),
                     "dp_min": float(seen.min()), "dp_max": float(seen.max())})
    return pd.DataFrame(rows)
