"""Figures of the strip-footing study, drawn from its saved tables
(:func:`soilwater.studies.footing.study.curves` and its
:func:`~soilwater.studies.footing.study.summary`): how far each method pushes the footing
(:func:`reach`), how its curve converges with the nodes (:func:`convergence`) and what the
accuracy costs (:func:`cost`). Pressures are the mean contact pressure over Prandtl's
``(2 + pi) s_u``, settlements over the footing width B; each figure is one slide
(:mod:`soilwater.studies.harness.figures`).
"""

import textwrap

from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from soilwater.studies.footing.study import (DEEP, FROM, REFERENCE, STEPPED, WITHIN,
                                             family)
from soilwater.studies.harness import figures

PRESSURE = "mean contact pressure / (2 + π) s$_u$ [-]"
SETTLEMENT = "settlement / B [-]"
#: What each method label stands for, in panel titles and legends.
NAMES = {"efg": "efg (EFG, recommended)", "efg-paper": "efg-paper (EFG, the paper's)",
         "fem-th": "fem-th (Taylor-Hood)", "fem-p1p1-stab": "fem-p1p1-stab (P1/P1, stabilised)",
         "fem-th+remesh": "fem-th+remesh (Taylor-Hood, re-meshed)"}
#: Why the curves rise above Prandtl's value: the note on every pressure figure.
GEOMETRY = ("Above 1: large deformation. The footing sinks and the soil heaves around "
            "it, so the mean contact pressure rises above Prandtl's small-strain limit "
            "(2 + π) s$_u$.")
#: Colours of the node densities, light (coarsest) to dark (finest).
DENSITY_COLOURS = ("#56B4E9", "#0072B2", "#000055")
#: Dash patterns of the extra step counts, fewest steps first.
STEP_DASHES = ((0, (4, 1.5)), (0, (1, 1.5)))


def _prandtl(ax):
    """Draw Prandtl's pressure (1) and the band within :data:`WITHIN` of it on ``ax``;
    returns their legend handles (:func:`_prandtl_handles`)."""
    ax.axhspan(1 - WITHIN, 1 + WITHIN, color="0.55", alpha=0.35, lw=0, zorder=1)
    ax.axhline(1.0, **figures.REFERENCE)
    return _prandtl_handles()


def _prandtl_handles():
    return [Line2D([], [], **figures.REFERENCE, label="Prandtl (2 + π) s$_u$"),
            Patch(color="0.55", alpha=0.35, label=f"within {WITHIN:.0%} of Prandtl")]


def _stop(ax, run, colour):
    """An :data:`~soilwater.studies.harness.figures.STOPPED` marker where ``run`` ends if
    it stops short of its target settlement; True if it does."""
    if run.reached.iloc[0] < run.to.iloc[0] - 1e-9:
        ax.plot(run.settlement.iloc[-1], run.pressure.iloc[-1], mfc=colour,
                **figures.STOPPED)
        return True
    return False


def _stop_handle():
    return Line2D([], [], mfc="white", label="run stops: no converged step",
                  **figures.STOPPED)


def reach(table, path, deep=DEEP):
    """``path``: each method pushed to ``deep`` B on the built-in nodes, its pressure
    against the settlement, where it stops marked; Prandtl's pressure and the note on
    why the curves rise above it. The legend sits at the lower right, below the curves
    (they rise from the origin above Prandtl's pressure).

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.footing.study.curves`.
    path : str or Path

    Returns
    -------
    pathlib.Path
    """
    deep_runs = table[table.label.str.endswith(f"to {deep:g} B")]
    with figures.style():
        fig, ax = figures.slide()
        handles = _prandtl(ax)
        stopped = False
        for label, run in deep_runs.groupby("label", sort=False):
            method = label.split(",")[0]
            colour = figures.METHOD_COLOURS[method]
            end = (f"stops at {run.reached.iloc[0]:.3g} B"
                   if run.reached.iloc[0] < run.to.iloc[0] - 1e-9 else f"reaches {deep:g} B")
            ax.plot(run.settlement, run.pressure, color=colour, lw=2.4,
                    label=f"{NAMES[method]}: {end}")
            stopped |= _stop(ax, run, colour)
        handles = ax.get_legend_handles_labels()[0] + handles
        if stopped:
            handles.append(_stop_handle())
        ax.text(0.02, 0.97, textwrap.fill(GEOMETRY, 48), transform=ax.transAxes,
                va="top", ha="left", fontsize=12,
                bbox={"facecolor": "white", "edgecolor": "0.6", "pad": 6})
        nodes = deep_runs.nodes.iloc[0].replace("x", " x ")
        ax.set(xlabel=SETTLEMENT, ylabel=PRESSURE, xlim=(0, deep * 1.02), ylim=(0, None),
               title=f"Strip footing on undrained clay: how far each method gets "
                     f"({nodes} nodes, pushed to {deep:g} B)")
        ax.legend(handles=handles, loc="lower right", frameon=True, framealpha=1)
        return figures.save(fig, path)


def convergence(table, path, reference=REFERENCE):
    """``path``: a panel per method (shared axes), its curve on each node density to
    0.5 B and, for :data:`~soilwater.studies.footing.study.STEPPED`, the coarsest nodes
    with more steps (dashed); the reference curve and Prandtl's pressure in every panel,
    early stops marked. The runs pushed further are :func:`reach`'s.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.footing.study.curves`.
    path : str or Path
    reference : (str, int)
        The reference run's label and density.

    Returns
    -------
    pathlib.Path
    """
    shallow = table[table.to <= table.to.min() + 1e-9]
    ref = shallow[(shallow.label == reference[0]) & (shallow.core == reference[1])]
    labels = family(shallow.label)
    methods = list(dict.fromkeys(labels))
    steps = shallow.steps.min()
    dashes = dict(zip(sorted(set(shallow.steps) - {steps}), STEP_DASHES))
    stopped = False
    cores = sorted(shallow.core.unique())
    colours = dict(zip(cores, DENSITY_COLOURS[-len(cores):]))
    with figures.style():
        fig, axes = figures.slide(2, 3, sharex=True, sharey=True)
        for ax, method in zip(axes.flat, methods):
            ax.plot(ref.settlement, ref.pressure, color="0.35", ls=(0, (5, 2)), lw=2.0,
                    zorder=2)
            _prandtl(ax)
            for (label, core), run in shallow[labels == method].groupby(
                    ["label", "core"], sort=False):
                colour = colours[core]
                ax.plot(run.settlement, run.pressure, color=colour, lw=2.2,
                        ls=dashes.get(run.steps.iloc[0], "-"))
                stopped |= _stop(ax, run, colour)
            ax.set_title(NAMES[method], fontsize=12)
        legend_ax = axes.flat[-1]
        legend_ax.set_axis_off()
        nodes = shallow.groupby("core").nodes.first()
        handles = [Line2D([], [], color=colours[c], lw=2.2,
                          label=f"{nodes[c].replace('x', ' x ')} nodes, {steps} steps")
                   for c in cores]
        handles += [Line2D([], [], color=colours[cores[0]], ls=ls, lw=2.2,
                           label=f"{STEPPED}, {nodes[cores[0]].replace('x', ' x ')} "
                                 f"nodes, {n} steps")
                    for n, ls in dashes.items()]
        handles += [Line2D([], [], color="0.35", ls=(0, (5, 2)), lw=2.0,
                           label=f"reference: {reference[0]}, "
                                 f"{nodes[reference[1]].replace('x', ' x ')} nodes"),
                    *_prandtl_handles()] + ([_stop_handle()] if stopped else [])
        legend_ax.legend(handles=handles, loc="center left")
        for ax in axes[-1]:
            ax.set_xlabel(SETTLEMENT)
        axes[0, -1].xaxis.set_tick_params(labelbottom=True)
        axes[0, -1].set_xlabel(SETTLEMENT)
        fig.supylabel(PRESSURE, fontsize=12)
        axes[0, 0].set(xlim=(0, 0.5), ylim=(0, None))
        fig.suptitle("Strip footing to 0.5 B: each method's curve as its nodes are refined"
                     "\n" + textwrap.fill(GEOMETRY, 120), fontsize=13)
        return figures.save(fig, path)


def cost(summary, path):
    """``path``: error against the reference curve over run time, log-log: per method a
    line through its densities (to 0.5 B at the case's step), the extra step counts as
    open markers, each marker labelled with its nodes and steps and, when the run stopped
    early (its error then covers a shorter range), where. The runs pushed to
    :data:`~soilwater.studies.footing.study.DEEP` B are left out (their time buys the
    deeper part).

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`soilwater.studies.footing.study.summary`.
    path : str or Path

    Returns
    -------
    pathlib.Path
    """
    shallow = summary[(summary.to <= summary.to.min() + 1e-9) & (summary.error > 0)]
    with figures.style():
        fig, ax = figures.slide()
        for method, group in shallow.groupby(family(shallow.label), sort=False):
            colour = figures.METHOD_COLOURS.get(method, "0.4")
            plain = group[group.label == method]
            extra = group[group.label != method]
            ax.loglog(plain.run_time, plain.error, "o-", color=colour, ms=8,
                      label=NAMES.get(method, method))
            if len(extra):
                ax.loglog(extra.run_time, extra.error, "o", mfc="none", ms=9, mew=1.8,
                          color=colour, label=f"{method}, more steps")
            for r in group.itertuples():
                note = f"{r.nodes}, {r.steps}"
                if r.reached < r.to - 1e-9:
                    note += f", stops {r.reached:.3g} B"
                ax.annotate(note, (r.run_time, r.error), fontsize=10, color=colour,
                            textcoords="offset points",
                            xytext=(7, 4) if r.label == method else (8, -14))
        ax.set(xlabel="run time [s]",
               ylabel=f"largest |p / p$_{{ref}}$ - 1| from {FROM:g} B [-]",
               title=f"Strip footing: error against {REFERENCE[0]} on the finest nodes, "
                     "and what it costs (labels: nodes, steps)")
        ax.grid(which="both")
        ax.margins(x=0.1)
        fig.legend(loc="outside lower center", ncol=3)
        return figures.save(fig, path)

