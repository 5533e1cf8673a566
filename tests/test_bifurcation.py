"""Uniqueness of the undrained solution: the discrete indicator, the continuum criterion
and the node jitter that probes round-off."""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from soilwater.studies.harness.onset import continuum_onset
from soilwater.efg.solver import solve as efg_solve
from soilwater.fem.solver import solve as fem_solve
from soilwater.diagnostics.bifurcation import DENSE_LIMIT, ellipticity, onset, restricted_eigenvalue
from soilwater.errors import InputError
from soilwater.case.loader import load_case
from soilwater.case.validation import case_from_dict


def test_restricted_eigenvalue_matches_an_independent_null_space():
    """Against an SVD null space and a Cholesky-reduced eigenproblem, on a random
    unsymmetric K, a rank-deficient B and an SPD G."""
    rng = np.random.default_rng(3)
    n, m = 40, 12
    K = rng.normal(size=(n, n))
    B = rng.normal(size=(m, n))
    B[-1] = B[0] + B[1]                                 # one dependent constraint row
    A = rng.normal(size=(n, n))
    G = A @ A.T + n * np.eye(n)
    Z = sla.null_space(B)
    assert Z.shape[1] == n - (m - 1)
    L = np.linalg.cholesky(Z.T @ G @ Z)
    S = np.linalg.solve(L, np.linalg.solve(L, Z.T @ (K + K.T) / 2 @ Z).T)
    expected = np.linalg.eigvalsh(S).min()
    assert restricted_eigenvalue(K, B, G) == pytest.approx(expected, rel=1e-10)


def test_ellipticity_of_an_isotropic_incompressible_solid_is_its_shear_modulus():
    """Unstressed, shear modulus 3: ``t.Q(n).t = G`` for every band normal."""
    d = np.eye(2)
    C = 3.0 * (np.einsum("fg,kl->fkgl", d, d) + np.einsum("fl,kg->fkgl", d, d))
    value, _ = ellipticity(np.stack([C, 2 * C]))
    np.testing.assert_allclose(value, [3.0, 6.0], rtol=1e-12)


def test_ellipticity_finds_the_weakest_direction():
    """A tangent soft in one band orientation only: the minimum and its angle are found
    (against brute force over 20 000 angles)."""
    rng = np.random.default_rng(0)
    A = rng.normal(size=(5, 2, 2, 2, 2))
    value, angle = ellipticity(A)
    a = np.linspace(0, np.pi, 20000, endpoint=False)
    n, t = np.stack([np.cos(a), np.sin(a)], 1), np.stack([-np.sin(a), np.cos(a)], 1)
    brute = np.einsum("af,ak,pfkgl,ag,al->pa", t, n, A, t, n)
    np.testing.assert_allclose(value, brute.min(1), atol=1e-7)
    np.testing.assert_allclose(np.radians(angle), a[brute.argmin(1)], atol=2e-4)


def test_continuum_onset_of_table1_is_near_the_critical_state():
    """Along the undrained plane-strain path the Rudnicki-Rice indicator starts at a
    positive fraction of the modulus and vanishes only once eta/M exceeds 0.999 (the
    associated model's plastic modulus goes to zero at critical state), with bands at
    about 45 degrees."""
    c = continuum_onset(strain=0.12, points=240)
    assert c.indicator.iloc[0] > 0.1
    strain = onset(c.strain, c.indicator)
    at = c.iloc[(c.strain - strain).abs().argmin()]
    assert 0.05 < strain < 0.12 and at.eta_over_M > 0.999
    assert 40 < at.band_angle < 50


@pytest.mark.parametrize("method", ["efg", "fem-th"])
def test_an_elastic_skeleton_keeps_its_uniqueness(method):
    """Known good: a linear elastic skeleton never loses uniqueness; its indicator stays
    positive and changes little over 10 % strain."""
    data = load_case("unconfined-compression", [
        "time.end=10.0", "time.steps=5", "diagnostics.uniqueness=true"]).to_dict()
    data["material"] = {"model": "elastic", "E": 1000.0, "nu": 0.3, "p0": 3.0}
    case = case_from_dict(data)
    solve = efg_solve if method == "efg" else (lambda c, **k: fem_solve(c, method, **k))
    u = solve(case, progress=False).history.uniqueness
    assert (u > 0.05).all() and u.max() / u.min() < 1.5


@pytest.mark.parametrize("method", ["efg", "fem-th"])
def test_cam_clay_loses_uniqueness_near_the_continuum_onset(method):
    """Known bad: the normally consolidated Cam-clay specimen loses it. The indicator is
    positive and falling in the first steps, and its first zero (on the homogeneous
    branch: nothing past it is compared) lies within 4 % strain of the continuum one
    (7.98 %)."""
    case = load_case("unconfined-compression", [
        "time.end=10.0", "time.steps=25", "efg.cells=squares", "efg.integration=paper",
        "diagnostics.uniqueness=true"])
    solve = efg_solve if method == "efg" else (lambda c, **k: fem_solve(c, method, **k))
    result = solve(case, progress=False)
    h, step = result.history, result.summary["uniqueness_onset_step"]
    assert h.uniqueness.iloc[0] > h.uniqueness.iloc[3] > 0
    assert abs(onset(h.eps_a, h.uniqueness) - 0.0798) < 0.04
    assert h.uniqueness.iloc[step - 1] <= 0 < h.uniqueness.iloc[:step - 1].min()


def test_jitter_moves_interior_nodes_only_and_is_reproducible():
    base = load_case("unconfined-compression")
    case = load_case("unconfined-compression", ["discretisation.jitter=1e-6"])
    moved = np.abs(case.nodes() - base.nodes()).max(1)
    boundary = base.boundary_loop()
    assert (moved[boundary] == 0).all()
    interior = np.setdiff1d(np.arange(len(moved)), boundary)
    assert (moved[interior] > 0).all()
    assert moved.max() <= 1e-6 * max(base.spacing)
    np.testing.assert_array_equal(case.nodes(), load_case(
        "unconfined-compression", ["discretisation.jitter=1e-6"]).nodes())
    other = load_case("unconfined-compression", ["discretisation.jitter=1e-6",
                                                 "discretisation.seed=1"])
    assert not np.array_equal(case.nodes(), other.nodes())


def test_the_indicator_refuses_a_tangent_too_large_for_dense_work():
    n = DENSE_LIMIT + 1
    with pytest.raises(InputError, match="diagnostics.uniqueness"):
        restricted_eigenvalue(sp.eye(n), sp.csr_matrix((0, n)), sp.eye(n))
