"""A strip-footing run as its pictures see it: its triangulation, footing and window
(:class:`RunView`), and the eps_s colour scale and window height shared by several runs.

The views show the ``ZOOM B`` wide, ``ZOOM B`` deep window next to the footing (symmetry
axis at x = 0), up to the highest node in it. EFG and FEM runs are drawn alike: each
triangle of :func:`soilwater.studies.harness.deformation.triangulation` (FEM: its
elements; EFG: the Delaunay triangles of its initial nodes) filled with its own eps_s,
on one linear colour scale that ends at a high percentile of the values in view
(:func:`strain_norm`), the few larger ones in the top colour, marked by the colour bar's
arrow.
"""

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.colors import Normalize
from matplotlib.patches import Rectangle

from soilwater.studies.harness import deformation, figures
from soilwater.studies.harness.footing import width
from soilwater.geometry.quality import DISTORTED, cell_quality

#: Width and depth of the window next to the footing [B].
ZOOM = 2.5
#: Colour map of eps_s, and its colour bar's label.
CMAP = figures.SEQUENTIAL
STRAIN_LABEL = "shear strain eps_s = sqrt(2/3 e':e'), Hencky [-]"
#: Percentile of the triangle values in view (all runs' final levels) at which the eps_s
#: colour scale ends: the largest values sit in a few slivers at the footing's edge.
STRAIN_PERCENTILE = 99.0


class RunView:
    """A run's triangulation, footing and window, shared by its pictures."""

    def __init__(self, result):
        self.result = result
        self.initial = np.asarray(result.snapshots[0].points, dtype=float)
        self.triangles = deformation.triangulation(result.snapshots[0])
        self.angle0 = deformation.smallest_angles(result.snapshots[:1], self.triangles)[0]
        self.B = width(result.case)
        self.surface = result.case.geometry.height
        (_, self.segment), = result.case.boundary.segments()
        self.final = len(result.snapshots) - 1

    @property
    def label(self):
        """The run's method as the study names it: ``efg-paper`` for EFG in the paper's
        configuration, else the result's method."""
        paper = self.result.summary.get("configuration") == "paper"
        return "efg-paper" if paper else self.result.method

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
        """Artists showing a snapshot coloured by eps_s on ``ax``: every triangle filled
        with its eps_s, the distorted ones (smallest angle below
        :data:`soilwater.geometry.quality.DISTORTED` of its undeformed value) outlined in
        red, inverted ones (NaN eps_s) magenta; and the footing. EFG and FEM alike (module
        docstring).

        Returns
        -------
        mappable : matplotlib.cm.ScalarMappable
            For the colour bar.
        show : callable
            ``show(k)`` puts snapshot ``k`` into the artists; returns the number of
            distorted and of inverted triangles.
        """
        footing = self.footing(ax, 0)
        cells = ax.add_collection(PolyCollection(
            self.initial[self.triangles], norm=norm, edgecolors="0.3", linewidths=0.15,
            cmap=plt.get_cmap(CMAP).with_extremes(bad="magenta")))
        outlines = ax.add_collection(PolyCollection(
            [], facecolors="none", edgecolors="red", linewidths=1.0, zorder=4))

        def show(k):
            footing.set_y(self.surface - self.loads(k)[0])
            corners = self.result.snapshots[k].points[self.triangles]
            angle, _ = cell_quality(corners)
            cells.set_verts(corners)
            cells.set_array(self.strain(k))
            distorted = angle < DISTORTED * self.angle0
            outlines.set_verts(corners[distorted])
            return int(distorted.sum()), int((angle <= 0).sum())
        return cells, show


def final_strains(runs):
    """eps_s of every triangle in view (by current centroid) at each run's final level,
    pooled; inverted triangles (NaN) left out."""
    values = np.concatenate([run.strain(run.final)[run.in_view(
        run.result.snapshots[run.final].points[run.triangles].mean(1))] for run in runs])
    return values[np.isfinite(values)]


def strain_norm(runs, percentile=STRAIN_PERCENTILE):
    """One linear colour scale for eps_s: 0 to ``percentile`` of :func:`final_strains`
    (values above take the top colour: draw the colour bar with ``extend="max"`` when
    :func:`strain_extend` says so)."""
    top = np.percentile(final_strains(runs), percentile)
    return Normalize(0.0, top if top > 0 else 1.0)  # 1: nothing strained


def strain_extend(runs, norm):
    """``"max"`` if some triangle in view at a run's final level is above ``norm``'s
    top (the colour bar's arrow marks them), else ``"neither"``."""
    return "max" if final_strains(runs).max(initial=0.0) > norm.vmax else "neither"


def window_top(runs):
    """Upper limit of the windows [m]: above the highest node any run has in view."""
    return max(run.highest() + 0.15 * run.B for run in runs)

