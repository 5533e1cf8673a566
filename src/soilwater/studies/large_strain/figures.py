"""Figures of the finite-strain consolidation study, drawn from its saved tables
(:func:`soilwater.studies.large_strain.study.curves`, ``small_strain`` and ``profiles``):
each method's settlement against Gibson's finite-strain reference (:func:`settlement`)
and the profiles along the centre line (:func:`profiles`). Each is one slide
(:mod:`soilwater.studies.harness.figures`).
"""

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from soilwater.studies.harness import figures
from soilwater.studies.large_strain.study import CASES, METHODS, WINDOWS

#: What each case is, in the panel titles.
TITLES = {"large-strain-column": "large-strain-column: a soft layer loaded tenfold",
          "self-weight-consolidation": "self-weight-consolidation: a fresh deposit"}
#: Range of the settlement error shown [%]; values beyond are drawn on it, marked.
ERROR_LIMIT = 5.0
#: The target on the settlement error [%] from :data:`TARGET_FROM` T on.
TARGET = 2.0
TARGET_FROM = WINDOWS[1]
TIME = "time t / T [-] (T = d$^2$ / c$_{v0}$)"
#: Line style of small-strain Terzaghi, a second reference.
TERZAGHI = {"color": "black", "ls": (0, (5, 3)), "lw": 1.6}


def _colour(method):
    return figures.METHOD_COLOURS.get(method, "0.4")


def settlement(table, small, path, limit=ERROR_LIMIT):
    """``path``: per case (a column each, sharing its time axis, log scale) the
    settlement of each method over Gibson's finite-strain one (above; for the loaded
    column also small-strain Terzaghi) and its relative error against Gibson (below,
    within ``limit`` %, values beyond drawn on the limit with a triangle pointing out),
    the target band from :data:`TARGET_FROM` T on shaded.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.large_strain.study.curves`.
    small : pandas.DataFrame
        :func:`soilwater.studies.large_strain.study.small_strain`.
    path : str or Path
    limit : float
        Largest error shown [%].

    Returns
    -------
    pathlib.Path
    """
    cases = [c for c in CASES if c in set(table.case)]
    clipped = False
    with figures.style():
        fig, axes = figures.slide(2, len(cases), sharex="col", sharey="row",
                                  height_ratios=(2, 1), squeeze=False)
        for j, name in enumerate(cases):
            runs = table[table.case == name]
            ref = runs[runs.method == runs.method.iloc[0]]
            top, bottom = axes[0, j], axes[1, j]
            top.semilogx(ref.t_over_T, ref.gibson, **figures.REFERENCE)
            if name == CASES[0]:
                top.semilogx(small.t_over_T, small.settlement, **TERZAGHI)
            t = ref.t_over_T
            bottom.fill_between(t, -TARGET, TARGET, where=t >= TARGET_FROM, color="0.8",
                                lw=0, zorder=0)
            bottom.axhline(0.0, color="black", lw=1.0)
            for method, run in runs.groupby("method", sort=False):
                colour = _colour(method)
                top.semilogx(run.t_over_T, run.settlement, color=colour, lw=1.6)
                error = 100 * run.error
                bottom.semilogx(run.t_over_T, error.clip(-limit, limit), color=colour,
                                lw=1.6)
                for sign, marker in ((1, "^"), (-1, "v")):
                    beyond = sign * error > limit
                    if beyond.any():
                        bottom.plot(run.t_over_T[beyond], np.full(beyond.sum(), sign * limit),
                                    marker, color=colour, mec="black", mew=0.4,
                                    clip_on=False, **figures.CLIPPED)
                        clipped = True
            top.set_title(TITLES.get(name, name))
            bottom.set(xlabel=TIME, ylim=(-limit, limit))
        axes[0, 0].set_ylabel("settlement [m]")
        axes[0, 0].invert_yaxis()
        axes[1, 0].set_ylabel("error against Gibson [%]")
        handles = [Line2D([], [], **figures.REFERENCE, label="Gibson (finite strain)"),
                   Line2D([], [], **TERZAGHI, label="Terzaghi (small strain,\ninitial "
                          "m$_v$, c$_v$)"),
                   *[Line2D([], [], color=_colour(m), lw=1.6, label=m) for m in METHODS
                     if m in set(table.method)],
                   Patch(color="0.8", label=f"target: within {TARGET:g} % of Gibson\n"
                                            f"from {TARGET_FROM:g} T on")]
        if clipped:
            handles.append(Line2D([], [], marker="^", color="0.6", mec="black",
                                  label=f"error beyond ±{limit:g} %\n(drawn on the limit)",
                                  **figures.CLIPPED))
        fig.legend(handles=handles, loc="outside right center")
        fig.suptitle("Finite-strain consolidation: settlement against Gibson's reference "
                     "(settlement downwards)")
        return figures.save(fig, path)


#: The profiles' quantities: column, axis label, log scale.
QUANTITIES = (("e", "void ratio e [-]", False), ("p_eff", "p' [kPa]", False),
              ("k", "permeability k [m/s]", True), ("p_w", "excess p$_w$ [kPa]", False))
MARKERS = ("o", "s", "^", "D")


def profiles(table, name, path):
    """``path``: void ratio, mean effective stress, permeability (log scale) and excess
    pore pressure against the current height at each profile time, one case, the panels
    sharing the height axis: Gibson's as lines, the methods as markers, a colour per
    time.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.large_strain.study.profiles`.
    name : str
        The case.
    path : str or Path

    Returns
    -------
    pathlib.Path
    """
    runs = table[table.case == name]
    methods = list(dict.fromkeys(runs.method))
    ref = runs[runs.method == methods[0]]
    times = sorted(ref.t_over_T.unique())
    with figures.style():
        fig, axes = figures.slide(1, len(QUANTITIES), sharey=True)
        for ax, (column, label, log) in zip(axes, QUANTITIES):
            for i, (_, at) in enumerate(ref.groupby("t_over_T", sort=True)):
                ax.plot(at[f"{column}_gibson"], at.height, color=f"C{i + 3}", lw=2.5,
                        alpha=0.6)
            for m, (method, run) in enumerate(runs.groupby("method", sort=False)):
                for i, (_, at) in enumerate(run.groupby("t_over_T", sort=True)):
                    ax.plot(at[column], at.height, MARKERS[m % len(MARKERS)], ms=5,
                            mfc="none", color=f"C{i + 3}")
            ax.set(xlabel=label, xscale="log" if log else "linear")
        axes[0].set_ylabel("current height above the base [m]")
        handles = [Line2D([], [], color=f"C{i + 3}", lw=2.5, alpha=0.6,
                          label=f"Gibson, t = {when:.2g} T") for i, when in enumerate(times)]
        handles += [Line2D([], [], marker=MARKERS[m % len(MARKERS)], mfc="none", ls="none",
                           color="0.3", label=method) for m, method in enumerate(methods)]
        fig.legend(handles=handles, loc="outside lower center", ncol=len(handles) // 2 + 1)
        fig.suptitle(f"{name}: profiles on the centre line (lines: Gibson; markers: the "
                     "methods; a colour per time)")
        return figures.save(fig, path)
