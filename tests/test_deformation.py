"""The shear-strain measure of the pictures (:mod:`soilwater.studies.harness.deformation`) against
closed forms: simple shear of amount gamma gives eps_s = (2 / sqrt(3)) asinh(gamma / 2),
pure shear with stretch lambda (2 / sqrt(3)) |ln lambda|, an in-plane dilation s
(2 / 3) |ln s| (plane strain keeps e_zz = 0 in the deviator), a rigid rotation 0; the
same values from homogeneous deformations of a triangulated grid, for EFG's Delaunay
triangles and FEM cells of either orientation, triangles or quadrilaterals."""

import numpy as np
import pytest

from soilwater.studies.harness.deformation import (deformation_gradient, nodal, shear_strain,
                                     snapshot_strain, triangulation)
from soilwater.results import Snapshot

GAMMAS = np.array([0.01, 0.3, 1.0, 3.0])


def _rotation(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def test_simple_shear_closed_form():
    F = np.zeros((len(GAMMAS), 2, 2))
    F[:, 0, 0] = F[:, 1, 1] = 1.0
    F[:, 0, 1] = GAMMAS
    expected = 2 / np.sqrt(3) * np.arcsinh(GAMMAS / 2)
    assert shear_strain(F) == pytest.approx(expected, rel=1e-10)
    # small shear: gamma / sqrt(3), the strain conjugate of q
    assert shear_strain(F)[0] == pytest.approx(0.01 / np.sqrt(3), rel=1e-4)


def test_pure_shear_and_dilation_closed_forms():
    stretch = np.array([0.5, 0.9, 1.2, 4.0])
    pure = np.array([np.diag([a, 1 / a]) for a in stretch])
    dilation = np.array([np.diag([a, a]) for a in stretch])
    assert shear_strain(pure) == pytest.approx(2 / np.sqrt(3) * np.abs(np.log(stretch)),
                                               rel=1e-10)
    assert shear_strain(dilation) == pytest.approx(2 / 3 * np.abs(np.log(stretch)),
                                                   rel=1e-10)


def test_rigid_rotation_gives_zero_and_rotation_changes_nothing():
    """A small-strain measure would give 1 - cos(angle) (0.5 at 60 degrees); the Hencky
    measure gives zero, and a superposed rotation leaves simple shear's value."""
    angles = np.radians([1.0, 60.0, 135.0, 180.0])
    rotations = np.array([_rotation(a) for a in angles])
    assert np.abs(shear_strain(rotations)).max() < 1e-12
    shear = np.array([[1.0, 1.0], [0.0, 1.0]])
    assert shear_strain(rotations @ shear) == pytest.approx(
        np.full(len(angles), 2 / np.sqrt(3) * np.arcsinh(0.5)), rel=1e-10)


def test_inverted_or_degenerate_is_nan():
    values = shear_strain([[[1.0, 0.0], [0.0, -1.0]], [[1.0, 1.0], [1.0, 1.0]],
                           [[1.0, 0.0], [0.0, 1.0]]])
    assert np.isnan(values[:2]).all() and values[2] == 0.0


def _grid(nx=4, ny=3):
    x, y = np.meshgrid(np.linspace(0.0, 3.0, nx), np.linspace(0.0, 2.0, ny))
    return np.column_stack([x.ravel(), y.ravel()])


def _cells(nx=4, ny=3, quads=False):
    """A grid's cells, half the triangles clockwise (as scikit-fem leaves them)."""
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1))
    a = (j * nx + i).ravel()
    b, c, d = a + 1, a + nx + 1, a + nx
    if quads:
        return [("quad", np.column_stack([a, b, c, d]))]
    return [("triangle", np.vstack([np.column_stack([a, b, c]),      # counter-clockwise
                                    np.column_stack([a, d, c])]))]   # clockwise


@pytest.mark.parametrize("cells", [[], _cells(), _cells(quads=True)],
                         ids=["delaunay", "triangles", "quads"])
def test_homogeneous_deformation_of_a_grid(cells):
    """x = R F X + c on every node: each triangle and each node carries the closed form."""
    X = _grid()
    triangles = triangulation(Snapshot(0.0, X, {}, cells))
    assert len(triangles) == 12
    corners = X[triangles]
    edges = np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]])
    assert (edges[0, :, 0] * edges[1, :, 1] - edges[0, :, 1] * edges[1, :, 0] > 0).all()
    F = _rotation(0.7) @ np.array([[1.0, 0.8], [0.0, 1.0]])
    x = X @ F.T + [5.0, -2.0]
    assert deformation_gradient(X, x, triangles) == pytest.approx(
        np.broadcast_to(F, (12, 2, 2)), abs=1e-12)
    eps = snapshot_strain(X, Snapshot(1.0, x, {}), triangles)
    expected = 2 / np.sqrt(3) * np.arcsinh(0.4)
    assert eps == pytest.approx(np.full(12, expected), rel=1e-10)
    assert nodal(eps, X, triangles) == pytest.approx(np.full(len(X), expected), rel=1e-10)


def test_nodal_average_weights_by_initial_area_and_skips_nan():
    """Two triangles sharing the edge 1-2, areas 1 and 3, values 1 and 2: the shared nodes
    take (1 x 1 + 3 x 2) / 4 = 1.75; a NaN triangle is left out."""
    X = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 1.0], [6.0, 1.0]])
    triangles = np.array([[0, 1, 2], [1, 3, 2]])
    assert nodal([1.0, 2.0], X, triangles) == pytest.approx([1.0, 1.75, 1.75, 2.0])
    values = nodal([1.0, np.nan], X, triangles)
    assert values[:3] == pytest.approx([1.0, 1.0, 1.0]) and np.isnan(values[3])
