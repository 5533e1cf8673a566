"""A Dask sweep on workers that share no cache with the client: results come back and
are cached by the client; a worker with other source code is refused in one line.

A real ``dask scheduler`` and ``dask worker`` processes on this machine, each worker with
its own ``SOILWATER_CACHE`` folder, stand for machines that share no file system."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

import soilwater
from soilwater.errors import SoilwaterError
from soilwater.studies.harness.runner import Job, run

JOBS = [Job("soil-column", "efg", ("time.end=100.0", f"efg.weight_p={w}"),
            labels=(("weights", w),)) for w in ("quartic", "exp:0.25")]
BROKEN = Job("soil-column", "efg", ("material.permeability=-1",))
DASK = [str(Path(sys.executable).parent / "dask")]
WORKER = ["worker", "--nworkers", "1", "--nthreads", "1", "--no-dashboard",
          "--death-timeout", "60"]


def _start(args, log, **env):
    """A process in its own session (so that its children can be ended with it)."""
    return subprocess.Popen(DASK + args, env={**os.environ, **env}, cwd=log.parent,
                            stdout=log.open("w"), stderr=subprocess.STDOUT,
                            start_new_session=True)


def _stop(process):
    """Terminate ``process`` and wait; then kill what is left of its session."""
    process.terminate()
    try:
        process.wait(timeout=15)
    except subprocess.TimeoutExpired:
        pass
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait()


def _worker(folder, address, **env):
    """A one-thread worker whose files and cache are in ``folder``."""
    folder.mkdir()
    return _start([*WORKER, "--local-directory", str(folder / "scratch"), address],
                  folder / "log.txt", SOILWATER_CACHE=str(folder / "cache"), **env)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """``(address, worker folders)`` of a scheduler on a free local port and two workers,
    each with its own cache."""
    root = tmp_path_factory.mktemp("cluster")
    processes = []
    try:
        info = root / "scheduler.json"
        processes.append(_start(["scheduler", "--host", "127.0.0.1", "--port", "0",
                                 "--no-dashboard", "--scheduler-file", str(info)],
                                root / "scheduler.txt"))
        for _ in range(300):
            if info.exists() and info.stat().st_size:
                break
            assert processes[0].poll() is None, (root / "scheduler.txt").read_text()
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        folders = [root / f"worker{k}" for k in (1, 2)]
        processes += [_worker(folder, address) for folder in folders]
        with distributed.Client(address, timeout=30) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, folders
    finally:
        for process in reversed(processes):
            _stop(process)


def _same(outcomes, serial):
    """Outcomes agree with a serial run: status, error and history to 1e-9."""
    assert [o.error for o in outcomes] == [o.error for o in serial]
    for a, b in zip(outcomes, serial):
        if b.ok:
            got, want = a.result.history.to_numpy(float), b.result.history.to_numpy(float)
            scale = np.nanmax(np.abs(want), initial=0.0)  # the history holds NaNs
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12 * scale)


def test_results_come_back_to_the_clients_cache(cluster, tmp_path, monkeypatch):
    address, folders = cluster
    cache = tmp_path / "client-cache"
    serial = run(JOBS + [BROKEN], workers=1, cache_dir=None, progress=False)
    remote = run(JOBS + [BROKEN], dask=address, cache_dir=cache, progress=False)
    _same(remote, serial)
    assert not any(o.cached for o in remote)
    stored = {path.name for path in cache.glob("*.pkl")}
    assert stored == {f"{job.key()}.pkl" for job in JOBS}
    # each worker cached what it ran in its own folder, none in another's
    on_workers = [{path.name for path in (f / "cache").glob("*.pkl")} for f in folders]
    assert set().union(*on_workers) == stored and sum(map(len, on_workers)) == len(JOBS)

    def refuse(*args, **kwargs):
        raise AssertionError("a sweep cached in full connected to the scheduler")

    monkeypatch.setattr("dask.distributed.Client", refuse)
    again = run(JOBS, dask=address, cache_dir=cache, progress=False)
    assert all(o.cached for o in again)
    _same(again, serial[:len(JOBS)])


@pytest.fixture
def stranger(cluster, tmp_path):
    """A third worker importing a copy of ``soilwater`` with one line of code added to a
    shared module (a comment would leave the hash: it hashes code, not text)."""
    address, _ = cluster
    src = tmp_path / "src"
    shutil.copytree(Path(soilwater.__file__).parent, src / "soilwater",
                    ignore=shutil.ignore_patterns("__pycache__"))
    with (src / "soilwater" / "errors.py").open("a") as fh:
        fh.write("ANOTHER_CHECKOUT = True\n")
    path = os.pathsep.join(filter(None, [str(src), os.environ.get("PYTHONPATH")]))
    process = _worker(tmp_path / "worker3", address, PYTHONPATH=path)
    try:
        yield src
    finally:
        _stop(process)


def test_a_worker_with_other_source_is_refused_in_one_line(cluster, stranger, tmp_path):
    address, _ = cluster
    with distributed.Client(address, timeout=30) as client:
        client.wait_for_workers(3, timeout=60)
        imported = client.run(lambda: soilwater.__file__)
    assert sum(Path(f).is_relative_to(stranger) for f in imported.values()) == 1
    with pytest.raises(SoilwaterError) as err:
        run(JOBS, dask=address, cache_dir=tmp_path / "client-cache", progress=False)
    message = str(err.value)
    assert "\n" not in message and message.startswith("Dask worker tcp://127.0.0.1:")
    assert "differs from this client's" in message and "same checkout" in message
    assert not list((tmp_path / "client-cache").glob("*.pkl"))
