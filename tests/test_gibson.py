"""Gibson's finite-strain 1-D consolidation reference (soilwater.references.gibson):
equilibrium, the small-strain limit (Terzaghi), the large-strain closed form (Xie and Leo
2004), the static end states, its tangent and its convergence."""

import dataclasses

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from soilwater.references.closed_forms import terzaghi, xie_leo
from soilwater.errors import InputError
from soilwater.references.gibson import (Column, consolidation_time, large_strain_column,
                                         refinement, solve)
from soilwater.references.gibson_clay import SOFT_CLAY, Clay
from soilwater.references.gibson_discrete import Discrete

GAMMA_W = 9.81
#: Relative accuracy the reference promises in settlement.
ACCURACY = 1e-4


def soft_clay(**changes):
    return dataclasses.replace(SOFT_CLAY, **changes)


def test_geostatic_start_stays_put():
    column = large_strain_column(load=(), ocr=1.5)
    result = solve(column, [0.0, 1e3 * consolidation_time(column)])
    assert np.abs(result.settlement).max() < 1e-12 * column.height
    assert np.abs(result.e[1] - result.e[0]).max() < 1e-12
    assert np.abs(result.u_e).max() < 1e-9 * column.surcharge
    # the geostatic state: sigma' = q + gamma' (Z - z), p_w hydrostatic
    gamma = (2.65 - 1) * GAMMA_W
    assert result.sigma_eff[0] == pytest.approx(
        20.0 + gamma * (result.solid_height - result.z), rel=1e-12)
    assert result.p_w[0] == pytest.approx(GAMMA_W * (10.0 - result.xi[0]), rel=1e-12)
    assert result.height[0] == pytest.approx(10.0, rel=1e-13)


@pytest.mark.parametrize("drained_bottom", [False, True])
def test_small_strain_limit_is_terzaghi(drained_bottom):
    """A weightless layer, constant mv and k, mv dq = 1e-5: Terzaghi's series."""
    mv, k, H, dq = 1e-3, 1e-8, 1.0, 0.01
    clay = Clay(compression="constant-mv", mv=mv, e_ref=1.0, sigma_v_ref=100.0,
                permeability=k)
    column = Column(clay, height=H, surcharge=100.0, load=((0.0, 100.0 + dq),),
                    self_weight=False, drained_bottom=drained_bottom)
    path = H / 2 if drained_bottom else H
    times = path**2 / (k / (GAMMA_W * mv)) * np.array([0.01, 0.1, 0.3, 1.0, 3.0])
    result = solve(column, times)
    for i, t in enumerate(times):
        # drained at both ends: the half layer above mid-height, symmetric
        height = np.abs(result.xi[i] - H / 2) if drained_bottom else result.xi[i]
        p, s = terzaghi(height, t, dq, path, 1 / mv, 1.0, 0.0, k / GAMMA_W)
        assert result.settlement[i] == pytest.approx(s * H / path, rel=ACCURACY)
        assert np.abs(result.u_e[i] - p).max() < ACCURACY * dq


@pytest.mark.parametrize("drained_bottom", [False, True])
def test_large_strain_closed_form(drained_bottom):
    """Xie and Leo (2004): constant mv, k (1 + e)^-2 constant, mv dq = 0.3 (26 %)."""
    mv, k, H, dq, e0 = 1e-3, 1e-8, 10.0, 300.0, 1.5
    clay = Clay(compression="constant-mv", mv=mv, e_ref=e0, sigma_v_ref=50.0,
                permeability=k, permeability_law="xie-leo")
    column = Column(clay, height=H, surcharge=50.0, load=((0.0, 50.0 + dq),),
                    self_weight=False, drained_bottom=drained_bottom)
    path = H / 2 if drained_bottom else H
    times = path**2 / (k / (GAMMA_W * mv)) * np.array([0.01, 0.1, 0.3, 1.0, 3.0])
    result = solve(column, times)
    depth = (result.solid_height - result.z) * (1 + e0)   # initial depth of each cell
    for i, t in enumerate(times):
        u, s = xie_leo(depth, t, dq, H, mv, k, GAMMA_W, drained_bottom)
        assert result.settlement[i] == pytest.approx(s, rel=ACCURACY)
        assert np.abs(result.u_e[i] - u).max() < ACCURACY * dq
    assert result.settlement[-1] / H > 0.25
    # the small-strain answer is far off: Terzaghi's final settlement is mv dq H
    assert mv * dq * H / result.settlement[-1] - 1 > 0.15


def continuous_settlement(clay, column, final_stress, start_e, Z):
    """Settlement between two void-ratio profiles in z, by quadrature."""
    gamma = column.buoyant_weight

    def drop(z):
        sigma = final_stress + gamma * (Z - z)
        return start_e(z) - clay.void_ratio(sigma, max(sigma, sigma_p0(column, Z, z)))

    return quad(drop, 0, Z, epsabs=1e-13, epsrel=1e-12, limit=200)[0]


def sigma_p0(column, Z, z):
    if column.start == "deposited":
        return column.clay.virgin_stress(column.e_deposited)
    return column.ocr * (column.surcharge + column.buoyant_weight * (Z - z))


def geostatic_solid_height(column):
    clay, gamma = column.clay, column.buoyant_weight

    def e0(Z, z):
        sigma = column.surcharge + gamma * (Z - z)
        return clay.void_ratio(sigma, column.ocr * sigma)

    return brentq(lambda Z: quad(lambda z: 1 + e0(Z, z), 0, Z, epsrel=1e-13)[0]
                  - column.height, 0.01, column.height, xtol=1e-14), e0


@pytest.mark.parametrize("ocr", [1.0, 3.0])
def test_consolidation_ends_in_the_static_state(ocr):
    """After the load step the layer settles to equilibrium under q1 and its weight:
    the settlement of the static profiles (by quadrature), over-consolidated or not."""
    column = large_strain_column(ocr=ocr, drained_bottom=True)
    Z, e0 = geostatic_solid_height(column)
    expected = continuous_settlement(column.clay, column, 200.0, lambda z: e0(Z, z), Z)
    result = solve(column, [1e3 * consolidation_time(column)], cells=400)
    assert result.settlement[-1] == pytest.approx(expected, rel=ACCURACY)
    assert np.abs(result.u_e[-1]).max() < 1e-6 * 200.0


def test_self_weight_consolidation_of_a_deposit():
    """A fresh deposit at e = 4 carries its weight in the pore water at first, then
    settles to the normally consolidated static state."""
    column = Column(SOFT_CLAY, height=10.0, start="deposited", e_deposited=4.0)
    gamma = column.buoyant_weight
    Z = 10.0 / 5.0
    t_end = 1e3 * consolidation_time(column)
    result = solve(column, [0.0, t_end], cells=400)
    assert result.u_e[0] == pytest.approx(gamma * (Z - result.z), rel=1e-12)
    base = column.clay.virgin_stress(4.0)
    expected = continuous_settlement(column.clay, column, base, lambda z: 4.0, Z)
    assert result.settlement[-1] == pytest.approx(expected, rel=ACCURACY)
    assert result.settlement[-1] / column.height > 0.2


def test_unloading_follows_the_swelling_line():
    """Load to 200 kPa, consolidate, unload to 100 kPa: the layer swells on the Cr line
    from the stress it reached (not back down the normal compression line)."""
    column = large_strain_column(drained_bottom=True)
    T = consolidation_time(column)
    unloaded = large_strain_column(drained_bottom=True,
                           load=((0.0, 200.0), (100 * T, 200.0), (100.01 * T, 100.0)))
    Z, e0 = geostatic_solid_height(column)
    clay, gamma = column.clay, column.buoyant_weight

    def swell(z):
        peak = 200.0 + gamma * (Z - z)
        return clay.void_ratio(peak - 100.0, peak) - clay.void_ratio(peak, peak)

    rebound = quad(swell, 0, Z, epsrel=1e-12)[0]
    result = solve(unloaded, [100 * T, 300 * T], cells=400)
    assert result.settlement[0] - result.settlement[1] == pytest.approx(rebound, rel=1e-4)
    assert rebound > 0.01


def test_slow_ramp_stays_near_equilibrium():
    """A ramp from 20 to 200 kPa over 1000 consolidation times: at its midpoint the
    layer carries 110 kPa almost drained (the excess pressure is about rate d^2 /
    (2 cv0) = 0.02 kPa)."""
    T = consolidation_time(large_strain_column())
    column = large_strain_column(drained_bottom=True, load=((0.0, 20.0), (1e3 * T, 200.0)))
    Z, e0 = geostatic_solid_height(column)
    expected = continuous_settlement(column.clay, column, 110.0, lambda z: e0(Z, z), Z)
    result = solve(column, [500 * T], cells=200)
    assert result.settlement[0] == pytest.approx(expected, rel=1e-3)
    assert np.abs(result.u_e[0]).max() < 1e-3 * 110.0


@pytest.mark.parametrize("law", ["constant", "taylor", "kozeny-carman", "xie-leo"])
@pytest.mark.parametrize("drained_bottom", [False, True])
def test_tangent_is_the_derivative_of_the_rates(law, drained_bottom):
    column = large_strain_column(clay=soft_clay(permeability_law=law), ocr=1.3,
                         drained_bottom=drained_bottom)
    system = Discrete(column, 12)
    rng = np.random.default_rng(0)
    e = system.e0 + 0.05 * rng.standard_normal(12)    # both sides of sigma'_p
    t = 1.0
    rate, (lower, diag, upper) = system.rates(e, t, system.sigma_p)
    J = np.diag(diag) + np.diag(upper, 1) + np.diag(lower, -1)
    h = 1e-7
    numeric = np.array([(system.rates(e + h * np.eye(12)[j], t, system.sigma_p)[0]
                         - system.rates(e - h * np.eye(12)[j], t, system.sigma_p)[0])
                        / (2 * h) for j in range(12)]).T
    assert np.abs(J - numeric).max() < 1e-6 * np.abs(J).max()


def test_convergence_of_the_large_strain_column():
    """Halving the cells and the log-time step: second order, and the default resolution
    (800 cells, 40 levels per decade) within 1e-4 of the extrapolated settlement from
    1 % to 3 consolidation times (settlement 4 % to 23 % of the height)."""
    column = large_strain_column()
    times = consolidation_time(column) * np.array([0.01, 0.1, 0.3, 1.0, 3.0])
    study = refinement(column, times)
    assert study["levels"][-1] == (800, 40)
    assert np.all(np.abs(study["order"][:4] - 2) < 0.3)
    assert np.all(study["error"] < ACCURACY)
    assert 0.2 < study["extrapolated"][-1] / column.height < 0.3


@pytest.mark.parametrize("spec, key", [
    (dict(specific_gravity=1.0), "specific_gravity"),
    (dict(permeability_ck=0.0), "permeability_ck"),
    (dict(e_ref=-1.0), "e_ref"),
    (dict(permeability_law="darcy"), "permeability_law"),
    (dict(lam=0.03), "lambda"),
])
def test_bad_clay_is_named(spec, key):
    with pytest.raises(InputError, match=key):
        soft_clay(**spec)


@pytest.mark.parametrize("spec, key", [
    (dict(surcharge=0.0), "surcharge"),
    (dict(ocr=0.5), "ocr"),
    (dict(load=((1.0, 50.0), (0.5, 60.0))), "load"),
    (dict(start="deposited"), "e_deposited"),
])
def test_bad_column_is_named(spec, key):
    with pytest.raises(InputError, match=key):
        large_strain_column(**spec)
