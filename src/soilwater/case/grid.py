"""The node layout of a case: a grid of ``nx x ny`` nodes, regular or laid out in pieces.

Coordinates [m] on the rectangle ``[0, width] x [0, height]`` of the case's geometry;
:meth:`soilwater.case.model.Case.nodes` turns a :class:`Discretisation` into nodes.
"""

from dataclasses import asdict, dataclass

import numpy as np

#: Node layouts: the grid nodes, or the grid nodes plus one node per cell centre.
LAYOUTS = ("grid", "grid+centres")
#: The layout of a case on a mesh (``geometry.mesh``): its vertices are the nodes, and
#: ``[discretisation]`` stays empty.
MESH = "mesh"


@dataclass(frozen=True)
class Discretisation:
    """Grid of ``nx x ny`` nodes, optionally plus one node per cell centre.

    The grid lines are regular, or, where ``x`` (``y``) is given, laid out piece by piece
    along x (y): each piece ``(to, spacings, ratio)`` runs from the end of the previous
    one (0 for the first) to ``to`` [m] in ``spacings`` grid spacings, the last of which is
    ``ratio`` times the first, growing geometrically in between (1: equal spacings).
    ``((1.0, 16, 1.0), (20.0, 24, 30.0))`` is 16 equal spacings over the first metre, then
    24 growing thirty-fold to 20 m: fine where a footing sits, coarse far from it. ``nx``
    (``ny``) is then one more than the pieces' spacings.

    ``jitter`` moves every interior node by a uniform random offset of up to ``jitter``
    times the smallest grid spacing in each direction (boundary nodes stay on their
    edges), drawn with ``numpy.random.default_rng(seed)``: a perturbation of the node set,
    used to probe how a result depends on round-off-sized changes of the geometry.
    """

    nx: int
    ny: int
    layout: str = "grid"
    jitter: float = 0.0
    seed: int = 0
    x: tuple[tuple[float, int, float], ...] = ()
    y: tuple[tuple[float, int, float], ...] = ()

    @property
    def regular(self):
        """True when the grid lines are equally spaced along both axes (no pieces; a mesh
        has no grid lines)."""
        return self.layout != MESH and not (self.x or self.y)

    def to_dict(self):
        """The ``[discretisation]`` table: ``x`` (``y``) instead of ``nx`` (``ny``) where
        the grid is laid out in pieces; empty on a mesh."""
        if self.layout == MESH:
            return {}
        data = {k: v for k, v in asdict(self).items() if k not in ("x", "y")}
        for axis in ("x", "y"):
            if getattr(self, axis):
                data.pop(f"n{axis}")
                data[axis] = getattr(self, axis)
        return data


def grid_line(length, n, pieces=()):
    """Grid coordinates [m] on ``[0, length]``: ``n`` equally spaced, or laid out by
    ``pieces`` ``(to, spacings, ratio)`` (:class:`Discretisation`).

    Examples
    --------
    >>> grid_line(1.0, 3).tolist()
    [0.0, 0.5, 1.0]
    >>> grid_line(8.0, 5, ((1.0, 1, 1.0), (8.0, 3, 4.0))).tolist()
    [0.0, 1.0, 2.0, 4.0, 8.0]
    """
    if not pieces:
        return np.linspace(0.0, length, n)
    lines, start = [[0.0]], 0.0
    for to, spacings, ratio in pieces:
        steps = ratio ** (np.arange(spacings) / max(spacings - 1, 1))
        lines.append(start + (to - start) * np.cumsum(steps) / steps.sum())
        lines[-1][-1] = start = to
    return np.concatenate(lines)
