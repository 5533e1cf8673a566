"""Background cells: areas, exactness, the paper's quarter cells, deformed shapes."""

import numpy as np
import pytest
from matplotlib.path import Path
from scipy.spatial import Delaunay

from soilwater.efg.quadrature import delaunay_cells, square_cells
from soilwater.errors import InputError
from soilwater.case.loader import load_case

W, H = 3.0, 4.0  # the unconfined-compression specimen [m]


def specimen(nx=7, ny=9, layout="grid+centres"):
    """The built-in specimen; 7 x 9 grid + 48 centres = 111 nodes by default."""
    return load_case("unconfined-compression", [f"discretisation.nx={nx}",
                                                f"discretisation.ny={ny}",
                                                f"discretisation.layout={layout}"])


def shoelace(polygon):
    """Signed area of a polygon [m2], positive counter-clockwise."""
    x, y = polygon.T
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def barrel(nodes, bulge):
    """Compress by 20 % and bulge the sides: x -> x (1 + bulge sin(pi y / H)).

    ``bulge < 0`` pinches a waist: the right side becomes concave.
    """
    x, y = nodes.T
    return np.column_stack([x * (1 + bulge * np.sin(np.pi * y / H)), 0.8 * y])


def stretch(nodes):
    """Uniform stretch 1.1 along x, 0.9 along y."""
    return nodes * [1.1, 0.9]


def outside(q, boundary):
    """Number of Gauss points outside the polygon."""
    return np.count_nonzero(~Path(boundary).contains_points(q.points))


def both(case, nodes=None):
    """Square and Delaunay cells of the case's nodes (initial unless given)."""
    nodes = case.nodes() if nodes is None else nodes
    boundary = nodes[case.boundary_loop()]
    return square_cells(boundary, case.spacing), delaunay_cells(nodes, boundary)


# -- Case.boundary_loop --------------------------------------------------------------------
@pytest.mark.parametrize("nx, ny, layout", [(7, 9, "grid+centres"), (7, 9, "grid"),
                                            (2, 2, "grid"), (2, 5, "grid+centres")])
def test_boundary_loop_is_the_ccw_rectangle(nx, ny, layout):
    case = specimen(nx, ny, layout)
    nodes, loop = case.nodes(), case.boundary_loop()
    polygon = nodes[loop]
    assert len(loop) == len(set(loop)) == 2 * (nx + ny) - 4
    on_edge = np.isclose(nodes, 0).any(1) | np.isclose(nodes, [W, H]).any(1)
    assert set(loop) == set(np.flatnonzero(on_edge))
    corners = np.cumsum([0, nx - 1, ny - 1, nx - 1])
    np.testing.assert_array_equal(polygon[corners], [[0, 0], [W, 0], [W, H], [0, H]])
    steps = np.linalg.norm(np.roll(polygon, -1, 0) - polygon, axis=1)
    assert np.allclose(np.sort(np.unique(steps.round(12))), np.unique(case.spacing))
    assert shoelace(polygon) == pytest.approx(W * H, rel=1e-14)


# -- the undeformed specimen ---------------------------------------------------------------
@pytest.mark.parametrize("nx, ny, layout", [(7, 9, "grid+centres"), (5, 4, "grid")])
def test_weights_sum_to_the_area(nx, ny, layout):
    for q in both(specimen(nx, ny, layout)):
        assert q.weights.sum() == pytest.approx(W * H, rel=1e-12)
        assert np.all(q.weights > 0)


@pytest.mark.parametrize("nx, ny, layout", [(7, 9, "grid+centres"), (5, 4, "grid")])
def test_each_point_lies_in_its_cell_and_each_cell_holds_its_area(nx, ny, layout):
    for q in both(specimen(nx, ny, layout)):
        for c in np.unique(q.cell):
            mine = q.cell == c
            assert Path(q.cells[c]).contains_points(q.points[mine]).all()
            assert q.weights[mine].sum() == pytest.approx(shoelace(q.cells[c]), rel=1e-12)
        assert set(q.cell) == set(range(len(q.cells)))


@pytest.mark.parametrize("nx, ny, layout", [(7, 9, "grid+centres"), (5, 4, "grid")])
def test_quarter_cells_form_the_ring_along_the_boundary(nx, ny, layout):
    case = specimen(nx, ny, layout)
    q, _ = both(case)
    hx, hy = case.spacing
    size = np.ptp(q.cells, axis=1)
    full = np.all(np.isclose(size, [hx, hy]), axis=1)
    quarter = np.all(np.isclose(size, [hx / 2, hy / 2]), axis=1)
    assert np.all(full | quarter)
    n_cells, n_inner = (nx - 1) * (ny - 1), (nx - 3) * (ny - 3)
    assert full.sum() == n_inner and quarter.sum() == 4 * (n_cells - n_inner)
    assert len(q.points) == 4 * len(q.cells)  # 2 x 2 Gauss points in every cell
    parent = np.floor(q.cells.min(1) / case.spacing + 1e-9).astype(int)
    ring = ((parent == 0) | (parent == [nx - 2, ny - 2])).any(1)
    np.testing.assert_array_equal(ring, quarter)


def test_the_paper_specimen_counts():
    """111 nodes: 24 full + 96 quarter cells (480 points); 192 triangles (576 points)."""
    case = specimen()
    squares, triangles = both(case)
    assert len(case.nodes()) == 111
    assert (len(squares.cells), len(squares.points)) == (120, 480)
    n, k = len(case.nodes()), len(case.boundary_loop())
    assert len(triangles.cells) == 2 * n - 2 - k == 192
    assert len(triangles.points) == 3 * 192


@pytest.mark.parametrize("px, py", [(0, 0), (1, 0), (0, 1), (2, 1), (3, 0), (2, 3), (3, 3)])
def test_squares_2x2_integrate_bicubics_exactly(px, py):
    q, _ = both(specimen())
    exact = W ** (px + 1) / (px + 1) * H ** (py + 1) / (py + 1)
    x, y = q.points.T
    assert q.weights @ (x ** px * y ** py) == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("px, py", [(2, 1), (4, 5), (5, 5)])
def test_squares_3x3_integrate_degree_5_exactly(px, py):
    case = specimen(5, 4, "grid")
    nodes = case.nodes()
    q = square_cells(nodes[case.boundary_loop()], case.spacing, order=3)
    exact = W ** (px + 1) / (px + 1) * H ** (py + 1) / (py + 1)
    x, y = q.points.T
    assert len(q.points) == 9 * len(q.cells)
    assert q.weights @ (x ** px * y ** py) == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("order, powers", [(1, [(1, 0), (0, 1)]),
                                           (2, [(2, 0), (1, 1), (0, 2)]),
                                           (3, [(2, 1), (3, 0), (0, 3)]),
                                           (4, [(2, 2), (4, 0), (1, 3)])])
def test_triangles_integrate_their_degree_exactly(order, powers):
    case = specimen()
    nodes = case.nodes()
    q = delaunay_cells(nodes, nodes[case.boundary_loop()], order=order)
    x, y = q.points.T
    for px, py in powers:
        exact = W ** (px + 1) / (px + 1) * H ** (py + 1) / (py + 1)
        assert q.weights @ (x ** px * y ** py) == pytest.approx(exact, rel=1e-12)


def test_the_triangle_rule_has_the_degree_asked_for():
    """On one triangle x^3 (integral 1/20) is exact with degree 3, not with degree 2."""
    corners = [[0, 0], [1, 0], [0, 1]]
    rules = delaunay_cells(corners, corners), delaunay_cells(corners, corners, order=3)
    cubic = [q.weights @ q.points[:, 0] ** 3 for q in rules]
    assert abs(cubic[0] - 1 / 20) > 1e-4 and cubic[1] == pytest.approx(1 / 20, rel=1e-12)


# -- deformed configurations ---------------------------------------------------------------
DEFORMED = {"bulge": lambda n: barrel(n, 0.1), "waist": lambda n: barrel(n, -0.1),
            "stretch": stretch}


@pytest.mark.parametrize("deform", DEFORMED)
@pytest.mark.parametrize("layout", ["grid+centres", "grid"])
def test_delaunay_tiles_the_deformed_polygon(deform, layout):
    case = specimen(7, 9, layout)
    nodes = DEFORMED[deform](case.nodes())
    boundary = nodes[case.boundary_loop()]
    q = delaunay_cells(nodes, boundary)
    assert q.weights.sum() == pytest.approx(shoelace(boundary), rel=1e-12)
    assert outside(q, boundary) == 0
    np.testing.assert_array_equal(q.cells, nodes[q.triangles])
    edges = q.cells[:, 1:] - q.cells[:, :1]
    assert np.all(edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0] > 0)
    n, k = len(nodes), len(boundary)
    assert len(q.triangles) == 2 * n - 2 - k  # every node a vertex, boundary edges kept


def test_delaunay_drops_the_triangles_of_a_concave_side():
    case = specimen()
    nodes = barrel(case.nodes(), -0.1)
    q = delaunay_cells(nodes, nodes[case.boundary_loop()])
    assert Delaunay(nodes).nsimplex > len(q.triangles) == 192


@pytest.mark.parametrize("deform", DEFORMED)
def test_square_cells_converge_to_the_deformed_area(deform):
    """|sum w - A| <= 0.1 P h_max: the area of a band a tenth of a cell wide along the
    boundary of length P, so it shrinks with the cells (measured: 0.07 to 0.37 of it; the
    error is O(h) with a constant that depends on where the boundary cuts the quarter
    cells, hence not monotonic)."""
    errors = []
    for n in (1, 2, 4, 8):
        case = specimen(6 * n + 1, 8 * n + 1)
        nodes = DEFORMED[deform](case.nodes())
        boundary = nodes[case.boundary_loop()]
        q = square_cells(boundary, case.spacing)
        perimeter = np.linalg.norm(np.roll(boundary, -1, 0) - boundary, axis=1).sum()
        errors.append(abs(q.weights.sum() - shoelace(boundary)))
        assert errors[-1] <= 0.1 * perimeter * max(case.spacing)
        assert outside(q, boundary) == 0
    assert errors[-1] < errors[0] / 2


def test_square_cells_cover_the_cells_of_a_stretched_specimen():
    """Cells keep the initial spacing on the origin grid and extend past the initial box."""
    case = specimen()
    nodes = stretch(case.nodes())
    q, _ = both(case, nodes)
    assert np.allclose(np.ptp(q.cells, axis=1).max(0), case.spacing)
    assert q.cells[..., 0].max() > 1.1 * W - case.spacing[0] / 2 > W
    on_grid = q.cells / np.asarray(case.spacing) * 2
    assert np.allclose(on_grid, on_grid.round())


def test_only_cells_the_boundary_meets_are_quartered():
    """Right triangle x + y <= 7.9, unit cells: the hypotenuse meets the cells with
    i + j = 6 or 7 (not every cell of its bounding box), so the 10 cells i, j >= 1,
    i + j <= 5 stay full."""
    triangle = np.array([[0, 0], [7.9, 0], [0, 7.9]])
    q = square_cells(triangle, (1.0, 1.0))
    full = np.isclose(np.ptp(q.cells, axis=1), 1).all(1)
    i, j = q.cells[full].min(1).T
    assert full.sum() == 10 and np.all((i >= 1) & (j >= 1) & (i + j <= 5))
    assert outside(q, triangle) == 0
    assert abs(q.weights.sum() - shoelace(triangle)) <= 0.1 * (2 + np.sqrt(2)) * 7.9


def test_a_slot_between_cell_corners_is_not_integrated():
    """A slot crossing a cell whose four corners are all inside: the cell is quartered and
    the points in the slot dropped (a corner test alone would keep the cell whole)."""
    slot = np.array([[0, 0], [4, 0], [4, 4], [1.8, 4], [1.8, 1.5], [1.2, 1.5], [1.2, 4],
                     [0, 4]])
    q = square_cells(slot, (1.0, 1.0))
    assert outside(q, slot) == 0
    full = np.isclose(np.ptp(q.cells, axis=1), 1).all(1)
    assert not np.any(full & np.isclose(q.cells.min(1), [1, 2]).all(1))
    perimeter = np.linalg.norm(np.roll(slot, -1, 0) - slot, axis=1).sum()
    assert abs(q.weights.sum() - shoelace(slot)) <= 0.1 * perimeter * 1.0


# -- bad input -----------------------------------------------------------------------------
SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]


@pytest.mark.parametrize("call, name", [
    (lambda: square_cells(SQUARE, (0.5, 0.5), order=0), "order"),
    (lambda: square_cells(SQUARE, (0.5, 0.5), order=1.5), "order"),
    (lambda: square_cells(SQUARE[:2], (0.5, 0.5)), "boundary"),
    (lambda: square_cells(SQUARE, (0.0, 0.5)), "spacing"),
    (lambda: square_cells(SQUARE, 0.5), "spacing"),
    (lambda: delaunay_cells(SQUARE, SQUARE, order=0), "order"),
    (lambda: delaunay_cells(SQUARE[:2], SQUARE), "nodes"),
    (lambda: delaunay_cells(SQUARE, SQUARE[:2]), "boundary"),
])
def test_bad_input_names_the_parameter(call, name):
    with pytest.raises(InputError, match=name) as err:
        call()
    assert "\n" not in str(err.value)
