"""The report's figure conventions, in one place: slide size, colours, fonts and saving.

Every figure of the report is sized for a slide (:data:`SLIDE`, 16:9, 1920 x 1080 px at
:data:`DPI`, read at 1280 px wide), draws with colour-blind-safe colours (the Okabe-Ito
cycle, :data:`CYCLE`; one colour per method, :data:`METHOD_COLOURS`; the maps
:data:`SEQUENTIAL` for unsigned fields and :data:`DIVERGING` for signed ones) and fonts
that stay legible on a slide (:func:`style`), and is written by :func:`save`: whole or not
at all, labelled as a quick report when one is being made
(:data:`soilwater.studies.harness.quick.LABEL`), then closed.

A figure function draws within ``with style():`` and ends with ``return save(fig,
path)``; :func:`slide` makes the figure and its panels. Closed forms and other
references are drawn in :data:`REFERENCE` (black) so they stand apart from the
coloured runs, and named in the legend.
"""

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import matplotlib as mpl
import matplotlib.pyplot as plt
from cycler import cycler

from soilwater.studies.harness import quick

#: Figure size [in]: 16:9. At :data:`DPI` it is 1920 x 1080 px; shown 1280 px wide, a
#: 10 pt font is about 14 px tall.
SLIDE = (12.8, 7.2)
#: Resolution of the saved PNGs [dots per inch].
DPI = 150
#: The Okabe-Ito colours, distinguishable with every common colour-vision deficiency.
OKABE_ITO = {"blue": "#0072B2", "vermillion": "#D55E00", "green": "#009E73",
             "purple": "#CC79A7", "orange": "#E69F00", "sky": "#56B4E9",
             "yellow": "#F0E442", "black": "#000000"}
#: The colour cycle of every figure (``"C0"``, ``"C1"``, ... within :func:`style`):
#: black seventh (references are black too, but drawn thick, dashed or dotted and named
#: in the legend), yellow last, as it is faint on white.
CYCLE = [OKABE_ITO[name] for name in ("blue", "vermillion", "green", "purple", "orange",
                                      "sky", "black", "yellow")]
#: One colour per method, the same in every figure.
METHOD_COLOURS = {"efg": OKABE_ITO["blue"], "efg-paper": OKABE_ITO["sky"],
                  "fem-th": OKABE_ITO["vermillion"], "fem-p1p1-stab": OKABE_ITO["green"],
                  "fem-p1p1": OKABE_ITO["purple"], "fem-th+remesh": OKABE_ITO["orange"]}
#: Colour maps: perceptually uniform for unsigned fields, diverging about zero for
#: signed ones (both readable with colour-vision deficiencies).
SEQUENTIAL = "viridis"
DIVERGING = "RdBu_r"
#: Line style of a reference (closed form, limit load, independent solution): black,
#: drawn beneath the runs.
REFERENCE = {"color": "black", "lw": 2.2, "zorder": 1.5}
#: Marker of a run's early end (it stopped: failed to converge or reached a limit).
STOPPED = {"marker": "X", "ms": 11, "mec": "black", "mew": 0.8, "ls": "none",
           "zorder": 6}
#: Marker of values beyond an axis limit (drawn on the limit).
CLIPPED = {"ms": 6, "ls": "none", "zorder": 6}

RC = {"figure.figsize": SLIDE, "figure.dpi": 100, "savefig.dpi": DPI,
      "font.size": 12, "axes.titlesize": 13, "axes.labelsize": 12,
      "xtick.labelsize": 11, "ytick.labelsize": 11, "legend.fontsize": 11,
      "legend.title_fontsize": 11, "figure.titlesize": 14,
      "axes.prop_cycle": cycler(color=CYCLE), "image.cmap": SEQUENTIAL,
      "axes.grid": True, "grid.alpha": 0.3, "lines.linewidth": 1.8,
      "legend.frameon": False}


@contextmanager
def style():
    """Draw within the block with the report's fonts, colour cycle and map (:data:`RC`).

    Colours named ``"C0"``, ``"C1"``, ... inside the block are those of :data:`CYCLE`.
    """
    with mpl.rc_context(RC):
        yield


def slide(nrows=1, ncols=1, **kwargs):
    """A figure of :data:`SLIDE` size with ``nrows`` x ``ncols`` panels laid out by
    matplotlib's constrained layout (``kwargs`` go to :func:`matplotlib.pyplot.subplots`).

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : matplotlib.axes.Axes or ndarray of them
    """
    kwargs.setdefault("layout", "constrained")
    return plt.subplots(nrows, ncols, figsize=SLIDE, **kwargs)


def stamp(fig):
    """Write :data:`soilwater.studies.harness.quick.LABEL` across the top of ``fig``
    (small, red on white) when a quick report is being made; nothing otherwise.

    The figure's title (:meth:`~matplotlib.figure.Figure.suptitle`, a blank one if it has
    none) gets a blank first line, which the layout keeps clear and the label fills; the
    title takes the current ``figure.titlesize``.
    """
    if quick.active():
        fig.suptitle("\n" + (fig.get_suptitle() or " "))
        fig.text(0.5, 0.998, quick.LABEL, ha="center", va="top", fontsize=9,
                 color=OKABE_ITO["vermillion"], zorder=10,
                 bbox={"facecolor": "white", "edgecolor": "none", "pad": 1})


@contextmanager
def written(path):
    """A temporary path beside ``path`` (same suffix, so the same format), renamed to
    ``path`` when the block succeeds and removed when it fails: a file is written whole
    or not at all. Creates ``path``'s folder."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.",
                               suffix=path.suffix)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o644)  # mkstemp's 0o600 is for the temporary name only
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


def save(fig, path, dpi=DPI):
    """Write ``fig`` to ``path`` at ``dpi`` (:func:`written`: whole or not at all),
    :func:`stamp`-ed, and close it, also when writing fails.

    Returns
    -------
    pathlib.Path
    """
    try:
        stamp(fig)
        with written(path) as tmp:
            fig.savefig(tmp, dpi=dpi)
    finally:
        plt.close(fig)
    return Path(path)
