"""Named edge segments and the rigid strip footing, in both solvers.

An elastic oedometer (a footing over the whole top of a laterally confined, drained
layer) checks the sign and size of ``pressure@NAME`` by hand: ``M x settlement /
height``, M the constrained modulus; a footing on half the top checks that the rest of
the edge stays traction free (the base's reaction balances the footing's); bad segments
are refused with one line; and a small undrained Cam-clay footing runs to 0.2 B.
"""

import copy
import json

import numpy as np
import pytest

import soilwater
from soilwater.methods import EFG_METHODS
from soilwater.fem.solver import solve as fem_solve
from soilwater.errors import InputError
from soilwater.case.loader import load_case
from soilwater.case.validation import case_from_dict

METHODS = ("efg", "fem-th", "fem-p1p1")


def _solve(case, method):
    if method in EFG_METHODS:
        return soilwater.solve(case, method, progress=False)
    return fem_solve(case, method, progress=False)


def _layer(footing, width=1.0, height=2.0, nx=3, ny=5, bottom=None, end=100.0, y=None):
    """A linear elastic, drained layer (k large: effective = total stress at the slow
    rate), sides ux fixed, base fixed, the given segment(s) on the top."""
    return {
        "name": "layer", "analysis": "coupled",
        "geometry": {"width": width, "height": height},
        "discretisation": {"nx": nx, **({"y": y} if y else {"ny": ny})},
        "material": {"model": "elastic", "E": 1000.0, "nu": 0.3, "permeability": 10.0,
                     "gamma_w": 1.0},
        "boundary": {"left": {"ux": "fixed"}, "right": {"ux": "fixed"},
                     "bottom": bottom or {"ux": "fixed", "uy": "fixed"},
                     "top": {"water": "drained", "footing": footing}},
        "time": {"end": end, "steps": 2}}


HEIGHT, END = 2.0, 100.0
SETTLEMENT = 1e-4 * HEIGHT  # small: the finite-strain difference is ~ strain / 2 = 5e-5


@pytest.mark.parametrize("y", [None, [[1.5, 3, 0.2], [2.0, 2]]])
@pytest.mark.parametrize("method", METHODS)
def test_oedometer_velocity_control_pressure_is_constrained_modulus_times_strain(method, y):
    """Smooth footing over the whole top, pushed down by 1e-4 of the height: contact
    pressure (compression positive) = M s / H within 0.1 % (measured 5.1e-5 in all
    three methods; the finite-strain difference is about strain / 2 = 5e-5). The strain
    is uniform, so a grid in pieces (spacings shrinking 5-fold upwards to a finer top
    half metre) must give the same."""
    case = case_from_dict(_layer({"from": 0.0, "to": 1.0, "ux": "free", "uy": "footing",
                                  "settlement_rate": SETTLEMENT / END}, nx=4, ny=6,
                                 y=y))
    h = _solve(case, method).history
    M = case.material().constrained_modulus()
    assert h["settlement@footing"].iloc[-1] == pytest.approx(SETTLEMENT, rel=1e-12)
    expected = M * h["settlement@footing"] / HEIGHT
    assert np.allclose(h["pressure@footing"], expected, rtol=1e-3)


@pytest.mark.parametrize("method", METHODS)
def test_oedometer_load_control_settlement_is_force_over_width_height_over_modulus(method):
    """The same layer under a footing force of 0.2 kN/m on 1 m: the pressure is 0.2 kPa
    and the settlement 0.2 H / M within 0.1 % (measured 3.7e-4 at five times this
    force, finite strain)."""
    force = 0.2
    case = case_from_dict(_layer({"from": 0.0, "to": 1.0, "ux": "free", "uy": "footing",
                                  "force": force}))
    h = _solve(case, method).history
    M = case.material().constrained_modulus()
    assert h["pressure@footing"].iloc[-1] == pytest.approx(force / 1.0, rel=1e-6)
    assert h["settlement@footing"].iloc[-1] == pytest.approx(force * HEIGHT / M, rel=1e-3)


@pytest.mark.parametrize("method", ("efg", "efg-paper", "fem-th"))
def test_half_footing_leaves_the_rest_of_the_top_traction_free(method):
    """A rough footing on half the top of a 2 x 1 layer; the base is a named segment too.

    The sides are frictionless (ux fixed, uy free), so with the rest of the top traction
    free the base's vertical reaction balances the footing's: pressure x width agree
    (within 0.5 %, penalty and tolerance). The footing's settlement is rate x t exactly,
    its nodes move with it (EFG: within 2 % with the penalty, 15 % with Nitsche), and the
    free half of the top does not.
    """
    rate = 1e-4 / END
    case = case_from_dict(_layer(
        {"from": 0.0, "to": 1.0, "ux": "fixed", "uy": "footing", "settlement_rate": rate},
        width=2.0, height=1.0, nx=9, ny=5,
        bottom={"base": {"from": 0.0, "to": 2.0, "ux": "fixed", "uy": "fixed"}}))
    result = _solve(case, method)
    h = result.history
    assert np.array_equal(h["settlement@footing"], rate * h["time"])
    footing_force = h["pressure@footing"] * 1.0
    base_force = -h["pressure@base"] * 2.0  # the base pulls up where the footing pushes
    assert (footing_force > 0).all()
    assert np.allclose(base_force, footing_force, rtol=5e-3)
    nodes = case.nodes()
    top = nodes[:, 1] == 1.0
    u = result.snapshots[-1].point_data["u"][: len(nodes)]
    under, rest = top & (nodes[:, 0] <= 1.0), top & (nodes[:, 0] > 1.0)
    # FEM imposes the nodes exactly; EFG's penalty acts at boundary Gauss points and
    # its MLS field does not interpolate: measured 1.3 % off at the footing's edge node.
    # Nitsche's weak condition lets the smooth MLS field round the corner where the
    # condition changes type: measured 10 % off at the edge node, 4 % at x = 0
    rtol = {"efg": 0.15, "efg-paper": 2e-2}.get(method, 1e-9)
    assert np.allclose(u[under, 1], -rate * END, rtol=rtol)
    assert np.all(np.abs(u[rest, 1]) < 0.9 * rate * END)  # it would be the footing's
    # motion, were the rest of the edge tied to the footing


def _small_footing():
    """Half a footing B = 2 m (from 0 to 1, symmetry at x = 0) on a 5 x 5 m undrained
    Table 1 Cam-clay layer, smooth, pushed at 0.02 m/s to 0.2 B = 0.4 m in 20 steps;
    grid 11 x 11 (spacing 0.5 m)."""
    return case_from_dict({
        "name": "small-footing", "analysis": "coupled",
        "geometry": {"width": 5.0, "height": 5.0},
        "discretisation": {"nx": 11, "ny": 11},
        "material": {"preset": "table1", "model": "original", "permeability": 0.0},
        "boundary": {"left": {"ux": "fixed"}, "right": {"ux": "fixed"},
                     "bottom": {"ux": "fixed", "uy": "fixed"},
                     "top": {"footing": {"from": 0.0, "to": 1.0, "ux": "free",
                                         "uy": "footing", "settlement_rate": 0.02}}},
        "time": {"end": 20.0, "steps": 20}})


@pytest.mark.parametrize("method", ("efg", "fem-th"))
def test_small_undrained_footing_runs_to_a_fifth_of_its_width(method):
    """Measured (2 cores, two runs at once): EFG 10.0 s, 149 Newton iterations, no
    cut-back, 10.54 kPa at 0.4 m; fem-th 11.7 s, 132 iterations, 2 cut-backs, 9.43 kPa
    (run time is not asserted: speed belongs to ``make bench``).
    (2 + pi) s_u = 6.69 kPa for this clay: the coarse grid is far from converged (the
    footing study converges it)."""
    result = _solve(_small_footing(), method)
    h = result.history
    assert h["settlement@footing"].iloc[-1] == pytest.approx(0.4, rel=1e-12)
    pressure = h["pressure@footing"].to_numpy()
    assert pressure[0] > 0 and np.all(np.diff(pressure[:10]) > 0)


GOOD = _layer({"from": 0.0, "to": 0.5, "ux": "fixed", "uy": "footing",
               "settlement_rate": 1e-6})


def _bad(path, value):
    data = copy.deepcopy(GOOD)
    table = data["boundary"]
    *parents, last = path
    for part in parents:
        table = table[part]
    if value is None:
        del table[last]
    else:
        table[last] = value
    return data


@pytest.mark.parametrize("path, value, words", [
    (("top", "footing", "width"), 1.0, ["boundary.top.footing", "unknown key 'width'"]),
    (("top", "footing", "from"), 0.5, ["boundary.top.footing", "from = 0.5", "to = 0.5"]),
    (("top", "footing", "to"), 1.5, ["boundary.top.footing", "to = 1.5", "<= 1"]),
    (("top", "footing", "from"), -0.1, ["boundary.top.footing", "from = -0.1"]),
    (("top", "pad"), {"from": 0.4, "to": 0.8, "uy": "fixed"},
     ["boundary.top.footing and boundary.top.pad overlap"]),
    (("top", "footing", "force"), 1.0, ["boundary.top.footing.uy = 'footing'",
                                        "settlement_rate and force"]),
    (("top", "footing", "settlement_rate"), None, ["boundary.top.footing.uy = 'footing'",
                                                   "neither"]),
    (("top", "footing", "uy"), "fixed", ["boundary.top.footing.settlement_rate",
                                         "footing only"]),
    (("top", "footing", "uy"), "rigid", ["boundary.top.footing.uy", "'rigid'"]),
    (("left", "side"), {"from": 0.0, "to": 1.0, "uy": "footing", "force": 1.0},
     ["boundary.left.side.uy = 'footing'", "top or bottom"]),
    (("top", "footing", "water"), "wet", ["boundary.top.footing.water"]),
])
def test_bad_segments_are_refused_naming_the_key(path, value, words):
    with pytest.raises(InputError) as err:
        case_from_dict(_bad(path, value))
    message = str(err.value)
    assert "\n" not in message
    for word in words:
        assert word in message


def test_segment_at_a_corner_counts_in_the_corner_check():
    """A footing reaching the top-left corner meets a fixed left uy: a conflict."""
    data = _bad(("left", "uy"), "fixed")
    with pytest.raises(InputError, match="boundary.left.uy and boundary.top.uy conflict"):
        case_from_dict(data)


def test_two_load_controlled_footings_are_refused():
    data = _bad(("top", "footing", "settlement_rate"), None)
    data["boundary"]["top"]["footing"]["force"] = 1.0
    data["boundary"]["top"]["other"] = {"from": 0.6, "to": 1.0, "uy": "footing",
                                        "force": 1.0}
    with pytest.raises(InputError, match="at most one rigid plate or load-controlled"):
        case_from_dict(data)


def test_segments_round_trip_and_override():
    case = case_from_dict(GOOD)
    assert case_from_dict(json.loads(json.dumps(case.to_dict()))) == case
    (side, seg), = case.boundary.segments()
    assert (side, seg.name, seg.start, seg.end, seg.uy) == ("top", "footing", 0.0, 0.5,
                                                            "footing")
    moved = load_case("terzaghi", ["boundary.top.traction=[0, 0]", "discretisation.nx=5",
                                   "boundary.top.pad.from=0.5", "boundary.top.pad.to=1.0",
                                   "boundary.top.pad.uy=footing",
                                   "boundary.top.pad.force=2.0",
                                   "boundary.top.pad.water=impermeable"])
    (_, pad), = moved.boundary.segments()
    assert (pad.start, pad.end, pad.force, pad.water) == (0.5, 1.0, 2.0, "impermeable")
    assert moved.plate_force(1.0) == -2.0
    kind, drained, index = moved.boundary.top.at([0.0, 0.5, 1.0, 2.0])
    assert kind[:, 1].tolist() == ["free", "rigid", "rigid", "free"]
    assert drained.tolist() == [True, False, False, True] and index.tolist() == [-1, 0, 0, -1]


def test_a_run_that_fails_can_stop_at_its_last_converged_level():
    """``time.on_failure = "stop"``: the fem-th footing (B = 2 m, so that its edge is a
    node) on a 5 x 5 m layer of 6 x 6 nodes, pushed to 0.02,
    0.2, 2 and 4 m (levels 1, 10, 100, 200 s at 0.02 m/s) fails before 4 m (measured:
    in the step to 2 m); the result keeps every level before the failure and says why.
    With the default ``error`` the same run raises."""
    from soilwater.errors import ConvergenceError

    base = ["geometry.width=5", "geometry.height=5", "discretisation.nx=6",
            "discretisation.ny=6", "boundary.top.footing.to=1.0",
            "time.dt0=1", "time.growth=10",
            "time.dt_max=100", "time.end=200", "boundary.top.footing.settlement_rate=0.02"]
    with pytest.raises(ConvergenceError):
        fem_solve(load_case("strip-footing", [*base, "time.on_failure=error"]), "fem-th",
                  progress=False)
    result = fem_solve(load_case("strip-footing", [*base, "time.on_failure=stop"]),
                       "fem-th", progress=False)
    stopped = result.summary["stopped"]
    assert stopped.startswith("at t = ") and "halvings" in stopped
    assert 0 < len(result.history) < 4
    assert len(result.snapshots) == len(result.history) + 1
    assert np.isfinite(result.history["pressure@footing"]).all()


def test_taylor_hood_time_step_error_at_a_tenth_of_the_width_is_small():
    """The built-in footing with 2 spacings per B at the footing (11 x 11 nodes), pushed
    to 0.1 B in 10 and in 20 steps: fem-th's pressure at 0.1 B moves by under 0.5 %
    (measured 0.20 %; 0.92 of Prandtl's pressure). EFG's moves by 11 % on the same
    nodes and steps (1.04, 0.98, 0.87 of Prandtl's in 5, 10, 20 steps; `make report`
    measures it on the built-in nodes): that is a finding of the report, not asserted."""
    from soilwater.studies.harness.footing import width
    from soilwater.studies.harness.grids import refined

    p = []
    for steps in (10, 20):
        case = load_case("strip-footing", [*refined(2), "time.end=10", f"time.steps={steps}"])
        h = fem_solve(case, "fem-th", progress=False).history
        p.append(np.interp(0.1 * width(case), h["settlement@footing"], h["pressure@footing"]))
    assert p[1] == pytest.approx(p[0], rel=5e-3)


@pytest.mark.parametrize("method", ("fem-th", "fem-p1p1-stab"))
def test_undrained_elastic_footing_settles_as_flamant_per_doubling(method):
    """A rigid smooth footing on an undrained linear elastic layer (the built-in footing,
    the skeleton elastic with Table 1's initial moduli) on square domains of 5, 10 and
    20 B: the compliance settlement / (pressure B) grows by Flamant's
    ``(1 - nu_u) ln 2 / (pi G)`` per doubling, nu_u = 1/2 (measured for fem-th 1.0 % and
    0.3 % below it, fem-p1p1-stab 3.2 % and 1.5 %; with the drained nu = 0.333 it would be
    33 % larger)."""
    from soilwater.studies.harness.grids import growing
    from soilwater.references.closed_forms import flamant_settlement, undrained_poisson

    compliance = []
    for domain in (5.0, 10.0, 20.0):
        case = load_case("strip-footing", [*growing(domain, core=4), "material.model=elastic",
                                           "boundary.top.footing.settlement_rate=1e-5",
                                           "time.end=1", "time.steps=1"])
        h = fem_solve(case, method, progress=False).history
        compliance.append(h["settlement@footing"].iloc[-1] / h["pressure@footing"].iloc[-1])
    clay = case.material()
    nu_u = undrained_poisson(clay, case.fluid)
    assert nu_u == 0.5
    expected = flamant_settlement(1.0, clay.moduli()[1], nu_u, 2.0)
    assert np.allclose(np.diff(compliance), expected, rtol=0.05)
