"""Which points lie inside a polygon, by a raster of cells over its bounding box.

The cells the boundary touches are found segment by segment (separating-axis test), the
untouched cells form connected regions that are wholly inside or wholly outside (one
point-in-polygon test each), and only points in touched cells go through
``Path.contains_points``. Vectorised over segments, cells and points; the EFG square
cells (:func:`soilwater.efg.quadrature.square_cells`) and the triangles of a polygon
(:mod:`soilwater.geometry.triangulation`) use it on the current, deformed boundary.
"""

import numpy as np
from scipy import ndimage

TOUCH = 1e-9
"""A cell touches the boundary when it comes within ``TOUCH x cell size`` of it."""

OUTSIDE, INSIDE, TOUCHED = 0, 1, 2
"""States of a raster cell (:func:`raster`)."""
SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1]])
"""Unit square corners, counter-clockwise."""


def inside(boundary, points):
    """Whether each point lies inside the polygon, via a raster of the mean edge length.

    Parameters
    ----------
    boundary : ndarray, shape (K, 2)
        Polygon vertices in order [m].
    points : ndarray, shape (P, 2)
        Points [m].

    Returns
    -------
    ndarray of bool, shape (P,)

    Examples
    --------
    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    >>> inside(square, np.array([[1.0, 1.0], [3.0, 1.0]])).tolist()
    [True, False]
    """
    size = np.linalg.norm(np.roll(boundary, -1, 0) - boundary, axis=1).mean()
    h = np.full(2, size)
    lo, state = raster(boundary, h)
    ij = np.floor(points / h).astype(int) - lo
    valid = ((ij >= 0) & (ij < state.shape)).all(1)
    where = np.full(len(points), OUTSIDE)
    where[valid] = state[tuple(ij[valid].T)]
    within = where == INSIDE
    within[where == TOUCHED] = path(boundary).contains_points(points[where == TOUCHED])
    return within


def raster(boundary, h):
    """Cells of size ``h`` over the polygon's bounding box, grid anchored at the origin.

    Returns the index ``lo`` (2,) of the first cell and the state (nx, ny) of every cell:
    OUTSIDE, INSIDE or TOUCHED (the closed square comes within ``TOUCH h`` of the boundary).
    """
    lo = np.floor(boundary.min(0) / h + TOUCH).astype(int)
    hi = np.maximum(np.ceil(boundary.max(0) / h - TOUCH).astype(int), lo + 1)
    touched = np.zeros(hi - lo, dtype=bool)
    ij = _touched_cells(boundary, h) - lo
    ij = ij[((ij >= 0) & (ij < touched.shape)).all(1)]
    touched[tuple(ij.T)] = True
    labels, _ = ndimage.label(~touched)
    region, first = np.unique(labels, return_index=True)
    first = first[region > 0]
    centres = (np.column_stack(np.unravel_index(first, labels.shape)) + lo + 0.5) * h
    within = np.zeros(region.max() + 1, dtype=bool)
    within[region[region > 0]] = path(boundary).contains_points(centres)
    return lo, np.where(touched, TOUCHED, np.where(within[labels], INSIDE, OUTSIDE))


def path(boundary):
    """The closed matplotlib path of the polygon (matplotlib is imported here, not with
    the package)."""
    from matplotlib.path import Path

    return Path(np.vstack([boundary, boundary[:1]]), closed=True)


def _touched_cells(boundary, h):
    """Indices (n, 2) of the grid cells the boundary touches (with repeats).

    The segments are cut into pieces no longer than the smaller cell side; candidates are
    the cells of each piece's bounding box (at most 3 x 3), and a separating-axis test
    along the piece's normal keeps those it meets.
    """
    a, b = _pieces(boundary, h.min())
    tol = TOUCH * h
    c0 = np.floor((np.minimum(a, b) - tol) / h).astype(int)
    c1 = np.floor((np.maximum(a, b) + tol) / h).astype(int)
    offsets = np.indices((c1 - c0).max(0) + 1).reshape(2, -1).T
    cells = c0[:, None] + offsets
    corners = (cells[:, :, None] + SQUARE) * h
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    normal = np.column_stack([-d[:, 1], d[:, 0]]) / np.where(length > 0, length, 1)[:, None]
    side = np.einsum("kscd,kd->ksc", corners - a[:, None, None], normal)
    meets = ~((side > tol.min()).all(-1) | (side < -tol.min()).all(-1))
    return cells[meets & (cells <= c1[:, None]).all(-1)]


def _pieces(boundary, size):
    """Start and end points (n, 2) of the polygon's edges cut into pieces <= ``size``."""
    edge = np.roll(boundary, -1, 0) - boundary
    count = np.maximum(np.ceil(np.hypot(edge[:, 0], edge[:, 1]) / size), 1).astype(int)
    k = np.repeat(np.arange(len(boundary)), count)
    t = (np.arange(len(k)) - np.repeat(np.cumsum(count) - count, count))[:, None]
    return (boundary[k] + edge[k] * t / count[k, None],
            boundary[k] + edge[k] * (t + 1) / count[k, None])
