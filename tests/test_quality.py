"""Cell quality in the histories: soilwater.geometry.quality.cell_quality against
hand values, the undeformed grid's cells in both solvers, the fem-th mesh distorting
under the strip footing, and EFG's support-coverage check."""

import numpy as np
import pytest

from soilwater.efg.solver import solve as efg_solve
from soilwater.fem.solver import solve as fem_solve
from soilwater.case.loader import load_case
from soilwater.geometry.quality import cell_quality

S3 = np.sqrt(3)


@pytest.mark.parametrize("cell, angle, quality", [
    ([[0, 0], [1, 0], [0.5, S3 / 2]], 60.0, 1.0),                  # equilateral
    ([[0, 0], [1, 0], [0, 1]], 45.0, S3 / 2),                       # right isosceles
    # flattened: height 1e-3 over a unit base, A = 5e-4, l^2 sum = 1 + 2 (0.25 + 1e-6)
    ([[0, 0], [1, 0], [0.5, 1e-3]], np.degrees(np.arctan(2e-3)), 4 * S3 * 5e-4 / 1.500002),
    ([[0, 0], [0, 1], [1, 0]], -90.0, -S3 / 2),                     # inverted (clockwise)
    ([[0, 0], [1, 0], [1, 1], [0, 1]], 90.0, 1.0),                  # square
    ([[0, 0], [2, 0], [2, 1], [0, 1]], 90.0, 0.8),                  # 2:1 rectangle: 8 A / sum
    ([[0, 0], [1, 1], [1, 0], [0, 1]], -45.0, -1.0),                # bow-tie
])
def test_cell_quality_hand_values(cell, angle, quality):
    a, q = cell_quality([cell])
    assert a[0] == pytest.approx(angle, rel=1e-9, abs=1e-12)
    assert q[0] == pytest.approx(quality, rel=1e-9, abs=1e-12)


def test_cell_quality_is_vectorised_and_ignores_the_starting_corner():
    cells = np.array([[[0, 0], [1, 0], [0.3, 0.7]], [[0.2, 0.1], [1.4, 0.3], [0.5, 1.2]]])
    a, q = cell_quality(cells)
    a1, q1 = cell_quality(np.roll(cells, 1, axis=1))
    assert a.shape == q.shape == (2,) and np.allclose(a, a1) and np.allclose(q, q1)
    assert np.all(a < 60) and np.all((0 < q) & (q < 1))


def test_straight_quadrilateral_corner_has_quality_zero():
    """A quad with a straight corner (a triangle with a mid-edge vertex): 180 degrees
    there, so the smallest angle (45) does not see it, but its corner triangle is
    degenerate: quality 0."""
    a, q = cell_quality([[[0, 0], [1, 0], [2, 0], [1, 1]]])
    assert a[0] == pytest.approx(45, rel=1e-12) and q[0] == pytest.approx(0, abs=1e-12)


def test_bad_cells_are_refused():
    with pytest.raises(ValueError, match="must be"):
        cell_quality(np.zeros((2, 5, 2)))


def _grid_case():
    """Terzaghi's column on square cells (3 x 11 nodes on 2 x 10 m), two small steps."""
    return load_case("terzaghi", ["discretisation.nx=3", "time.steps=2"])


@pytest.mark.parametrize("method, angle, quality", [
    ("fem-th", 45.0, S3 / 2),   # two right isosceles triangles per square of the grid
    ("fem-p1p1", 45.0, S3 / 2),
    ("fem-q1q1", 90.0, 1.0),    # the squares themselves
    ("efg", 45.0, S3 / 2),      # Delaunay triangles of the square grid
])
def test_undeformed_grid_cells(method, angle, quality):
    """On the column's first level (the vertical strain is below 1e-3, measured
    deviations 1e-3 degrees), the cells are still the grid's."""
    case = _grid_case()
    result = (efg_solve(case, progress=False) if method == "efg"
              else fem_solve(case, method, progress=False))
    h = result.history
    assert h["min_angle"].iloc[0] == pytest.approx(angle, abs=0.05)
    assert h["min_quality"].iloc[0] == pytest.approx(quality, abs=1e-3)
    assert ("min_rcond" in h) == (method == "efg")


def test_efg_square_cells_stay_squares():
    case = load_case("terzaghi", ["discretisation.nx=3", "time.steps=2",
                                  "efg.cells=squares", "efg.integration=paper"])
    h = efg_solve(case, progress=False).history
    assert np.allclose(h["min_angle"], 90.0) and np.allclose(h["min_quality"], 1.0)


def _footing(method):
    case = load_case("strip-footing", ["geometry.width=5", "geometry.height=5",
                                       "discretisation.nx=11", "discretisation.ny=11"])
    if method == "efg":
        return efg_solve(case, progress=False).history
    return fem_solve(case, method, progress=False).history


def test_fem_mesh_distorts_under_the_strip_footing():
    """fem-th on the built-in footing, on a 5 B x 5 B domain of 11 x 11 nodes, to 0.5 B: the
    smallest angle falls from 44.8 to 18.3 degrees (measured: 38.1 at 0.1 B, 25.3 at
    0.3 B), quality from 0.86 to 0.50; no element inverts."""
    h = _footing("fem-th")
    angle, quality = h["min_angle"].to_numpy(), h["min_quality"].to_numpy()
    assert h["settlement@footing"].iloc[-1] == pytest.approx(0.5, rel=1e-9)
    assert angle[-1] < angle[0] - 20 and quality[-1] < quality[0] - 0.3
    assert np.all(angle > 10) and np.all(quality > 0)
    tenths = np.interp([0.1, 0.2, 0.3, 0.4, 0.5], h["settlement@footing"], angle)
    assert np.all(np.diff(tenths) < 0)  # monotonic at every tenth of B


def test_efg_background_cells_and_support_coverage_under_the_strip_footing():
    """EFG re-triangulates: its smallest angle falls less (measured 44.9 to 27.2 degrees,
    42.2 at 0.1 B, 35.6 at 0.3 B), and rcond stays near its start (1.47e-2 to 1.22e-2)."""
    h = _footing("efg")
    angle, rcond = h["min_angle"].to_numpy(), h["min_rcond"].to_numpy()
    assert np.all(np.isfinite(rcond)) and np.all(rcond > 0)
    assert rcond.min() > 0.5 * rcond[0]
    assert np.all(angle > 0) and angle[-1] < angle[0] - 10
