"""Return mapping of finite-strain Cam-clay: accuracy, consistency, objectivity, bounds."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import table1
from soilwater.material.driver import run_test
from soilwater.errors import InputError
from soilwater.material.kinematics import invariants, rotate, rotate_strain
from soilwater.material.presets import material_from_spec

MODELS = [("original", 1.0), ("modified", 1.0), ("modified", 2.0)]


def march(clay, dstrain, dspin, steps, state=None):
    """Apply the same increment ``steps`` times to one point; return (p, q) per step."""
    stress, st_ = state or clay.initial_state(1)
    out = [invariants(stress)]
    for _ in range(steps):
        stress, st_, _ = clay.update(stress, st_, np.array([dstrain]), np.array([dspin]))
        out.append(invariants(stress))
    p, q = np.array(out)[:, :, 0].T
    return p, q, stress, st_


@pytest.mark.parametrize("model,ocr", MODELS)
@pytest.mark.parametrize("test,strain,dstrain,dspin", [
    ("undrained-plane-strain", 0.2, (0.004, -0.004, 0.0, 0.0), 0.0),
    ("undrained-simple-shear", 0.3, (0.0, 0.0, 0.0, 0.006), 0.003),
])
def test_return_mapping_path_follows_driver(model, ocr, test, strain, dstrain, dspin):
    """50 steps: every (p', q) point lies within 1e-3 p'0 of the driver's path (distance
    to the polyline in the stress plane, so a vertical path needs no special case), and
    both end at the same q."""
    clay = table1(model, ocr)
    p, q, *_ = march(clay, dstrain, dspin, 50)
    ref = run_test(clay, test, strain, points=4000)
    gap = distance_to_polyline(np.column_stack([p, q]), ref[["p", "q"]].to_numpy())
    assert gap.max() / clay.p0 < 1e-3
    assert abs(q[-1] - ref.q.iloc[-1]) / clay.p0 < 1e-3


def distance_to_polyline(points, line):
    """Distance of each point (N, 2) to the polyline through ``line`` (K, 2)."""
    a, b = line[:-1], line[1:]
    ab = b - a
    t = np.einsum("nkd,kd->nk", points[:, None] - a, ab) / np.maximum(
        np.einsum("kd,kd->k", ab, ab), np.finfo(float).tiny)
    foot = a + np.clip(t, 0, 1)[..., None] * ab
    return np.linalg.norm(points[:, None] - foot, axis=-1).min(axis=1)


def test_return_mapping_converges_first_order_at_equal_strain():
    """At equal axial strain the error halves with the step (backward Euler)."""
    clay = table1()
    errors = []
    for n in (50, 100):
        p, q, *_ = march(clay, (0.2 / n, -0.2 / n, 0, 0), 0.0, n)
        ref = run_test(clay, "undrained-plane-strain", 0.2, points=n)
        errors.append(np.hypot(p - ref.p, q - ref.q).max() / clay.p0)
    assert errors[0] < 0.015
    assert 1.8 < errors[0] / errors[1] < 2.2


@pytest.mark.parametrize("model,ocr", MODELS)
@pytest.mark.parametrize("dstrain,dspin", [
    ((0.001, -0.0015, 0.0002, 0.0013), 0.0),   # plastic loading
    ((-0.002, -0.001, 0.0, 0.0004), 0.01),     # compression with spin
    ((0.0005, 0.0004, 0.0003, 0.0), 0.0),      # unloading: elastic
])
def test_consistent_tangent_matches_finite_differences(model, ocr, dstrain, dspin):
    clay = table1(model, ocr)
    *_, stress, state = march(clay, (0.003, -0.003, 0, 0.001), 0.0, 5)
    d = np.array([dstrain])
    w = np.array([dspin])
    _, _, tangent = clay.update(stress, state, d, w)
    h = 1e-7
    fd = np.empty((4, 4))
    for j in range(4):
        e = np.zeros((1, 4))
        e[0, j] = h
        fd[:, j] = (clay.update(stress, state, d + e, w)[0][0]
                    - clay.update(stress, state, d - e, w)[0][0]) / (2 * h)
    assert np.abs(tangent[0] - fd).max() <= 1e-6 * np.abs(fd).max()


@pytest.mark.parametrize("model,ocr", MODELS)
def test_superposed_rotation_of_90_degrees_changes_nothing(model, ocr):
    """Rotating the initial stress and every increment by 90 degrees is invisible."""
    clay = table1(model, ocr)
    rng = np.random.default_rng(1)
    c, s = 0.0, 1.0
    a = clay.initial_state(1)
    b = (rotate(a[0], c, s), dict(a[1]))
    for _ in range(30):
        d = rng.normal(scale=2e-3, size=(1, 4))
        w = rng.normal(scale=1e-2, size=1)
        a = clay.update(*a[:2], d, w)
        b = clay.update(*b[:2], rotate_strain(d, c, s), w)
        np.testing.assert_allclose(rotate(a[0], c, s), b[0], rtol=0, atol=1e-10 * clay.p0)
        for key in ("pc", "v"):
            np.testing.assert_allclose(a[1][key], b[1][key], rtol=1e-12)


def test_pure_spin_keeps_invariants_and_state():
    clay = table1()
    *_, stress, state = march(clay, (0.003, -0.003, 0, 0.002), 0.0, 10)
    new, new_state, _ = clay.update(stress, state, np.zeros((1, 4)), np.array([0.7]))
    np.testing.assert_allclose(invariants(new), invariants(stress), rtol=1e-12)
    assert not np.allclose(new, stress)
    assert new_state["pc"] == pytest.approx(state["pc"][0], rel=1e-14)


increments = st.lists(
    st.tuples(*[st.floats(-4e-3, 4e-3) for _ in range(4)], st.floats(-0.05, 0.05)),
    min_size=1, max_size=12)


@pytest.mark.parametrize("model", ["original", "modified"])
@settings(max_examples=60, deadline=None)
@given(history=increments, ocr=st.floats(1.0, 3.0))
def test_stress_stays_on_or_inside_the_yield_surface(model, history, ocr):
    clay = table1(model, ocr)
    stress, state = clay.initial_state(1)
    for *d, w in history:
        stress, state, _ = clay.update(stress, state, np.array([d]), np.array([w]))
        assert clay.yield_value(stress, state)[0] <= 1e-9
        assert np.all(np.isfinite(stress)) and invariants(stress)[0][0] > 0


def test_update_is_vectorised_over_points():
    """Many points in one call give the same answers as one point at a time."""
    clay = table1("modified", 1.5)
    rng = np.random.default_rng(0)
    stress, state = clay.initial_state(64)
    d = rng.normal(scale=3e-3, size=(64, 4))
    w = rng.normal(scale=1e-2, size=64)
    together = clay.update(stress, state, d, w)
    for i in (0, 17, 63):
        alone = clay.update(stress[i:i + 1], {k: v[i:i + 1] for k, v in state.items()},
                            d[i:i + 1], w[i:i + 1])
        np.testing.assert_allclose(together[0][i], alone[0][0], rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("spec,word", [
    ({"preset": "table1", "lambda": 0.03}, "lambda"),
    ({"preset": "table1", "kappa": 0.11}, "lambda"),
    ({"preset": "table1", "nu": 0.5}, "nu"),
    ({"preset": "table1", "nu": -1.2}, "nu"),
    ({"preset": "table1", "p0": 0.0}, "p0"),
    ({"preset": "table1", "e0": -0.1}, "e0"),
    ({"preset": "table1", "M": 0.0}, "M"),
    ({"preset": "table1", "friction": 30}, "friction"),
    ({"preset": "table3"}, "preset"),
    ({"model": "elastic", "E": -1.0, "nu": 0.2}, "E"),
    ({"lambda": 0.2, "kappa": 0.05, "e0": 1.0, "p0": 10.0}, "needs M, nu: set them"),
    ({"model": "elastic", "nu": 0.3}, "needs E: set it"),
    ({"preset": "table1", "Cc": 0.5, "lambda": 0.2}, "give Cc or lambda, not both"),
    ({"model": "elastic", "mv": 1e-3, "E": 5.0, "nu": 0.3}, "give E or mv, not both"),
    ({"model": "elastic", "mv": -1e-3, "nu": 0.3}, "material.mv"),
])
def test_bad_parameters_name_themselves(spec, word):
    with pytest.raises(InputError, match=word):
        material_from_spec(spec)


def test_mv_is_the_inverse_constrained_modulus_and_xie_leo_k_grows_as_v_squared():
    from soilwater.material.fluid import Fluid

    skeleton = material_from_spec({"model": "elastic", "mv": 2e-3, "nu": 0.25})
    K, G = skeleton.moduli()
    assert K + 4 * G / 3 == pytest.approx(1 / 2e-3, rel=1e-12)
    fluid = Fluid(permeability=1e-9, permeability_law="xie-leo", permeability_e=1.0)
    k, dk = fluid.mobility_at(np.array([2.0, 1.5]))
    np.testing.assert_allclose(k * fluid.gamma_w, [1e-9, 1e-9 * 0.75**2], rtol=1e-12)
    np.testing.assert_allclose(dk, 2 * k / np.array([2.0, 1.5]), rtol=1e-12)


def test_compression_indices_are_slopes_per_decade():
    clay = material_from_spec({"preset": "table1", "Cc": 0.46, "Cr": 0.092})
    assert clay.lam == pytest.approx(0.46 / np.log(10)) and clay.kappa == pytest.approx(
        0.092 / np.log(10))
    # e falls by Cc over a tenfold stress on the normal compression line
    p = np.array([10.0, 100.0])
    v = clay.volume(p, p, (3.0, 3.0, 1.83))
    assert v[0] - v[1] == pytest.approx(0.46, rel=1e-12)


def test_elastic_skeleton_from_a_cam_clay_preset_has_its_initial_moduli():
    clay = material_from_spec({"preset": "table1"})
    elastic = material_from_spec({"preset": "table1", "model": "elastic"})
    assert np.allclose(elastic.moduli(), clay.moduli(), rtol=1e-12)
    assert elastic.p0 == clay.p0 and not elastic.plastic
    with pytest.raises(InputError, match="lambda"):
        material_from_spec({"preset": "table1", "model": "elastic", "lambda": 0.2})
