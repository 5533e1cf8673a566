"""Step loads (a load that jumps at t = 0+) in every method: the first level is the
undrained response, a failing first level spreads the jump over its halves
(soilwater.nonlinear.march), and a run that cannot take the step says why."""

import pytest

import soilwater
from soilwater.case.loader import load_case
from soilwater.errors import ConvergenceError
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


def test_a_step_load_that_fails_says_why_and_what_to_do():
    """A level that fails after a step load on a drained boundary names the thin drained
    skin and the three cures measured on the column (fem-th fails with time.dt0 = 1e5 s,
    growth 1.5, and takes dt0 = 1e6 s, a load ramped over 1e6 s, or 81 rows of nodes);
    without a step load the advice is the general one."""
    step = _Fake(limit=0.0)
    for case, advice in ((load_case("large-strain-column", STEP), "time.dt0"),
                         (load_case("large-strain-column"), "reduce time steps")):
        with pytest.raises(ConvergenceError, match=advice):
            march.march(case, 0.0, step, None, lambda c, t: None, {}, progress=False)
