"""MLS weights and shape functions: consistency, derivatives, supports and safeguards."""

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from soilwater.efg.mls import RCOND_MIN, ShapeFunctions
from soilwater.efg.mls_supports import neighbours, support_radii
from soilwater.efg.weights import evaluate
from soilwater.efg.settings import Weight
from soilwater.errors import InputError
from soilwater.case.loader import load_case

WEIGHTS = ("quartic", "cubic", "exp:0.5", "exp:0.25")


def grid(n, size=1.0, origin=(0.0, 0.0)):
    """``n x n`` square grid of nodes over ``[0, size]^2`` shifted by ``origin``."""
    x = np.linspace(0.0, size, n)
    return np.stack(np.meshgrid(x, x), axis=-1).reshape(-1, 2) + origin


def gauss_points(x, y, order):
    """Tensor Gauss points of the cells of the grid lines ``x`` and ``y``."""
    g = (np.polynomial.legendre.leggauss(order)[0] + 1) / 2
    gx = (x[:-1, None] + np.diff(x)[:, None] * g).ravel()
    gy = (y[:-1, None] + np.diff(y)[:, None] * g).ravel()
    return np.stack(np.meshgrid(gx, gy), axis=-1).reshape(-1, 2)


def specimen_gauss_points(order):
    """The 111-node unconfined-compression specimen and Gauss points of its square cells."""
    case = load_case("unconfined-compression")
    (w, h), (nx, ny) = (case.geometry.width, case.geometry.height), (
        case.discretisation.nx, case.discretisation.ny)
    return case.nodes(), gauss_points(np.linspace(0, w, nx), np.linspace(0, h, ny), order)


@st.composite
def layouts(draw):
    """Jittered grid (optionally with cell centres), random points, scale; spacing h."""
    n = draw(st.integers(6, 12))
    size = draw(st.floats(0.5, 20.0))
    origin = np.array([draw(st.floats(-100.0, 100.0)), draw(st.floats(-100.0, 100.0))])
    h = size / (n - 1)
    nodes = grid(n, size)
    if draw(st.booleans()):
        nodes = np.concatenate([nodes, grid(n - 1, size - h) + h / 2])
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    jitter = draw(st.floats(0.0, 0.3)) * h
    nodes = nodes + rng.uniform(-jitter, jitter, nodes.shape)
    points = rng.uniform(0.0, size, (25, 2))
    return nodes + origin, points + origin, origin, h, draw(st.floats(1.3, 1.6))


# -- weights -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", WEIGHTS)
def test_weight_is_one_at_zero_and_vanishes_beyond_one(name):
    w, dw = evaluate(Weight.parse(name), np.array([0.0, 1.0, 1.5]))
    top = 2 / 3 if name == "cubic" else 1.0
    np.testing.assert_allclose(w, [top, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(dw[[0, 2]], 0.0, atol=0)


@pytest.mark.parametrize("name", WEIGHTS)
def test_weight_derivative_matches_finite_differences(name):
    weight, r, eps = Weight.parse(name), np.linspace(0.01, 0.99, 97), 1e-6
    fd = (evaluate(weight, r + eps)[0] - evaluate(weight, r - eps)[0]) / (2 * eps)
    np.testing.assert_allclose(evaluate(weight, r)[1], fd, atol=1e-8)


def test_weight_names_and_aliases():
    assert Weight.parse("Q") == Weight.parse("quartic")
    assert Weight.parse("E-A") == Weight.parse("exp:0.5")
    assert Weight.parse(" e-b ").name == "exp:0.25"
    assert str(Weight.parse("exp:0.3")) == "exp:0.3"
    for bad in ("gauss", "exp:", "exp:0", "exp:-1", "exp:abc"):
        with pytest.raises(InputError, match="quartic .*cubic.*exp:C"):
            Weight.parse(bad)


# -- consistency (hypothesis) --------------------------------------------------------------
@pytest.mark.parametrize("name", WEIGHTS)
@settings(max_examples=40, deadline=None)
@given(layout=layouts())
def test_partition_of_unity_and_linear_reproduction(name, layout):
    nodes, points, origin, h, scale = layout
    sf = ShapeFunctions.build(nodes, points, name, scale)
    local_nodes, local_points = nodes - origin, points - origin
    np.testing.assert_allclose(sf.phi.sum(axis=1), 1.0, atol=1e-10)
    np.testing.assert_allclose(sf.phi @ local_nodes, local_points, atol=1e-10 * h)
    for k, dphi in enumerate((sf.dphi_dx, sf.dphi_dy)):
        np.testing.assert_allclose(h * dphi.sum(axis=1), 0.0, atol=1e-10)
        expected = np.zeros_like(points)
        expected[:, k] = 1.0
        np.testing.assert_allclose(dphi @ local_nodes, expected, atol=1e-10)


# -- properties on fixed layouts -----------------------------------------------------------
def test_pattern_is_shared_sorted_and_matches_supports():
    nodes = grid(8, 3.5)
    points = np.random.default_rng(0).uniform(0, 3.5, (60, 2))
    sf = ShapeFunctions.build(nodes, points, "E-A", 1.4)
    for m in (sf.dphi_dx, sf.dphi_dy):
        assert np.shares_memory(m.indptr, sf.indptr) and np.shares_memory(m.indices,
                                                                         sf.indices)
    assert sf.phi.shape == (60, 64) and sf.phi.has_sorted_indices
    h = 3.5 / 7
    np.testing.assert_allclose(sf.support[9], 1.4 * np.sqrt(2) * h)
    rows = np.repeat(np.arange(60), np.diff(sf.indptr))
    distance = np.linalg.norm(points[rows] - nodes[sf.indices], axis=1)
    assert np.all(distance < sf.support[sf.indices])
    all_pairs = np.linalg.norm(points[:, None] - nodes[None], axis=2) < sf.support
    assert all_pairs.sum() == sf.phi.nnz


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 80), st.floats(0.01, 3.0))
def test_neighbour_search_equals_brute_force(seed, n, spread):
    """Clustered nodes with radii over two decades, points also outside the nodes' box:
    the cell list finds exactly the pairs ``|x_p - x_J| < d_J``, rows sorted."""
    rng = np.random.default_rng(seed)
    nodes = rng.normal(0, 1, (n, 2)) * rng.uniform(0.01, 1, (n, 1))
    support = spread * 10 ** rng.uniform(-2, 0, n)
    points = rng.uniform(-2, 2, (50, 2))
    indptr, indices = neighbours(nodes, points, support)
    inside = np.linalg.norm(points[:, None] - nodes[None], axis=2) < support
    np.testing.assert_array_equal(indptr, np.concatenate([[0], np.cumsum(inside.sum(1))]))
    np.testing.assert_array_equal(indices, np.nonzero(inside)[1])


def test_exponential_b_is_nearly_interpolating():
    nodes = grid(11)
    off_boundary = np.all((nodes > 0) & (nodes < 1), axis=1)
    values = {}
    for name in ("Q", "cubic", "E-A", "E-B"):
        own = ShapeFunctions.build(nodes, nodes, name, 1.3).phi.diagonal()[off_boundary]
        values[name] = own
        print(f"phi_I(x_I), scale 1.3, 11 x 11 grid, off-boundary nodes: {name}: "
              f"min {own.min():.4f} mean {own.mean():.4f} max {own.max():.4f}")
    assert values["E-B"].min() > 0.9
    assert values["Q"].max() < 0.5 and values["E-A"].max() < 0.5


@pytest.mark.parametrize("name", WEIGHTS)
def test_derivatives_match_central_differences(name):
    rng = np.random.default_rng(7)
    h = 0.4
    nodes = grid(8, 7 * h) + rng.uniform(-0.25 * h, 0.25 * h, (64, 2))
    points = rng.uniform(0.0, 7 * h, (40, 2))
    support = support_radii(nodes, 1.4)
    # the exponential weight has a kink at r = 1: keep the stencil off every support rim
    rim = np.abs(np.linalg.norm(points[:, None] - nodes[None], axis=2) - support)
    points = points[rim.min(axis=1) > 1e-4 * h]
    eps = 1e-6 * h
    sf = ShapeFunctions.build(nodes, points, name, 1.4)
    for k, dphi in enumerate((sf.dphi_dx, sf.dphi_dy)):
        step = np.zeros(2)
        step[k] = eps
        plus = ShapeFunctions.build(nodes, points + step, name, 1.4).phi.toarray()
        minus = ShapeFunctions.build(nodes, points - step, name, 1.4).phi.toarray()
        exact = dphi.toarray()
        scale = np.abs(exact).max(axis=1, keepdims=True)
        assert np.all(np.abs((plus - minus) / (2 * eps) - exact) <= 1e-6 * scale)


def test_batched_equals_point_by_point():
    rng = np.random.default_rng(3)
    nodes = grid(9, 2.0) + rng.uniform(-0.05, 0.05, (81, 2))
    points = rng.uniform(0.0, 2.0, (50, 2))
    batch = ShapeFunctions.build(nodes, points, "exp:0.25", 1.5)
    for p in (0, 17, 49):
        alone = ShapeFunctions.build(nodes, points[[p]], "exp:0.25", 1.5)
        for name in ("phi", "dphi_dx", "dphi_dy"):
            np.testing.assert_allclose(getattr(alone, name).toarray()[0],
                                       getattr(batch, name)[[p]].toarray()[0],
                                       rtol=1e-13, atol=1e-13)


# -- safeguards ----------------------------------------------------------------------------
def test_small_scale_fails_naming_the_point_and_the_fix():
    nodes, points = specimen_gauss_points(3)
    assert ShapeFunctions.build(nodes, points, "Q", 0.8).rcond.min() > 1e-4
    with pytest.raises(InputError) as err:
        ShapeFunctions.build(nodes, points, "Q", 0.7)
    message = str(err.value)
    found = re.search(r"point (\d+) at \(([-\d.e]+), ([-\d.e]+)\) sees only (\d) node",
                      message)
    assert found, message
    index = int(found.group(1))
    np.testing.assert_allclose([float(found.group(2)), float(found.group(3))],
                               points[index], rtol=1e-5)
    assert "weight quartic, scale factor 0.7" in message
    assert message.endswith("increase the scale factor, e.g. to 1.3")


def test_collinear_and_ill_conditioned_points_fail():
    line = np.column_stack([np.arange(12.0), np.zeros(12)])
    with pytest.raises(InputError, match=r"point 0 at \(4\.5, 0\) sees \d+ nodes, all on "
                                         "one line.*or add nodes off that line$"):
        ShapeFunctions.build(line, [[4.5, 0.0]])
    almost = np.concatenate([line, [[4.5, 1e-8]]])
    with pytest.raises(InputError, match="ill-conditioned moment matrix .*"
                                         f"< {RCOND_MIN:g}"):
        ShapeFunctions.build(almost, [[4.5, 0.0]])


@pytest.mark.parametrize("nodes, points, weight, scale, match", [
    (grid(3)[:8], [[0.5, 0.5]], "Q", 1.3, "at least 9 nodes"),
    (grid(4), [[0.5, 0.5, 0.0]], "Q", 1.3, r"points must have shape \(n, 2\)"),
    (grid(4), [[np.nan, 0.5]], "Q", 1.3, "NaN"),
    (grid(4), [[0.5, 0.5]], "gauss", 1.3, "weight 'gauss' is unknown"),
    (grid(4), [[0.5, 0.5]], "Q", 0.0, "scale factor = 0.0 must be positive"),
    (np.zeros((10, 2)), [[0.5, 0.5]], "Q", 1.3, "remove duplicate nodes"),
])
def test_bad_input_is_an_input_error(nodes, points, weight, scale, match):
    with pytest.raises(InputError, match=match):
        ShapeFunctions.build(nodes, points, weight, scale)
