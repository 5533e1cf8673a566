"""Stabilised conforming nodal integration (``efg.integration = "nodal"``).

Chen, Wu, Yoon and You (2001, "A stabilized conforming nodal integration for Galerkin
mesh-free methods", IJNME 50): every node is an integration point, weighted by the area of
its smoothing cell, and the gradient there is the cell's mean gradient, written by the
divergence theorem as a boundary integral of the shape functions,

    grad~ phi_I(x_L) = (1 / A_L) sum_(segments s of cell L) phi_I(x_s) n_s l_s,

so no shape function is differentiated and the nodes are the material points: the stress
that satisfies equilibrium lives on them and nothing is interpolated. The smoothing cells
are the median-dual cells of a triangulation of the nodes: each triangle gives each of its
corners the quadrilateral of the corner, its two edge midpoints and its centroid (a third
of its area). A segment between two cells counts for both with opposite normals, so the
smoothed gradients satisfy the discrete divergence theorem whatever the rule on a segment
(``order`` Gauss-Legendre points).
"""

from typing import NamedTuple

import numpy as np
from numpy.polynomial.legendre import leggauss
from scipy.sparse import csr_array

from soilwater.efg.quadrature import Quadrature, triangle_areas


class SmoothingSegments(NamedTuple):
    """The Gauss points of the smoothing cells' boundary segments.

    Attributes
    ----------
    points : ndarray, shape (S, 2)
        Gauss points on the segments [m].
    normal : ndarray, shape (S, 2)
        Outward unit normal of the segment times its Gauss weight and length [m], seen
        from the cell ``inner``.
    inner, outer : ndarray of int, shape (S,)
        The cell each point's normal points out of, and the one it points into (-1 on
        the domain's boundary).
    """

    points: np.ndarray
    normal: np.ndarray
    inner: np.ndarray
    outer: np.ndarray


def nodal_cells(nodes, triangles):
    """The nodes as integration points of their median-dual smoothing cells.

    Parameters
    ----------
    nodes : ndarray, shape (N, 2)
        Current node coordinates [m].
    triangles : ndarray of int, shape (C, 3)
        A triangulation of the nodes, counter-clockwise.

    Returns
    -------
    Quadrature
        ``points`` the nodes, ``weights`` the cells' areas [m2] (a third of each
        triangle's area to each corner), ``cells`` and ``triangles`` the triangles (which
        :func:`soilwater.geometry.quality.cell_quality` measures), ``cell`` the node's own
        index.

    Raises
    ------
    ConvergenceError
        Where a triangle has turned over (:func:`soilwater.efg.quadrature.triangle_areas`).

    Examples
    --------
    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2], [1, 1.]])
    >>> q = nodal_cells(square, np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))
    >>> q.weights.round(6).tolist()
    [0.666667, 0.666667, 0.666667, 0.666667, 1.333333]
    """
    nodes, triangles = np.asarray(nodes, dtype=float), np.asarray(triangles)
    cells = nodes[triangles]
    area = triangle_areas(cells)
    weights = np.bincount(triangles.ravel(), np.repeat(area / 3, 3), minlength=len(nodes))
    return Quadrature(nodes, weights, cells, np.arange(len(nodes)), triangles)


def segments(nodes, triangles, order=2):
    """The Gauss points, weighted normals and cells of every smoothing-cell segment.

    Inside each triangle (a, b, c) the segment from the midpoint of ab to the centroid
    separates a's cell from b's (and likewise for bc and ca); on a triangle edge that no
    other triangle shares (the domain's boundary), each half belongs to the cell of its
    end node.
    """
    nodes, triangles = np.asarray(nodes, dtype=float), np.asarray(triangles)
    corners = nodes[triangles]                                   # (C, 3, 2)
    centroid = corners.mean(1)
    ends = np.roll(triangles, -1, axis=1)                       # b, c, a
    mid = 0.5 * (corners + nodes[ends])                          # m_ab, m_bc, m_ca
    pieces = [(mid.reshape(-1, 2), np.repeat(centroid, 3, 0),     # m_ab -> g: a's cell
               triangles.ravel(), ends.ravel())]                 # on its left

    edges = np.sort(np.stack([triangles, ends], -1).reshape(-1, 2), axis=1)
    _, index, count = np.unique(edges, axis=0, return_index=True, return_counts=True)
    boundary = index[count == 1]                                 # edges of one triangle
    start, end = triangles.ravel()[boundary], ends.ravel()[boundary]
    half = mid.reshape(-1, 2)[boundary]
    none = np.full(len(boundary), -1)
    pieces += [(nodes[start], half, start, none), (half, nodes[end], end, none)]
    xi, w = leggauss(order)
    out = []
    for a, b, cell_in, cell_out in pieces:
        d = b - a
        normal = np.column_stack([d[:, 1], -d[:, 0]])          # right of a -> b, times |d|
        at = a[:, None] + 0.5 * (xi[None, :, None] + 1) * d[:, None]
        out.append((at.reshape(-1, 2), (0.5 * w[None, :, None] * normal[:, None]).reshape(-1, 2),
                    np.repeat(cell_in, order), np.repeat(cell_out, order)))
    return SmoothingSegments(*(np.concatenate(parts) for parts in zip(*out)))


def shape_functions(quad, build, order=2):
    """The nodes' shape functions with smoothed gradients on the cells ``quad``
    (:func:`nodal_cells`); ``build(points)`` gives the MLS shape functions of the nodes at
    ``points`` and ``order`` is the Gauss rule of each segment."""
    segs = segments(quad.points, quad.triangles, order)
    return smoothed(build(quad.points), build(segs.points), segs, quad.weights)


def smoothed(shape_nodes, shape_segments, segs, areas):
    """Shape functions at the nodes with the smoothed gradients, on one CSR pattern.

    Parameters
    ----------
    shape_nodes : ShapeFunctions
        MLS at the nodes (their ``phi`` is kept).
    shape_segments : ShapeFunctions
        MLS at ``segs.points``.
    segs : SmoothingSegments
    areas : ndarray, shape (N,)
        The smoothing cells' areas [m2].

    Returns
    -------
    ShapeFunctions
        ``phi`` of ``shape_nodes`` and ``dphi_dx``, ``dphi_dy`` the smoothed gradients,
        all three on the union of their patterns (a node sees every node that any point of
        its cell's boundary sees); ``rcond`` the smallest over the node and its segments.
    """
    n = len(areas)
    rows = np.concatenate([segs.inner, segs.outer[segs.outer >= 0]])
    sign = np.concatenate([np.ones(len(segs.inner)), -np.ones(np.sum(segs.outer >= 0))])
    cols = np.concatenate([np.arange(len(segs.inner)), np.flatnonzero(segs.outer >= 0)])
    grads = []
    for k in range(2):
        values = sign * segs.normal[cols, k] / areas[rows]
        C = csr_array((values, (rows, cols)), shape=(n, len(segs.inner)))
        grads.append((C @ shape_segments.phi).tocsr())
    pattern = sum(_structure(m) for m in (shape_nodes.phi, *grads))
    pattern.sort_indices()
    phi, dx, dy = (_on(pattern, m) for m in (shape_nodes.phi, *grads))
    worst = np.full(n, np.inf)
    np.minimum.at(worst, segs.inner, shape_segments.rcond)
    return type(shape_nodes)(phi, dx, dy, shape_nodes.support, shape_nodes.weight,
                             shape_nodes.scale, np.minimum(shape_nodes.rcond, worst))


def _structure(matrix):
    """Ones on every stored entry of ``matrix`` (so that a sum of structures keeps all)."""
    matrix = csr_array(matrix)
    return csr_array((np.ones(matrix.nnz), matrix.indices, matrix.indptr),
                     shape=matrix.shape)


def _on(pattern, matrix):
    """``matrix`` stored on ``pattern`` (whose entries include its own), zeros kept."""
    coo = matrix.tocoo()
    width = pattern.shape[1]
    rows = np.repeat(np.arange(pattern.shape[0]), np.diff(pattern.indptr))
    keys = rows * width + pattern.indices
    position = np.searchsorted(keys, coo.row.astype(np.int64) * width + coo.col)
    data = np.zeros(pattern.nnz)
    data[position] = coo.data
    return csr_array((data, pattern.indices.copy(), pattern.indptr.copy()),
                     shape=pattern.shape)
