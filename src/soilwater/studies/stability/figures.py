"""Figures of the report's pore-pressure stability section: the Table 2 sweep
(:func:`table2`) and the column profiles (:func:`column_profiles`), each one slide
(:mod:`soilwater.studies.harness.figures`); each saves a PNG and returns its path."""

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.lines import Line2D

from soilwater.studies.harness import figures
from soilwater.studies.harness.metrics import BAD, GOOD
from soilwater.studies.stability.study import COMBINATIONS

#: The weight functions of :data:`~soilwater.studies.stability.study.COMBINATIONS`
#: spelled out.
WEIGHT_NAMES = {"quartic": "quartic", "exp:0.5": "exponential c = 0.5",
                "exp:0.25": "exponential c = 0.25"}
#: Colour range of the interior pollution over the load [-] (log scale).
POLLUTION_RANGE = (0.1, 30.0)
#: Its colour bar's ticks (with the ratings' bounds).
POLLUTION_TICKS = (0.1, 3.0, 10.0, 30.0)
#: Limits of the pore pressure over the load in the profiles [-]; values beyond are
#: drawn on the limit with a marker.
PROFILE_LIMITS = (-0.6, 2.2)


def weights_label(name):
    """``"Q/Q"`` -> ``"quartic / quartic"``: a combination's displacement and
    pore-pressure weights spelled out."""
    u, p = COMBINATIONS[name]
    return f"{WEIGHT_NAMES[u]} / {WEIGHT_NAMES[p]}"


def table2(table, path):
    """Heat map of the Table 2 sweep: weight combination (displacement / pore pressure)
    against the support scale factor (and the measured mean nodes per support), colour
    the first step's interior pollution over the load on a log scale (colour bar in
    true values, the ratings' bounds marked on it), the value printed in each cell; one
    panel per permeability (shared axes), the paper's rating beside each row.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.stability.study.table2`.
    path : str or Path

    Returns
    -------
    pathlib.Path
    """
    perms = sorted(set(table.permeability))
    norm = LogNorm(*POLLUTION_RANGE)
    with figures.style():
        fig, axes = figures.slide(1, len(perms), sharex=True, sharey=True, squeeze=False)
        for ax, k in zip(axes[0], perms):
            part = table[table.permeability == k]
            grid = part.pivot(index="weights", columns="scale", values="interior")
            grid = grid.loc[list(dict.fromkeys(part.weights))]
            values = grid.to_numpy()
            image = ax.imshow(values, cmap=figures.SEQUENTIAL, norm=norm, aspect="auto")
            for (i, j), value in np.ndenumerate(values):
                dark = norm(value) < 0.6           # viridis: dark below, light above
                ax.text(j, i, f"{value:.2g}", ha="center", va="center", fontsize=13,
                        color="white" if dark else "black")
            counts = part.groupby("scale").nodes_per_support.mean()
            ax.set_xticks(range(len(grid.columns)),
                          [f"×{s:g}\n{counts[s]:.0f}" for s in grid.columns])
            paper = part.groupby("weights").paper.first()
            ax.set_yticks(range(len(grid.index)),
                          [f"{weights_label(w)}\npaper: {paper[w] or 'not in the paper'}"
                           for w in grid.index])
            ax.set_title("undrained, k = 0 m/s" if k == 0 else f"k = {k:g} m/s")
            ax.grid(False)
        fig.supxlabel("support scale factor (×) and mean nodes per support [-]",
                      fontsize=12)
        axes[0, 0].set_ylabel("weights: displacement / pore pressure [-]")
        bar = fig.colorbar(image, ax=axes[0].tolist(), shrink=0.9,
                           label="interior pollution / load [-] (log scale)")
        ticks = sorted({*POLLUTION_TICKS, GOOD, BAD})
        bar.set_ticks(ticks, labels=[f"{v:g}" + (" good ≤" if v == GOOD else
                                                 " bad >" if v == BAD else "")
                                     for v in ticks])
        bar.minorticks_off()
        for bound in (GOOD, BAD):
            bar.ax.axhline(bound, color="white", lw=2)
        fig.suptitle("Table 2 as a sweep: soil column 5 x 41 nodes, first step; the "
                     "paper's rating from low to high density (× bad, △ better, ○ good)")
        return figures.save(fig, path)


def column_profiles(table, path, limits=PROFILE_LIMITS):
    """Pore pressure along the column's axis after the first step, one panel per run
    (shared axes), against Terzaghi's with the initial stiffness; values beyond
    ``limits`` are drawn on the limit with a triangle pointing out of the frame.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.stability.study.column_profiles`.
    path : str or Path
    limits : (float, float)
        Range of the pore pressure over the load shown [-].

    Returns
    -------
    pathlib.Path
    """
    runs = list(dict.fromkeys(table.run))
    cols = -(-len(runs) // 2)
    low, high = limits
    with figures.style():
        fig, axes = figures.slide(2, cols, sharex=True, sharey=True, squeeze=False)
        clipped = False
        for ax, run in zip(axes.flat, runs):
            part = table[table.run == run]
            ax.plot(part.reference, part.y, **figures.REFERENCE)
            ax.plot(part.p_w.clip(low, high), part.y, "o-", ms=3, color="C1")
            for side, marker, beyond in ((low, "<", part.p_w < low),
                                         (high, ">", part.p_w > high)):
                if beyond.any():
                    ax.plot(np.full(beyond.sum(), side), part.y[beyond], marker,
                            color="C1", mec="black", **figures.CLIPPED)
                    clipped = True
            ax.set_title(run, fontsize=12)
            ax.axvline(1.0, color="0.5", lw=0.8, ls=":")
        for ax in axes.flat[len(runs):]:
            ax.set_visible(False)
        for ax in axes[-1]:
            ax.set_xlabel("p$_w$ / load [-]")
        axes[0, 0].set(xlim=limits)
        fig.supylabel("height y [m]", fontsize=12)
        handles = [Line2D([], [], **figures.REFERENCE, label="Terzaghi, initial stiffness"),
                   Line2D([], [], marker="o", ms=3, color="C1", label="p$_w$ on the axis")]
        if clipped:
            handles.append(Line2D([], [], marker=">", color="C1", mec="black",
                                  label=f"beyond {low:g} or {high:g} (drawn on the limit)",
                                  **figures.CLIPPED))
        fig.legend(handles=handles, loc="outside lower center", ncol=3)
        fig.suptitle("Soil column (paper Fig. 8), first step of 40 s: h$^2$/(c$_v$ dt) = 30")
        return figures.save(fig, path)
