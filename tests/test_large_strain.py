"""The finite-strain consolidation study (soilwater/studies/large_strain/study.py): its reference
column is the case's, and its summary measures what it says."""

import numpy as np
import pandas as pd
import pytest

from soilwater.studies.large_strain import study as large_strain
from soilwater.references import gibson
from soilwater.physics.geostatic import initial_state
from soilwater.case.loader import load_case


def test_reference_column_starts_where_the_case_starts():
    """Gibson's geostatic start for the large-strain column has the case's void ratio
    at every height (1e-9) and the same solid height."""
    case = load_case("large-strain-column")
    ref = gibson.solve(large_strain.column(case), [1e-3], cells=400)
    xi = ref.xi[0]
    _, state = initial_state(case, case.material(), np.column_stack([0 * xi, xi]))
    np.testing.assert_allclose(ref.e[0], state["v"] - 1, atol=1e-6)


def test_static_settlement_is_gibsons_end():
    """Two independent ends of consolidation agree: the study's quadrature from the
    case's start and Gibson's march to 10 T (both loaded-column numbers, 1e-5)."""
    case = load_case("large-strain-column")
    ref = large_strain.column(case)
    end = gibson.solve(ref, [10 * gibson.consolidation_time(ref)]).settlement[-1]
    assert large_strain.static_settlement(case) == pytest.approx(end, rel=1e-5)


def test_summary_windows_take_the_largest_error_from_each_on():
    t = np.array([0.001, 0.01, 0.05, 0.1, 0.5, 1.0, 2.0])
    error = np.array([0.5, -0.3, 0.04, -0.02, 0.01, 0.005, -0.001])
    table = pd.DataFrame({"case": "large-strain-column", "method": "fem-th", "time": t,
                          "t_over_T": t, "settlement": 2.3 * (1 + error),
                          "gibson": 2.3, "error": error, "iterations": 4,
                          "run_time": 1.0})
    row = large_strain.summary(table).iloc[0]
    assert row["error_from_0.01T"] == pytest.approx(0.3)
    assert row["error_from_0.1T"] == pytest.approx(0.02)
    assert row["error_from_1T"] == pytest.approx(0.005)
    assert row.final_error == pytest.approx(-0.001)


@pytest.mark.parametrize("method", ["efg", "fem-th", "fem-p1p1-stab"])
def test_xie_leo_case_is_within_3_percent_of_the_closed_form(method):
    """The built-in xie-leo case (constant mv, k ~ (1 + e)^2, step load, 18 % strain)
    against Xie and Leo's closed form at its output times: the settlement within 3 % of
    the closed form's and the pore pressure at mid-depth within 3 % of the load."""
    from soilwater.methods import solve
    from soilwater.references.closed_forms import xie_leo

    case = load_case("xie-leo")
    result = solve(case, method, progress=False)
    fluid, load, height = case.fluid, 200.0, case.geometry.height
    mv = 1e-3
    rows = result.history.set_index("time")
    assert [s.time for s in result.snapshots][1:] == list(case.time.output)
    for t in case.time.output:
        u, settlement = xie_leo([height / 2], t, load, height, mv, fluid.permeability,
                                fluid.gamma_w)
        row = rows.loc[t]
        assert row["settlement"] == pytest.approx(settlement, rel=0.03), (t, row)
        assert abs(row["p_w@mid"] - u[0]) < 0.03 * load, (t, row["p_w@mid"], u[0])
