"""Re-meshing of the FEM reference (``fem.remesh = "delaunay"``).

A mesh that needs no re-meshing is left alone; the transfer of the quadrature state is
exact for linear fields inside the body, keeps integrals and ranges; an elastic body
re-meshed after every step stays on the fixed mesh's answer (exactly when the answer is
homogeneous, within the mesh's own discretisation error otherwise); the admissibility fix
puts a stress outside Cam-clay's surface on it; a small strip footing re-meshes on its
way to 0.2 B with its quality restored above the threshold each time.
"""

import numpy as np
import pandas as pd
import pytest

from soilwater.fem.assembly import Shapes
from soilwater.fem.model import Model, Topology
from soilwater.fem.remesh import remesh as _remesh
from soilwater.fem.solver import _initial_state
from soilwater.fem.solver import solve as fem_solve
from soilwater.fem.spaces import Space, cell_bases
from soilwater.fem.transfer import project, transfer
from soilwater.nonlinear.history import TIMERS
from soilwater.errors import ConvergenceError, InputError
from soilwater.material.kinematics import invariants
from soilwater.case.loader import load_case
from soilwater.geometry.triangulation import delaunay_triangles
from soilwater.case.validation import case_from_dict

FOOTING = "strip-footing"
#: The footing on a 5 B x 5 B regular grid of 11 x 11 nodes (spacing B/2).
SMALL = ("geometry.width=5", "geometry.height=5", "discretisation.nx=11",
         "discretisation.ny=11")
REMESH = ("fem.remesh=delaunay",)
EVERY_STEP = (*REMESH, "fem.remesh_quality=1")   # every mesh is below 1: re-triangulate


def _run(case, method, overrides, elastic=False):
    """Solve a built-in case with overrides; ``elastic``: the linear elastic skeleton with
    the Cam-clay preset's initial moduli (``material.model = "elastic"``)."""
    case = load_case(case, overrides)
    if elastic:
        from soilwater.material.presets import FLUID_KEYS

        data = case.to_dict()
        fluid = {k: v for k, v in data["material"].items() if k in FLUID_KEYS}
        data["material"] = {"preset": "table1", "model": "elastic", **fluid}
        case = case_from_dict(data)
    return fem_solve(case, method, progress=False)


def _remeshed_pair(overrides=("discretisation.jitter=0.2",)):
    """A jittered 11 x 11 footing grid's initial space (structured diagonals) and the
    space of the Delaunay triangles of the same nodes, with their P1 bases."""
    case = load_case(FOOTING, (*SMALL, *overrides))
    space = Space.build(case, "fem-p1p1")
    nodes = case.nodes()
    triangles, _ = delaunay_triangles(nodes, nodes[case.boundary_loop()])
    new = space.remeshed(case, nodes, triangles)
    return case, space, new, cell_bases(space.mesh0, space.pair)[1], \
        cell_bases(new.moved(nodes), new.pair)[1]


def _points(basis):
    """Quadrature points (E Q, 2) of a basis [m], element-major."""
    x = basis.mapping.F(basis.X)
    return np.stack([x[0].ravel(), x[1].ravel()], axis=1)


# -- nothing to do ----------------------------------------------------------------------
def test_a_footing_whose_quality_stays_above_the_threshold_is_not_touched():
    """11 x 11 footing to 0.1 B: the worst element stays near 0.8, above the default 0.3,
    so the re-meshing run is the fixed-mesh run, value for value."""
    steps = ("time.end=10", "time.steps=20")
    fixed = _run(FOOTING, "fem-p1p1-stab", (*SMALL, *steps))
    option = _run(FOOTING, "fem-p1p1-stab", (*SMALL, *steps, *REMESH))
    assert option.summary["remeshes"] == 0 and option.summary["remesh_refused"] == 0
    assert fixed.history.min_quality.min() > 0.3
    pd.testing.assert_frame_equal(option.history[fixed.history.columns], fixed.history,
                                  check_exact=True)


def test_a_delaunay_mesh_asked_to_re_mesh_is_returned_as_it_is():
    """A grid + centres mesh of jittered nodes is the Delaunay triangulation of its
    nodes (unique: no four nodes on a circle): asked to re-mesh (threshold 1, above its
    quality), the state comes back untouched, not a transfer onto the same triangles."""
    case = load_case("unconfined-compression", ("discretisation.jitter=0.2", *EVERY_STEP))
    model = Model.build(case, "fem-p1p1")
    state = _initial_state(model)
    assert _remesh(model, state, 0.0, dict.fromkeys(TIMERS, 0.0)) is state


# -- the transfer -----------------------------------------------------------------------
def test_the_projection_reproduces_a_linear_field_and_keeps_integrals():
    """The L2 projection onto the vertex basis is exact for a linear field at every
    vertex, and keeps the integral of any field (the basis sums to one)."""
    case, space, _, old, _ = _remeshed_pair()
    x = _points(old)
    linear = np.column_stack([2.0 - 3.0 * x[:, 0] + 0.5 * x[:, 1], x[:, 1]])
    vertices = project(Shapes.of(old), old.dx, linear)
    p = space.mesh0.p
    np.testing.assert_allclose(vertices, np.column_stack([2.0 - 3.0 * p[0] + 0.5 * p[1],
                                                          p[1]]), rtol=0, atol=1e-11)
    wavy = np.sin(3 * x[:, :1]) * np.exp(x[:, 1:] / 5)
    shapes = Shapes.of(old)
    ones = np.zeros(old.dx.shape + (1, 3))
    ones[..., 0, 0] = old.dx
    lumped = shapes.vector(ones)                                # int N_i [m2]
    integral = lumped @ project(shapes, old.dx, wavy)[:, 0]
    assert integral == pytest.approx((old.dx.ravel() * wavy[:, 0]).sum(), rel=1e-12)


def test_the_transfer_is_exact_for_a_linear_field_inside_and_within_range_at_the_edge():
    """Grid mesh to the Delaunay mesh of the same jittered nodes: a linear field arrives
    exactly at the points of every new element with no boundary vertex (the limiter is
    inactive where a vertex lies inside its neighbourhood's points); at boundary
    vertices it is capped, so every carried value stays within the old range; constants
    are exact everywhere and the area is the same."""
    case, _, new, old, new_basis = _remeshed_pair()
    x_old, x_new = _points(old), _points(new_basis)
    field = lambda x: np.column_stack([-3.0 + 0.4 * x[:, 0] - 0.2 * x[:, 1],   # noqa: E731
                                       np.full(len(x), 1.83)])
    carried = transfer(old, new_basis, field(x_old))
    boundary = np.zeros(len(case.nodes()), bool)
    boundary[case.boundary_loop()] = True
    inner = ~boundary[new.mesh0.t].any(axis=0)                  # new elements, (E,)
    inner = np.repeat(inner, new_basis.dx.shape[1])
    assert inner.sum() > len(inner) / 2
    np.testing.assert_allclose(carried[inner, 0], field(x_new)[inner, 0], rtol=0,
                               atol=1e-11)
    np.testing.assert_allclose(carried[:, 1], 1.83, rtol=1e-14)
    assert field(x_old)[:, 0].min() - 1e-12 <= carried[:, 0].min()
    assert carried[:, 0].max() <= field(x_old)[:, 0].max() + 1e-12
    assert new_basis.dx.sum() == pytest.approx(old.dx.sum(), rel=1e-12)


def test_probes_are_material_points_across_a_re_meshing():
    """A probe's position (its element's interpolation of the vertices) is the same
    before and after the topology changes."""
    case = load_case(FOOTING, (*SMALL, "discretisation.jitter=0.2",
                               "probes.below=[0.3, 4.1]", "probes.corner=[5.0, 5.0]"))
    space = Space.build(case, "fem-p1p1")
    nodes = case.nodes() * [1.02, 0.97]
    triangles, _ = delaunay_triangles(nodes, nodes[case.boundary_loop()])
    before = Topology.initial(case, space)
    after = before.remeshed(case, nodes, triangles)
    np.testing.assert_allclose(after.probes @ nodes, before.probes @ nodes, atol=1e-12)
    np.testing.assert_allclose(after.probes @ nodes, [[0.306, 3.977], [5.1, 4.85]],
                               atol=1e-12)


# -- whole runs -------------------------------------------------------------------------
def test_homogeneous_elastic_compression_re_meshed_every_step_is_the_fixed_mesh_run():
    """Elastic, undrained, frictionless compression of a jittered grid (the stabilised
    pair, whose pore pressure is unique): P1 holds the homogeneous solution on any
    triangulation and the transfer carries constants exactly, so re-meshing (the
    structured diagonals become Delaunay triangles, which change again as the specimen
    shortens) leaves p, q and the pore pressures at the fixed mesh's values to within
    the Newton tolerance (1e-8 of the stress scale; compared at 1e-6)."""
    common = ("discretisation.layout=grid", "discretisation.jitter=0.2", "time.end=10",
              "time.steps=10")
    fixed = _run("unconfined-compression", "fem-p1p1-stab", common, elastic=True)
    option = _run("unconfined-compression", "fem-p1p1-stab", (*common, *EVERY_STEP),
                  elastic=True)
    assert option.summary["remeshes"] >= 2
    for column in ("p", "q", "p_w@centre", "p_w@corner", "eps_a"):
        np.testing.assert_allclose(option.history[column], fixed.history[column],
                                   rtol=1e-6, atol=1e-6 * 3.0)


@pytest.mark.parametrize("method", ["fem-p1p1-stab", "fem-th"])
def test_an_elastic_footing_re_meshed_every_step_adds_no_error_beyond_the_mesh_own(method):
    """An elastic footing (the clay's initial moduli), 11 x 11 nodes, to 0.1 B,
    re-triangulated after every step (the grid's structured diagonals become Delaunay
    triangles, which keep changing as the surface deforms): its contact pressure is at
    least as close to the 21 x 21 grid's as the fixed mesh's is. The re-meshed run is
    another mesh of the same nodes, so the fixed mesh's own discretisation error is the
    scale a transfer may not exceed."""
    common = ("time.end=10", "time.steps=10")
    fixed = _run(FOOTING, method, (*SMALL, *common), elastic=True)
    finer = _run(FOOTING, method, (*SMALL[:2], "discretisation.nx=21",
                                   "discretisation.ny=21", *common), elastic=True)
    option = _run(FOOTING, method, (*SMALL, *common, *EVERY_STEP), elastic=True)
    assert option.summary["remeshes"] >= 3
    pressure = finer.history["pressure@footing"]
    after = option.history.remeshes.to_numpy() > 0
    assert after.sum() >= 8
    assert np.all(np.abs(option.history["pressure@footing"] - pressure)[after]
                  <= np.abs(fixed.history["pressure@footing"] - pressure)[after])


@pytest.mark.parametrize("method", ["fem-p1p1-stab", "fem-th"])
def test_a_small_footing_re_meshes_to_02B_and_each_re_meshing_restores_the_quality(method):
    """11 x 11 footing, Cam-clay, to 0.2 B with a threshold of 0.8 (the undeformed
    grid's triangles are 0.866; the fixed mesh falls below 0.8 near 0.1 B): at every
    level that re-meshed the new mesh's worst element is above the threshold, the
    imbalance of the carried stress is recorded, and the run gets there."""
    result = _run(FOOTING, method, (*SMALL, "time.end=20", "time.steps=40", *REMESH,
                                    "fem.remesh_quality=0.8"))
    h = result.history
    grew = np.diff(np.r_[0, h.remeshes]) > 0
    assert h["settlement@footing"].iloc[-1] == pytest.approx(0.2)
    assert result.summary["remeshes"] == h.remeshes.iloc[-1] >= 1
    assert (h.min_quality[grew] > 0.8).all()
    assert (h.remesh_residual[grew] > 0).all() and np.isfinite(h.remesh_residual).all()


# -- the admissibility fix and refusals -------------------------------------------------
@pytest.mark.parametrize("model", ["original", "modified"])
def test_the_fix_puts_a_stress_outside_the_yield_surface_on_it(model):
    """Stresses of every kind (p' 0.3 to 3, q up to 2 M p', any direction) with p'c = 3:
    those outside the surface end on it (|f| at round-off), those inside keep their p'c."""
    clay = load_case(FOOTING, (f"material.model={model}",)).material()
    rng = np.random.default_rng(1)
    p = rng.uniform(0.3, 3.0, 200)
    s = rng.normal(size=(200, 4)) * [1, 1, 1, 0.5]
    s[:, :3] -= s[:, :3].mean(axis=1, keepdims=True)
    ratio = rng.uniform(0, 2, 200) * clay.M * p / invariants(s)[1]
    stress = -p[:, None] * [1, 1, 1, 0] + s * ratio[:, None]
    state = {"pc": np.full(200, 3.0), "v": np.full(200, 1.83)}
    outside = clay.yield_value(stress, state) > 0
    assert 20 < outside.sum() < 180
    fixed = clay.admissible(stress, state)
    f = clay.yield_value(stress, fixed)
    assert np.abs(f[outside]).max() < 1e-12
    assert np.array_equal(fixed["pc"][~outside], state["pc"][~outside])
    assert (f <= 1e-12).all() and fixed["v"] is state["v"]
    with pytest.raises(ConvergenceError, match="p'"):
        clay.admissible(-stress, state)


def test_elastic_states_are_always_admissible():
    elastic = load_case("soil-column", ("material.model=elastic",)).material()
    state = {"v": np.ones(3)}
    assert elastic.admissible(np.ones((3, 4)), state) is state


@pytest.mark.parametrize("override, word", [
    ("fem.remesh=always", "fem.remesh"),
    ("fem.remesh_quality=0", "fem.remesh_quality"),
    ("fem.remesh_quality=1.5", "fem.remesh_quality"),
    ("fem.quality=0.3", "fem: unknown key"),
])
def test_bad_settings_are_refused_naming_the_key(override, word):
    with pytest.raises(InputError, match=word):
        load_case(FOOTING, (override,))


def test_quadrilaterals_cannot_be_re_triangulated():
    with pytest.raises(InputError, match="fem.remesh"):
        _run(FOOTING, "fem-q1q1", (*SMALL, *REMESH))
