"""Which nodes each point sees: MLS support radii and the point-to-node search.

Supports: ``d_mJ = scale x d_J``, ``d_J`` the distance from node J to its 8th nearest other
node (``sqrt(2) h`` inside a square grid of spacing h, the paper's "second shortest
distance"). A point sees node J if ``|x - x_J| < d_mJ``. Coordinates and radii in m.
"""

import numba
import numpy as np
from scipy.spatial import cKDTree

from soilwater.errors import InputError

#: The support radius of a node is the distance to this nearest other node, times the scale.
NEIGHBOURS = 8


def support_radii(nodes, scale):
    """Support radii ``d_mJ = scale x d_J`` [m], ``d_J`` the 8th-nearest-node distance.

    Parameters
    ----------
    nodes : ndarray, shape (n_nodes, 2)
        Node coordinates [m], at least 9 of them.
    scale : float
        Scale factor (dimensionless).

    Returns
    -------
    ndarray, shape (n_nodes,)

    Examples
    --------
    >>> import numpy as np
    >>> x = np.arange(5.0)
    >>> nodes = np.stack(np.meshgrid(x, x), axis=-1).reshape(-1, 2)
    >>> bool(np.isclose(support_radii(nodes, 1.0)[12], np.sqrt(2)))  # interior: sqrt(2) h
    True
    """
    distance, _ = cKDTree(nodes).query(nodes, k=NEIGHBOURS + 1)
    d = distance[:, NEIGHBOURS]
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        raise InputError(f"node {bad[0]} at ({nodes[bad[0], 0]:g}, {nodes[bad[0], 1]:g}) "
                         f"coincides with {NEIGHBOURS} other nodes: remove duplicate nodes")
    return scale * d


def neighbours(nodes, points, support):
    """CSR pattern of the nodes each point sees: ``|x_p - x_J| < d_mJ``.

    A cell list over supports: the plane is cut into square bins (side the median radius,
    at most about 4 bins per node), each node is listed in every bin its support's bounding
    square overlaps (in node order, so lists are sorted), and a point tests only the nodes
    listed in its own bin: about 30 candidates for 10 hits, no sort. Binning by nodes
    instead (bins of the largest radius, the 9 around the point) tested 120: the corner
    nodes' radii are twice the interior's.

    Parameters
    ----------
    nodes : ndarray, shape (n_nodes, 2)
        Node coordinates [m].
    points : ndarray, shape (n_points, 2)
        Evaluation points [m].
    support : ndarray, shape (n_nodes,)
        Support radii [m].

    Returns
    -------
    indptr : ndarray, shape (n_points + 1,)
    indices : ndarray, shape (nnz,)
        Node indices of each point, sorted within a row. int32 when the sizes allow it
        (the type scipy.sparse keeps without copying).

    Examples
    --------
    >>> import numpy as np
    >>> nodes = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]])
    >>> indptr, indices = neighbours(nodes, np.array([[0.5, 0.0], [2.9, 0.0]]),
    ...                              np.array([1.0, 1.0, 0.5]))
    >>> indptr.tolist(), indices.tolist()
    ([0, 2, 3], [0, 1, 2])
    """
    origin = nodes.min(axis=0)
    extent = np.maximum(nodes.max(axis=0) - origin, 1e-300)
    size = max(float(np.median(support)), np.sqrt(extent.prod() / (4 * len(nodes))))
    shape = np.maximum(np.ceil(extent / size), 1).astype(np.int64)
    start, binned, order = _bins(nodes, support, origin, size, shape)
    indptr, indices = _search(points, origin, size, shape, start, binned, order)
    small = max(indices.size, len(nodes), len(points)) < np.iinfo(np.int32).max
    kind = np.int32 if small else np.int64
    return indptr.astype(kind), indices.astype(kind)


@numba.njit(cache=True)
def _bin_of(x, y, origin, size, shape):
    """Bin (column, row) of a point, clipped to the grid of bins."""
    i = min(max(int(np.floor((x - origin[0]) / size)), 0), shape[0] - 1)
    j = min(max(int(np.floor((y - origin[1]) / size)), 0), shape[1] - 1)
    return i, j


@numba.njit(cache=True)
def _bins(nodes, support, origin, size, shape):
    """Bin lists of the nodes whose support square overlaps each bin, in node order:
    bin b lists ``order[start[b]:start[b + 1]]``, with their (x, y, radius^2) in
    ``binned`` (contiguous per bin). Two passes: count, then fill."""
    start = np.zeros(shape[0] * shape[1] + 1, np.int64)
    for fill in range(2):
        if fill:
            start = np.cumsum(start)
            at = start[:-1].copy()
            order = np.empty(start[-1], np.int64)
            binned = np.empty((start[-1], 3))
        for n in range(len(nodes)):
            x, y, r = nodes[n, 0], nodes[n, 1], support[n]
            i0, j0 = _bin_of(x - r, y - r, origin, size, shape)
            i1, j1 = _bin_of(x + r, y + r, origin, size, shape)
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    b = i * shape[1] + j
                    if fill:
                        order[at[b]] = n
                        binned[at[b], 0], binned[at[b], 1], binned[at[b], 2] = x, y, r * r
                        at[b] += 1
                    else:
                        start[b + 1] += 1
    return start, binned, order


@numba.njit(cache=True)
def _search(points, origin, size, shape, start, binned, order):
    """Both passes of the search (row counts, then columns): a point's own bin only."""
    indptr = np.zeros(len(points) + 1, np.int64)
    for fill in range(2):
        if fill:
            indices = np.empty(indptr[-1], np.int64)
        else:
            indices = np.empty(0, np.int64)
        for p in range(len(points)):
            x, y = points[p, 0], points[p, 1]
            i, j = _bin_of(x, y, origin, size, shape)
            b, count = i * shape[1] + j, 0
            for m in range(start[b], start[b + 1]):
                dx, dy = x - binned[m, 0], y - binned[m, 1]
                if dx * dx + dy * dy < binned[m, 2]:
                    if fill:
                        indices[indptr[p] + count] = order[m]
                    count += 1
            if not fill:
                indptr[p + 1] = indptr[p] + count
    return indptr, indices
