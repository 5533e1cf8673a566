"""Delaunay triangles of the current nodes inside the current boundary polygon.

One home for the triangulation of a deformed node set: the EFG background cells
(:func:`soilwater.efg.quadrature.delaunay_cells`) integrate on it, and the FEM reference re-meshes
its vertices with it (``fem.remesh = "delaunay"``, :mod:`soilwater.fem.solver`), where the
triangles must also tile the polygon (:func:`conforms`): :func:`close_boundary` adds the
triangle behind a boundary edge that is no Delaunay edge when that gap is one triangle.
"""

import numpy as np
from scipy.spatial import Delaunay

from soilwater.material.kinematics import determinant
from soilwater.geometry.polygon import inside

DEGENERATE = 1e-12
"""A triangle whose area is below this fraction of the mean is degenerate and dropped."""


def delaunay_triangles(nodes, boundary):
    """Delaunay triangles of the nodes whose centroid lies inside the boundary polygon.

    Triangles outside the polygon (the concave parts of a deformed boundary) and
    degenerate ones (area below :data:`DEGENERATE` of the mean) are dropped.

    Parameters
    ----------
    nodes : ndarray, shape (N, 2)
        Current node coordinates [m], N >= 3, not all on one line.
    boundary : ndarray, shape (K, 2)
        Current boundary polygon [m], K >= 3 vertices in order.

    Returns
    -------
    triangles : ndarray of int, shape (C, 3)
        Node indices, counter-clockwise.
    jac : ndarray, shape (C,)
        Twice each triangle's area [m2] (positive).

    Examples
    --------
    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    >>> triangles, jac = delaunay_triangles(np.vstack([square, [[1, 1]]]), square)
    >>> triangles.shape, float(jac.sum() / 2)
    ((4, 3), 4.0)
    """
    triangles = Delaunay(nodes).simplices
    edges = nodes[triangles[:, 1:]] - nodes[triangles[:, :1]]
    jac = determinant(edges)
    triangles[jac < 0] = triangles[jac < 0][:, [0, 2, 1]]
    jac = np.abs(jac)
    keep = jac > DEGENERATE * jac.mean()
    keep[keep] = inside(boundary, nodes[triangles[keep]].mean(1))
    return triangles[keep], jac[keep]


def close_boundary(triangles, loop, nodes):
    """The triangles plus the one that closes each boundary edge missing from them, where
    the gap behind it is a single triangle.

    A boundary edge (a, b) that is no Delaunay edge (another node lies inside every
    circle through a and b, as at a thin concave corner) is crossed by a Delaunay edge
    whose triangles lie outside the polygon and are dropped, leaving a gap. When the gap
    is one triangle (a, b, c), that is, c is joined to both a and b by edges of a single
    triangle each, that triangle is added: it is the constrained Delaunay triangle of the
    edge. Larger gaps are left (:func:`conforms` then fails).

    Parameters
    ----------
    triangles : ndarray of int, shape (C, 3)
        Counter-clockwise (:func:`delaunay_triangles`).
    loop : ndarray of int, shape (K,)
        The boundary nodes, counter-clockwise.
    nodes : ndarray, shape (N, 2)
        Node coordinates [m].

    Returns
    -------
    ndarray of int, shape (C + G, 3)
        Counter-clockwise; G gaps closed.

    Examples
    --------
    A block with a footing pushed 1 m into its top, and a node at (1.25, 1.4) next to
    the steep edge from the surface (1.2, 2) down to the footing's corner (1, 1): that
    edge is no Delaunay edge.

    >>> nodes = np.array([[0, 0], [2, 0], [2, 2], [1.2, 2], [1, 1], [0, 1], [1.25, 1.4]])
    >>> loop = np.arange(6)
    >>> triangles, _ = delaunay_triangles(nodes, nodes[loop])
    >>> closed = close_boundary(triangles, loop, nodes)
    >>> conforms(triangles, loop, 7), conforms(closed, loop, 7), len(closed) - len(triangles)
    (False, True, 1)
    """
    n = len(nodes)
    edges, count = np.unique(_keys(triangles, np.roll(triangles, -1, axis=1), n).ravel(),
                             return_counts=True)
    after = np.roll(loop, -1)
    missing = ~np.isin(_keys(loop, after, n), edges)
    if not missing.any():
        return triangles
    single = edges[count == 1]
    ends = np.column_stack([single // n, single % n])
    ends = np.vstack([ends, ends[:, ::-1]])                  # (a, c) both ways
    b_of = np.full(n, -1)
    b_of[loop[missing]] = after[missing]
    a, c = ends[b_of[ends[:, 0]] >= 0].T
    b = b_of[a]
    closes = (c != b) & np.isin(_keys(c, b, n), single)
    new = np.column_stack([a, b, c])[closes]
    d1, d2 = nodes[new[:, 1]] - nodes[new[:, 0]], nodes[new[:, 2]] - nodes[new[:, 0]]
    new = new[d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0] > 0]
    return np.vstack([triangles, new])


def conforms(triangles, loop, n):
    """Whether triangles form a conforming triangulation of the polygon ``loop``.

    True when every one of the ``n`` nodes is a vertex, no edge belongs to more than
    two triangles, and the edges that belong to one triangle are exactly the polygon's
    edges (consecutive entries of ``loop``, closed): the triangles then tile the polygon
    with no hole, overlap or hanging node, and every boundary edge is a mesh edge.
    Delaunay triangles miss a boundary edge where another node lies inside every circle
    through its two ends (a thin concave corner), which this detects.

    Parameters
    ----------
    triangles : ndarray of int, shape (C, 3)
    loop : ndarray of int, shape (K,)
        The boundary nodes in order.
    n : int
        Number of nodes.

    Examples
    --------
    >>> conforms(np.array([[0, 1, 2], [0, 2, 3]]), np.array([0, 1, 2, 3]), 4)
    True
    >>> conforms(np.array([[0, 1, 2]]), np.array([0, 1, 2, 3]), 4)
    False
    """
    edges = _keys(triangles, np.roll(triangles, -1, axis=1), n).ravel()
    unique, count = np.unique(edges, return_counts=True)
    boundary = np.unique(_keys(loop, np.roll(loop, -1), n))
    return bool(np.unique(triangles).size == n and count.max(initial=0) <= 2
                and np.array_equal(unique[count == 1], boundary))


def _keys(a, b, n):
    """One integer per undirected edge (a, b) of n nodes."""
    return np.minimum(a, b).astype(np.int64) * n + np.maximum(a, b)
