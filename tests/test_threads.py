"""The kernels that run on parts of their work side by side (soilwater.linalg.threads): the same
results on any number of threads, and a clear error for a bad thread count."""

import numpy as np
import pytest

import soilwater.efg.solver
from soilwater.studies.bench.plan import compression
from soilwater.errors import InputError
from soilwater.linalg.backends import linear_solver
from soilwater.linalg.threads import parts, run


@pytest.mark.parametrize("value", ["0", "two", "-1", "1.5"])
def test_a_bad_thread_count_is_named(monkeypatch, value):
    monkeypatch.setenv("SOILWATER_THREADS", value)
    with pytest.raises(InputError, match="SOILWATER_THREADS"):
        parts(0, 10)
    with pytest.raises(InputError, match="SOILWATER_THREADS"):
        run(lambda lo, hi: None, [(0, 5), (5, 10)])


def test_an_efg_step_is_the_same_on_one_thread_and_on_three(monkeypatch):
    """Cam-clay's return mapping, the EFG scatter and nothing else split by threads: a
    step of the bench case (SuperLU, whose solve is serial) gives identical arrays."""
    results = {}
    for count in ("1", "3"):
        monkeypatch.setenv("SOILWATER_THREADS", count)
        with linear_solver("superlu"):
            result = soilwater.efg.solver.solve(compression(300), progress=False)
        results[count] = result
    one, three = results["1"], results["3"]
    assert one.history.equals(three.history)
    for key, value in one.snapshots[-1].point_data.items():
        assert np.array_equal(value, three.snapshots[-1].point_data[key]), key
