"""A fair large-deformation comparison on the strip footing: each method at equal vertices,
at equal displacement unknowns and at equal run time, smooth and rough, to 1 B, against
a converged reference.

The built-in ``strip-footing`` case (weightless NC Cam-clay, undrained) is pushed to
:data:`TO` B at its own step (200 steps to 1 B), smooth and rough (:data:`ROUGHNESS`), by
each method of :data:`SIZES` on the node sets refined to its cores (spacings per B at the
footing, :func:`soilwater.studies.harness.grids.refined`): EFG in the recommended and the
paper's configurations and fem-p1p1-stab on the same vertices, and Taylor-Hood on half
their density as well, which has about EFG's displacement unknowns (its P2 nodes are the
vertices of a grid twice as fine). The reference at each settlement of :data:`LEVELS` is
the Richardson extrapolation of Taylor-Hood's three densities (:func:`richardson`), with
its observed order and its own error estimate; where the three do not converge
monotonically there is no reference at that settlement.

Embedding is the independent check: a rigid rough strip footing wished into weightless
Tresca clay at depth D carries ``(2 + pi) s_u (1 + 0.27 sqrt(D / B))`` (Salgado, Lyamin,
Sloan and Yu 2004, :func:`embedded`), 6.1 s_u at 0.5 B and 6.5 s_u at 1 B. A footing
pushed from the surface differs: the clay heaves beside it instead of standing level at
the base, nothing acts on its sides, and Cam-clay's undrained strength is Tresca's
``s_u`` only at constant volume and at critical state (its stress path reaches it after
some shear strain; the smooth footing has no base adhesion). The check is of the trend.
"""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from soilwater.case.loader import load_case
from soilwater.geometry.quality import DISTORTED
from soilwater.methods import EFG_METHODS
from soilwater.references.closed_forms import PRANDTL, undrained_strength
from soilwater.studies.harness import deformation, figures, tables
from soilwater.studies.harness.footing import CASE, time_steps, width
from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.grids import refined
from soilwater.studies.harness.runs import solved

#: The footing's base: smooth (the built-in case) or rough (no sideways motion).
ROUGHNESS = pick({"smooth": (), "rough": ("boundary.top.footing.ux=fixed",)},
                 {"smooth": ()})
#: Settlement [B] every run is pushed to.
TO = pick(1.0, 0.25)
#: Each method's densities (spacings per B at the footing): Taylor-Hood also on half
#: the others' density (about their displacement unknowns); its three make the reference.
SIZES = pick({"efg": (4, 8), "efg-paper": (4, 8), "fem-p1p1-stab": (4, 8),
              "fem-th": (2, 4, 8)},
             {"efg": (2, 4), "efg-paper": (2, 4), "fem-p1p1-stab": (2, 4),
              "fem-th": (2, 4, 8)})
#: The method whose densities give the Richardson reference.
REFERENCE = "fem-th"
#: Settlements [B] at which pressures and errors are compared.
LEVELS = pick((0.1, 0.25, 0.5, 0.75, 1.0), (0.1, 0.25))
#: Observed orders outside this range make a Richardson estimate unreliable (no
#: reference there).
ORDERS = (0.5, 4.0)


def runs(sizes=SIZES, roughness=ROUGHNESS, to=TO):
    """``(roughness, method, core, overrides)`` of every run."""
    case = load_case(CASE)
    factor = to / (case.time.end * _rate(case) / width(case))
    end, steps = case.time.end * factor, time_steps(case, factor)
    return [(rough, method, core, (*refined(core), *extra, f"time.end={end!r}",
                                   f"time.steps={steps}"))
            for rough, extra in roughness.items()
            for method, cores in sizes.items() for core in cores]


def _rate(case):
    (_, footing), = case.boundary.segments()
    return footing.settlement_rate


def curves(study=None):
    """Load-settlement curves of every run of :func:`runs`.

    Returns
    -------
    pandas.DataFrame
        One row per time level: ``roughness, method, core, nodes`` (vertices),
        ``u_unknowns`` and ``p_unknowns`` (EFG: two and one per node; FEM: the pair's
        displacement DOFs and its P1 pressure's, one per vertex), ``settlement`` [B],
        ``pressure`` (mean contact pressure over ``(2 + pi) s_u``), ``distortion`` (the
        smallest ratio of a triangle's smallest angle to its undeformed one over the
        triangles of the initial vertices moved with them; negative once one inverts),
        and per run ``run_time`` [s] and ``reached`` [B].
    """
    study = runs() if study is None else study
    case = load_case(CASE)
    B, s_u = width(case), undrained_strength(case.material())
    frames = []
    for (rough, method, core, overrides), result in zip(
            study, solved([(CASE, o, m) for _, m, _, o in study])):
        h, nodes = result.history, len(result.case.nodes())
        u = 2 * nodes if method in EFG_METHODS else result.summary["dofs"] - nodes
        triangles = deformation.triangulation(result.snapshots[0])
        angles = deformation.smallest_angles(result.snapshots, triangles)
        frames.append(pd.DataFrame({
            "roughness": rough, "method": method, "core": core, "nodes": nodes,
            "u_unknowns": u, "p_unknowns": result.summary["dofs"] - u,
            "settlement": h["settlement@footing"].to_numpy() / B,
            "pressure": h["pressure@footing"].to_numpy() / (PRANDTL * s_u),
            "distortion": (angles / angles[0]).min(axis=1)[1:],
            "run_time": result.summary["timings"]["total_s"],
            "reached": h["settlement@footing"].iloc[-1] / B}))
    return pd.concat(frames, ignore_index=True)


def embedded(depth):
    """Bearing pressure of a rigid rough strip footing embedded ``depth`` widths deep in
    weightless Tresca clay, over Prandtl's ``(2 + pi) s_u``: Salgado et al.'s (2004)
    depth factor ``1 + 0.27 sqrt(D / B)`` from finite element limit analysis.

    Examples
    --------
    >>> [round(float(PRANDTL * embedded(d)), 2) for d in (0.0, 0.5, 1.0)]
    [5.14, 6.12, 6.53]
    """
    return 1.0 + 0.27 * np.sqrt(depth)


def richardson(coarse, middle, fine, ratio=2.0, orders=ORDERS):
    """Richardson extrapolation of three results on spacings ``ratio`` apart.

    Returns
    -------
    (estimate, order, error) : floats
        The extrapolated value, the observed order ``log(d1 / d2) / log(ratio)`` (``d1 =
        middle - coarse``, ``d2 = fine - middle``) and the finest result's estimated
        error ``d2 / (ratio^order - 1)``; all NaN when the differences change sign or the
        order lies outside ``orders`` (no asymptotic convergence to extrapolate).

    Examples
    --------
    Second-order results on halved spacings, ``1 + h^2`` for h = 0.4, 0.2, 0.1:

    >>> [round(v, 6) for v in richardson(1.16, 1.04, 1.01)]
    [1.0, 2.0, 0.01]
    """
    d1, d2 = middle - coarse, fine - middle
    if not d1 * d2 > 0:
        return np.nan, np.nan, np.nan
    order = np.log(d1 / d2) / np.log(ratio)
    if not orders[0] <= order <= orders[1]:
        return np.nan, float(order), np.nan
    error = d2 / (ratio ** order - 1)
    return float(fine + error), float(order), float(abs(error))


def _at(run, level):
    """A run's pressure at settlement ``level`` [B], NaN beyond its reach."""
    s, p = run.settlement.to_numpy(), run.pressure.to_numpy()
    return float(np.interp(level, s, p)) if s[-1] >= level - 1e-9 else np.nan


def reference(table, levels=LEVELS, method=REFERENCE):
    """The Richardson reference per roughness and settlement: ``roughness, settlement,
    coarse, middle, fine`` (the reference method's pressures, densities ascending),
    ``reference``, ``order``, ``error`` (the finest's estimated error) and ``embedded``
    (:func:`embedded` at that depth)."""
    rows = []
    for rough, group in table[table.method == method].groupby("roughness", sort=False):
        ordered = [run for _, run in sorted(group.groupby("core"))]
        for level in levels:
            p = [_at(run, level) for run in ordered]
            estimate, order, error = richardson(*p[-3:])
            rows.append({"roughness": rough, "settlement": level, "coarse": p[-3],
                         "middle": p[-2], "fine": p[-1], "reference": estimate,
                         "order": order, "error": error, "embedded": embedded(level)})
    return pd.DataFrame(rows)


def summary(table, ref, levels=LEVELS):
    """Per run: its size, cost, reach, distortion and pressure and error at each level.

    Returns
    -------
    pandas.DataFrame
        ``roughness, method, core, nodes, u_unknowns, p_unknowns, run_time`` [s],
        ``reached`` [B], ``distorted_at`` (the first settlement [B] with a triangle
        below :data:`soilwater.geometry.quality.DISTORTED` of its undeformed smallest
        angle; NaN if none), ``p_<level>`` (pressure over Prandtl's at each level),
        ``e_<level>`` (``p / reference - 1``; NaN without a reference or beyond the
        run's reach) and ``error`` (the largest ``|e|`` over the levels it has).
    """
    rows = []
    for (rough, method, core), run in table.groupby(["roughness", "method", "core"],
                                                    sort=False):
        at = ref[ref.roughness == rough].set_index("settlement").reference
        distorted = np.flatnonzero(run.distortion.to_numpy() < DISTORTED)
        row = {"roughness": rough, "method": method, "core": core,
               "nodes": run.nodes.iloc[0], "u_unknowns": run.u_unknowns.iloc[0],
               "p_unknowns": run.p_unknowns.iloc[0], "run_time": run.run_time.iloc[0],
               "reached": run.reached.iloc[0],
               "distorted_at": (run.settlement.iloc[distorted[0]] if distorted.size
                                else np.nan)}
        errors = []
        for level in levels:
            p = _at(run, level)
            row[f"p_{level:g}"] = p
            row[f"e_{level:g}"] = p / at.get(level, np.nan) - 1
            errors.append(abs(row[f"e_{level:g}"]))
        row["error"] = np.nanmax(errors) if np.isfinite(errors).any() else np.nan
        rows.append(row)
    return pd.DataFrame(rows)


def pairs(summary):
    """Each EFG run beside Taylor-Hood, per roughness: the Taylor-Hood run nearest it in
    displacement unknowns (``th_*``: its nodes, unknowns, reach, error and run time),
    the one nearest it in run time (``time_th_*``) and the one on its vertices
    (``th_error_same_vertices``). Nearest is on a log scale."""
    rows = []
    for r in summary[summary.method.isin(EFG_METHODS)].itertuples():
        th = summary[(summary.method == REFERENCE) & (summary.roughness == r.roughness)]
        near = th.iloc[np.argmin(np.abs(np.log(th.u_unknowns / r.u_unknowns)))]
        timed = th.iloc[np.argmin(np.abs(np.log(th.run_time / r.run_time)))]
        same = th[th.nodes == r.nodes]
        rows.append({"roughness": r.roughness, "method": r.method, "nodes": r.nodes,
                     "u_unknowns": r.u_unknowns, "reached": r.reached, "error": r.error,
                     "run_time": r.run_time, "th_nodes": near.nodes,
                     "th_u_unknowns": near.u_unknowns, "th_reached": near.reached,
                     "th_error": near.error, "th_run_time": near.run_time,
                     "time_th_nodes": timed.nodes, "time_th_reached": timed.reached,
                     "time_th_error": timed.error, "time_th_run_time": timed.run_time,
                     "th_error_same_vertices": (same.error.iloc[0] if len(same)
                                                else np.nan)})
    return pd.DataFrame(rows)


def verdict(paired):
    """The paper's claim that EFG handles large, non-uniform deformation where FEM meets
    mesh distortion, judged at equal displacement unknowns and at equal run time:
    ``(verdict, measured)``.

    A pairing favours EFG when its run gets further than Taylor-Hood's and is no
    further from the reference, or gets as far and is nearer; it favours Taylor-Hood
    the other way round. Supported if some EFG run is favoured at equal unknowns or at
    equal run time; refuted if Taylor-Hood is favoured in both pairings of every EFG
    run; open otherwise.
    """
    def favours_efg(reached, error, th_reached, th_error):
        return ((reached > th_reached + 1e-9 and error <= th_error)
                or (reached >= th_reached - 1e-9 and error < th_error))

    wins, losses = [], []
    for r in paired.itertuples():
        for prefix in ("th", "time_th"):
            other = (getattr(r, f"{prefix}_reached"), getattr(r, f"{prefix}_error"))
            wins.append(favours_efg(r.reached, r.error, *other))
            losses.append(favours_efg(*other, r.reached, r.error))
    word = ("supported" if any(wins) else "refuted" if all(losses) else "open")
    return word, (
        f"strip footing smooth and rough to {TO:g} B, error the largest |p / p_ref - 1| "
        f"over {', '.join(f'{v:g}' for v in LEVELS)} B against the Richardson "
        f"extrapolation of {REFERENCE}: " + "; ".join(
            f"{r.roughness} {r.method} ({r.nodes} nodes, {r.u_unknowns} u) reached "
            f"{r.reached:.3g} B, error {r.error:.2g}, {r.run_time:.0f} s; {REFERENCE} at "
            f"equal unknowns ({r.th_nodes} nodes, {r.th_u_unknowns} u) {r.th_reached:.3g} "
            f"B, {r.th_error:.2g}, {r.th_run_time:.0f} s; at equal run time ("
            f"{r.time_th_nodes} nodes) {r.time_th_reached:.3g} B, {r.time_th_error:.2g}"
            for r in paired.itertuples()))


def figure(table, ref, path):
    """Load-settlement curves, smooth and rough side by side: every run (each method's
    finest solid), where a run stops marked with a cross in its panel, the Richardson
    reference with its error bar, the embedded-footing trend."""
    fig, axes = plt.subplots(1, len(ROUGHNESS), figsize=(12.8, 5.6), sharey=True,
                             constrained_layout=True, squeeze=False)
    colors = {method: f"C{k}" for k, method in enumerate(SIZES)}
    for ax, rough in zip(axes[0], ROUGHNESS):
        panel = table[table.roughness == rough]
        for (method, core), run in panel.groupby(["method", "core"], sort=False):
            color = colors.get(method, "k")
            finest = core == max(SIZES[method])
            label = f"{method}, {run.nodes.iloc[0]} nodes, {run.u_unknowns.iloc[0]} u"
            if run.reached.iloc[0] < TO - 1e-9:     # the panel's own stops, marked
                end = (run.settlement.iloc[-1], run.pressure.iloc[-1])
                ax.plot(*end, "x", color=color, ms=8)
                ax.annotate(f"stops {end[0]:.2f} B", end, fontsize=7, color=color,
                            textcoords="offset points", xytext=(4, -10))
            ax.plot(run.settlement, run.pressure, "-" if finest else "--", color=color,
                    lw=1.6 if finest else 1.0, alpha=1.0 if finest else 0.7, label=label)
        r = ref[ref.roughness == rough]
        ax.errorbar(r.settlement, r.reference, yerr=r.error, fmt="ks", ms=5, capsize=3,
                    label=f"reference: Richardson on {REFERENCE}")
        depth = np.linspace(0.0, TO, 50)
        ax.plot(depth, embedded(depth), "k:", lw=1.2,
                label="embedded rough footing, Tresca (Salgado et al. 2004)")
        ax.axhline(1.0, color="0.5", lw=0.8)
        ax.set(title=f"{rough} footing", xlabel="settlement / B [-]")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("mean contact pressure / (2 + pi) s_u [-]")
    handles, labels = axes[0, -1].get_legend_handles_labels()
    axes[0, -1].legend(handles, labels, fontsize=7, loc="upper left",
                       bbox_to_anchor=(1.02, 1.0))
    return figures.save(fig, path, dpi=110)


def cost_figure(summary, path):
    """Error against the reference over displacement unknowns and over run time, smooth
    (filled) and rough (open); runs that stop early marked with their reach."""
    fig, axes = plt.subplots(1, 2, figsize=(12.8, 5.2), sharey=True,
                             constrained_layout=True)
    for k, (method, group) in enumerate(summary.groupby("method", sort=False)):
        for rough, marker in zip(ROUGHNESS, ("o", "s")):
            g = group[(group.roughness == rough) & group.error.notna()].sort_values("core")
            for ax, x in zip(axes, ("u_unknowns", "run_time")):
                ax.loglog(g[x], g.error, marker + "-", color=f"C{k}",
                          mfc=f"C{k}" if rough == "smooth" else "none",
                          label=f"{method}, {rough}")
                for r in g[g.reached < TO - 1e-9].itertuples():
                    ax.annotate(f"stops {r.reached:.2f} B", (getattr(r, x), r.error),
                                fontsize=7, textcoords="offset points", xytext=(4, 4))
    axes[0].set(xlabel="displacement unknowns [-]",
                ylabel="largest |p / p_ref - 1| over the settlements reached [-]")
    axes[1].set(xlabel="run time [s]")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
    axes[1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return figures.save(fig, path, dpi=110)


def section(summary, ref, paired):
    """The report's section."""
    return [
        "### A fair comparison: equal unknowns, equal run time, smooth and rough, to 1 B",
        "",
        "![fair footing](figures/footing_fair.png)",
        "",
        f"The built-in footing pushed to {TO:g} B at its own step, smooth and rough "
        "(`--set boundary.top.footing.ux=fixed`), by `efg` (recommended), `efg-paper`, "
        "`fem-p1p1-stab` on the same vertices and `fem-th` also on half their density, "
        "which has about EFG's displacement unknowns (`u_unknowns`). Cores (spacings per B "
        "at the footing): " + "; ".join(f"{m} {', '.join(map(str, c))}"
                                        for m, c in SIZES.items())
        + ". The reference at each settlement is the Richardson extrapolation of "
        f"{REFERENCE} on its three densities (`order` its observed order, `error` the "
        "finest run's estimated error; none where they do not converge monotonically, "
        f"or at an order outside {ORDERS[0]:g} to {ORDERS[1]:g}); `embedded` is the "
        "bearing pressure of a rough footing wished into weightless Tresca clay at that "
        "depth (Salgado et al. 2004), a check of the trend only: the pushed footing's "
        "clay heaves beside it, nothing acts on its sides, and Cam-clay reaches s_u "
        "only at critical state. Pressures over Prandtl's (2 + pi) s_u. Taylor-Hood's "
        "errors are against an extrapolation of its own runs, which favours it where its "
        "runs share an error the extrapolation cannot see (the fixed mesh's); where "
        "they do not converge there is no error for any method.",
        "",
        tables.to_markdown(ref, floatfmt="{:.4g}"),
        "",
        tables.to_markdown(summary, floatfmt="{:.3g}"),
        "",
        "Each EFG run beside Taylor-Hood at about its displacement unknowns (`th_*`) "
        "and on its own vertices (`th_error_same_vertices`): errors are the largest "
        "over the settlements each reached.",
        "",
        tables.to_markdown(paired, floatfmt="{:.3g}"),
        "",
        "![fair footing cost](figures/footing_fair_cost.png)",
        "",
    ]
