"""The strip footing's pictures in the report: deformed configurations, pore pressure
(:mod:`soilwater.studies.footing.pictures`) and animations
(:mod:`soilwater.studies.footing.gif`)."""

from pathlib import Path

from soilwater.geometry.quality import DISTORTED
from soilwater.studies.footing.gif import animations, frames
from soilwater.studies.footing.pictures import (EDGE_RADIUS, LEVEL_PERCENTILES,
                                                deformed_figure, measures,
                                                pore_pressure_figure, runs)
from soilwater.studies.footing.view import STRAIN_PERCENTILE, ZOOM, RunView
from soilwater.studies.harness import tables

NAME = "footing-pictures"


def run(root, inputs):
    """Runs the footing on the built-in nodes (:func:`~soilwater.studies.footing.
    pictures.runs`) and writes its pictures; returns :func:`write`'s data."""
    data, _ = write(root, runs())
    return data


def section(data):
    """The report's lines on the pictures from :func:`write`'s data."""
    table = data["footing deformation"]
    counted = table[table.distorted != ""]      # outputs saved before EFG was counted
    nx, ny = data["grid"]
    snapshots = data["snapshots"]
    gifs = " ".join(f"![{m}](figures/footing_{m}.gif)" for m in snapshots)
    return [
        "### Strip footing: deformed configurations, pore pressure, animations",
        "",
        "![deformed configurations](figures/footing_deformed.png)",
        "",
        f"The runs on {nx} x {ny} nodes at their last level, {ZOOM:g} B x {ZOOM:g} B "
        "next to the footing, coloured by the shear strain eps_s = sqrt(2/3 e':e') of "
        "the Hencky strain (e' its deviator, plane strain) of each triangle of the "
        "initial nodes, EFG and FEM alike: each triangle filled with its own value on "
        f"one linear scale ending at percentile {STRAIN_PERCENTILE:g} of the values in "
        "view, the few larger ones (slivers at the footing's edge) in the top colour "
        "(FEM: its elements' corners; EFG: the Delaunay triangles of its "
        "initial nodes, moved with them, which `efg` integrates on until it rebuilds "
        "them and `efg-paper` does not use). The largest "
        f"eps_s within {EDGE_RADIUS:g} B of the footing's edge: "
        + ", ".join(f"{r.method} {r.eps_s_edge:.3g}" for r in table.itertuples())
        + ". Triangles outlined in red are distorted, their smallest angle below "
        f"{DISTORTED:.2g} of its undeformed value: "
        + ("; ".join(f"{r.method} {r.distorted} at the last level ({r.inverted} "
                     "inverted)" for r in counted.itertuples()) if len(counted) else
           "none counted")
        + ".",
        "",
        "![excess pore pressure](figures/footing_pore_pressure.png)",
        "",
        "Excess pore pressure p_w - p_w0 (kPa, compression positive) on the deformed "
        "configuration at the last level; in view it ranges over "
        + "; ".join(f"{r.method} {r.dp_min:.3g} to {r.dp_max:.3g} kPa"
                    for r in table.itertuples())
        + " (the contour levels span percentiles {:g} to {:g} of all of them; beyond, "
        "the end colours).".format(*LEVEL_PERCENTILES),
        "",
        gifs,
        "",
        "Each method's deformation (" + ", ".join(
            f"{m} {len(frames(n))} of its {n}" for m, n in snapshots.items())
        + " snapshots; one colour scale), the settlement and "
        "contact pressure in the title.",
        "",
    ]


def write(root, results):
    """The pictures of ``results`` (:func:`runs`) under ``root``: ``tables/
    footing_deformation`` (:func:`measures`), the figures ``footing_deformed`` and
    ``footing_pore_pressure`` and one animation per method.

    Returns
    -------
    data : dict
        ``"footing deformation"`` (the table), ``"grid"`` (nodes ``(nx, ny)``) and
        ``"snapshots"`` (method -> number of snapshots): what :func:`section` reads.
    written : list of pathlib.Path
    """
    root = Path(root)
    grid = results[0].case.discretisation
    data = {"footing deformation": measures(results), "grid": (grid.nx, grid.ny),
            "snapshots": {RunView(r).label: len(r.snapshots) for r in results}}
    written = [*tables.write(data["footing deformation"],
                             root / "tables" / "footing_deformation"),
               deformed_figure(results, root / "figures" / "footing_deformed.png"),
               pore_pressure_figure(results, root / "figures" / "footing_pore_pressure.png"),
               *animations(results, root / "figures")]
    return data, written
