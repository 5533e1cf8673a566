"""The runner on a Dask distributed scheduler gives what the local pool gives."""

import numpy as np
import pytest
from dask.distributed import LocalCluster

from soilwater.studies.harness.runner import Job, run, table

JOBS = [Job("soil-column", "efg", ("time.end=100.0", f"efg.weight_p={w}"),
            labels=(("weights", w),)) for w in ("quartic", "exp:0.25")]
BROKEN = Job("soil-column", "efg", ("material.permeability=-1",))


@pytest.fixture(scope="module")
def scheduler():
    """Address of a one-worker local cluster (worker in its own process, so jobs and
    results cross a process boundary as they do on a real cluster)."""
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        yield cluster.scheduler_address


def test_dask_equals_the_local_pool_and_failures_are_reported(scheduler):
    remote = run(JOBS + [BROKEN], dask=scheduler, cache_dir=None, progress=False)
    local = run(JOBS + [BROKEN], workers=2, cache_dir=None, progress=False)
    for a, b in zip(remote[:2], local[:2]):
        np.testing.assert_array_equal(a.result.history.to_numpy(float),
                                      b.result.history.to_numpy(float))
    rows = table(remote)
    assert list(rows.status) == ["ok", "ok", "failed"]
    assert list(rows.weights[:2]) == ["quartic", "exp:0.25"]
    assert "permeability" in remote[2].error and remote[2].error == local[2].error
