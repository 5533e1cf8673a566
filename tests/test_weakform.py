"""The shared weak form: its tangent is the derivative of its residual."""

import numpy as np
import pytest

from soil.elastic import LinearElastic
from soil.kinematics import strain_increment
from soil.case import Fluid
from soil import weakform

FLUID = Fluid(permeability=1e-4, gamma_w=10.0, biot_alpha=0.8, storage=1e-3)
DT, BETA = 2.0, 1e-3


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
    return r[0], c[0]


@pytest.mark.parametrize("size", [1e-4, 1e-3])
def test_tangent_is_the_derivative_of_the_residual(size):
    """Central differences in every trial slot (grad u, p, grad p) against
    :func:`soil.weakform.tangent`: the pressure and coupling terms to 1e-7, the momentum
    block to within the tangent's stated approximation (the spin acting on the updated
    stress: of the order of the increment, here below 10 x its size)."""
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
        scale = np.abs(c).max()
        tol = 1e-7 if g == 2 else 10 * size
        np.testing.assert_allclose(c[:, :, g, t], numeric, atol=tol * scale)
