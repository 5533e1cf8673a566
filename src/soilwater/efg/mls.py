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
node; a point sees node J if ``|x - x_J| < d_mJ`` (:mod:`soilwater.efg.mls_supports`
finds them). The values and gradients are a numba kernel,
:mod:`soilwater.efg.mls_kernel`.

Safeguard: every point must see at least 3 non-collinear nodes and its scaled moment
matrix must have a reciprocal condition number (1-norm) of at least :data:`RCOND_MIN`;
otherwise :meth:`ShapeFunctions.build` raises :class:`InputError` naming the worst point,
the case entry of the scale factor (``efg.scale_u`` or ``efg.scale_p``) and the fix.
"""

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_array

from soilwater.efg.mls_kernel import shape_kernel
from soilwater.efg.mls_supports import NEIGHBOURS, neighbours, support_radii
from soilwater.efg.settings import DEFAULT_SCALE, Weight
from soilwater.errors import InputError, require

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
            A name read by :meth:`soilwater.efg.settings.Weight.parse`: ``quartic``
            (``Q``), ``cubic`` or ``exp:C`` (``E-A`` = ``exp:0.5``, ``E-B`` = ``exp:0.25``).
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
        phi, dx, dy, rcond = shape_kernel(points, nodes, support, indptr, indices,
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
