"""Background cells for the EFG integrals: squares with quarter cells along the boundary,
or Delaunay triangles of the current nodes (paper Figs. 2, 3 and 5).

Both builders take the current configuration and are vectorised (no loop over cells or
points), so they can be rebuilt at every step of a large-deformation run. The boundary is
the current polygon, e.g. ``nodes[case.boundary_loop()]``, counter-clockwise or not.

Inside/outside tests use a raster of cells over the polygon's bounding box: the cells the
boundary touches are found segment by segment (separating-axis test), the untouched cells
form connected regions that are wholly inside or wholly outside (one point-in-polygon test
each), and only points in touched cells go through ``Path.contains_points``.
"""

from typing import NamedTuple

import numpy as np
from matplotlib.path import Path
from numpy.polynomial.legendre import leggauss
from scipy import ndimage
from scipy.spatial import Delaunay
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTri

from soil.errors import require

TOUCH = 1e-9
"""A cell touches the boundary when it comes within ``TOUCH x cell size`` of it."""

OUTSIDE, INSIDE, TOUCHED = 0, 1, 2
_SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1]])  # unit square corners, CCW


class Quadrature(NamedTuple):
    """Integration points and the cells they come from, on the current configuration.

    Attributes
    ----------
    points : ndarray, shape (M, 2)
        Gauss points [m].
    weights : ndarray, shape (M,)
        Gauss weight x cell Jacobian [m2]; their sum is the integrated area.
    cells : ndarray, shape (C, V, 2)
        Vertices of the cells that carry at least one point, counter-clockwise [m]: V = 4
        for squares (full cells first, then quarter cells), V = 3 for triangles.
    cell : ndarray of int, shape (M,)
        The cell each point lies in (an index into ``cells``).
    triangles : ndarray of int, shape (C, 3), or None
        Node indices of the Delaunay triangles (``cells == nodes[triangles]``); None for
        square cells.
    """

    points: np.ndarray
    weights: np.ndarray
    cells: np.ndarray
    cell: np.ndarray
    triangles: np.ndarray | None = None


def background(case, nodes, loop, settings):
    """Integration points of a case's background cells on the configuration ``nodes``.

    Parameters
    ----------
    case : Case
        Its grid spacing sizes the square cells.
    nodes : ndarray, shape (N, 2)
        Current node positions [m].
    loop : ndarray of int
        The boundary nodes in counter-clockwise order.
    settings : EFGSettings
        ``cells`` (``squares`` or ``delaunay``) and the Gauss ``order``.
    """
    if settings.cells == "squares":
        return square_cells(nodes[loop], case.spacing, order=settings.order)
    return delaunay_cells(nodes, nodes[loop], order=settings.order)


def square_cells(boundary, spacing, order=2):
    """Square cells of the initial nodal spacing, quartered where they meet the boundary.

    The cells lie on a grid anchored at the origin and cover the bounding box of the
    current boundary polygon. A cell whose closed square stays clear of the boundary is a
    full cell if it lies inside and is dropped if outside; a cell that touches or crosses
    the boundary is split into four quarter cells, each with its own Gauss points, and the
    points outside the polygon are dropped. In the undeformed rectangle the quarter cells
    are exactly the ring of cells along the boundary.

    Parameters
    ----------
    boundary : array_like, shape (K, 2)
        Current boundary polygon [m], K >= 3 vertices in order.
    spacing : pair of float
        Cell size ``(hx, hy)`` [m], the initial nodal spacing (``Case.spacing``).
    order : int
        Gauss-Legendre points per direction (``order x order`` per cell, exact for
        polynomials of degree ``2 order - 1`` in each variable); default 2.

    Returns
    -------
    Quadrature

    Raises
    ------
    InputError
        Bad ``boundary``, ``spacing`` or ``order``.

    Examples
    --------
    >>> square = [[0, 0], [2, 0], [2, 2], [0, 2]]
    >>> q = square_cells(square, (0.5, 0.5))
    >>> len(q.cells), len(q.points), float(q.weights.sum())
    (52, 208, 4.0)
    """
    boundary, h = _polygon(boundary), _spacing(spacing)
    _order(order)
    lo, state = _raster(boundary, h)
    full = (np.argwhere(state == INSIDE) + lo) * h
    quarter = (((np.argwhere(state == TOUCHED) + lo) * h)[:, None] + _SQUARE * h / 2)
    quarter = quarter.reshape(-1, 2)
    fp, fw = _gauss_squares(full, h, order)
    qp, qw = _gauss_squares(quarter, h / 2, order)
    keep = _path(boundary).contains_points(qp.reshape(-1, 2)).reshape(qw.shape)
    kept = keep.any(1)
    cells = np.concatenate([full[:, None] + _SQUARE * h,
                            quarter[kept, None] + _SQUARE * h / 2])
    quarter_cell = len(full) + np.cumsum(kept) - 1
    cell = np.concatenate([np.repeat(np.arange(len(full)), order**2),
                           np.broadcast_to(quarter_cell[:, None], keep.shape)[keep]])
    return Quadrature(np.concatenate([fp.reshape(-1, 2), qp[keep]]),
                      np.concatenate([fw.ravel(), qw[keep]]), cells, cell)


def delaunay_cells(nodes, boundary, order=2):
    """Delaunay triangles of the current nodes, with a triangle rule of degree ``order``.

    Triangles whose centroid lies outside the boundary polygon (the concave parts of a
    deformed boundary) and degenerate ones (area below 1e-12 of the mean) are dropped.
    The rule is scikit-fem's for the reference triangle; the default degree 2 has 3 points
    with positive weights (degree 3 has a negative weight).

    Parameters
    ----------
    nodes : array_like, shape (N, 2)
        Current node coordinates [m], N >= 3, not all on one line.
    boundary : array_like, shape (K, 2)
        Current boundary polygon [m], K >= 3 vertices in order.
    order : int
        Polynomial degree integrated exactly on each triangle; default 2.

    Returns
    -------
    Quadrature
        With ``triangles`` (node indices, counter-clockwise).

    Raises
    ------
    InputError
        Bad ``nodes``, ``boundary`` or ``order``.

    Examples
    --------
    >>> square = [[0, 0], [2, 0], [2, 2], [0, 2]]
    >>> q = delaunay_cells(square + [[1, 1]], square)
    >>> q.triangles.shape, len(q.points), float(q.weights.sum())
    ((4, 3), 12, 4.0)
    """
    nodes, boundary = np.asarray(nodes, dtype=float), _polygon(boundary)
    require(nodes.ndim == 2 and nodes.shape[1] == 2 and len(nodes) >= 3,
            f"nodes: shape {nodes.shape} must be (N, 2) with N >= 3 [m]")
    _order(order)
    triangles = Delaunay(nodes).simplices
    edges = nodes[triangles[:, 1:]] - nodes[triangles[:, :1]]
    jac = edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]
    triangles[jac < 0] = triangles[jac < 0][:, [0, 2, 1]]
    jac = np.abs(jac)
    keep = jac > 1e-12 * jac.mean()
    keep[keep] = _inside(boundary, nodes[triangles[keep]].mean(1))
    cells = nodes[triangles[keep]]
    xi, w = get_quadrature(RefTri, order)
    points = cells[:, :1] + np.einsum("pj,tjd->tpd", xi.T, cells[:, 1:] - cells[:, :1])
    return Quadrature(points.reshape(-1, 2), (jac[keep, None] * w).ravel(), cells,
                      np.repeat(np.arange(len(cells)), len(w)), triangles[keep])


def _gauss_squares(corners, size, order):
    """``order x order`` Gauss-Legendre points and weights of squares (C, G, 2), (C, G).

    ``corners`` (C, 2) are the lower-left corners, ``size`` (2,) the side lengths [m].
    """
    xi, w = leggauss(order)
    unit = np.stack(np.meshgrid((xi + 1) / 2, (xi + 1) / 2, indexing="ij"), -1)
    weights = np.outer(w, w).ravel() * np.prod(size) / 4
    return (corners[:, None] + unit.reshape(-1, 2) * size,
            np.broadcast_to(weights, (len(corners), order * order)))


def _inside(boundary, points):
    """Whether each point lies inside the polygon, via a raster of the mean edge length."""
    size = np.linalg.norm(np.roll(boundary, -1, 0) - boundary, axis=1).mean()
    h = np.full(2, size)
    lo, state = _raster(boundary, h)
    ij = np.floor(points / h).astype(int) - lo
    valid = ((ij >= 0) & (ij < state.shape)).all(1)
    where = np.full(len(points), OUTSIDE)
    where[valid] = state[tuple(ij[valid].T)]
    inside = where == INSIDE
    inside[where == TOUCHED] = _path(boundary).contains_points(points[where == TOUCHED])
    return inside


def _raster(boundary, h):
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
    inside = np.zeros(region.max() + 1, dtype=bool)
    inside[region[region > 0]] = _path(boundary).contains_points(centres)
    return lo, np.where(touched, TOUCHED, np.where(inside[labels], INSIDE, OUTSIDE))


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
    corners = (cells[:, :, None] + _SQUARE) * h
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


def _path(boundary):
    """The closed matplotlib path of the polygon."""
    return Path(np.vstack([boundary, boundary[:1]]), closed=True)


def _polygon(boundary):
    boundary = np.asarray(boundary, dtype=float)
    require(boundary.ndim == 2 and boundary.shape[1] == 2 and len(boundary) >= 3,
            f"boundary: shape {boundary.shape} must be (K, 2) with K >= 3 polygon "
            "vertices [m]")
    return boundary


def _spacing(spacing):
    h = np.asarray(spacing, dtype=float)
    require(h.shape == (2,) and np.all(np.isfinite(h)) and np.all(h > 0),
            f"spacing = {spacing!r} must be two positive cell sizes (hx, hy) [m]")
    return h


def _order(order):
    require(isinstance(order, (int, np.integer)) and not isinstance(order, bool)
            and order >= 1, f"order = {order!r} must be an integer >= 1")
