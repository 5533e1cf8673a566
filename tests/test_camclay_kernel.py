"""Cam-clay's numba return mapping against the numpy oracle it replaced, and its errors.

Tolerances. Kernel and oracle solve the same local equations to the same tolerance,
``|R| < 1e-11`` on residuals scaled to be dimensionless (ln p', q / p'_n, ln p'c, f), but
the oracle iterates every point until the slowest has converged while the kernel stops
each point at its own convergence. They therefore differ by the Newton error left at that
tolerance, not by round-off. Measured with ``tests/camclay_speed.py`` (6e5 points per
model, increments up to 2 %): stress 2.5e-11 p'_n, tangent 1.5e-9 of its norm (original,
near the apex; 3.6e-11 modified), p'c 1.9e-11 relative. The bounds below are about ten
times these, far above round-off, so they hold on any CPU.

One quantity is ill-conditioned by the physics: the radial-return ratio ``q / q_tr`` in
the tangent's deviatoric part. The residual fixes q only to ``tol x p'_n``, so the ratio,
and the tangent with it, is known only to ``tol x p'_n / q_tr``; at a normally
consolidated isotropic state of the original model (the vertex) a small increment has
``q_tr`` of 1e-5 p'_n and the two codes' tangents differ by up to 2.6e-8 (found by
hypothesis). The tangent bound adds ten times that sensitivity, point by point (at
most 1e-4: a larger difference is a fault, whatever q_tr).
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import camclay_oracle as oracle
from conftest import table1
from soilwater.material import camclay_kernel as camclay
from soilwater.material.camclay import CamClay
from soilwater.nonlinear.newton import material_update
from soilwater.errors import ConvergenceError
from soilwater.material.kinematics import (DEVIATORIC, deviator, double_dot, hughes_winget,
                                           invariants)

STRESS_TOL = 2e-10    # of p' at the start of the step
TANGENT_TOL = 2e-8    # of the tangent's Frobenius norm
PC_TOL = 2e-10        # relative
LOCAL_TOL = 1e-11     # the return mapping's residual tolerance (CamClay.update)

CLAYS = {
    "original": table1("original"),
    "modified": table1("modified"),
    "modified, constant G": CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83,
                                    p0=3.0, model="modified", G=60.0),
}


def assert_agree(clay, points, kernel, numpy):
    """The kernel's (stress, state, tangent) within the tolerances of the oracle's."""
    p_n = invariants(hughes_winget(points[0], points[3]))[0]
    stress = np.abs(kernel[0] - numpy[0]).max(axis=1) / p_n
    tangent = (np.linalg.norm(kernel[2] - numpy[2], axis=(1, 2))
               / np.linalg.norm(numpy[2], axis=(1, 2)))
    assert stress.max() < STRESS_TOL
    sensitivity = 10 * LOCAL_TOL * p_n / np.maximum(_q_trial(clay, points), 1e-300)
    assert np.all(tangent < TANGENT_TOL + np.minimum(sensitivity, 1e-4))
    np.testing.assert_allclose(kernel[1]["pc"], numpy[1]["pc"], rtol=PC_TOL, atol=0)
    np.testing.assert_allclose(kernel[1]["v"], numpy[1]["v"], rtol=1e-14, atol=0)


def _q_trial(clay, points):
    """The elastic trial deviator stress q_tr of each point (compression positive)."""
    stress, state, dstrain, dspin = points
    rotated = hughes_winget(stress, dspin)
    G = clay.moduli(invariants(rotated)[0], state["v"])[1]
    s_tr = deviator(rotated) + 2 * G[:, None] * (dstrain @ DEVIATORIC.T)
    return np.sqrt(1.5 * double_dot(s_tr, s_tr))


uniform_rows = st.lists(st.lists(st.floats(0.0, 1.0), min_size=oracle.UNIFORMS,
                                 max_size=oracle.UNIFORMS), min_size=1, max_size=4)


@pytest.mark.parametrize("name", CLAYS)
@settings(max_examples=150, deadline=None)
@given(rows=uniform_rows)
def test_kernel_matches_the_numpy_oracle(name, rows):
    """Random admissible states and increments up to 2 % (one to four points a call)."""
    clay = CLAYS[name]
    points = oracle.admissible_points(clay, np.array(rows))
    assert_agree(clay, points, clay.update(*points), oracle.update(clay, *points))


@pytest.mark.parametrize("model", ["original", "modified"])
def test_kernel_matches_the_oracle_on_every_kind_of_return(model):
    """20000 points: elastic unloading, hardening (wet side) and softening (dry side)
    returns, the original model's vertex and the modified model's hardening at the mean
    specific volume of large volumetric increments all occur, and all agree."""
    clay = table1(model)
    points = oracle.admissible_points(clay, np.random.default_rng(5).random(
        (20000, oracle.UNIFORMS)))
    kernel, numpy = clay.update(*points), oracle.update(clay, *points)
    assert_agree(clay, points, kernel, numpy)
    pc_n, pc = points[1]["pc"], kernel[1]["pc"]
    dev = points[2][:, :3].sum(axis=1)
    assert min(np.sum(pc == pc_n), np.sum(pc > pc_n), np.sum(pc < pc_n)) > 2000
    on_vertex = (invariants(kernel[0])[1] == 0) & (pc != pc_n)
    if model == "original":
        assert on_vertex.sum() > 400
    else:
        assert not on_vertex.any()
        assert np.sum((pc != pc_n) & (np.abs(dev) > 1e-3)) > 2000


def test_a_start_in_tension_is_refused():
    clay = table1()
    stress, state = clay.initial_state(3)
    stress[1] = [0.5, 0.2, 0.1, 0.0]
    with pytest.raises(ConvergenceError, match=r"p' > 0 at every point.*p' = -0\.267$"):
        clay.update(stress, state, np.zeros((3, 4)), np.zeros(3))


def test_a_solver_names_the_kind_of_point_that_failed():
    """:func:`soilwater.nonlinear.newton.material_update` adds what a point is (a node, a background
    cell, a boundary point) to the material's message."""
    clay = table1()
    stress, state = clay.initial_state(3)
    stress[1] = [0.5, 0.2, 0.1, 0.0]
    with pytest.raises(ConvergenceError, match=r"p' = -0\.267 \(at a boundary point\)$"):
        material_update(clay, stress, state, np.zeros((3, 2, 2)), {}, "a boundary point")


@pytest.mark.parametrize("update", [CLAYS["original"].update,
                                    lambda *a, **k: oracle.update(CLAYS["original"], *a, **k)])
def test_too_few_iterations_name_the_points_that_did_not_converge(update):
    """Kernel and oracle: two plastic points of three, one Newton iteration allowed."""
    stress, state = CLAYS["original"].initial_state(3)
    dstrain = np.array([[-0.01, -0.01, -0.01, 0.0], [0.0] * 4, [0.01, -0.01, 0.0, 0.0]])
    with pytest.raises(ConvergenceError) as error:
        update(stress, state, dstrain, np.zeros(3), max_iter=1)
    assert str(error.value) == ("Cam-clay return mapping did not converge at 2 point(s) in "
                                "1 iterations: reduce the time step (strain increment per "
                                "step)")


@pytest.mark.parametrize("update", [CLAYS["original"].update,
                                    lambda *a, **k: oracle.update(CLAYS["original"], *a, **k)])
def test_a_diverging_increment_raises(update):
    """A 4.6 % shearing increment from the original surface (eta = 0.76): Newton's method
    does not converge (not even in 1000 iterations); two substeps do."""
    clay = CLAYS["original"]
    stress = np.array([[-8.85, -4.99, -4.34, -1.06]])
    state = {"pc": clay.size(*invariants(stress)), "v": np.array([2.0])}
    dstrain = np.array([[-0.032, 0.013, 0.027, -0.013]])
    with pytest.raises(ConvergenceError, match="did not converge at 1 point"):
        update(stress, state, dstrain, np.zeros(1))
    for _ in range(2):
        stress, state, _ = update(stress, state, dstrain / 2, np.zeros(1))
    assert state["pc"][0] > clay.size(6.06, 4.6)


def test_a_nan_increment_raises():
    clay = table1("modified")
    stress, state = clay.initial_state(2)
    dstrain = np.array([[0.001, 0.0, 0.0, 0.0], [np.nan, 0.0, 0.0, 0.0]])
    with pytest.raises(ConvergenceError, match="did not converge at 1 point"):
        clay.update(stress, state, dstrain, np.zeros(2))


def test_a_singular_local_jacobian_is_reported_in_one_line():
    """A zero pivot stops the factorisation; its status gives the oracle's message."""
    work = camclay._workspace()
    singular = np.array([[1.0, 2, 0, 0], [2, 4, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    assert not camclay._lu_factor(singular, work[3], work[4])
    assert camclay._lu_factor(singular + np.diag([0, 1e-12, 0, 0]), work[3], work[4])
    status = np.array([camclay.CONVERGED, camclay.NOT_CONVERGED, camclay.SINGULAR], np.int8)
    with pytest.raises(ConvergenceError, match="^Cam-clay return mapping met a singular "
                       "local Jacobian: reduce the strain increment per step$"):
        camclay.raise_on(status, 60)


@pytest.mark.parametrize("model", ["original", "modified"])
def test_size_puts_points_on_the_surface_in_their_shape(model):
    """``size``, ``yield_value`` and ``hardening`` keep their arguments' shapes."""
    clay = table1(model)
    p, q = np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([0.5, 3.0])
    pc = clay.size(p, q)
    assert pc.shape == (2, 2) and np.isscalar(clay.size(2.0, 1.0))
    stress = -p[..., None] * np.array([1.0, 1, 1, 0]) + q[:, None] / np.sqrt(3) * np.array(
        [1.0, -1, 0, 0])
    np.testing.assert_allclose(clay.yield_value(stress.reshape(4, 4),
                                                {"pc": pc.ravel()}), 0, atol=1e-14)
    assert clay.hardening(np.ones((3, 2))).shape == (3, 2)
