"""Figures of the report's pore-pressure stability section: the Table 2 sweep and the
column profiles; each saves a PNG and returns its path."""

import matplotlib.pyplot as plt
import numpy as np


def table2(table, path):
    """Heat map of the Table 2 sweep: weight combination against the measured nodes per
    support, colour the first step's interior pollution (log scale, over the load), one
    panel per permeability, the paper's symbols beside each row."""
    perms = sorted(set(table.permeability))
    fig, axes = plt.subplots(1, len(perms), figsize=(6.2 * len(perms), 3.8),
                             constrained_layout=True, squeeze=False)
    for ax, k in zip(axes[0], perms):
        part = table[table.permeability == k]
        grid = part.pivot(index="weights", columns="scale", values="interior")
        grid = grid.loc[list(dict.fromkeys(part.weights))]
        image = ax.imshow(np.log10(grid.to_numpy()), cmap="RdYlGn_r", vmin=-2, vmax=1,
                          aspect="auto")
        for (i, j), value in np.ndenumerate(grid.to_numpy()):
            ax.text(j, i, f"{value:.2g}", ha="center", va="center", fontsize=8)
        counts = part.groupby("scale").nodes_per_support.mean()
        ax.set_xticks(range(len(grid.columns)),
                      [f"x{s:g}\n{counts[s]:.0f} nodes" for s in grid.columns], fontsize=8)
        paper = part.groupby("weights").paper.first()
        ax.set_yticks(range(len(grid.index)),
                      [f"{w}  {paper[w] or '(not in paper)'}" for w in grid.index],
                      fontsize=8)
        ax.set(title=f"k = {k:g} m/s", xlabel="scale factor, mean nodes per support")
    fig.colorbar(image, ax=axes[0].tolist(), label="log10 interior pollution / load")
    fig.suptitle("Table 2 redesigned: soil column 5 x 41, first step; the paper's symbols "
                 "(× bad, △ better, ○ good, low to high density) beside the rows",
                 fontsize=10)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def column_profiles(table, path):
    """Pore pressure along the column after the first step, one panel per run."""
    runs = list(dict.fromkeys(table.run))
    cols = 4
    rows = -(-len(runs) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 4.2 * rows), sharey=True,
                             constrained_layout=True, squeeze=False)
    for ax, run in zip(axes.flat, runs):
        part = table[table.run == run]
        ax.plot(part.reference, part.y, "k-", lw=3, alpha=0.3, label="Terzaghi, initial "
                "stiffness")
        ax.plot(part.p_w, part.y, "o-", ms=3, color="C3", label="p$_w$ on the axis")
        ax.set(title=run, xlabel="p$_w$ / load", xlim=(-0.6, 2.2))
        ax.axvline(1.0, color="k", lw=0.5, ls=":")
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(runs):]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel("height y (m)")
    axes.flat[0].legend(fontsize=7, loc="lower left")
    fig.suptitle("Soil column (paper Fig. 8), first step of 40 s: h$^2$/(c$_v$ dt) = 30")
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path
