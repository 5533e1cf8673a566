"""Gravity, the geostatic start and void-ratio-dependent permeability (soilwater.physics.geostatic),
in both solvers, against closed forms and Gibson's finite-strain reference."""

import meshio
import numpy as np
import pytest

from soilwater.efg.solver import solve as efg_solve
from soilwater.fem.solver import solve as fem_solve
from soilwater.references import gibson
from soilwater.references.closed_forms import self_weight_settlement
from soilwater.material.camclay import CamClay
from soilwater.errors import InputError
from soilwater.physics.geostatic import buoyant_weight, initial_state
from soilwater.case.loader import load_case
from soilwater.case.schema import apply_override
from soilwater.case.validation import case_from_dict

def _layer(*overrides):
    """The large-strain column's 10 m layer made linear elastic (E = 1e4 kPa, nu = 0.3,
    e0 = 1), constant k = 1e-6 m/s, started weightless and unloaded."""
    data = load_case("large-strain-column").to_dict()
    data["material"] = {"model": "elastic", "E": 1e4, "nu": 0.3, "e0": 1.0,
                        "permeability": 1e-6}
    data["initial"] = {}
    data["boundary"]["top"] = {"water": "drained"}
    data.pop("probes")
    data.pop("loading")
    for item in overrides:
        apply_override(data, item)
    return case_from_dict(data)


def _solve(case, method):
    if method == "efg":
        return efg_solve(case, progress=False)
    return fem_solve(case, method, progress=False)


@pytest.mark.parametrize("override, key", [
    ("material.specific_gravity=1.0", "material.specific_gravity"),
    ("material.permeability_ck=0.0", "material.permeability_ck"),
    ("material.permeability_law=darcy", "material.permeability_law"),
    ("initial.k0=1.2", "initial.k0"),
    ("initial.k0=0.0", "initial.k0"),
    ("initial.e_ref=2.0", "initial.e_ref: the compression line's anchor is the material's"),
    ("material.e_ref=0.0", "material.e_ref"),
    ("initial.stress=layered", "initial.stress"),
    ("initial.surcharge=0.0", "initial.surcharge"),
    ("initial.pore_pressure=balance", "initial.pore_pressure"),
    ("gravity.g=-9.81", "gravity.g"),
    ("gravity.gg=9.81", "gravity"),
    ("material.biot_alpha=0.9", "material.biot_alpha"),
])
def test_bad_values_name_their_key(override, key):
    with pytest.raises(InputError, match=key.replace(".", r"\.")) as err:
        load_case("large-strain-column", overrides=[override])
    assert "\n" not in str(err.value)


def test_geostatic_keys_need_a_geostatic_start():
    with pytest.raises(InputError, match="initial.surcharge"):
        load_case("soil-column", overrides=["initial.surcharge=5.0"])


def test_k0_nc_is_the_ratio_of_one_dimensional_compression():
    """The modified Cam-clay's :meth:`k0_nc` is where a point compressed one-dimensionally
    from an isotropic state ends up (the stress-point update, 1000 steps of 0.1 %)."""
    clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0,
                   model="modified")
    stress, state = clay.initial_state(1)
    for _ in range(1000):
        stress, state, _ = clay.update(stress, state, np.array([[0, -1e-3, 0, 0]]),
                                       np.zeros(1))
    assert stress[0, 0] / stress[0, 1] == pytest.approx(clay.k0_nc(), abs=2e-4)


def test_geostatic_state_is_on_the_compression_line():
    """The large-strain column's start: sigma'_v grows by the buoyant weight of each
    depth, e lies on the line through e_ref at sigma_v_ref (slope lambda in ln sigma'_v)
    and every point is on its yield surface (normally consolidated)."""
    case = load_case("large-strain-column")
    clay = case.material()
    y = np.linspace(0, 10, 201)
    stress, state = initial_state(case, clay, np.column_stack([0 * y + 0.5, y]))
    sv = -stress[:, 1]
    assert sv[-1] == pytest.approx(20.0)
    weight = buoyant_weight(case, state["v"])
    np.testing.assert_allclose(-np.gradient(sv, y)[1:-1], weight[1:-1], rtol=1e-5)
    e = state["v"] - 1
    np.testing.assert_allclose(e, 2.4 - 0.4 * np.log(sv / 10.0), atol=1e-10)
    np.testing.assert_allclose(clay.yield_value(stress, state), 0.0, atol=1e-10)
    np.testing.assert_allclose(stress[:, 0] / stress[:, 1], clay.k0_nc())


@pytest.mark.parametrize("method, bound, overrides", [
    ("fem-th", 1e-12, ()), ("efg", 1e-3, ()), ("efg", 1e-3, ("efg.essential=nitsche",))],
    ids=["fem-th", "efg-penalty", "efg-nitsche"])
def test_geostatic_elastic_layer_stays_put(method, bound, overrides):
    """Started geostatically and not loaded, nothing moves: exactly with Taylor-Hood
    (its quadratic displacement holds the linear stress field; round-off bound
    1e-12 of the self-weight settlement), to the EFG's integration error otherwise
    (measured 3.9e-4 of it with the penalty, 3.6e-4 with Nitsche, whose flux through
    the fixed base is the column's weight: adding the initial stress's traction there
    too lifted the column by 4.9e-2 of it). The base's reaction is reported beyond the
    initial stress's, so it stays near zero too (measured 0.032 kPa with the penalty,
    0.029 with Nitsche, against the 91 kPa the base carries)."""
    case = _layer("initial.stress=geostatic", "initial.surcharge=10.0", "initial.k0=0.5",
                  "time.end=1e4", "time.steps=2", *overrides)
    data = case.to_dict()
    data["boundary"]["bottom"] = {"base": {"from": 0.0, "to": 1.0, "ux": "fixed",
                                           "uy": "fixed"}}
    result = _solve(case_from_dict(data), method)
    scale = self_weight_settlement(1.65 * 9.81 / 2, 10.0, 1e4 * 0.7 / (1.3 * 0.4))
    u = result.snapshots[-1].point_data["u"]
    assert np.abs(u).max() < bound * scale
    carried = 10.0 + 1.65 * 9.81 / 2 * 10.0          # surcharge and buoyant weight [kPa]
    assert np.abs(result.history["pressure@base"]).max() < 1e-3 * carried


def test_geostatic_camclay_layer_stays_put_with_taylor_hood():
    """The large-strain column without its load: its nonlinear sigma'_v(y) leaves at
    most the quadrature error of Taylor-Hood (measured: no motion at all; EFG moves
    5e-5 m; bound 1e-8 of the height)."""
    case = load_case("large-strain-column", overrides=["loading.load=0.0", "time.end=1e6",
                                                       "time.steps=2"])
    u = _solve(case, "fem-th").snapshots[-1].point_data["u"]
    assert np.abs(u).max() < 1e-8 * 10.0


@pytest.mark.parametrize("method, rtol", [("fem-th", 1e-4), ("efg", 1e-3)])
def test_weightless_layer_loaded_by_gravity_settles_to_the_static_solution(method, rtol):
    """Started weightless (uniform, zero stress), the weight acts from t = 0+: the
    excess pore pressure drains and the top settles to the finite-strain closed form
    (:func:`soilwater.references.closed_forms.self_weight_settlement`; measured 2.3e-6 for fem-th,
    1.0e-4 for EFG). The small-strain value is 0.2 % larger."""
    case = _layer("time.end=1e6", "time.dt0=100.0", "time.growth=1.5", "time.dt_max=2e5")
    history = _solve(case, method).history
    exact = self_weight_settlement(1.65 * 9.81 / 2, 10.0, 1e4 * 0.7 / (1.3 * 0.4))
    assert history["settlement"].iloc[-1] == pytest.approx(exact, rel=rtol)
    assert history["settlement"].iloc[0] < 0.01 * exact        # undrained at first


@pytest.mark.parametrize("method", ["fem-th", "efg"])
def test_large_strain_column_ends_at_gibsons_settlement(method, tmp_path):
    """The built-in large-strain column, in 30 coarse steps: the final settlement (23 %
    of the height) within 1 % of Gibson's (soilwater.references.gibson, converged to 1e-4); the VTU
    fields carry Taylor's k of each node's void ratio."""
    case = load_case("large-strain-column", overrides=["time.growth=1.6"])
    result = _solve(case, method)
    column = gibson.large_strain_column(load=((0.0, 20.0), (1e6, 200.0)))
    reference = gibson.solve(column, [case.time.end], cells=400).settlement[-1]
    assert result.history["settlement"].iloc[-1] == pytest.approx(reference, rel=1e-2)
    result.write(tmp_path / "out")
    last = sorted((tmp_path / "out").glob("fields_*.vtu"))[-1]
    data = meshio.read(last).point_data
    e = data["v"] - 1
    np.testing.assert_allclose(data["e"], e, rtol=1e-12)
    np.testing.assert_allclose(data["k"], 1e-9 * 10 ** ((e - 2.4) / 1.2), rtol=1e-12)
    assert data["k"].max() < 0.5e-9                   # compressed: k fell
