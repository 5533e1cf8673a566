"""The shared weak form: its tangent is the derivative of its residual, and its compact
coefficients are the dense construction's, term by term."""

import numpy as np
import pytest

from soilwater.material.elastic import LinearElastic
from soilwater.material.kinematics import in_plane, spatial_tangent, strain_increment
from soilwater.material.fluid import Fluid
from soilwater.physics import weakform

FLUID = Fluid(permeability=1e-4, gamma_w=10.0, biot_alpha=0.8, storage=1e-3)
DT, BETA = 2.0, 1e-3


def _dense(coeff):
    """The (M, ft, 3, fs, 3) array of compact coefficients: zero where they have no term."""
    ft, fs = coeff.fields
    c = np.zeros((len(coeff.values), ft, 3, fs, 3))
    for term, column in coeff.columns().items():
        c[(slice(None), *term)] = column
    return c


def _residual(material, H, p, grad_p, state):
    """The residual coefficients at one point after the increment gradient H."""
    stress0, st, p_n, grad_p_n = state
    F = np.eye(2) + H
    J = np.linalg.det(F)
    deps, dw = strain_increment(H[None], np.array([J]))
    stress, _, C = material.update(stress0, st, deps, dw)
    total = weakform.total_stress(stress, np.array([p]), FLUID)
    r = weakform.residual(total, np.array([J]), np.linalg.inv(F)[None], np.array([0.7]),
                          np.array([p]), p_n, grad_p[None], FLUID, DT, BETA, grad_p_n)
    c = weakform.tangent(C, stress, total, np.array([J]), np.linalg.inv(F)[None],
                         np.array([0.7]), FLUID, DT, BETA)
    return r[0], _dense(c)[0]


@pytest.mark.parametrize("size", [1e-4, 1e-3])
def test_tangent_is_the_derivative_of_the_residual(size):
    """Central differences in every trial slot (grad u, p, grad p) against
    :func:`soilwater.physics.weakform.tangent`: the continuity rows (to 1e-7 of their own largest
    coefficient) and the pressure columns to 1e-7, the momentum block to within the
    tangent's stated approximation (the spin acting on the updated stress: of the order of
    the increment, here below 10 x its size)."""
    rng = np.random.default_rng(1)
    material = LinearElastic(E=1000.0, nu=0.3, p0=5.0)
    stress0, st = material.initial_state(1)
    state = (stress0, st, np.array([2.0]), np.array([[0.3, -0.1]]))
    H, p, grad_p = size * rng.normal(size=(2, 2)), 2.5, np.array([0.5, 0.2])
    r0, c = _residual(material, H, p, grad_p, state)
    h = 1e-7
    for g, t in [(g, t) for g in range(2) for t in (1, 2)] + [(2, 0), (2, 1), (2, 2)]:
        def at(e):
            dH, dp, dg = np.zeros((2, 2)), 0.0, np.zeros(2)
            if g < 2:
                dH[g, t - 1] = e
            elif t == 0:
                dp = e
            else:
                dg[t - 1] = e
            return _residual(material, H + dH, p + dp, grad_p + dg, state)[0]
        numeric = (at(h) - at(-h)) / (2 * h)
        tol = 1e-7 if g == 2 else 10 * size
        np.testing.assert_allclose(c[:2, :, g, t], numeric[:2], atol=tol * np.abs(c).max())
        np.testing.assert_allclose(c[2, :, g, t], numeric[2], atol=1e-7 * np.abs(c[2]).max())


@pytest.mark.parametrize("law", ["taylor", "kozeny-carman"])
def test_flux_tangent_follows_the_void_ratio(law):
    """With k = k(e), the flux rows' derivative in grad u (through ``v = v_n J``) is exact
    in :func:`soilwater.physics.weakform.tangent`: central differences to 1e-7; and the
    buoyant weight is a dead load (the momentum rows' value slot is ``w gamma'``, with no
    tangent)."""
    fluid = Fluid(permeability=1e-4, gamma_w=10.0, permeability_law=law,
                  permeability_e=0.9, permeability_ck=0.4)
    material = LinearElastic(E=1000.0, nu=0.3, p0=5.0)
    stress0, st = material.initial_state(1)
    v_n, w, weight = np.array([1.8]), np.array([0.7]), 8.0
    rng = np.random.default_rng(2)
    H0, p, grad_p = 1e-2 * rng.normal(size=(2, 2)), 2.5, np.array([[0.5, 0.2]])

    def coefficients(H):
        F = np.eye(2) + H
        J = np.array([np.linalg.det(F)])
        Finv = np.linalg.inv(F)[None]
        deps, dw = strain_increment(H[None], J)
        stress, _, C = material.update(stress0, st, deps, dw)
        total = weakform.total_stress(stress, np.array([p]), fluid)
        r = weakform.residual(total, J, Finv, w, np.array([p]), np.array([2.0]), grad_p,
                              fluid, DT, v_n=v_n, weight=weight)
        c = weakform.tangent(C, stress, total, J, Finv, w, fluid, DT, v_n=v_n,
                             grad_p=grad_p)
        return r[0], _dense(c)[0]

    r0, c = coefficients(H0)
    assert r0[1, 0] == pytest.approx(0.7 * weight) and r0[0, 0] == 0
    h = 1e-7
    for g in range(2):
        for t in range(2):
            dH = np.zeros((2, 2))
            dH[g, t] = h
            numeric = (coefficients(H0 + dH)[0] - coefficients(H0 - dH)[0]) / (2 * h)
            scale = np.abs(c[2, 1:, :2, 1:]).max()
            assert scale > 0
            np.testing.assert_allclose(c[2, 1:, g, t + 1], numeric[2, 1:], atol=1e-7 * scale)
            assert numeric[1, 0] == pytest.approx(0.0, abs=1e-9)


def _dense_tangent(C, effective, total, J, Finv, w, fluid, dt, beta, v_n, grad_p):
    """The tangent as it was built before the compact coefficients: the dense (M, 3, 3, 3,
    3) array, written out here as the reference."""
    wJ = w * J
    A = spatial_tangent(C, in_plane(effective), in_plane(total))
    c = np.zeros((len(w), 3, 3, 3, 3))
    c[:, :2, 1:, :2, 1:] = np.einsum("mik,mfkgl,mjl->mfigj", Finv,
                                     wJ[:, None, None, None, None] * A, Finv)
    c[:, :2, 1:, 2, 0] = -fluid.biot_alpha * wJ[:, None, None] * np.swapaxes(Finv, 1, 2)
    c[:, 2, 0, :2, 1:] = c[:, :2, 1:, 2, 0]
    c[:, 2, 0, 2, 0] = -fluid.storage * w
    mobility, slope = fluid.mobility_at(v_n * J)
    c[:, 2, 1, 2, 1] = c[:, 2, 2, 2, 2] = -(dt * mobility + beta) * w
    c[:, 2, 1:, :2, 1:] = -(dt * w * slope * v_n * J)[:, None, None, None] * (
        grad_p[:, :, None, None] * np.swapaxes(Finv, 1, 2)[:, None])
    return c


@pytest.mark.parametrize("law, storage, permeability, terms", [
    ("constant", 0.0, 0.0, 24),         # undrained, incompressible: momentum and coupling
    ("constant", 1e-3, 1e-4, 27),       # with storage and flow
    ("kozeny-carman", 1e-3, 1e-4, 35)])  # and the flux's change with the void ratio
def test_compact_tangent_is_the_dense_construction_term_by_term(law, storage, permeability,
                                                                terms):
    """On random input at 50 points, every term of :func:`soilwater.physics.weakform.tangent`
    equals the dense construction's to 1e-14 of its largest coefficient, and every coefficient the
    compact form leaves out is exactly zero there."""
    rng = np.random.default_rng(7)
    M = 50
    fluid = Fluid(permeability=permeability, gamma_w=10.0, biot_alpha=0.9, storage=storage,
                  permeability_law=law, permeability_e=0.9, permeability_ck=0.4)
    C = rng.normal(size=(M, 4, 4))
    effective = -rng.uniform(1, 5, size=(M, 4))
    total = effective - 2.0 * np.array([1.0, 1.0, 1.0, 0.0])
    Finv = np.eye(2) + 0.05 * rng.normal(size=(M, 2, 2))
    J = 1 / np.linalg.det(Finv)
    w, v_n, grad_p = rng.uniform(0.1, 1, M), rng.uniform(1.7, 1.9, M), rng.normal(size=(M, 2))
    args = (C, effective, total, J, Finv, w, fluid, DT, 0.0, v_n, grad_p)
    compact = weakform.tangent(*args)
    reference = _dense_tangent(*args)
    assert compact.fields == (3, 3) and len(compact.terms) == terms
    assert len(set(compact.terms)) == terms and compact.values.shape == (M, terms)
    scale = np.abs(reference).max()
    for (f, s, g, t), column in compact.columns().items():
        np.testing.assert_allclose(column, reference[:, f, s, g, t], rtol=0,
                                   atol=1e-14 * scale)
    absent = np.ones((3, 3, 3, 3), bool)
    absent[tuple(np.array(compact.terms).T)] = False
    assert not reference[:, absent].any()


def test_blocks_and_slot_matrices_select_and_renumber_terms():
    """``block`` keeps the terms of its fields, renumbered, with their columns; ``slots``
    is the dense (M, 3, 3) of one field pair."""
    rng = np.random.default_rng(8)
    terms = {(0, 1, 2, 0): rng.normal(size=4), (2, 0, 1, 2): rng.normal(size=4),
             (2, 1, 2, 1): rng.normal(size=4), (1, 2, 0, 1): rng.normal(size=4)}
    c = weakform.Coefficients.of(terms, (3, 3))
    pu = c.block(range(2, 3), range(0, 2))
    assert pu.fields == (1, 2) and pu.terms == ((0, 0, 1, 2),)
    np.testing.assert_array_equal(pu.values[:, 0], terms[2, 0, 1, 2])
    assert c.block(range(0, 2), range(0, 2)).terms == ((1, 2, 0, 1),)
    assert c.pairs == ((0, 2), (1, 0), (2, 1), (2, 2))
    slots = c.slots(2, 2)
    np.testing.assert_array_equal(slots[:, 1, 1], terms[2, 1, 2, 1])
    assert np.count_nonzero(slots) == np.count_nonzero(terms[2, 1, 2, 1])
