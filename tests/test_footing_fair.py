"""The fair footing comparison's measures on synthetic curves: the Richardson reference,
the errors against it and the verdict's pairings."""

import numpy as np
import pandas as pd
import pytest

from soilwater.studies.footing_fair import study


def _curve(method, core, pressure, reached=1.0, u=None, run_time=10.0):
    s = np.linspace(0.0, reached, 21)
    return pd.DataFrame({"roughness": "smooth", "method": method, "core": core,
                         "nodes": (5 * core + 1) ** 2, "u_unknowns": u or 2 * core ** 2,
                         "p_unknowns": core ** 2, "settlement": s,
                         "pressure": pressure(s), "distortion": 1.0 - s,
                         "run_time": run_time, "reached": reached})


def test_richardson_recovers_a_second_order_limit_and_refuses_oscillation():
    h = np.array([0.4, 0.2, 0.1])
    estimate, order, error = study.richardson(*(2.0 + 3.0 * h ** 2))
    assert estimate == pytest.approx(2.0) and order == pytest.approx(2.0)
    assert error == pytest.approx(0.03)
    assert np.isnan(study.richardson(1.0, 0.9, 0.95)[0])       # differences change sign
    assert np.isnan(study.richardson(1.0, 0.99, 0.9)[0])       # order below 0.5


def test_errors_are_measured_against_the_extrapolated_reference():
    table = pd.concat([_curve("fem-th", c, lambda s, c=c: 1.0 + s + (1.0 / c) ** 2)
                       for c in (2, 4, 8)]
                      + [_curve("efg", 8, lambda s: 1.1 * (1.0 + s), reached=0.5)])
    ref = study.reference(table, levels=(0.5, 1.0))
    assert ref.reference.to_numpy() == pytest.approx([1.5, 2.0])
    assert ref.order.to_numpy() == pytest.approx([2.0, 2.0])
    summary = study.summary(table, ref, levels=(0.5, 1.0)).set_index("method")
    assert summary.loc["efg", "e_0.5"] == pytest.approx(0.1)
    assert np.isnan(summary.loc["efg", "p_1"])                  # beyond its reach
    assert summary.loc["efg", "error"] == pytest.approx(0.1)


def test_the_verdict_pairs_equal_unknowns_and_equal_run_time():
    # Taylor-Hood's errors: 0.17, 0.042, 0.010 of the reference 1 + s at 0.5 B
    th = [_curve("fem-th", c, lambda s, c=c: 1.0 + s + (1.0 / c) ** 2, u=u, run_time=t)
          for c, u, t in ((2, 700, 3.0), (4, 3400, 25.0), (8, 14000, 100.0))]
    base = pd.concat(th)
    ref = study.reference(base, levels=(0.5, 1.0))
    far = _curve("efg", 4, lambda s: 1.05 * (1.0 + s), reached=1.0, u=900, run_time=20.0)
    short = _curve("efg", 4, lambda s: 1.2 * (1.0 + s), reached=0.5, u=900, run_time=20.0)
    for efg, word in ((far, "supported"), (short, "refuted")):
        summary = study.summary(pd.concat([base, efg]), ref, levels=(0.5, 1.0))
        paired = study.pairs(summary)
        assert paired.th_u_unknowns.iloc[0] == 700               # nearest in unknowns
        assert paired.time_th_run_time.iloc[0] == 25.0            # nearest in run time
        assert study.verdict(paired)[0] == word
