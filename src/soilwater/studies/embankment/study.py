"""The embankment on soft clay: the built-in ``embankment`` (a fill raised 1 m every 20
days to 10 m on a 2 m crust over 10 m of soft clay, a gmsh mesh with two material
regions, then 10 years of consolidation) by EFG, the paper's EFG and two FEM pairs.

Each run goes as far as it can (``time.on_failure = "stop"``): the fill height where it
stops is part of the answer. Measured per method: the settlement under the crest, the
lateral displacement under the toe, the excess pore pressure at mid-depth of the clay,
the worst cell (angle and quality) and the run time.

The first loading stage is checked against a closed form (:func:`first_stage`): the
embankment's load, at once, on an elastic half-plane approximated by a domain 400 m x
200 m (``half_plane.geo``), undrained: the pore pressure takes the mean total stress,
which :func:`soilwater.references.closed_forms.surface_load_pressure` gives.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.collections import PolyCollection

from soilwater.case.loader import load_case
from soilwater.case.validation import case_from_dict
from soilwater.methods import solve
from soilwater.references.closed_forms import surface_load_pressure
from soilwater.studies.harness import figures, tables
from soilwater.studies.harness.runs import solved
from soilwater.studies.harness.quick import pick

CASE = "embankment"
#: The methods compared: recommended EFG, the paper's EFG, Taylor-Hood, stabilised P1/P1.
METHODS = ("efg", "efg-paper", "fem-th", "fem-p1p1-stab")
#: Fill height at full load [m]: 20 kPa per metre, 200 kPa under the crest.
FILL = 10.0
DAY = 86400.0
#: The half-plane of the first-stage check, and its probes: name -> (x, depth) [m].
HALF_PLANE = Path(__file__).with_name("half_plane.msh")
PROBES = {"axis 1 m": (0.0, 1.0), "axis 2 m": (0.0, 2.0), "axis 4 m": (0.0, 4.0),
          "axis 8 m": (0.0, 8.0), "crest edge 4 m": (8.0, 4.0), "toe 2 m": (15.0, 2.0)}


def first_stage(methods=("efg", "fem-th", "fem-p1p1-stab")):
    """The embankment's full load, applied at once (one step of 1 s), on an elastic
    half-plane of 400 m x 200 m (E = 5e5 kPa, so stiff that the strains stay below
    0.1 %, the closed form's small strain; nu = 0.3, incompressible constituents, the
    surface impermeable): the undrained pore pressure at :data:`PROBES` against
    :func:`soilwater.references.closed_forms.surface_load_pressure`.

    Returns
    -------
    pandas.DataFrame
        ``method``, ``probe``, ``p_w`` and ``exact`` [kPa], ``offset`` (their difference
        [kPa]).
    """
    profile = load_case(CASE).boundary.surface.traction
    xs, qs = [row[0] for row in profile], [-row[2] for row in profile]
    depth = 200.0
    case = case_from_dict({
        "name": "embankment-half-plane",
        "geometry": {"mesh": str(HALF_PLANE)},
        "material": {"model": "elastic", "E": 5e5, "nu": 0.3, "permeability": 1e-9},
        "boundary": {"base": {"displacement": "fixed"}, "axis": {"displacement": "roller"},
                     "far": {"displacement": "roller"},
                     "surface": {"traction": [list(row) for row in profile]}},
        "time": {"end": 1.0, "steps": 1},
        "probes": {f"p{k}": [x, depth - z] for k, (x, z) in enumerate(PROBES.values())}})
    rows = []
    for method in methods:
        first = solve(case, method, progress=False).history.iloc[0]
        for k, (name, (x, z)) in enumerate(PROBES.items()):
            exact = float(surface_load_pressure(x, z, xs, qs))
            rows.append({"method": method, "probe": name, "p_w": first[f"p_w@p{k}"],
                         "exact": exact, "offset": first[f"p_w@p{k}"] - exact})
    return pd.DataFrame(rows)


#: The quick report's mesh: ``embankment.geo`` meshed with sizes twice the built-in
#: mesh's (210 vertices instead of 690; ``gmsh -2 -clscale 2 -format msh41``).
QUICK_MESH = Path(__file__).with_name("quick.msh")
#: Overrides of the built-in case: none, or in a quick report :data:`QUICK_MESH`, a first
#: step twice as long, faster growth and steps of up to 180 days once the fill is placed.
STEPPING = pick((), (f"geometry.mesh={QUICK_MESH}", "time.dt0=2 d", "time.growth=1.6",
                     "time.dt_max=180 d"))


def runs(methods=METHODS):
    """The results of the built-in case, per method (the cached runner), with
    :data:`STEPPING`."""
    return dict(zip(methods, solved([(CASE, STEPPING, m) for m in methods])))


def curves(results):
    """The histories of the runs.

    Returns
    -------
    pandas.DataFrame
        ``method``, ``time`` [d], ``fill`` [m] (the fill height of the load at that
        time), ``crest`` (settlement under the crest [m], down positive), ``toe``
        (lateral displacement at the base of the crust under the toe [m], outwards
        positive), ``excess`` (excess pore pressure at mid-depth of the clay under the
        crest's edge [kPa]), ``min_angle`` [degrees] and ``min_quality`` of the worst
        cell, ``run_time`` [s].
    """
    case = load_case(CASE)
    frames = []
    for method, result in results.items():
        h = result.history
        frames.append(pd.DataFrame({
            "method": method, "time": h["time"].to_numpy() / DAY,
            "fill": FILL * case.loading.factor(h["time"].to_numpy()),
            "crest": -h["uy@crest"].to_numpy(), "toe": h["ux@toe"].to_numpy(),
            "excess": h["p_w@mid"].to_numpy() - case.initial_pore_pressure,
            "min_angle": h["min_angle"].to_numpy(),
            "min_quality": h["min_quality"].to_numpy(),
            "run_time": result.summary["timings"]["total_s"]}))
    return pd.concat(frames, ignore_index=True)


def summary(table, results):
    """Per method: how far it got and what it measured there.

    Returns
    -------
    pandas.DataFrame
        ``method``, ``fill`` [m] reached, ``time`` [d] reached, ``crest_built`` and
        ``toe_built`` [m] at the end of construction (200 d; NaN if not reached),
        ``crest`` and ``toe`` [m] at the last level, ``excess_max`` [kPa], ``min_angle``
        [degrees] and ``min_quality`` (the worst over the run), ``steps``, ``run_time``
        [s] and ``stopped`` (why the run ended early, or ``-``).
    """
    rows = []
    built = float(load_case(CASE).loading.load[-1][0]) / DAY
    for method, run in table.groupby("method", sort=False):
        at = run[np.isclose(run.time, built)]
        last = run.iloc[-1]
        stopped = results[method].summary.get("stopped")
        rows.append({
            "method": method, "fill": last.fill, "time": last.time,
            "crest_built": at.crest.iloc[0] if len(at) else np.nan,
            "toe_built": at.toe.iloc[0] if len(at) else np.nan,
            "crest": last.crest, "toe": last.toe, "excess_max": run.excess.max(),
            "min_angle": run.min_angle.min(), "min_quality": run.min_quality.min(),
            "steps": len(run), "run_time": last.run_time,
            "stopped": _reason(stopped)})
    return pd.DataFrame(rows)


def _reason(stopped):
    """The cause of an early stop, from the march's message (``-`` if none): what failed
    in the last halving, e.g. ``an element inverts (J = -3.1)``."""
    if not stopped:
        return "-"
    head = "of the time step ("
    if head not in stopped:
        return stopped
    inner = stopped.split(head, 1)[1]
    return inner[:inner.rfind("): ")] if "): " in inner else inner


def figure(table, path):
    """Crest settlement, toe displacement and excess pore pressure over time, one panel
    each, the fill height on the first; a cross where a run stopped."""
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True, constrained_layout=True)
    quantities = (("crest", "settlement under the crest [m]"),
                  ("toe", "lateral displacement under the toe [m]"),
                  ("excess", "excess pore pressure at mid-depth [kPa]"))
    end = table.time.max()
    for k, (method, run) in enumerate(table.groupby("method", sort=False)):
        for ax, (column, _) in zip(axes, quantities):
            ax.plot(run.time, run[column], color=f"C{k}", label=method)
            if run.time.iloc[-1] < end * (1 - 1e-9):
                ax.plot(run.time.iloc[-1], run[column].iloc[-1], "x", color=f"C{k}",
                        ms=9, mew=2)
    fill = table[table.method == table.method.iloc[0]]
    twin = axes[0].twinx()
    whole = np.geomspace(fill.time.min(), end, 400)
    twin.plot(whole, FILL * load_case(CASE).loading.factor(whole * DAY), color="0.5",
              ls=":", label="fill height")
    twin.set_ylabel("fill height [m]")
    for ax, (_, label) in zip(axes, quantities):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
        ax.set_xscale("log")
    axes[-1].set_xlabel("time [d]")
    handles = axes[0].get_legend_handles_labels()
    extra = twin.get_legend_handles_labels()
    axes[0].legend(handles[0] + extra[0], handles[1] + extra[1], fontsize=8,
                   loc="upper left", title="x: the run stopped")
    return figures.save(fig, path, dpi=120)


def deformed(results, path):
    """The cells in the current configuration coloured by their shear strain, on one
    colour scale, over the initial ground line: every method at the last output time
    they all reached, then the run that went furthest at its end."""
    common = min(result.snapshots[-1].time for result in results.values())
    panels = [(method, result, [s.time for s in result.snapshots].index(common))
              for method, result in results.items()]
    furthest = max(results, key=lambda m: results[m].snapshots[-1].time)
    if results[furthest].snapshots[-1].time > common:
        panels.append((furthest, results[furthest], len(results[furthest].snapshots) - 1))
    meshes = [result.mesh(i) for _, result, i in panels]
    strains = np.concatenate([m.cell_data["shear_strain"][0] for m in meshes])
    top = float(np.percentile(strains, 99.5))
    low = min(float(m.points[:, 1].min()) for m in meshes)
    high = max(float(m.points[:, 1].max()) for m in meshes)
    case = load_case(CASE)
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.6 * len(panels)), sharex=True,
                             constrained_layout=True)
    for ax, (method, result, i), mesh in zip(np.atleast_1d(axes), panels, meshes):
        cells = mesh.cells[0].data[:, :3]
        polys = PolyCollection(mesh.points[cells, :2], array=mesh.cell_data[
            "shear_strain"][0], cmap="viridis", clim=(0, top), edgecolors="none")
        ax.add_collection(polys)
        ax.axhline(case.geometry.height, color="k", lw=0.6, ls="--",
                   label="initial ground")
        time = result.snapshots[i].time
        fill = FILL * float(case.loading.factor(time))
        ax.set(xlim=(0, 25), ylim=(max(low, 4.0), high + 0.5), aspect="equal",
               ylabel="y [m]", title=f"{method}: t = {time / DAY:.0f} d, fill {fill:.1f} m")
        fig.colorbar(polys, ax=ax, label="shear strain (Hencky) [-]", extend="max")
    np.atleast_1d(axes)[0].legend(fontsize=8, loc="lower right")
    np.atleast_1d(axes)[-1].set_xlabel("x [m]")
    return figures.save(fig, path, dpi=120)


def section(table, check):
    """The report's lines on the embankment: its summary (:func:`summary`) and the
    first-stage check (:func:`first_stage`)."""
    done = table[table.stopped == "-"]
    stopped = table[table.stopped != "-"]
    lines = [
        "### An embankment on soft clay: a user's geometry (gmsh) with two soils",
        "",
        "![embankment histories](figures/embankment.png)",
        "",
        "![embankment deformed](figures/embankment_deformed.png)",
        "",
        "The built-in `embankment`: a fill raised 1 m every 20 days to 10 m (a surface "
        "load of 20 kPa per metre under the crest, 5 m either side of the axis, falling to "
        "0 at the toe, 15 m out) on a crust 2 m thick over 10 m of normally consolidated "
        "soft clay (modified Cam-clay, each layer on its own compression line, the crust "
        "ten times more permeable), then left to consolidate for 10 years; the gmsh mesh "
        "`src/soilwater/case/builtin/embankment.geo` (690 nodes, 0.4 m at the toe), the "
        "same for every method. Each run goes as far as it can.",
        "",
    ]
    if len(stopped):
        lines += [
            "Stopped early: " + "; ".join(
                f"{r.method} at a fill of {r.fill:.1f} m ({r.time:.0f} d; {r.stopped})"
                for r in stopped.itertuples()) + ". "
            + ("Ran to the end: " + ", ".join(done.method) + "." if len(done) else ""),
            "",
            _compared(table) + " The deformed configurations are drawn on each method's "
            "own cells (EFG's integration triangles, the FEM elements), first all at the "
            "last output time every run reached.",
            "",
        ]
    lines += [
        "| method | fill reached [m] | crest settlement at 200 d [m] | toe at 200 d [m] "
        "| crest settlement, last level [m] | toe, last level [m] | largest excess p_w [kPa] "
        "| worst angle [deg] | worst quality | steps | run time [s] | stopped by |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in table.itertuples():
        lines.append(
            f"| {r.method} | {r.fill:.1f} | {_f(r.crest_built)} | {_f(r.toe_built)} | "
            f"{r.crest:.3g} | {r.toe:.3g} | {r.excess_max:.3g} | {r.min_angle:.1f} | "
            f"{r.min_quality:.2f} | {r.steps} | {r.run_time:.0f} | {r.stopped} |")
    spread = check.groupby("method", sort=False).offset.agg(["min", "max"])
    load = load_case(CASE).boundary.surface.largest_traction
    lines += [
        "",
        "First loading stage against a closed form: the same load, applied at once, on an "
        "elastic half-plane (400 m x 200 m, `half_plane.geo` in the study's folder; E = "
        "5e5 kPa, stiff enough for small strains, nu = 0.3, incompressible constituents), "
        "undrained. In plane strain the "
        "stresses of a surface load on a half-plane do not depend on the elastic "
        "constants, and the pore pressure takes the mean total stress: Poisson's integral "
        "of the load (`soilwater.references.closed_forms.surface_load_pressure`). At six "
        "points under the axis (1 to 8 m deep), the crest's edge and the toe, p_w minus "
        "the closed form is " + ", ".join(
            f"{m} {r['min']:+.2g} to {r['max']:+.2g} kPa" for m, r in spread.iterrows())
        + f" (the load is {load:.0f} kPa under the crest): a nearly uniform offset, the "
        "finite domain's (an incompressible body held at its base and sides heaves "
        "beside the load), within which the three methods agree. What this checks: the "
        "load profile, the undrained coupling and each method's pressure field on a mesh; "
        "not the Cam-clay stages that follow.",
        "",
        tables.to_markdown(check, floatfmt="{:.3g}"),
        "",
    ]
    return lines


def _compared(table):
    """How far the recommended EFG got against Taylor-Hood, and what stopped it."""
    rows = table.set_index("method")
    if not {"efg", "fem-th"} <= set(rows.index):
        return ""
    efg, th = rows.loc["efg"], rows.loc["fem-th"]
    word = ("as far as" if abs(efg.fill - th.fill) < 0.05 else
            "further than" if efg.fill > th.fill else "less far than")
    why = (" It stopped when one of its Lagrangian integration cells inverted: they "
           "distort with the soil as the elements do." if "cell inverts" in efg.stopped
           else "")
    return (f"The recommended EFG went {word} Taylor-Hood on the same nodes (fill "
            + ", ".join(f"{m} {r.fill:.1f} m" for m, r in rows.iterrows())
            + "; worst cell angle " + ", ".join(f"{m} {r.min_angle:.1f}"
                                                for m, r in rows.iterrows())
            + " degrees)." + why)


def _f(value):
    return "-" if value != value else f"{value:.3g}"
