"""The partially drained strip footing: the built-in ``strip-footing-consolidation``
(the footing of ``strip-footing`` loaded in 10 s to half Prandtl's pressure, then held
while the clay, k = 1e-6 m/s, consolidates) by each method of
:data:`soilwater.studies.harness.footing.PLAIN` on the built-in nodes (a label with overrides, such
as ``fem-th+remesh``, is not a method name).

Right after loading the clay has had no time to drain, so the footing must have settled
as far as the undrained footing of ``strip-footing`` at the same pressure: a check of
load control against velocity control, by the same method on the same nodes.
"""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from soilwater.studies.harness import figures, tables
from soilwater.studies.harness.footing import PLAIN, width
from soilwater.studies.harness.grids import refined
from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.runs import solved
from soilwater.references.closed_forms import PRANDTL, undrained_strength
from soilwater.case.loader import load_case

CASE = "strip-footing-consolidation"
#: Spacings per B at the footing (:func:`soilwater.studies.harness.grids.refined`): the
#: built-in nodes', or the footing study's middle density in a quick report.
CORE = pick(8, 4)
#: The end of loading [s] (the load function's first plateau).
LOADED = 10.0


def curves(methods=tuple(PLAIN)):
    """Settlement and the probe's excess pore pressure against time, per method.

    Returns
    -------
    pandas.DataFrame
        ``method, time`` [s], ``settlement`` (over B), ``pressure`` (mean contact
        pressure over ``(2 + pi) s_u``), ``excess`` (the probe's p_w minus its initial
        value over the footing pressure at full load), ``iterations`` and per run
        ``run_time`` [s].
    """
    case = load_case(CASE)
    B, s_u = width(case), undrained_strength(case.material())
    (_, footing), = case.boundary.segments()
    q = footing.force / (footing.end - footing.start)
    (probe, ) = case.probes
    frames = []
    for method, result in zip(methods, solved([(CASE, refined(CORE), m) for m in methods])):
        h = result.history
        frames.append(pd.DataFrame({
            "method": method, "time": h["time"].to_numpy(),
            "settlement": h["settlement@footing"].to_numpy() / B,
            "pressure": h["pressure@footing"].to_numpy() / (PRANDTL * s_u),
            "excess": (h[f"p_w@{probe.name}"].to_numpy()
                       - case.initial_pore_pressure) / q,
            "iterations": h["iterations"].to_numpy(),
            "run_time": result.summary["timings"]["total_s"]}))
    return pd.concat(frames, ignore_index=True)


def summary(table, undrained):
    """Per method: settlement when loaded and at the end, the time to half the
    consolidation settlement, the probe's excess pore pressure, and the undrained
    footing's settlement at the same pressure.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`curves`.
    undrained : pandas.DataFrame
        :func:`soilwater.studies.footing.study.curves` (the built-in nodes' runs of each method are
        used).

    Returns
    -------
    pandas.DataFrame
        ``method``, ``loaded_at`` [s] (the first output time at or after
        :data:`LOADED`: the output times do not fall on it, and interpolating across
        the end of the ramp would take a level short of the full load), ``pressure``
        there (over ``(2 + pi) s_u``), ``loaded`` (settlement over B there),
        ``undrained`` (the velocity-controlled footing's settlement over B at the same
        pressure), ``final`` (at the end), ``t50`` [s] (the first output time by which
        half of ``final - loaded`` has come), ``excess_loaded``, ``excess_final`` (over
        the footing pressure), ``run_time`` [s], ``iterations_per_step``.
    """
    rows = []
    for method, run in table.groupby("method", sort=False):
        t, s = run.time.to_numpy(), run.settlement.to_numpy()
        at = np.flatnonzero(t >= LOADED * (1 - 1e-9))[0]
        loaded, final = s[at], s[-1]
        ref = undrained[(undrained.label == method) & (undrained.core == CORE)]
        half = np.flatnonzero(s >= loaded + (final - loaded) / 2)
        rows.append({
            "method": method, "loaded_at": t[at], "pressure": run.pressure.iloc[at],
            "loaded": loaded,
            "undrained": np.interp(run.pressure.iloc[at], ref.pressure, ref.settlement),
            "final": final, "t50": t[half[0]] if half.size else np.nan,
            "excess_loaded": run.excess.iloc[at],
            "excess_final": run.excess.iloc[-1], "run_time": run.run_time.iloc[0],
            "iterations_per_step": run.iterations.mean()})
    return pd.DataFrame(rows)


def figure(table, path):
    """Settlement and the probe's excess pore pressure over log time, per method."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for k, (method, run) in enumerate(table.groupby("method", sort=False)):
        axes[0].semilogx(run.time, run.settlement, color=f"C{k}", label=method)
        axes[1].semilogx(run.time, run.excess, color=f"C{k}", label=method)
    axes[0].set(xlabel="time [s]", ylabel="settlement / B [-]",
                title="footing under half Prandtl's pressure")
    axes[0].invert_yaxis()
    axes[1].set(xlabel="time [s]", ylabel="excess pore pressure / footing pressure [-]",
                title="on the axis, B/2 under the footing")
    for ax in axes:
        ax.axvline(LOADED, color="k", lw=0.8, ls=":")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    return figures.save(fig, path)


def section(summary):
    """The report's lines on the partially drained footing."""
    return [
        "### Partially drained: the footing held at half its undrained capacity",
        "",
        "![footing consolidation](figures/footing_consolidation.png)",
        "",
        "The built-in `strip-footing-consolidation`: the footing loaded in 10 s to half "
        "Prandtl's pressure, then held to 1e6 s while the clay (k = 1e-6 m/s) drains "
        "through the top beside it. At the first output after loading ("
        + ", ".join(f"{t:.3g}" for t in dict.fromkeys(summary.loaded_at))
        + " s; the pressure " + ", ".join(f"{p:.3g}" for p in summary.pressure)
        + " of Prandtl's) it has settled "
        + ", ".join(f"{r.method} {r.loaded:.3g} B" for r in summary.itertuples())
        + "; the undrained footing of `strip-footing` at the same pressure, same method "
        "and nodes, " + ", ".join(f"{r.undrained:.3g}" for r in summary.itertuples())
        + " B (" + ", ".join(f"{100 * (r.loaded / r.undrained - 1):+.2g} %"
                             for r in summary.itertuples())
        + "). The excess pore pressure on the axis B/2 under the footing is then "
        + ", ".join(f"{r.method} {r.excess_loaded:.3g}" for r in summary.itertuples())
        + " of the footing pressure, at the end "
        + ", ".join(f"{r.excess_final:.2g}" for r in summary.itertuples())
        + ". At the end (1e6 s): " + ", ".join(f"{r.method} {r.final:.3g} B"
                                             for r in summary.itertuples())
        + "; half of the consolidation settlement has come by "
        + ", ".join(f"{r.t50:.2g} s" for r in summary.itertuples())
        + " (the first output time past it; the output times grow 25 % per step).",
        "",
        tables.to_markdown(summary, floatfmt="{:.3g}"),
        "",
    ]
