"""Delaunay triangles of the current nodes inside the current boundary polygon.

One home for the triangulation of a deformed node set: the EFG background cells
(:func:`efg.quadrature.delaunay_cells`) integrate on it, and the FEM reference re-meshes
its vertices with it (``fem.remesh = "delaunay"``, :mod:`fem_reference.solver`), where the
triangles must also :func:`conform` to the boundary.
"""

import numpy as np
from scipy.spatial import Delaunay

from soil.polygon import inside

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
    jac = edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]
    triangles[jac < 0] = triangles[jac < 0][:, [0, 2, 1]]
    jac = np.abs(jac)
    keep = jac > DEGENERATE * jac.mean()
    keep[keep] = inside(boundary, nodes[triangles[keep]].mean(1))
    return triangles[keep], jac[keep]


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
    def keys(a, b):
        return np.minimum(a, b).astype(np.int64) * n + np.maximum(a, b)

    edges = keys(triangles, np.roll(triangles, -1, axis=1)).ravel()
    unique, count = np.unique(edges, return_counts=True)
    boundary = np.unique(keys(loop, np.roll(loop, -1)))
    return bool(np.unique(triangles).size == n and count.max(initial=0) <= 2
                and np.array_equal(unique[count == 1], boundary))
