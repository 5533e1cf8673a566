"""The rough-platen compression study: the shear band each method finds, against the
band the loss of ellipticity predicts, and the load-displacement curves.

The built-in ``rough-compression`` case (the unconfined-compression quarter specimen with
its top platen rough, undrained, to 20 % axial strain) is run by EFG, fem-th and
fem-p1p1-stab at two node densities (:data:`DENSITIES`). At each output step the nodes'
shear strain (:func:`soilwater.studies.harness.deformation.nodal_strain`, the same for every
method) is rated by :func:`soilwater.studies.harness.metrics.band`: the band's inclination to the
horizontal in the current configuration, or "no band". The prediction is Rudnicki and
Rice's loss of ellipticity along the driver's homogeneous undrained path
(:func:`prediction`). A band is a bifurcation, so each run is repeated with the other
linear solver and with its interior nodes jittered by 1e-9 of the spacing
(:data:`VARIANTS`): the spread of the angle over these is a finding, not noise to hide.
"""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from soilwater.studies.harness import figures, runner
from soilwater.studies.harness import tables
from soilwater.studies.harness.deformation import nodal_strain
from soilwater.studies.harness.metrics import band
from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.onset import continuum_onset, solvers
from soilwater.diagnostics.bifurcation import onset
from soilwater.material.driver import continuum_path
from soilwater.errors import SoilwaterError
from soilwater.linalg.backends import backend
from soilwater.case.loader import load_case

CASE = "rough-compression"
METHODS = ("efg", "fem-th", "fem-p1p1-stab")
#: Node densities: the paper's 111 nodes (7 x 9 grid + cell centres) and twice the nodes
#: per side (13 x 17 + centres, 413 nodes).
DENSITIES = pick({"coarse": (), "fine": ("discretisation.nx=13", "discretisation.ny=17")},
                 {"coarse": ("time.steps=50",)})
#: Axial strains at which the table reports the band (the last: the end of the case).
STRAINS = (0.1, 0.15, 0.2)
#: Variants of each run that may move a bifurcation onto another branch: the linear
#: solver (``Job.linear_solver``; None: :func:`soilwater.linalg.backends.backend`'s choice) and
#: overrides (interior nodes jittered by a fraction of the spacing, as the uniqueness
#: ensemble does). The study's own run is the variant of the default solver.
VARIANTS = {"pardiso": ("pardiso", ()), "superlu": ("superlu", ()),
            "jitter 1e-12": (None, ("discretisation.jitter=1e-12",)),
            "jitter 1e-9": (None, ("discretisation.jitter=1e-9",))}


def prediction(case=CASE, strain=0.2, points=400):
    """The shear band predicted by the loss of ellipticity of the homogeneous state.

    :func:`soilwater.studies.harness.onset.continuum_onset` follows the driver's undrained
    plane-strain path of the case's material; at the first zero of the Rudnicki-Rice
    indicator (:func:`soilwater.diagnostics.bifurcation.onset`) its minimising direction is the band
    normal ``n``. The band contains the direction ``t`` normal to ``n``, so the band's
    inclination to the horizontal is 90 degrees minus the normal's (both folded to 0-90
    degrees: a band and its mirror image are equivalent).

    Returns
    -------
    dict
        ``onset`` (axial logarithmic strain), ``normal`` (the band normal's inclination
        to the horizontal [degrees]) and ``angle`` (the band's inclination [degrees]);
        NaN where the indicator stays positive up to ``strain``.
    """
    path = continuum_onset(case, strain, points)
    start = onset(path.strain, path.indicator)
    normal = float(np.interp(start, path.strain, path.band_angle)) if np.isfinite(start) \
        else float("nan")
    return {"onset": start, "normal": normal, "angle": 90.0 - normal}


def homogeneous_pressure(case=CASE, strain=0.2, points=200):
    """Axial pressure of the homogeneous (smooth-platen) specimen along the driver path.

    The lateral total stress is zero, so the platen pressure is ``sigma'_xx - sigma'_yy``
    [kPa, compression positive].

    Returns
    -------
    pandas.DataFrame
        ``strain`` (axial, logarithmic) and ``pressure`` [kPa].
    """
    raw, _ = continuum_path(load_case(case).material(), "undrained-plane-strain", strain,
                            points)
    return pd.DataFrame({"strain": -raw.eyy.to_numpy(),
                         "pressure": (raw.sxx - raw.syy).to_numpy()})


def runs(methods=METHODS, densities=DENSITIES, variants=VARIANTS):
    """Every run of the study through the cached parallel runner.

    Variants naming a linear solver that is not installed are left out.

    Returns
    -------
    list of (method, density, variant, Result)
        The study's own runs are those whose variant is :func:`default`.

    Raises
    ------
    SoilwaterError
        If a run failed outright (a run that cannot converge stops at its last level,
        ``time.on_failure = "stop"``, and is kept).
    """
    usable = {name: v for name, v in variants.items() if v[0] is None or v[0] in solvers()}
    labels = [(m, d, v) for d in densities for m in methods for v in usable]
    jobs = [runner.Job(CASE, m, densities[d] + usable[v][1], linear_solver=usable[v][0])
            for m, d, v in labels]
    outcomes = runner.run(jobs)
    failed = [o for o in outcomes if not o.ok]
    if failed:
        raise SoilwaterError(f"{len(failed)} shear-band run(s) failed, first: "
                             f"{failed[0].job.method} {' '.join(failed[0].job.overrides)}: "
                             f"{failed[0].error}")
    return [(*label, o.result) for label, o in zip(labels, outcomes)]


def default():
    """The variant of the study's own runs: that of the default linear solver."""
    return backend()


def bands(result):
    """The band at every output step of a run.

    Returns
    -------
    pandas.DataFrame
        ``strain`` (axial), ``angle`` [degrees, NaN: no band], ``localisation``,
        ``aspect`` (:class:`soilwater.studies.harness.metrics.Band`), ``mean_shear`` (area-weighted
        mean shear strain), and ``diagonal``: the inclination of the line from the
        specimen's centre (the lower-left corner) to the platen's edge (the top-right
        node) [degrees], the geometric direction a band from the centre to the platen's
        edge would take.
    """
    X = result.case.nodes()
    corner = np.argmax(X.sum(1))
    rows = []
    for snap, strain in zip(result.snapshots[1:], result.history.eps_a):
        gamma, area = nodal_strain(result.snapshots[0], snap)
        rated = band(snap.points, gamma, area)
        edge = snap.points[corner] - snap.points[np.argmin(X.sum(1))]
        rows.append({"strain": strain, "angle": rated.angle,
                     "localisation": rated.localisation, "aspect": rated.aspect,
                     "mean_shear": float(np.average(gamma, weights=area)),
                     "diagonal": float(np.degrees(np.arctan2(edge[1], edge[0])))})
    return pd.DataFrame(rows)


def curves(study):
    """Load-displacement curves and band ratings per step of the study's default runs.

    Returns
    -------
    pandas.DataFrame
        One row per step: ``method, density, nodes, strain`` (axial), ``pressure`` (mean
        platen pressure, ``pressure@platen``, over p'0), the columns of :func:`bands`, and
        per run ``run_time`` [s], ``iterations`` (Newton, this step) and ``stopped``
        (True where a step failed after every halving, ``time.on_failure = "stop"``).
    """
    frames = []
    for method, density, variant, result in study:
        if variant != default():
            continue
        h = result.history
        frames.append(bands(result).assign(
            method=method, density=density, nodes=len(result.case.nodes()),
            pressure=h["pressure@platen"].to_numpy() / result.case.material().p0,
            iterations=h.iterations.to_numpy(),
            run_time=result.summary["timings"]["total_s"],
            stopped=bool(result.summary.get("stopped"))))
    first = ["method", "density", "nodes", "strain", "pressure"]
    table = pd.concat(frames, ignore_index=True)
    return table[first + [c for c in table.columns if c not in first]]


def _at(run, strain):
    """A run's row at the output step nearest ``strain``, or None beyond its end."""
    s = run.strain.to_numpy()
    if s[-1] < strain - 0.5 * np.diff(s).min():
        return None
    return run.iloc[int(np.argmin(np.abs(s - strain)))]


def summary(table, predicted):
    """Per run: the band when it appears, at :data:`STRAINS`, against the prediction.

    Returns
    -------
    pandas.DataFrame
        ``method, density, nodes, reached`` (last axial strain), ``appears_at`` (first
        strain rated a band; NaN: never), ``angle_S`` per strain S of :data:`STRAINS`
        (NaN: no band there, or not reached), ``angle_end``, ``localisation``,
        ``aspect`` and ``diagonal`` at the last step, ``predicted`` (:func:`prediction`'s angle),
        ``pressure_end`` (over p'0), ``run_time`` [s], ``iterations_per_step`` and
        ``stopped`` (True where a step failed after every halving before the end).
    """
    rows = []
    for (method, density), run in table.groupby(["method", "density"], sort=False):
        found = run[np.isfinite(run.angle)]
        last = run.iloc[-1]
        row = {"method": method, "density": density, "nodes": int(last.nodes),
               "reached": last.strain,
               "appears_at": found.strain.iloc[0] if len(found) else np.nan}
        for strain in STRAINS:
            at = _at(run, strain)
            row[f"angle_{strain:g}"] = np.nan if at is None else at.angle
        rows.append({**row, "angle_end": last.angle, "localisation": last.localisation,
                     "aspect": last.aspect,
                     "diagonal": last.diagonal, "predicted": predicted["angle"],
                     "pressure_end": last.pressure, "run_time": last.run_time,
                     "iterations_per_step": run.iterations.mean(),
                     "stopped": last.stopped})
    return pd.DataFrame(rows)


def robustness(study):
    """The band of each run under every variant at their last common strain, and the
    spread.

    Returns
    -------
    pandas.DataFrame
        ``method, density, strain`` (the smallest last axial strain of the variants, or
        20 % where all reach the end), per variant ``angle[VARIANT]`` [degrees] and
        ``localisation[VARIANT]`` at the output step nearest that strain, ``reached``
        (the variants' last strains, smallest to largest) and ``spread``: the largest
        minus the smallest angle [degrees] (NaN where some variant finds no band).
    """
    groups = {}
    for method, density, variant, result in study:
        groups.setdefault((method, density), []).append((variant, bands(result)))
    rows = []
    for (method, density), members in groups.items():
        ends = sorted(b.strain.iloc[-1] for _, b in members)
        row = {"method": method, "density": density, "strain": ends[0]}
        for variant, b in members:
            at = _at(b, ends[0])
            row[f"angle[{variant}]"] = at.angle
            row[f"localisation[{variant}]"] = at.localisation
        row["reached"] = " ".join(f"{e:.3g}" for e in ends)
        rows.append(row)
    table = pd.DataFrame(rows)
    angles = table.filter(like="angle[")
    table["spread"] = (angles.max(axis=1) - angles.min(axis=1)).where(
        angles.notna().all(axis=1))
    return table


def figure(study, table, predicted, path):
    """Platen pressure against axial strain (with the homogeneous specimen), and the last
    configuration of each of the study's own runs coloured by shear strain (the scale
    ends at the largest 99th percentile of the runs), with the predicted and the
    measured band directions drawn from the specimen's centre (the lower-left corner,
    where the full specimen's two bands cross)."""
    own = [(m, d, r) for m, d, v, r in study if v == default()]
    densities = list(dict.fromkeys(d for _, d, _ in own))
    methods = list(dict.fromkeys(m for m, _, _ in own))
    fig = plt.figure(figsize=(4.2 * (len(methods) + 1.3), 4.2 * len(densities)),
                     constrained_layout=True)
    grid = fig.add_gridspec(len(densities), len(methods) + 1,
                            width_ratios=[1.3] + [1] * len(methods))
    ax = fig.add_subplot(grid[:, 0])
    homogeneous = homogeneous_pressure()
    p0 = load_case(CASE).material().p0
    ax.plot(homogeneous.strain * 100, homogeneous.pressure / p0, "k-", lw=4, alpha=0.25,
            label="homogeneous (smooth platen), driver")
    for (method, density), run in table.groupby(["method", "density"], sort=False):
        ax.plot(run.strain * 100, run.pressure, ["-", "--", ":"][densities.index(density)],
                color=f"C{methods.index(method)}", label=f"{method}, {run.nodes.iloc[0]} nodes")
    ax.axvline(predicted["onset"] * 100, color="k", lw=0.8, ls=":",
               label="loss of ellipticity (driver)")
    ax.set(xlabel="axial strain [%]", ylabel="mean platen pressure / p'$_0$ [-]",
           title="Rough platen: load-displacement")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    vmax = max(np.nanpercentile(nodal_strain(r.snapshots[0], r.snapshots[-1])[0], 99)
               for _, _, r in own)
    for method, density, result in own:
        ax = fig.add_subplot(grid[densities.index(density), 1 + methods.index(method)])
        image = _configuration(ax, result, vmax)
        run = table[(table.method == method) & (table.density == density)].iloc[-1]
        reach = 1.15 * np.hypot(*result.snapshots[-1].points.max(0))
        for angle, style, label in ((predicted["angle"], "k--", "predicted"),
                                    (run.angle, "r-", "measured")):
            if np.isfinite(angle):
                ray = reach * np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
                ax.plot([0, ray[0]], [0, ray[1]], style, lw=1.2,
                        label=f"{label} {angle:.1f}°")
        ax.set(title=f"{method}, {len(result.case.nodes())} nodes, "
               f"{100 * run.strain:.0f} %", aspect="equal", xlim=(-0.1, 4.0),
               ylim=(-0.1, 4.1))
        if densities.index(density) == len(densities) - 1:
            ax.set_xlabel("x [m]")
        if methods.index(method) == 0:
            ax.set_ylabel("y [m]")
        ax.legend(fontsize=7, loc="upper right")
    fig.colorbar(image, ax=fig.axes[1:], shrink=0.8, extend="max",
                 label="shear strain eps_s = sqrt(2/3 e':e'), Hencky [-]")
    return figures.save(fig, path, dpi=130)


def _configuration(ax, result, vmax):
    """The last configuration: FEM's mesh (its elements' edges) or EFG's nodes, the nodal
    shear strain in colour."""
    snap = result.snapshots[-1]
    gamma, _ = nodal_strain(result.snapshots[0], snap)
    x, y = snap.points.T
    if snap.cells:
        triangles = snap.cells[0][1][:, :3]
        image = ax.tripcolor(x, y, triangles, gamma, shading="gouraud", vmin=0, vmax=vmax,
                             cmap="viridis")
        ax.triplot(x, y, triangles, color="w", lw=0.3)
    else:
        image = ax.scatter(x, y, c=gamma, s=3000 / len(x), vmin=0, vmax=vmax,
                           cmap="viridis")
    return image


def section(data):
    """The report's shear-band section: figure, tables and what they show."""
    predicted, table = data["shearband prediction"], data["shearband"]
    spread = data["shearband robustness"]
    members = [c[len("angle["):-1] for c in spread.filter(like="angle[").columns]
    return [
        "## Rough-platen compression: the shear band",
        "",
        "![shearband](figures/shearband.png)",
        "",
        "The unconfined-compression quarter specimen with a rough top platen (ux fixed), "
        "undrained, to 20 % axial strain (`soilwater run rough-compression --method "
        "METHOD`), on the paper's 111 nodes and on 413 (twice the nodes per side). The "
        "band is rated from each run's nodal shear strain eps_s (the Hencky strain's "
        "deviatoric invariant from the node displacements, as in the footing pictures, "
        "the same for every method): the inclination to the horizontal "
        "(current configuration) of the principal axis of the smallest zone carrying "
        "half the shear strain, where the field is localised (half the strain in less "
        "than a quarter of the body: localisation >= 0.5) and the zone slender (at most "
        "half as wide as long); else no band (NaN, shown as -). Predicted: Rudnicki and "
        "Rice's loss "
        f"of ellipticity on the driver's homogeneous path, at {100 * predicted['onset']:.2f}"
        f" % axial strain, for a band normal inclined {predicted['normal']:.1f} degrees, "
        f"so a band inclined {predicted['angle']:.1f} degrees. `diagonal` is the "
        "inclination of the line from the centre to the platen's edge; pressures are "
        "the mean platen pressure over p'0.",
        "",
        tables.to_markdown(table, floatfmt="{:.3g}"),
        _findings(table, predicted),
        "",
        "Each run repeated (" + ", ".join(members) + "; a bifurcation: round-off may "
        "choose the branch), compared at the last strain all of them reach; `spread` is "
        f"the largest minus the smallest angle there, at most {spread.spread.max():.2g} "
        "degrees:",
        "",
        tables.to_markdown(spread[["method", "density", "strain",
                                   *spread.filter(like="angle[").columns, "reached",
                                   "spread"]], floatfmt="{:.3g}"),
        "",
    ]


def _findings(table, predicted):
    """The paragraph under the study's table: angles against the prediction and the
    diagonal, when bands appear, which runs stopped."""
    ended = table[np.isfinite(table.angle_end)]
    found = table.appears_at.dropna()
    stopped = table[table.stopped]
    text = "No run ends with a band. "
    if len(ended):
        text = ("Band angle at the last step: " + "; ".join(
            f"{r.method} {r.nodes} nodes {r.angle_end:.1f} (at {100 * r.reached:.1f} %)"
            for r in ended.itertuples())
            + f" degrees; {ended.angle_end.max() - ended.angle_end.min():.1f} degrees "
            "between the methods and densities, at most "
            f"{(ended.angle_end - predicted['angle']).abs().max():.1f} from the "
            f"{predicted['angle']:.1f} predicted and at most "
            f"{(ended.angle_end - ended.diagonal).abs().max():.1f} from the diagonal "
            f"({ended.diagonal.min():.1f} to {ended.diagonal.max():.1f}), itself "
            f"{(ended.diagonal - predicted['angle']).abs().min():.1f} to "
            f"{(ended.diagonal - predicted['angle']).abs().max():.1f} degrees from the "
            "prediction. ")
    text += (f"Bands are first rated at {100 * found.min():.1f} to "
             f"{100 * found.max():.1f} % axial strain" if len(found)
             else "No run is rated a band")
    text += (f" (the homogeneous state loses ellipticity at "
             f"{100 * predicted['onset']:.2f} %). ")
    if stopped.empty:
        return text + "Every run reaches 20 %."
    return (text + "Runs that stop early (a step that fails after every halving; "
            "`time.on_failure = \"stop\"`): " + "; ".join(
                f"{r.method} on {r.nodes} nodes at {100 * r.reached:.1f} %"
                for r in stopped.itertuples()) + ".")
