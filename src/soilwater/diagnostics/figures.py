"""The inf-sup test's figure (``soilwater infsup`` and the report's stability section)."""

import matplotlib.pyplot as plt

from soilwater.targets import SOFTWARE


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
    fig.savefig(path, dpi=150, format="png", metadata={"Software": SOFTWARE})
    plt.close(fig)
    return path
