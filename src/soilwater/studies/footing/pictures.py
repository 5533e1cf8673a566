"""Pictures of the strip-footing runs: the deformed configurations
coloured by shear strain, the excess pore pressure, and an animation of each method.

Every picture is drawn from :class:`soilwater.results.Result` objects of the built-in
``strip-footing`` case (or a variant with one footing segment on the top edge), from the
node positions and nodal fields of their snapshots; the shear strain is
:mod:`soilwater.studies.harness.deformation`'s ``eps_s`` on a triangulation of the initial nodes. The
views show the ``ZOOM B`` wide, ``ZOOM B`` deep window next to the footing (symmetry
axis at x = 0), up to the highest node in it. Files are written whole or not at all (a
temporary file renamed into place).
"""

import os
import tempfile
import textwrap
from contextlib import contextmanager
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.animation import PillowWriter
from matplotlib.collections import PolyCollection
from matplotlib.colors import Normalize, PowerNorm
from matplotlib.patches import Rectangle
from matplotlib.ticker import MaxNLocator
from matplotlib.tri import Triangulation

from soilwater.studies.harness import deformation
from soilwater.studies.footing.study import DENSITIES
from soilwater.studies.harness.footing import CASE, PLAIN, width
from soilwater.studies.harness.grids import refined
from soilwater.studies.harness.runs import solved
from soilwater.geometry.quality import DISTORTED, cell_quality

#: Spacings per B at the footing of the runs the report draws: the built-in case's.
CORE = DENSITIES[len(DENSITIES) // 2]
#: Width and depth of the window next to the footing [B].
ZOOM = 2.5
#: Distance from the footing's edge [B] within which :func:`measures` takes the largest
#: eps_s ("under the footing edge").
EDGE_RADIUS = 0.5
#: Percentiles of the excess pore pressures in view that the contour levels span;
#: values beyond take the end colours (the titles give the full range).
LEVEL_PERCENTILES = (1.0, 99.0)
#: Most frames of an animation, and its frame rate [1/s].
FRAMES = 50
FPS = 10
CMAP = "viridis"
STRAIN_LABEL = "shear strain eps_s = sqrt(2/3 e':e'), Hencky [-]"
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


class _Run:
    """A run's triangulation, footing and window, shared by its pictures."""

    def __init__(self, result):
        self.result = result
        self.initial = np.asarray(result.snapshots[0].points, dtype=float)
        self.triangles = deformation.triangulation(result.snapshots[0])
        self.angle0 = deformation.smallest_angles(result.snapshots[:1], self.triangles)[0]
        self.B = width(result.case)
        self.surface = result.case.geometry.height
        (_, self.segment), = result.case.boundary.segments()
        self.cloud = not result.snapshots[0].cells
        self.final = len(result.snapshots) - 1

    @property
    def label(self):
        return self.result.method

    def strain(self, k):
        """eps_s of each triangle at snapshot ``k``."""
        return deformation.snapshot_strain(self.initial, self.result.snapshots[k],
                                           self.triangles)

    def loads(self, k):
        """Settlement [m, down positive] and mean contact pressure [kPa, compression
        positive] of snapshot ``k`` (snapshot 0 is t = 0, snapshot k > 0 the end of
        history row k - 1)."""
        if k == 0:
            return 0.0, 0.0
        row = self.result.history.iloc[k - 1]
        name = self.segment.name
        return float(row[f"settlement@{name}"]), float(row[f"pressure@{name}"])

    def excess_pressure(self, k):
        """p_w minus its initial value at each node [kPa], compression positive."""
        snaps = self.result.snapshots
        return snaps[k].point_data["p_w"] - snaps[0].point_data["p_w"]

    def in_view(self, points):
        """Which ``points`` (current positions [m]) lie in the window."""
        return ((points[:, 0] <= ZOOM * self.B)
                & (points[:, 1] >= self.surface - ZOOM * self.B))

    def highest(self):
        """Highest node of the window over all snapshots [m]."""
        return max(snap.points[self.in_view(snap.points), 1].max()
                   for snap in self.result.snapshots)

    def window(self, ax, top):
        """Zoom ``ax`` on the window, from ``ZOOM B`` below the surface up to ``top``
        [m]; axes in m, equal aspect."""
        ax.set_xlim(-0.04 * self.B, ZOOM * self.B)
        ax.set_ylim(self.surface - ZOOM * self.B, top)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")

    def footing(self, ax, k):
        """Draw the rigid footing (its segment, lowered by the settlement of snapshot
        ``k``); returns the patch."""
        return ax.add_patch(Rectangle(
            (self.segment.start, self.surface - self.loads(k)[0]),
            self.segment.end - self.segment.start, 0.12 * self.B, facecolor="0.35",
            edgecolor="k", lw=0.8, zorder=5))

    def strain_view(self, ax, norm):
        """Artists showing a snapshot coloured by eps_s on ``ax``: EFG nodes as dots
        (area-averaged nodal values), FEM elements filled, the distorted ones (smallest
        angle below :data:`soilwater.geometry.quality.DISTORTED` of its undeformed value) outlined in
        red, inverted ones (NaN eps_s) magenta; and the footing.

        Returns
        -------
        mappable : matplotlib.cm.ScalarMappable
            For the colour bar.
        show : callable
            ``show(k)`` puts snapshot ``k`` into the artists; returns the number of
            distorted and of inverted elements (None for EFG).
        """
        footing = self.footing(ax, 0)
        if self.cloud:
            dots = ax.scatter(*self.initial.T, c=np.zeros(len(self.initial)), s=10,
                              cmap=CMAP, norm=norm, edgecolors="none", zorder=3)

            def draw(points, eps):
                dots.set_offsets(points)
                dots.set_array(deformation.nodal(eps, self.initial, self.triangles))
            mappable = dots
        else:
            cells = ax.add_collection(PolyCollection(
                self.initial[self.triangles], norm=norm, edgecolors="0.3",
                linewidths=0.15, cmap=plt.get_cmap(CMAP).with_extremes(bad="magenta")))
            outlines = ax.add_collection(PolyCollection(
                [], facecolors="none", edgecolors="red", linewidths=1.0, zorder=4))

            def draw(points, eps):
                corners = points[self.triangles]
                angle, _ = cell_quality(corners)
                cells.set_verts(corners)
                cells.set_array(eps)
                distorted = angle < DISTORTED * self.angle0
                outlines.set_verts(corners[distorted])
                return int(distorted.sum()), int((angle <= 0).sum())
            mappable = cells

        def show(k):
            footing.set_y(self.surface - self.loads(k)[0])
            return draw(self.result.snapshots[k].points, self.strain(k))
        return mappable, show


def _strain_norm(runs):
    """One colour scale for eps_s: 0 to the largest triangle value in view at any run's
    final level, square-root spaced (``PowerNorm(0.5)``) so that the small strains
    away from the footing stay visible; the colour bar shows the spacing."""
    largest = max(np.nanmax(run.strain(run.final)[run.in_view(
        run.result.snapshots[run.final].points[run.triangles].mean(1))]) for run in runs)
    return PowerNorm(0.5, 0.0, largest if largest > 0 else 1.0)  # 1: nothing strained


def _top(runs):
    """Upper limit of the windows [m]: above the highest node any run has in view."""
    return max(run.highest() + 0.15 * run.B for run in runs)


@contextmanager
def _written(path):
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
        with _written(path) as tmp:
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
    runs = [_Run(r) for r in results]
    norm, top = _strain_norm(runs), _top(runs)
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
    runs = [_Run(r) for r in results]
    fields = [run.excess_pressure(run.final) for run in runs]
    levels, norm = _pressure_levels(runs, fields)
    top = _top(runs)
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


def frames(count, most=FRAMES):
    """Snapshot indices of an animation: every k-th of ``count`` snapshots, k the
    smallest step that keeps at most ``most`` frames, and always the last.

    Examples
    --------
    >>> frames(11).tolist(), frames(11, most=5).tolist()
    ([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10], [0, 3, 6, 9, 10])
    """
    step = max(1, -(-(count - 1) // (most - 1)))
    return np.append(np.arange(0, count - 1, step), count - 1)


def animation(result, path, norm=None, top=None, most=FRAMES):
    """``path`` (GIF): the run's deformation, snapshot by snapshot (:func:`frames`),
    coloured by eps_s, the settlement and contact pressure in each frame's title.

    Parameters
    ----------
    result : soilwater.results.Result
    path : str or Path
    norm : matplotlib.colors.Normalize, optional
        Colour scale of eps_s (default: the run's own, as in :func:`deformed_figure`).
    top : float, optional
        Upper limit of the window [m] (default: the run's own).
    most : int
        Most frames.

    Returns
    -------
    Path
    """
    run = _Run(result)
    fig, ax = plt.subplots(figsize=(5.6, 5.0), constrained_layout=True)
    mappable, show = run.strain_view(ax, norm or _strain_norm([run]))
    run.window(ax, top or _top([run]))
    fig.colorbar(mappable, ax=ax, shrink=0.9, label=STRAIN_LABEL)
    title = ax.set_title(" ", fontsize=9)
    fig.canvas.draw()
    fig.set_layout_engine("none")  # the first frame's layout holds for all
    writer = PillowWriter(fps=FPS)
    try:
        with _written(path) as tmp, writer.saving(fig, tmp, dpi=90):
            for k in frames(len(result.snapshots), most):
                show(k)
                s, p = run.loads(k)
                title.set_text(f"{run.label}: settlement {s:.3g} m ({s / run.B:.2f} B), "
                               f"contact pressure {p:.3g} kPa")
                writer.grab_frame()
    finally:
        plt.close(fig)
    return Path(path)


def animations(results, folder):
    """One GIF per run, ``folder/footing_METHOD.gif``, on one colour scale and window.

    Returns
    -------
    list of Path
    """
    runs = [_Run(r) for r in results]
    norm, top = _strain_norm(runs), _top(runs)
    return [animation(r, Path(folder) / f"footing_{r.method}.gif", norm, top)
            for r in results]


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
    for run in map(_Run, results):
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
