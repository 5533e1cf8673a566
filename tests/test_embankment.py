"""The embankment study (soilwater/studies/embankment): its first loading stage against
a closed form, and its summary on a small stand-in for the built-in case's runs."""

import numpy as np
import pandas as pd
import pytest

from soilwater.case.loader import load_case
from soilwater.references.closed_forms import surface_load_pressure
from soilwater.studies.embankment import study


def test_the_builtin_case_loads_and_names_its_parts():
    case = load_case("embankment")
    assert case.geometry.mesh.groups == ("axis", "base", "far", "surface")
    assert case.material().names == ("clay", "crust")
    assert case.boundary.surface.traction_at([[0.0, 12.0], [10.0, 12.0], [20.0, 12.0]]
                                             ).tolist() == [[0.0, -200.0], [0.0, -100.0],
                                                            [0.0, 0.0]]


@pytest.mark.parametrize("method", ["efg", "fem-th", "fem-p1p1-stab"])
def test_first_loading_stage_is_the_closed_forms_up_to_the_domains_offset(method):
    """The embankment's load at once on a stiff elastic half-plane (400 m x 200 m),
    undrained: at six points under the axis, the crest's edge and the toe, p_w differs
    from Poisson's integral of the load by a nearly uniform offset, the finite domain's
    (measured -2.9 to -3.8 kPa of a 200 kPa load; it halves when the domain doubles):
    within 2.5 % of the load, and its spread over the points within 1 %."""
    table = study.first_stage((method,))
    load = 200.0
    assert np.abs(table.offset).max() < 0.025 * load
    assert np.ptp(table.offset) < 0.01 * load


def test_the_closed_form_is_poissons_integral():
    """Against a numerical quadrature of the Poisson kernel over the mirrored load."""
    from scipy.integrate import quad

    xs, qs = [0.0, 5.0, 15.0], [200.0, 200.0, 0.0]

    def q(s):
        return np.interp(abs(s), xs, qs, right=0.0)

    for x, z in [(0.0, 1.0), (8.0, 4.0), (15.0, 2.0), (30.0, 5.0)]:
        numeric = quad(lambda s: q(s) * z / ((x - s)**2 + z**2), -15, 15,
                       points=[-5, 5], limit=200)[0] / np.pi
        assert surface_load_pressure(x, z, xs, qs) == pytest.approx(numeric, rel=1e-9)


class _Run:
    def __init__(self, stopped):
        self.summary = {"stopped": stopped, "timings": {"total_s": 1.0}}


def test_summary_reads_how_far_each_run_got():
    day = study.DAY
    table = pd.DataFrame({
        "method": ["a"] * 3 + ["b"] * 2, "time": [100.0, 200.0, 3650.0, 100.0, 160.0],
        "fill": [5.0, 10.0, 10.0, 5.0, 8.0], "crest": [0.1, 0.5, 1.0, 0.1, 0.4],
        "toe": [0.0, 0.2, 0.3, 0.0, 0.5], "excess": [50.0, 120.0, 10.0, 40.0, 130.0],
        "min_angle": [30.0, 20.0, 19.0, 30.0, 10.0], "min_quality": [0.6, 0.4, 0.4, 0.6, 0.3],
        "run_time": [1.0] * 5})
    stop = (f"at t = {160 * day:g} s: step failed after 6 halvings of the time step (an "
            "element inverts (J = -3)): ...")
    rows = study.summary(table, {"a": _Run(None), "b": _Run(stop)}).set_index("method")
    assert rows.loc["a", "crest_built"] == 0.5 and rows.loc["a", "stopped"] == "-"
    assert np.isnan(rows.loc["b", "crest_built"]) and rows.loc["b", "fill"] == 8.0
    assert rows.loc["b", "stopped"] == "an element inverts (J = -3)"
    assert rows.loc["b", "min_angle"] == 10.0 and rows.loc["a", "excess_max"] == 120.0


def test_the_verdict_rows_a_reach_beyond_fem_supported_and_short_of_it_refuted():
    from soilwater.studies.verdicts import embankment

    def summary(efg, fem):
        return pd.DataFrame({"method": ["efg", "fem-th"], "fill": [efg, fem],
                             "stopped": ["-", "an element inverts (J = -1)"]})

    assert "| supported |" in embankment(summary(10.0, 8.0))
    assert "| refuted |" in embankment(summary(7.3, 8.0))
    assert "| open |" in embankment(summary(8.0, 8.0))
