"""Step loads (a load that jumps at t = 0+) in every method: the first level is the
undrained response, a failing first level spreads the jump over its halves
(soilwater.nonlinear.march), and a run that cannot take the step says why."""

import numpy as np
import pytest

import soilwater
from soilwater.case.loader import load_case
from soilwater.errors import ConvergenceError, InputError
from soilwater.nonlinear import march
from soilwater.studies.large_strain import study as large_strain

#: The large-strain column of Fox and Pu's (2015) kind: soft Cam-clay (lambda = 0.4)
#: under self-weight, geostatic under 20 kPa, then 180 kPa more at once on the drained top.
STEP = ("loading.load=1.0", "time.end=1e11", "time.dt0=1e6", "time.growth=1.5",
        "time.dt_max=2e10")


@pytest.mark.parametrize("method", soilwater.METHODS)
def test_step_loaded_column_runs_in_every_method(method):
    """Every method takes the step load: the first level (1e6 s, 1e-4 of the column's
    consolidation time) leaves the load on the water at mid-depth (180 kPa within 1 %),
    and the column ends within 1 % of the static settlement of its loaded compression
    line (2.30 m, 23 %)."""
    case = load_case("large-strain-column", STEP)
    result = soilwater.solve(case, method, progress=False)
    assert result.history["p_w@mid"].iloc[0] == pytest.approx(180.0, rel=0.01)
    static = large_strain.static_settlement(case)
    assert result.history["settlement"].iloc[-1] == pytest.approx(static, rel=0.01)


class _Fake:
    """A step that fails whenever its load factor grows by more than ``limit``."""

    def __init__(self, limit):
        self.limit, self.loads = limit, []

    def __call__(self, current, t0, t1, load):
        if load - current > self.limit:
            raise ConvergenceError("too large a load increment")
        self.loads.append(load)
        return load, 1, 0.0


def test_a_failing_step_load_is_spread_over_the_halves_of_the_first_level():
    """The jump of 1 at t = 0 fails whole and in halves; in quarters it passes, each
    quarter adding a quarter of the load; the next level carries the load whole."""
    case = load_case("terzaghi", ("loading.load=1.0", "time.steps=2", "time.end=1.0"))
    step = _Fake(limit=0.3)
    history, _ = march.march(case, 0.0, step, lambda c, t, dt, info: {"load": c,
                             "substeps": info["substeps"]}, lambda c, t: None,
                             {}, progress=False)
    assert step.loads == [0.25, 0.5, 0.75, 1.0, 1.0]
    assert history["substeps"].tolist() == [4, 1]


def test_a_failing_step_says_why_and_what_to_do():
    """The advice follows the cause: a step load on the drained top whose shortest
    sub-step (1e6 s / 2^MAX_CUTS) drains a skin of about 0.08 m, under the 0.5 m node
    spacing, names the skin and its three cures measured on the column (fem-th fails with
    time.dt0 = 1e5 s, growth 1.5, and takes dt0 = 1e6 s, a load ramped over 1e6 s, or 81
    rows of nodes); the same load with a first step 1e6 times longer (a skin of metres)
    names the capacity instead; a ramp names the load's growth; an inverted element the
    mesh; and every message says that time.on_failure = "stop" keeps what converged."""
    step = _Fake(limit=0.0)
    long = (*STEP, "time.dt0=1e12", "time.end=1e13", "time.dt_max=1e13")
    for case, advice in ((load_case("large-strain-column", STEP), r"skin of about 0\.081 m"),
                         (load_case("large-strain-column", long), "bearing capacity"),
                         (load_case("large-strain-column"), "bearing capacity")):
        with pytest.raises(ConvergenceError, match=advice) as err:
            march.march(case, 0.0, step, None, lambda c, t: None, {}, progress=False)
        assert 'time.on_failure = "stop" keeps the levels that converged' in str(err.value)
    assert "time.dt0" not in march._advice(load_case("large-strain-column", long), 0.0,
                                           1e12, "Newton diverged")
    inverted = march._advice(load_case("large-strain-column", STEP), 0.0, 1e6,
                             "element 3 inverts (J = -0.1)")
    assert "re-mesh" in inverted and "time.dt0" not in inverted


def test_a_load_past_the_modulus_is_named_as_the_cause():
    """A traction of 1e12 on Terzaghi's soil (E = 7.2) fails every halving; the message
    names the size of the input, not the step or the mesh."""
    case = load_case("terzaghi", ("boundary.top.traction=[0, -1e12]", "time.steps=5",
                                  "time.end=1"))
    with pytest.raises(ConvergenceError, match="exceeds the soil's initial P-wave "
                       "modulus") as err:
        soilwater.solve(case, "fem-th", progress=False)
    assert "re-mesh" not in str(err.value) and "time.dt0" not in str(err.value)


@pytest.mark.parametrize("change, words", [
    ("material.E=1e300", r"more than 1e\+12 times apart"),
    ("material.E=1e-300", r"more than 1e\+12 times apart"),
    ("material.storage=1e300", "times more compressible than the skeleton")])
@pytest.mark.parametrize("method", ["efg", "fem-th"])
def test_moduli_loads_and_storage_out_of_double_precision_are_refused(change, words,
                                                                       method):
    """A modulus 1e300 or 1e-300 times the loads (a singular factorisation before) or a
    storage that makes the water 1e300 times softer than the skeleton (a pore pressure
    of 1e-305 before) is refused before the run, naming the two values."""
    case = load_case("terzaghi", (change, "time.steps=2", "time.end=0.1"))
    with pytest.raises(InputError, match=words):
        soilwater.solve(case, method, progress=False)


#: A user's column: Xie and Leo's layer drained at both ends under 360 kPa at once
#: (mv q = 0.36, 30 % strain), geometric steps from 1e3 s, 0.25 m wide so that its
#: nodes are square.
TWO_WAY = ("boundary.bottom.water=drained", "boundary.top.traction=[0, -360]",
           "time.dt0=1e3", "time.growth=2", "geometry.width=0.25",
           "probes.mid=[0.125, 5.0]", "probes.base=[0.125, 0.0]")


@pytest.mark.parametrize("method, ny", [*((m, 41) for m in soilwater.METHODS),
                                        ("fem-th", 81)])
def test_a_step_loaded_large_strain_column_drained_at_both_ends_runs(method, ny):
    """Every method runs the step-loaded column with two-way drainage (fem-th also on
    81 rows of nodes) and ends consolidated at the closed form's settlement
    H (1 - exp(-mv q)) = 3.02 m within 1 %."""
    case = load_case("xie-leo", (*TWO_WAY, f"discretisation.ny={ny}"))
    history = soilwater.solve(case, method, progress=False).history
    assert history["settlement"].iloc[-1] == pytest.approx(10 * (1 - np.exp(-0.36)),
                                                           rel=0.01)
