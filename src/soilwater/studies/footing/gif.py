"""Animations of the strip-footing runs: one GIF per method, its deformation snapshot by
snapshot coloured by eps_s (:class:`soilwater.studies.footing.view.RunView`), written whole
or not at all (:func:`soilwater.studies.harness.figures.written`), labelled as a quick
report when one is being made (:func:`soilwater.studies.harness.figures.stamp`).
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import PillowWriter

from soilwater.studies.footing.view import (STRAIN_LABEL, RunView, strain_extend, strain_norm,
                                            window_top)
from soilwater.studies.harness import figures

#: Most frames of an animation, and its frame rate [1/s].
FRAMES = 50
FPS = 10


def frames(count, most=FRAMES):
    """Snapshot indices of an animation: every k-th of ``count`` snapshots, k the
    smallest step that keeps at most ``most`` frames, and always the last.

    Examples
    --------
    >>> frames(11).tolist(), frames(11, most=5).tolist()
    ([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10], [0, 3, 6, 9, 10])
    """
    step = max(1, -(-(count - 1) // (most - 1)))
    return np.append(np.arange(0, count - 1, step), count - 1)


def animation(result, path, norm=None, top=None, most=FRAMES):
    """``path`` (GIF): the run's deformation, snapshot by snapshot (:func:`frames`),
    coloured by eps_s, the settlement and contact pressure in each frame's title.

    Parameters
    ----------
    result : soilwater.results.Result
    path : str or Path
    norm : matplotlib.colors.Normalize, optional
        Colour scale of eps_s (default: the run's own, as in :func:`deformed_figure`).
    top : float, optional
        Upper limit of the window [m] (default: the run's own).
    most : int
        Most frames.

    Returns
    -------
    Path
    """
    run = RunView(result)
    with figures.style():
        fig, ax = plt.subplots(figsize=(5.6, 5.0), constrained_layout=True)
        norm = norm or strain_norm([run])
        mappable, show = run.strain_view(ax, norm)
        run.window(ax, top or window_top([run]))
        ax.grid(False)
        fig.colorbar(mappable, ax=ax, shrink=0.9, label=STRAIN_LABEL,
                     extend=strain_extend([run], norm))
        title = ax.set_title(" ", fontsize=9)
        figures.stamp(fig)
    fig.canvas.draw()
    fig.set_layout_engine("none")  # the first frame's layout holds for all
    writer = PillowWriter(fps=FPS)
    try:
        with figures.written(path) as tmp, writer.saving(fig, tmp, dpi=90):
            for k in frames(len(result.snapshots), most):
                show(k)
                s, p = run.loads(k)
                title.set_text(f"{run.label}: settlement {s:.3g} m ({s / run.B:.2f} B), "
                               f"contact pressure {p:.3g} kPa")
                writer.grab_frame()
    finally:
        plt.close(fig)
    return Path(path)


def animations(results, folder):
    """One GIF per run, ``folder/footing_METHOD.gif``, on one colour scale and window.

    Returns
    -------
    list of Path
    """
    runs = [RunView(r) for r in results]
    norm, top = strain_norm(runs), window_top(runs)
    return [animation(r.result, Path(folder) / f"footing_{r.label}.gif", norm, top)
            for r in runs]

