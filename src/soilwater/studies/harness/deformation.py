"""Shear strain of a run's snapshots, one measure for EFG and FEM: the logarithmic
(Hencky) strain of each triangle of a triangulation of the initial nodes.

Both methods move nodes (EFG nodes, FEM vertices); the measure uses nothing else. Each
triangle's deformation gradient ``F`` (initial -> current configuration) is constant,
from its three corners' positions; the triangles are the FEM run's own cells (corner
vertices; a quadrilateral is split along its 0-2 diagonal) or, for EFG (a point cloud),
the Delaunay triangles of the initial node set.

Definition (plane strain, ``F_zz = 1``): the Hencky strain ``e = ln V``, ``V = sqrt(F
F^T)`` the left stretch, has the in-plane principal values ``ln lambda_1, ln lambda_2``
(the principal stretches, singular values of ``F``) and ``e_zz = 0``; with ``e'`` its
deviator (3 x 3, ``e' = e - tr(e) I / 3``), the deviatoric invariant is

    eps_s = sqrt(2/3 e':e')

(dimensionless; ``gamma / sqrt(3)`` in small simple shear of amount gamma, the strain
work-conjugate of ``q``). It is independent of rotation and undefined for a triangle
turned inside out (``det F <= 0``), where it is NaN.
"""

import numpy as np
from scipy.spatial import ConvexHull

from soilwater.efg.quadrature import delaunay_cells
from soilwater.material.kinematics import determinant, inverse
from soilwater.geometry.quality import cell_quality


def triangulation(snapshot):
    """Triangles of a snapshot's initial nodes, counter-clockwise there.

    Parameters
    ----------
    snapshot : soilwater.results.Snapshot
        The run's first snapshot (t = 0): FEM snapshots carry cells (triangles or
        quadrilaterals), EFG snapshots are a point cloud.

    Returns
    -------
    ndarray of int, shape (T, 3)
        Node indices: the cells' corner vertices (a quadrilateral ``abcd`` as ``abc``
        and ``acd``), or the Delaunay triangles of the points
        (:func:`soilwater.efg.quadrature.delaunay_cells` on their convex hull) when there are no
        cells.
    """
    points = np.asarray(snapshot.points, dtype=float)
    if not snapshot.cells:
        hull = points[ConvexHull(points).vertices]
        return delaunay_cells(points, hull).triangles
    (_, cells), = snapshot.cells
    if cells.shape[1] == 4:
        cells = np.concatenate([cells[:, [0, 1, 2]], cells[:, [0, 2, 3]]])
    cells = cells.copy()
    clockwise = _signed_area(points, cells) < 0
    cells[clockwise] = cells[clockwise][:, ::-1]
    return cells


def deformation_gradient(initial, current, triangles):
    """Deformation gradient of each triangle, constant over it.

    Parameters
    ----------
    initial, current : array_like, shape (N, 2)
        Node positions [m] in the initial and the current configuration.
    triangles : array_like of int, shape (T, 3)
        Node indices, counter-clockwise in the initial configuration.

    Returns
    -------
    ndarray, shape (T, 2, 2)
        ``F_ij = dx_i / dX_j``.
    """
    initial, current = np.asarray(initial, float), np.asarray(current, float)
    triangles = np.asarray(triangles)
    dX = _edges(initial, triangles)
    dx = _edges(current, triangles)
    return dx @ inverse(dX)


def shear_strain(F):
    """Deviatoric invariant ``eps_s = sqrt(2/3 e':e')`` of the plane-strain Hencky
    strain (module docstring).

    Parameters
    ----------
    F : array_like, shape (..., 2, 2)
        In-plane deformation gradients (``F_zz = 1``).

    Returns
    -------
    ndarray, shape (...)
        eps_s (dimensionless, >= 0); NaN where ``det F <= 0``.

    Examples
    --------
    Simple shear of amount 1 gives ``(2 / sqrt(3)) asinh(1/2)``:

    >>> round(float(shear_strain([[1.0, 1.0], [0.0, 1.0]])), 9)
    0.555655553
    """
    F = np.asarray(F, dtype=float)
    stretch = np.linalg.svd(F, compute_uv=False)        # principal stretches
    with np.errstate(divide="ignore", invalid="ignore"):   # a degenerate F: NaN below
        e = np.concatenate([np.log(stretch), np.zeros(F.shape[:-2] + (1,))], axis=-1)
        deviator = e - e.mean(axis=-1, keepdims=True)
        eps = np.sqrt(2.0 / 3.0 * (deviator ** 2).sum(axis=-1))
    return np.where(determinant(F) > 0, eps, np.nan)


def nodal(values, initial, triangles):
    """Triangle values averaged to the nodes, weighted by the triangles' initial areas.

    Parameters
    ----------
    values : array_like, shape (T,)
        One value per triangle; NaN ones (inverted triangles) are left out.
    initial : array_like, shape (N, 2)
        Initial node positions [m].
    triangles : array_like of int, shape (T, 3)
        Node indices, counter-clockwise in the initial configuration.

    Returns
    -------
    ndarray, shape (N,)
        NaN at a node whose triangles all have NaN values (or that no triangle holds).
    """
    values, triangles = np.asarray(values, float), np.asarray(triangles)
    area = np.where(np.isnan(values), 0.0, _signed_area(np.asarray(initial, float),
                                                        triangles))
    n = len(initial)
    weight = np.bincount(triangles.ravel(), np.repeat(area, 3), minlength=n)
    total = np.bincount(triangles.ravel(), np.repeat(area * np.nan_to_num(values), 3),
                        minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(weight > 0, total / weight, np.nan)


def node_areas(initial, triangles):
    """Tributary area of each node [m2]: a third of each of its triangles' initial
    areas."""
    area = _signed_area(np.asarray(initial, float), np.asarray(triangles))
    return np.bincount(np.asarray(triangles).ravel(), np.repeat(area / 3, 3),
                       minlength=len(initial))


def nodal_strain(first, snapshot):
    """eps_s at the nodes of a snapshot and their tributary areas, both (N,): the
    triangles of :func:`triangulation` of the run's first snapshot ``first``, averaged
    by :func:`nodal`."""
    initial = np.asarray(first.points, float)
    triangles = triangulation(first)
    return (nodal(snapshot_strain(initial, snapshot, triangles), initial, triangles),
            node_areas(initial, triangles))


def snapshot_strain(initial, snapshot, triangles):
    """eps_s of each triangle at one snapshot (:func:`shear_strain` of
    :func:`deformation_gradient`), from the snapshot's node positions."""
    return shear_strain(deformation_gradient(initial, snapshot.points, triangles))


def smallest_angles(snapshots, triangles):
    """Smallest interior angle [degrees] of each triangle at each snapshot, (S, T):
    :func:`soilwater.geometry.quality.cell_quality` of the triangles on the snapshots' node
    positions (negative where a triangle has inverted)."""
    corners = np.stack([np.asarray(snap.points)[triangles] for snap in snapshots])
    return cell_quality(corners.reshape(-1, 3, 2))[0].reshape(len(corners), -1)


def _edges(points, triangles):
    """Edge vectors from corner 0 to corners 1 and 2, as the columns of (T, 2, 2)."""
    corners = points[triangles]
    return np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]],
                    axis=-1)


def _signed_area(points, triangles):
    """Signed area of each triangle [m^2], positive counter-clockwise."""
    return 0.5 * determinant(_edges(points, triangles))
