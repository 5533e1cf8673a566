"""Background cells for the EFG integrals: squares with quarter cells along the boundary,
or Delaunay triangles of the current nodes (paper Figs. 2, 3 and 5).

Both builders take the current configuration and are vectorised (no loop over cells or
points), so they can be rebuilt at every step of a large-deformation run. The boundary is
the current polygon, e.g. ``nodes[case.boundary_loop()]``, counter-clockwise or not.
Inside/outside tests are :mod:`soilwater.geometry.polygon`'s raster; the triangles are
:func:`soilwater.geometry.triangulation.delaunay_triangles`, which the FEM reference re-meshes with.
"""

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve
from numpy.polynomial.legendre import leggauss
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTri

from soilwater.errors import ConvergenceError, require
from soilwater.geometry.polygon import INSIDE, SQUARE, TOUCHED, path, raster
from soilwater.geometry.triangulation import delaunay_triangles


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
    rebuilds : tuple of dict
        The records of the rebuilds of Lagrangian cells these cells descend from, oldest
        first (:func:`soilwater.efg.rebuild.record`; ``efg.integration = "gauss"``).
    """

    points: np.ndarray
    weights: np.ndarray
    cells: np.ndarray
    cell: np.ndarray
    triangles: np.ndarray | None = None
    rebuilds: tuple = ()


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
    lo, state = raster(boundary, h)
    full = (np.argwhere(state == INSIDE) + lo) * h
    quarter = (((np.argwhere(state == TOUCHED) + lo) * h)[:, None] + SQUARE * h / 2)
    quarter = quarter.reshape(-1, 2)
    fp, fw = _gauss_squares(full, h, order)
    qp, qw = _gauss_squares(quarter, h / 2, order)
    keep = path(boundary).contains_points(qp.reshape(-1, 2)).reshape(qw.shape)
    kept = keep.any(1)
    cells = np.concatenate([full[:, None] + SQUARE * h,
                            quarter[kept, None] + SQUARE * h / 2])
    quarter_cell = len(full) + np.cumsum(kept) - 1
    cell = np.concatenate([np.repeat(np.arange(len(full)), order**2),
                           np.broadcast_to(quarter_cell[:, None], keep.shape)[keep]])
    return Quadrature(np.concatenate([fp.reshape(-1, 2), qp[keep]]),
                      np.concatenate([fw.ravel(), qw[keep]]), cells, cell)


def delaunay_cells(nodes, boundary, order=2):
    """Delaunay triangles of the current nodes, with a triangle rule of degree ``order``.

    The triangles are :func:`soilwater.geometry.triangulation.delaunay_triangles`: those whose
    centroid
    lies outside the boundary polygon (the concave parts of a deformed boundary) and
    degenerate ones are dropped. The rule is scikit-fem's for the reference triangle; the default
    degree 2 has 3 points
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
    triangles, _ = delaunay_triangles(nodes, boundary)
    return lagrangian_cells(nodes, triangles, order)


def lagrangian_cells(nodes, triangles, order=2):
    """Fixed triangles of nodes, at the nodes' current positions, with a triangle rule of
    degree ``order``: the background cells of ``efg.integration = "gauss"``, whose Gauss
    point ``3 t + k`` is the same material point at every step until the triangles are
    rebuilt (:mod:`soilwater.efg.rebuild`).

    Parameters
    ----------
    nodes : array_like, shape (N, 2)
        Current node coordinates [m].
    triangles : array_like of int, shape (C, 3)
        Node indices, counter-clockwise in the initial configuration.
    order : int
        Polynomial degree integrated exactly on each triangle; default 2.

    Returns
    -------
    Quadrature
        With ``triangles``.

    Raises
    ------
    ConvergenceError
        Where a triangle has turned over or collapsed (its area is no longer positive).

    Examples
    --------
    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1.]])
    >>> q = lagrangian_cells(square, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    >>> len(q.points), float(q.weights.sum())
    (12, 4.0)
    """
    nodes, triangles = np.asarray(nodes, dtype=float), np.asarray(triangles)
    _order(order)
    cells = nodes[triangles]
    jac = 2 * triangle_areas(cells)
    xi, w = get_quadrature(RefTri, order)
    points = cells[:, :1] + np.einsum("pj,tjd->tpd", xi.T, cells[:, 1:] - cells[:, :1])
    return Quadrature(points.reshape(-1, 2), (jac[:, None] * w).ravel(), cells,
                      np.repeat(np.arange(len(cells)), len(w)), triangles)


def triangle_areas(cells):
    """Areas (C,) [m2] of triangles (C, 3, 2) whose corners were counter-clockwise.

    Raises
    ------
    ConvergenceError
        Where a triangle has turned over or collapsed (its area is no longer positive).
    """
    edges = cells[:, 1:] - cells[:, :1]
    area = 0.5 * (edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0])
    if not np.all(area > 0):
        raise ConvergenceError(f"a background cell inverts (area {area.min():.3g} m2 "
                               f"in cell {int(np.argmin(area))})")
    return area


def nodal_average(quad, n, values):
    """Gauss-point values projected onto the ``n`` nodes of triangular cells: the L2
    projection onto linear triangles, ``M f_nodes = sum_q w_q N(x_q) f_q`` with the
    consistent mass ``M``, exact for a field linear over the cells (a node no triangle
    touches gets NaN).

    Parameters
    ----------
    quad : Quadrature
        Triangular cells (``triangles`` set), the same rule on every triangle.
    n : int
        Number of nodes.
    values : ndarray, shape (M, ...)
        One value (or array) per Gauss point.

    Examples
    --------
    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1.]])
    >>> q = lagrangian_cells(square, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    >>> f = nodal_average(q, 5, 2 * q.points[:, 0] + q.points[:, 1])
    >>> bool(np.allclose(f, 2 * square[:, 0] + square[:, 1]))
    True
    """
    triangles, w, cells = quad.triangles, quad.weights, quad.cells
    per = len(w) // len(triangles)
    local = quad.points.reshape(len(cells), per, 2) - cells[:, None, 0]
    edges = np.swapaxes(cells[:, 1:] - cells[:, :1], 1, 2)                   # (C, 2, 2)
    coords = np.linalg.solve(edges[:, None], local[..., None])[..., 0]        # (C, per, 2)
    N = np.concatenate([1 - coords.sum(-1, keepdims=True), coords], -1).reshape(-1, 3)
    rows = np.repeat(triangles, per, axis=0)                                 # (M, 3)
    tested = sp.csr_matrix(((w[:, None] * N).ravel(),
                            (rows.ravel(), np.repeat(np.arange(len(w)), 3))),
                           shape=(n, len(w)))
    interpolation = sp.csr_matrix((N.ravel(), (np.repeat(np.arange(len(w)), 3),
                                               rows.ravel())), shape=(len(w), n))
    mass = (tested @ interpolation).tocsc()
    touched = np.asarray(tested.sum(1)).ravel() > 0
    mass = mass + sp.diags((~touched).astype(float))
    values = np.asarray(values, dtype=float)
    nodal = np.atleast_2d(spsolve(mass, tested @ values.reshape(len(w), -1)).T).T
    nodal[~touched] = np.nan
    return nodal.reshape((n,) + values.shape[1:])


def _gauss_squares(corners, size, order):
    """``order x order`` Gauss-Legendre points and weights of squares (C, G, 2), (C, G).

    ``corners`` (C, 2) are the lower-left corners, ``size`` (2,) the side lengths [m].
    """
    xi, w = leggauss(order)
    unit = np.stack(np.meshgrid((xi + 1) / 2, (xi + 1) / 2, indexing="ij"), -1)
    weights = np.outer(w, w).ravel() * np.prod(size) / 4
    return (corners[:, None] + unit.reshape(-1, 2) * size,
            np.broadcast_to(weights, (len(corners), order * order)))


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
