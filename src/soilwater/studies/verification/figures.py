"""Figures of the verification sections: the problems, shape functions, background cells
and cantilever convergence (the stress paths of Figs. 4 and 6 are
:mod:`soilwater.studies.verification.path_figures`); each is one slide
(:mod:`soilwater.studies.harness.figures`), saves a PNG and returns its path."""

import textwrap

import matplotlib.pyplot as plt
import numpy as np

from soilwater.efg.settings import DEFAULT_SCALE
from soilwater.studies.harness import figures


@figures.style()
def background_cells(path):
    """Paper Figs. 3 and 5: background cells of the 111-node unconfined-compression specimen.

    Four panels, axes in m: square cells of the initial nodal spacing, quartered along the
    boundary, with their 2 x 2 Gauss points; the Delaunay triangles with their 3 Gauss
    points (degree 2); the triangles with their dual Voronoi diagram; both cell types
    rebuilt on the specimen compressed by 20 % and barrelled,
    x -> x (1 + 0.15 cos(pi y / 2H)), y -> 0.8 y.
    """
    from matplotlib.collections import PolyCollection
    from scipy.spatial import Voronoi, voronoi_plot_2d

    from soilwater.efg.quadrature import delaunay_cells, square_cells
    from soilwater.case.loader import load_case

    case = load_case("unconfined-compression")
    nodes, loop, height = case.nodes(), case.boundary_loop(), case.geometry.height
    x, y = nodes.T
    bulged = np.column_stack([x * (1 + 0.15 * np.cos(np.pi * y / (2 * height))), 0.8 * y])

    def squares(ax, points):
        q = square_cells(points[loop], case.spacing)
        quarter = np.ptp(q.cells[:, :, 0], axis=1) < 0.75 * case.spacing[0]
        for cells, colour, label in ((q.cells[~quarter], "0.3", "full square cell"),
                                     (q.cells[quarter], "C0", "quarter cell")):
            ax.add_collection(PolyCollection(cells, facecolors="none", edgecolors=colour,
                                             linewidths=0.8, label=label))
        ax.plot(*q.points.T, "+", color="C3", ms=3, mew=0.6, label="Gauss point")
        return f"{np.sum(~quarter)} full + {np.sum(quarter)} quarter cells, {len(q.points)}"

    def triangles(ax, points, **style):
        q = delaunay_cells(points, points[loop])
        ax.triplot(*points.T, q.triangles, color="C2", label="Delaunay triangle", **style)
        return f"{len(q.triangles)} triangles, {len(q.points)}", q.points

    fig, axes = figures.slide(1, 4, sharex=True, sharey=True)
    counts, points = triangles(axes[1], nodes, lw=0.8)
    axes[1].plot(*points.T, "+", color="C3", ms=3, mew=0.6)
    voronoi_plot_2d(Voronoi(nodes), axes[2], show_points=False, show_vertices=False,
                    line_colors="C1", line_width=0.9)
    axes[2].plot([], [], color="C1", label="Voronoi edge")
    triangles(axes[2], nodes, lw=0.6, alpha=0.6)
    titles = [f"Square cells: {squares(axes[0], nodes)} points",
              f"Delaunay cells: {counts} points",
              f"{counts.split(',')[0]} and their dual Voronoi diagram",
              f"20 % compressed and barrelled:\nsquares {squares(axes[3], bulged)} points;"
              f"\n{triangles(axes[3], bulged, lw=0.5, alpha=0.7)[0]} points"]
    axes[3].plot(*np.vstack([bulged[loop], bulged[:1]]).T, "k", lw=1.4,
                 label="current boundary")
    limits = (-0.25, bulged[:, 0].max() + 0.25), (-0.25, height + 0.25)
    for ax, title, shown in zip(axes, titles, (nodes, nodes, nodes, bulged)):
        ax.plot(*shown.T, "ko", ms=2.5, label="node")
        ax.set(aspect="equal", xlim=limits[0], ylim=limits[1], xlabel="x [m]")
        ax.set_title(textwrap.fill(title, 32), fontsize=11)
        ax.grid(False)
    axes[0].set_ylabel("y [m]")
    handles = {}
    for ax in axes[[3, 2]]:
        handles.update(zip(*ax.get_legend_handles_labels()[::-1]))
    fig.legend(handles.values(), handles.keys(), loc="outside lower center", ncol=4)
    fig.suptitle("Background cells of the 111-node specimen (paper Figs. 3 and 5), initial "
                 "nodal spacing {:g} x {:g} m".format(*case.spacing))
    return figures.save(fig, path)


@figures.style()
def shape_functions(path, scale=DEFAULT_SCALE):
    """Paper Fig. 7: an interior node's MLS shape function and its x-derivative.

    phi_I and h dphi_I/dx along the line y = y_I through a centre node of a square grid,
    for the weights Q (quartic), E-A (exponential, c = 0.5) and E-B (c = 0.25). Two nodal
    densities with the same support radius d_mI = scale sqrt(2) h: spacing h (scale factor
    ``scale``) and h/2 (twice the scale factor), so the dense grid holds about four times
    as many nodes in a support. At one scale factor a refined grid only shrinks the
    supports with the spacing (d_mI follows the 8th-nearest-node distance) and the curves
    in x/h would not change. x is normalised by the coarse spacing h; nodes on the line
    are ticked along the bottom of each panel. The exponential weights are only C0 at
    r = 1, so their dphi/dx jumps where the line crosses the edge of a node's support.
    """
    from soilwater.efg.mls import ShapeFunctions

    weights = {"Q": "Q (quartic)", "E-A": "E-A (exp, c = 0.5)", "E-B": "E-B (exp, c = 0.25)"}
    centre = 6.0  # grid over [0, 12 h]^2: boundary nodes' larger supports stay clear of I
    x = np.linspace(-2.4, 2.4, 961)
    line = np.column_stack([x + centre, np.full_like(x, centre)])
    fig, axes = figures.slide(2, 2, sharex=True, sharey="row")
    for column, spacing in enumerate((1.0, 0.5)):
        ticks = np.linspace(0.0, 2 * centre, int(round(2 * centre / spacing)) + 1)
        nodes = np.stack(np.meshgrid(ticks, ticks), axis=-1).reshape(-1, 2)
        node = int(np.argmin(np.linalg.norm(nodes - centre, axis=1)))
        factor = scale / spacing
        for name, label in weights.items():
            sf = ShapeFunctions.build(nodes, line, name, factor)
            axes[0, column].plot(x, sf.phi[:, [node]].toarray(), lw=1.8, label=label)
            axes[1, column].plot(x, sf.dphi_dx[:, [node]].toarray(), lw=1.8, label=label)
        radius = sf.support[node]
        inside = int(np.sum(np.linalg.norm(nodes - nodes[node], axis=1) < radius))
        axes[0, column].set_title(f"nodal spacing {'h' if spacing == 1 else 'h/2'}, scale "
                                  f"factor {factor:g}\n{inside} nodes in the support "
                                  f"(radius d$_{{mI}}$ = {radius:.2f} h)", fontsize=12)
        for ax in axes[:, column]:
            ax.axhline(0.0, color="0.6", lw=0.6)
            for edge in (-radius, radius):
                ax.axvline(edge, color="0.4", ls=":", lw=1)
            on_line = ticks[np.abs(ticks - centre) <= 2.4] - centre
            ax.plot(on_line, np.zeros_like(on_line), "|", color="k", ms=9,
                    transform=ax.get_xaxis_transform(), label="node on the line")
        axes[1, column].set_xlabel("(x - x$_I$)/h [-] (h: coarse nodal spacing)")
    axes[0, 0].set_ylabel("shape function $\\phi_I$ [-]")
    axes[1, 0].set_ylabel("h d$\\phi_I$/dx [-]")
    axes[0, 0].plot([], [], ":", color="0.4", label="support edge, |x - x$_I$| = d$_{mI}$")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles[:5], labels[:5], loc="outside lower center", ncol=5)
    fig.suptitle("Paper Fig. 7: MLS shape function (linear basis) of an interior node I "
                 "and its x-derivative along y = y$_I$\nsame support radius in both "
                 "columns, the right one with twice the nodal density")
    return figures.save(fig, path)


@figures.style()
def efg_convergence(table, path):
    """Energy-norm error of the cantilever against nodal spacing, log-log, per weight/cells.

    ``table`` is :func:`soilwater.studies.verification.study.cantilever_convergence`.
    """
    fig, ax = figures.slide()
    styles = {"delaunay": "-", "squares": "--"}
    colours = {"Q": "C0", "E-A": "C1", "E-B": "C2"}
    for (weight, cells), group in table.groupby(["weight", "cells"], sort=False):
        ax.loglog(group.h, group.energy, styles[cells], marker="o", color=colours[weight],
                  label=f"{weight}, {cells} cells")
    h = np.array([table.h.min(), table.h.max()])
    e = table.energy.min() * (h / h[0])
    ax.loglog(h, e, "k:", lw=1.5, label="slope 1")
    ax.set(xlabel="nodal spacing h [m] (beam 48 x 12 m)",
           ylabel="relative energy-norm error [-]",
           title="EFG cantilever (Timoshenko beam), plane strain, VCI")
    ax.grid(which="both")
    spacings = sorted(table.h.unique())
    ax.set_xticks(spacings, [f"{s:g}" for s in spacings])
    ax.minorticks_off()
    fig.legend(loc="outside right upper")
    return figures.save(fig, path)


@figures.style()
def problems(path, names=("unconfined-compression", "soil-column")):
    """Paper Figs. 3 and 8: nodes and boundary conditions of the two problems.

    Edges are drawn by their condition: fixed components as ticks across (ux) or along
    (uy) the edge, prescribed motion as arrows of L x, tractions as arrows, drained edges
    in blue.
    """
    from soilwater.case.loader import load_case

    fig, axes = figures.slide(1, len(names), gridspec_kw={"width_ratios": [1.3, 1]})
    for ax, name in zip(axes, names):
        case = load_case(name)
        nodes, loop = case.nodes(), case.boundary_loop()
        ring = nodes[np.r_[loop, loop[:1]]]
        ax.plot(ring[:, 0], ring[:, 1], "k-", lw=1)
        ax.plot(nodes[:, 0], nodes[:, 1], "o", ms=3, color="0.3")
        size = 0.06 * max(case.geometry.width, case.geometry.height)
        for edge_name, edge in case.boundary.items():
            _edge(ax, case, edge_name, edge, size)
        ax.set_aspect("equal")
        ax.set(title=f"{name}: {len(nodes)} nodes", xlabel="x [m]", ylabel="y [m]")
        ax.margins(0.12)
        ax.grid(False)
    handles = [plt.Line2D([], [], color="C3", marker="|", ls="none", ms=8, label="fixed "
                          "component"),
               plt.Line2D([], [], color="C2", marker=">", ls="none", label="prescribed v = L x"),
               plt.Line2D([], [], color="C1", marker="v", ls="none", label="traction"),
               plt.Line2D([], [], color="C0", lw=3, label="drained (p$_w$ = 0)")]
    fig.legend(handles=handles, loc="outside lower center", ncol=4)
    return figures.save(fig, path)


def _edge(ax, case, name, edge, size):
    """Draw one edge's conditions (see :func:`problems`)."""
    W, H = case.geometry.width, case.geometry.height
    along = {"left": ([0, 0], [0, H]), "right": ([W, W], [0, H]),
             "bottom": ([0, W], [0, 0]), "top": ([0, W], [H, H])}[name]
    xs = np.linspace(*along[0], 7)[1:-1]
    ys = np.linspace(*along[1], 7)[1:-1]
    if edge.drained:
        ax.plot(*along, color="C0", lw=3, alpha=0.7)
    for f, kind in enumerate((edge.ux, edge.uy)):
        if kind == "fixed":
            dx, dy = (size / 2, 0) if f == 0 else (0, size / 2)
            for x, y in zip(xs, ys):
                ax.plot([x - dx, x + dx], [y - dy, y + dy], color="C3", lw=1.5)
        elif kind == "prescribed":
            v = np.stack([xs, ys], 1) @ case.loading.L.T
            v = v / max(np.abs(v).max(), 1e-300) * size * 1.5
            ax.quiver(xs, ys, v[:, 0] * (f == 0), v[:, 1] * (f == 1), color="C2",
                      angles="xy", scale_units="xy", scale=1, width=0.006)
    if edge.traction != "exact" and np.any(edge.traction):
        t = np.asarray(edge.traction, float)
        t = t / np.abs(t).max() * size * 1.5
        ax.quiver(xs - t[0], ys - t[1], t[0] + 0 * xs, t[1] + 0 * ys, color="C1",
                  angles="xy", scale_units="xy", scale=1, width=0.02)
