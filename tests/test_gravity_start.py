"""The gravity start (initial.stress = "gravity", soilwater.nonlinear.gravity_start): the
self-weight switched on drained before t = 0 by the method that then runs the case. Its
refusals, its state against the geostatic closed form on a level column, and the
equilibrium it leaves: a run with no load started from it stays still, on the level
column and on a user's slope, in every method."""

from pathlib import Path

import numpy as np
import pytest

import soilwater
from soilwater.case.loader import load_case
from soilwater.case.schema import apply_override
from soilwater.case.validation import case_from_dict
from soilwater.efg import solver as efg_solver
from soilwater.errors import InputError
from soilwater.fem import solver as fem_solver
from soilwater.fem.spaces import cell_bases
from soilwater.references.closed_forms import self_weight_settlement

DATA = Path(__file__).parent / "data"
#: Buoyant unit weight of Gs = 2.65 solids at e0 = 1 [kN/m3].
GAMMA = 1.65 * 9.81 / 2


def _column(*overrides, elastic=True):
    """The soil column (1 m x 10 m, rollers on the sides, fixed base, drained top, 11
    nodes up) unloaded under its own weight from a gravity start: linear elastic (E =
    1e4 kPa, nu = 0.3, e0 = 1, p'0 = 0) or the paper's Cam-clay (p'0 = 3 kPa, e0 = 0.83)."""
    data = load_case("soil-column").to_dict()
    if elastic:
        data["material"] = {"model": "elastic", "E": 1e4, "nu": 0.3, "e0": 1.0,
                            "permeability": 1e-6}
    for item in ("gravity.g=9.81", "initial.stress=gravity", "discretisation.ny=11",
                 "boundary.top.traction=[0.0, 0.0]", "time.end=1e4", "time.steps=2",
                 *overrides):
        apply_override(data, item)
    return case_from_dict(data)


def _slope(*overrides):
    """The user's slope of fill over clay (tests/data/slope.msh, linear elastic, two
    regions) unloaded under its own weight from a gravity start."""
    return load_case(DATA / "slope.toml", ("gravity.g=9.81", "initial.stress=gravity",
                                           "boundary.crest.traction=[0.0, 0.0]",
                                           "time.end=1e4", "time.steps=2", *overrides))


def _settled(case, method):
    """The material points' initial positions (M, 2) [m], their effective stress and
    state after the gravity phase (the state the run starts from), and the phase's
    largest displacement [m]."""
    if method == "efg":
        model = efg_solver.Model.build(case)
        _, points, summary = efg_solver._start(model, progress=False)
        return (efg_solver._cells(model, case.nodes()).points, points.stress, points.state,
                summary["gravity_start"]["largest_displacement"])
    model = fem_solver.Model.build(case, method)
    ub, _ = cell_bases(model.space.mesh0, model.space.pair)
    _, state, summary = fem_solver._start(model, progress=False)
    return (np.asarray(ub.global_coordinates()).reshape(2, -1).T, state.stress, state.state,
            summary["gravity_start"]["largest_displacement"])


@pytest.mark.parametrize("overrides, message", [
    ((), "add \\[gravity\\] with g = 9.81"),
    (("gravity.g=9.81", "initial.ocr=2.0"), "initial.ocr only apply"),
    (("gravity.g=9.81", "initial.pore_pressure=5.0"), "initial.pore_pressure = 5.0: a "
                                                       "gravity start"),
    (("gravity.g=9.81", "initial.pore_pressure=balance"), "initial.pore_pressure"),
    (("gravity.g=9.81", "initial.increments=0"), "initial.increments = 0 must lie"),
    (("gravity.g=9.81", "initial.increments=2.5"), "initial.increments = 2.5 must be an "
                                                    "integer"),
])
def test_bad_gravity_starts_are_refused_in_one_line(overrides, message):
    with pytest.raises(InputError, match=message) as err:
        load_case("soil-column", ("initial.stress=gravity", *overrides))
    assert "\n" not in str(err.value)


def test_gravity_start_keys_need_a_gravity_start():
    with pytest.raises(InputError, match="initial.increments only applies"):
        load_case("soil-column", ("initial.increments=4",))
    with pytest.raises(InputError, match="initial.stress = \"gravity\" needs analysis"):
        load_case("patch-test", ("gravity.g=9.81", "initial.stress=gravity"))


def test_a_sloping_geostatic_start_names_the_gravity_start():
    with pytest.raises(InputError, match="use initial.stress = \"gravity\""):
        load_case(DATA / "slope.toml", ("gravity.g=9.81", "initial.stress=geostatic"))


def test_the_gravity_start_round_trips_through_its_table():
    case = _slope("initial.increments=3")
    assert case.to_dict()["initial"] == {"stress": "gravity", "increments": 3}
    assert case.replace("time.steps=3").initial == case.initial


@pytest.mark.parametrize("method, tol, rel", [("fem-th", 1e-5, 1e-4), ("efg", 2e-2, 3e-3)])
def test_elastic_column_matches_the_geostatic_closed_form(method, tol, rel):
    """Each material point ends the phase at the geostatic state of its initial depth:
    sigma'_v = gamma' (H - Y) (the solids above it weigh what they did, whatever the
    compression) within ``tol`` of the base's (measured 6.6e-6 with Taylor-Hood, 9.5e-3
    with EFG, its integration error at the edges), sigma'_h = sigma'_zz = nu / (1 - nu)
    sigma'_v, the column's own k0 under lateral confinement, within tol / 10 (measured
    4e-7, 3.6e-4; a geostatic start would take it as initial.k0). The top settles by the
    finite-strain closed form (0.030 m) within ``rel`` (measured 7.3e-6, 1.0e-3)."""
    X, stress, _, settlement = _settled(_column("initial.increments=2"), method)
    base = GAMMA * 10.0
    sigma_v = -stress[:, 1]
    assert np.abs(sigma_v - GAMMA * (10.0 - X[:, 1])).max() < tol * base
    for horizontal in (stress[:, 0], stress[:, 2]):
        assert np.abs(-horizontal - 0.3 / 0.7 * sigma_v).max() < tol / 10 * base
    exact = self_weight_settlement(GAMMA, 10.0, 1e4 * 0.7 / (1.3 * 0.4))
    assert settlement == pytest.approx(exact, rel=rel)


@pytest.mark.parametrize("method, tol", [("fem-th", 1e-2), ("efg", 2e-2)])
def test_camclay_column_is_normally_consolidated_under_its_weight(method, tol):
    """From p'0 = 3 kPa the paper's Cam-clay compresses 14 % under its weight (1.42 m),
    yielding all the way: sigma'_v = p'0 + gamma'(e0) (H - Y) at each point's initial
    depth within ``tol`` of the base's (measured 5.3e-3 with Taylor-Hood, 1.2e-2 with
    EFG: the top's compression is the largest), no point outside its yield surface and
    none further inside than 1e-3 of its p'c (measured 1.6e-4 and 4.7e-5: the phase's
    last step, at the full weight, unloads a few a little) and, where sigma'_v > 10 p'0,
    sigma'_h / sigma'_v within 2 % of the normally consolidated k0 (measured 0.740 to
    0.750 against 0.749)."""
    case = _column(elastic=False)
    clay = case.material()
    X, stress, state, _ = _settled(case, method)
    weight = 1.65 * 9.81 / (1 + clay.e0)
    exact = clay.p0 + weight * (10.0 - X[:, 1])
    sigma_v = -stress[:, 1]
    assert np.abs(sigma_v - exact).max() < tol * exact.max()
    on = clay.yield_value(stress, state) / state["pc"]
    assert np.all(on < 1e-12) and np.all(on > -1e-3)
    deep = sigma_v > 10 * clay.p0
    np.testing.assert_allclose(stress[deep, 0] / stress[deep, 1], clay.k0_nc(), rtol=2e-2)


def _drift(result, height):
    """The largest displacement [m] and excess pore pressure [kPa] over the run's
    snapshots, over the phase's largest displacement and the buoyant weight of the
    height."""
    fields = [s.point_data for s in result.snapshots]
    u = max(np.abs(f["u"]).max() for f in fields)
    p = max(np.abs(f["p_w"]).max() for f in fields)
    return (u / result.summary["gravity_start"]["largest_displacement"],
            p / (GAMMA * height))


@pytest.mark.parametrize("method, bound", [
    ("fem-th", 1e-6), ("fem-q2q1", 1e-6), ("fem-q1q1", 1e-6), ("efg", 1e-5)])
def test_camclay_column_started_by_gravity_stays_still(method, bound):
    """With no load the coupled run from the gravity start is in equilibrium: its
    displacements and excess pore pressures stay below ``bound`` times the phase's
    settlement (1.42 m) and the base's buoyant weight (measured: fem-th 9.8e-9 and
    2.0e-8, fem-q2q1 7.5e-9 and 6.9e-9, fem-q1q1 nothing at all, efg 4.5e-7 and
    4.6e-7; 5.3e-6 and 6.0e-6 with Taylor-Hood without the phase's last step at the
    full weight, where the weight, a dead load on the start-of-step configuration, had
    not yet acted on the one the run starts from)."""
    u, p = _drift(soilwater.solve(_column(elastic=False), method, progress=False), 10.0)
    assert u < bound and p < bound


@pytest.mark.parametrize("method, bound", [
    ("fem-th", 1e-6), ("fem-p1p1", 1e-6), ("fem-p1p1-stab", 1e-6), ("efg", 1e-5),
    ("efg-paper", 5e-3)])
def test_slope_started_by_gravity_stays_still(method, bound):
    """The user's slope, whose sloping ground a geostatic start refuses: the gravity
    phase moves it 0.027 m, and the unloaded coupled run from there stays still, its
    displacements and excess pore pressures below ``bound`` times that and the buoyant
    weight of its 10 m (measured: nothing at all with fem-th, the P1/P1 pairs and efg,
    whose first step starts below the Newton tolerance; efg-paper, whose carried nodal
    state is never in equilibrium, 1.1e-3 and 8.4e-4). Started uniform instead, the same
    slope takes its weight at t = 0+, undrained: 0.29 and 0.90 with fem-th."""
    u, p = _drift(soilwater.solve(_slope(), method, progress=False), 10.0)
    assert u < bound and p < bound
