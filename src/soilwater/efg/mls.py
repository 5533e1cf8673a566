"""Moving-least-squares shape functions and their gradients, batched over points.

Linear basis, shifted to the evaluation point and scaled (Belytschko,
Lu and Gu 1994, "Element-free Galerkin methods", IJNME 37)::

    q_J = [1, (x_J - x)/h, (y_J - y)/h],   A = sum_J w_J q_J q_J^T,   B_J = w_J q_J
    phi_J(x) = gamma^T B_J,                A gamma = p(0) = [1, 0, 0]
    A gamma_,i = p_,i - A_,i gamma,        p_,x = [0, 1/h, 0], p_,y = [0, 0, 1/h]
    phi_J,i = gamma_,i^T B_J + gamma^T B_J,i

The frame ``(x, h)`` is frozen while differentiating: the shape functions of a linear basis
do not depend on the origin or the length of the basis, so the gradients are exact. ``h``
is the mean support radius of the nodes the point sees, which makes the scaled moment
matrix dimensionless with entries of order one; its conditioning then measures the node
layout only, not the units.

Supports: ``d_mJ = scale x d_J``, ``d_J`` the distance from node J to its 8th nearest other
node (``sqrt(2) h`` inside a square grid of spacing h, the paper's "second shortest
distance"). A point sees node J if ``|x - x_J| < d_mJ``.

Safeguard: every point must see at least 3 non-collinear nodes and its scaled moment
matrix must have a reciprocal condition number (1-norm) of at least :data:`RCOND_MIN`;
otherwise :meth:`ShapeFunctions.build` raises :class:`InputError` naming the worst point,
the case entry of the scale factor (``efg.scale_u`` or ``efg.scale_p``) and the fix.
"""

import dataclasses
from dataclasses import dataclass

import numba
import numpy as np
from scipy.sparse import csr_array
from scipy.spatial import cKDTree

from soilwater.efg.weights import weight_scalar
from soilwater.errors import InputError, require
from soilwater.efg.settings import DEFAULT_SCALE, Weight

RCOND_MIN = 1e-10
"""Smallest accepted reciprocal condition number (1-norm) of a point's scaled moment matrix.

Measured on the built-in cases (Gauss points of square cells, 1 to 4 per direction, with
and without quarter cells; soilwater.efg.quadrature's square and Delaunay cells; Gauss points on
the boundary edges; the nodes themselves), the worst rcond is, at scale factor 0.8:
3e-6 (quartic), 2e-6 (cubic), 8e-4 (E-A), 8e-8 (E-B), all at mid-edge boundary points;
at 1.0: 7e-3, 5e-3, 1e-2, 3e-5; at 1.2 to 1.5: above 1e-2 (3e-4 for E-B). Below a scale
factor of about 0.77 (2 x 2 Gauss points) or 0.73 (3 x 3) in the square cells of the
111-node specimen some points see fewer than 3 nodes.
"""

NEIGHBOURS = 8


@dataclass(frozen=True, eq=False)
class ShapeFunctions:
    """MLS shape functions of ``n_nodes`` nodes at ``n_points`` points, with gradients.

    Attributes
    ----------
    phi : scipy.sparse.csr_array, shape (n_points, n_nodes)
        ``phi[p, J] = phi_J(x_p)`` (dimensionless); ``phi @ u`` interpolates nodal
        parameters ``u`` to the points.
    dphi_dx, dphi_dy : scipy.sparse.csr_array, shape (n_points, n_nodes)
        Derivatives of ``phi`` with respect to the point's x and y [1/m]. The three
        matrices share the same ``indptr`` and ``indices`` arrays (column indices sorted
        within each row; entries whose value is zero are kept in the pattern).
    support : ndarray, shape (n_nodes,)
        Support radii ``d_mJ`` [m].
    weight : Weight
        The weight function (``str(weight)`` is its canonical name).
    scale : float
        Scale factor ``d_mJ / d_J`` (dimensionless).
    rcond : ndarray, shape (n_points,)
        Reciprocal condition number (1-norm) of each point's scaled moment matrix.
    """

    phi: csr_array
    dphi_dx: csr_array
    dphi_dy: csr_array
    support: np.ndarray
    weight: Weight
    scale: float
    rcond: np.ndarray

    def subset(self, rows):
        """The shape functions at some of the points (a slice or an index array)."""
        return dataclasses.replace(self, phi=self.phi[rows], dphi_dx=self.dphi_dx[rows],
                                   dphi_dy=self.dphi_dy[rows], rcond=self.rcond[rows])

    def tested(self, r):
        """``sum_s S_s^T r[:, s]`` over the slots ``S = (phi, dphi/dx, dphi/dy)``, (N,).

        ``r`` (P, 3) holds one field's residual coefficients at the points (weights
        included, :mod:`soilwater.physics.weakform`'s layout); all-zero slots are skipped.
        """
        out = np.zeros(self.phi.shape[1])
        for s, N in enumerate((self.phi, self.dphi_dx, self.dphi_dy)):
            if r[:, s].any():
                out += N.T @ r[:, s]
        return out

    @property
    def indptr(self):
        """Row pointers of the shared CSR pattern, shape (n_points + 1,)."""
        return self.phi.indptr

    @property
    def indices(self):
        """Node index of every stored entry of the shared CSR pattern, shape (nnz,)."""
        return self.phi.indices

    @classmethod
    def build(cls, nodes, points, weight="quartic", scale=DEFAULT_SCALE, key="efg.scale_u",
              support=None):
        """Shape functions and gradients of ``nodes`` at ``points``.

        Parameters
        ----------
        nodes : array_like, shape (n_nodes, 2)
            Node coordinates [m]; at least 9 nodes (the support needs an 8th neighbour).
        points : array_like, shape (n_points, 2)
            Evaluation points [m].
        weight : str or Weight
            A name read by :meth:`soilwater.efg.settings.Weight.parse`: ``quartic`` (``Q``), ``cubic``
            or ``exp:C`` (``E-A`` = ``exp:0.5``, ``E-B`` = ``exp:0.25``).
        scale : float
            Scale factor of the supports, ``d_mJ = scale x d_J`` (usually 1.2 to 1.5).
        key : str
            The case entry ``scale`` comes from (``efg.scale_u`` or ``efg.scale_p``),
            named in the message when the supports are too small.
        support : ndarray, shape (n_nodes,), optional
            The radii [m] of these nodes at this scale (:func:`support_radii`, the
            ``support`` of shape functions built before on the same nodes), so that a
            second set of points does not search the nodes' neighbours again.

        Returns
        -------
        ShapeFunctions

        Raises
        ------
        InputError
            Bad arrays, weight or scale, or a point that sees fewer than 3 nodes, only
            collinear ones, or an ill-conditioned moment matrix.

        Examples
        --------
        >>> import numpy as np
        >>> x = np.linspace(0.0, 2.0, 5)
        >>> nodes = np.stack(np.meshgrid(x, x), axis=-1).reshape(-1, 2)
        >>> sf = ShapeFunctions.build(nodes, [[0.3, 1.1], [1.7, 0.2]], "E-A", 1.3)
        >>> np.allclose(sf.phi @ nodes, [[0.3, 1.1], [1.7, 0.2]])
        True
        """
        nodes, points = _coordinates(nodes, "nodes"), _coordinates(points, "points")
        require(len(nodes) > NEIGHBOURS, f"MLS shape functions need at least "
                f"{NEIGHBOURS + 1} nodes (the support radius is the distance to the "
                f"{NEIGHBOURS}th nearest node); got {len(nodes)}")
        weight = Weight.parse(weight)
        scale = float(scale)
        require(np.isfinite(scale) and scale > 0, f"scale factor = {scale} must be "
                f"positive (usually 1.2 to 1.5, e.g. {DEFAULT_SCALE})")
        support = support_radii(nodes, scale) if support is None else support
        indptr, indices = neighbours(nodes, points, support)
        phi, dx, dy, rcond = _shape_kernel(points, nodes, support, indptr, indices,
                                           weight.kind, weight.c, RCOND_MIN)
        _require_regular(rcond, points, nodes, indptr, indices, weight, scale, key)
        shape = (len(points), len(nodes))
        phi, dx, dy = (csr_array((data, indices, indptr), shape=shape)
                       for data in (phi, dx, dy))
        return cls(phi, dx, dy, support, weight, scale, rcond)


def _coordinates(values, name):
    """``values`` as a finite float array of shape (n, 2)."""
    array = np.asarray(values, dtype=float)
    require(array.ndim == 2 and array.shape[1] == 2, f"{name} must have shape (n, 2) "
            f"(x, y in m); got shape {array.shape}")
    require(np.all(np.isfinite(array)), f"{name} contain NaN or infinite coordinates")
    return np.ascontiguousarray(array)


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


@numba.njit(cache=True)
def _shape_kernel(points, nodes, support, indptr, indices, kind, c, rcond_min):
    """Shape-function values and gradients on the CSR pattern, and each point's rcond.

    Points with fewer than 3 nodes or ``rcond < rcond_min`` get zeros (the caller raises).
    The output arrays first hold the weights and their derivatives, then the shape
    functions; the moment matrices live in one (3, 3, 3) buffer: A, A_,x, A_,y.
    """
    nnz = indices.size
    phi, dx, dy = np.zeros(nnz), np.zeros(nnz), np.zeros(nnz)
    rcond = np.zeros(len(points))
    moments = np.empty((3, 3, 3))
    inverse, gamma = np.empty((3, 3)), np.empty(3)
    gamma_x, gamma_y, rhs = np.empty(3), np.empty(3), np.empty(3)
    for p in range(len(points)):
        start, stop = indptr[p], indptr[p + 1]
        if stop - start < 3:
            continue
        x, y = points[p, 0], points[p, 1]
        h = 0.0
        for k in range(start, stop):
            h += support[indices[k]]
        h /= stop - start
        inv_h = 1.0 / h
        moments[:] = 0.0
        for k in range(start, stop):
            j = indices[k]
            phi[k], dx[k], dy[k] = _weight(x - nodes[j, 0], y - nodes[j, 1], support[j],
                                           kind, c)
            _accumulate(moments, (nodes[j, 0] - x) * inv_h, (nodes[j, 1] - y) * inv_h,
                        phi[k], dx[k], dy[k])
        _symmetrise(moments)
        rcond[p] = _inverse3(moments[0], inverse)
        if rcond[p] < rcond_min:
            phi[start:stop], dx[start:stop], dy[start:stop] = 0.0, 0.0, 0.0
            continue
        gamma[:] = inverse[:, 0]
        _gamma_derivative(inverse, moments[1], gamma, 1, h, rhs, gamma_x)
        _gamma_derivative(inverse, moments[2], gamma, 2, h, rhs, gamma_y)
        for k in range(start, stop):
            j = indices[k]
            bx, by = (nodes[j, 0] - x) * inv_h, (nodes[j, 1] - y) * inv_h
            base = gamma[0] + bx * gamma[1] + by * gamma[2]
            dx[k] = phi[k] * (gamma_x[0] + bx * gamma_x[1] + by * gamma_x[2]) + dx[k] * base
            dy[k] = phi[k] * (gamma_y[0] + bx * gamma_y[1] + by * gamma_y[2]) + dy[k] * base
            phi[k] *= base
    return phi, dx, dy, rcond


@numba.njit(cache=True)
def _weight(ex, ey, support, kind, c):
    """Weight of a node at offset ``(ex, ey) = x - x_J`` [m] and its x and y derivatives."""
    d = np.sqrt(ex * ex + ey * ey)
    w, dw_dr = weight_scalar(kind, c, d / support)
    slope = dw_dr / (d * support) if d > 0 else 0.0
    return w, slope * ex, slope * ey


@numba.njit(cache=True)
def _accumulate(moments, bx, by, w, wx, wy):
    """Add ``(w, w_,x, w_,y) b b^T`` of one node, ``b = [1, bx, by]``, to the moments."""
    b = (1.0, bx, by)
    for a in range(3):          # upper triangle; :func:`_symmetrise` fills the rest
        for e in range(a, 3):
            bb = b[a] * b[e]
            moments[0, a, e] += w * bb
            moments[1, a, e] += wx * bb
            moments[2, a, e] += wy * bb


@numba.njit(cache=True)
def _symmetrise(moments):
    """Lower triangles of the three moment matrices from their upper ones."""
    for m in range(3):
        moments[m, 1, 0], moments[m, 2, 0] = moments[m, 0, 1], moments[m, 0, 2]
        moments[m, 2, 1] = moments[m, 1, 2]


@numba.njit(cache=True)
def _gamma_derivative(inverse, moment_i, gamma, i, h, rhs, out):
    """``out = gamma_,i = A^-1 (p_,i - A_,i gamma)`` with ``p_,i = e_i / h``."""
    for a in range(3):
        rhs[a] = 1.0 / h if a == i else 0.0
        for e in range(3):
            rhs[a] -= moment_i[a, e] * gamma[e]
    for a in range(3):
        out[a] = 0.0
        for e in range(3):
            out[a] += inverse[a, e] * rhs[e]


@numba.njit(cache=True)
def _inverse3(a, inverse):
    """Inverse of a symmetric 3x3 matrix by cofactors into ``inverse``; returns its 1-norm
    rcond (0 if singular)."""
    inverse[0, 0] = a[1, 1] * a[2, 2] - a[1, 2] ** 2
    inverse[0, 1] = a[0, 2] * a[1, 2] - a[0, 1] * a[2, 2]
    inverse[0, 2] = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    inverse[1, 1] = a[0, 0] * a[2, 2] - a[0, 2] ** 2
    inverse[1, 2] = a[0, 1] * a[0, 2] - a[0, 0] * a[1, 2]
    inverse[2, 2] = a[0, 0] * a[1, 1] - a[0, 1] ** 2
    det = a[0, 0] * inverse[0, 0] + a[0, 1] * inverse[0, 1] + a[0, 2] * inverse[0, 2]
    if not det > 0:
        return 0.0
    inverse[1, 0], inverse[2, 0], inverse[2, 1] = inverse[0, 1], inverse[0, 2], inverse[1, 2]
    inverse /= det
    norm_a, norm_inv = 0.0, 0.0
    for e in range(3):
        norm_a = max(norm_a, abs(a[0, e]) + abs(a[1, e]) + abs(a[2, e]))
        norm_inv = max(norm_inv, abs(inverse[0, e]) + abs(inverse[1, e]) + abs(inverse[2, e]))
    return 1.0 / (norm_a * norm_inv)


def _require_regular(rcond, points, nodes, indptr, indices, weight, scale, key):
    """Raise InputError naming the worst point and ``key`` unless all rcond >= RCOND_MIN."""
    bad = np.flatnonzero(~(rcond >= RCOND_MIN))
    if bad.size == 0:
        return
    p = bad[np.argmin(rcond[bad])]
    seen = nodes[indices[indptr[p]:indptr[p + 1]]]
    better = DEFAULT_SCALE if scale < DEFAULT_SCALE else round(scale + 0.2, 2)
    reason, extra = _diagnosis(seen, rcond[p])
    raise InputError(
        f"MLS shape functions: point {p} at ({points[p, 0]:.6g}, {points[p, 1]:.6g}) "
        f"{reason} (weight {weight}, scale factor {scale:g} from {key}; {bad.size} of "
        f"{len(points)} points fail): increase the scale factor, e.g. to {better:g}{extra}")


def _diagnosis(seen, rcond):
    """Why a point's moment matrix is unusable, and any fix besides a larger scale factor.

    ``seen`` holds the coordinates of the nodes the point sees; they count as collinear
    when their second principal spread is below 1e-12 of the first (rounding level).
    """
    if len(seen) == 0:
        return "lies outside every node's support", ""
    if len(seen) < 3:
        return f"sees only {len(seen)} node(s) within their supports (needs 3 not on a " \
            "line)", ""
    spread = np.linalg.svd(seen - seen.mean(axis=0), compute_uv=False)
    if spread[1] <= 1e-12 * spread[0]:
        return f"sees {len(seen)} nodes, all on one line", ", or add nodes off that line"
    return (f"has an ill-conditioned moment matrix (reciprocal condition number "
            f"{rcond:.1e} < {RCOND_MIN:g}; it sees {len(seen)} nodes)"), ""
