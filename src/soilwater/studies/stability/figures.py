"""Figures of the report's pore-pressure stability section: the inf-sup test and the
Table 2 sweep; each saves a PNG and returns its path."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def infsup(table, slopes, path):
    """Inf-sup value beta against the nodal spacing h (log-log), one line per pair and
    setting, a panel per boundary variant; the legend gives each line's last local slope
    (:func:`soilwater.diagnostics.pairs.slopes`; sizes where beta is zero are left out)."""
    boundaries = list(dict.fromkeys(table.boundary))
    fig, axes = plt.subplots(1, len(boundaries), figsize=(6 * len(boundaries), 4.8),
                             sharey=True, constrained_layout=True, squeeze=False)
    keys = ["method", "weights", "scale_u", "scale_p"]
    fits = slopes.set_index(keys + ["boundary"])
    for ax, boundary in zip(axes[0], boundaries):
        part = table[table.boundary == boundary]
        for k, (key, group) in enumerate(part.groupby(keys, sort=False, dropna=False)):
            fit = fits.loc[(*key, boundary)]
            label = key[0] if key[0] != "efg" else f"efg {key[1]} x{key[2]:g}/{key[3]:g}"
            group = group[group.beta > 0]          # no displacement sees a pressure
            ax.loglog(group.h, group.beta, "o-" if fit.stable else "s--", ms=4,
                      color=f"C{k % 10}", label=f"{label}: slope {fit.slope:.2f}")
        ax.set(title=f"v {'free' if boundary == 'free' else '= 0'} on the boundary",
               xlabel="nodal spacing h (unit square)")
        ax.invert_xaxis()
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    axes[0, 0].set_ylabel("inf-sup value beta")
    fig.suptitle("Numerical inf-sup test (Chapelle and Bathe): solid lines level off "
                 "(stable), dashed lines decay", fontsize=10)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


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
