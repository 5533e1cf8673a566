"""The sweep runner: parallel equals serial, failures are rows, the cache is used."""

import numpy as np

from soilwater.studies.harness.runner import Job, run, table

JOBS = [Job("soil-column", "efg", ("time.end=100.0", f"efg.weight_p={w}"),
            labels=(("weights", w),)) for w in ("quartic", "exp:0.25")]
BROKEN = Job("soil-column", "efg", ("material.permeability=-1",))


def test_parallel_equals_serial_and_failures_are_reported(tmp_path):
    serial = run(JOBS, workers=1, cache_dir=None, progress=False)
    parallel = run(JOBS + [BROKEN], workers=2, cache_dir=None, progress=False)
    for a, b in zip(serial, parallel):
        np.testing.assert_array_equal(a.result.history.to_numpy(float),
                                      b.result.history.to_numpy(float))
    rows = table(parallel)
    assert list(rows.status) == ["ok", "ok", "failed"]
    assert "permeability" in rows.error.iloc[2] and rows.weights.iloc[0] == "quartic"


def test_a_rerun_reads_the_cache(tmp_path):
    first = run(JOBS[:1], workers=1, cache_dir=tmp_path, progress=False)
    again = run(JOBS[:1], workers=1, cache_dir=tmp_path, progress=False)
    assert not first[0].cached and again[0].cached
    np.testing.assert_array_equal(first[0].result.history.to_numpy(float),
                                  again[0].result.history.to_numpy(float))
    changed = run([Job("soil-column", "efg", ("time.end=100.0", "efg.scale_p=1.4"))],
                  workers=1, cache_dir=tmp_path, progress=False)
    assert not changed[0].cached


def test_the_cache_folder_is_a_setting(tmp_path, monkeypatch):
    """SOILWATER_CACHE moves the default cache (a shared or copied folder); so does
    ``soilwater report --cache DIR``, which sets it for its process."""
    from soilwater.cli import main
    from soilwater.studies.harness.paths import ROOT, cache_folder

    monkeypatch.delenv("SOILWATER_CACHE", raising=False)
    assert cache_folder() == ROOT / ".cache" / "runs"
    monkeypatch.setenv("SOILWATER_CACHE", str(tmp_path / "shared"))
    first = run(JOBS[:1], workers=1, progress=False)
    assert not first[0].cached and len(list((tmp_path / "shared").glob("*.pkl"))) == 1
    assert run(JOBS[:1], workers=1, progress=False)[0].cached
    assert main(["report", "--cache", str(tmp_path / "other"), "--only", "nothing"]) == 2
    assert cache_folder() == tmp_path / "other"


def test_a_result_of_another_linear_solver_is_never_reused(tmp_path, monkeypatch):
    """The cache key holds the solver's name and version: the same job under another
    solver (or another version of it) is run, not read, and its summary names it."""
    import soilwater.studies.harness.runner as runner

    job = Job("soil-column", "efg", ("time.end=100.0",), linear_solver="superlu")
    first = run([job], workers=1, cache_dir=tmp_path, progress=False)[0]
    assert first.result.summary["linear_solver"].startswith("superlu scipy ")
    assert run([job], workers=1, cache_dir=tmp_path, progress=False)[0].cached
    key = job.key()
    monkeypatch.setattr(runner, "identity", lambda: "superlu scipy 0.0-other")
    assert job.key() != key
    assert not run([job], workers=1, cache_dir=tmp_path, progress=False)[0].cached


def test_a_method_s_settings_do_not_key_the_other_methods_runs():
    """``[efg]`` keys EFG's runs only and ``[fem]`` FEM's only."""
    efg, fem = Job("soil-column", "efg"), Job("soil-column", "fem-th")
    assert Job("soil-column", "fem-th", ("efg.scale_u=1.6",)).key() == fem.key()
    assert Job("soil-column", "efg", ("fem.remesh=delaunay",)).key() == efg.key()
    assert Job("soil-column", "efg", ("efg.scale_u=1.6",)).key() != efg.key()
    paper = Job("soil-column", "efg-paper")
    assert Job("soil-column", "efg-paper", ("fem.remesh=delaunay",)).key() == paper.key()
    assert paper.key() != efg.key()


def test_a_change_to_one_solver_keeps_the_other_solvers_runs(tmp_path, monkeypatch):
    """The cache key hashes only the code a method's solver can run: editing ``efg/``
    changes EFG's keys and not FEM's; editing the shared library changes both; editing a
    study, or a comment, changes neither."""
    import shutil

    import soilwater.studies.harness.runner as runner
    from soilwater.studies.harness import sources

    copy = tmp_path / "package"
    shutil.copytree(sources.PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(sources, "PACKAGE", copy)
    efg, fem = Job("soil-column", "efg"), Job("soil-column", "fem-th")

    def keys():
        runner.code_version.cache_clear()
        return efg.key(), fem.key()

    def append(path, text):
        path.write_text(path.read_text() + text)

    first = keys()
    append(copy / "efg" / "solver.py", "\n_EDITED = 1\n")
    second = keys()
    assert second[0] != first[0] and second[1] == first[1]
    append(copy / "physics" / "weakform.py", "\n# a comment only\n")
    assert keys() == second
    append(copy / "physics" / "weakform.py", "\n_EDITED = 1\n")
    third = keys()
    assert third[0] != second[0] and third[1] != second[1]
    append(copy / "studies" / "footing" / "study.py", "\n_EDITED = 1\n")
    assert keys() == third
    runner.code_version.cache_clear()


def test_a_sweep_says_what_is_cached_to_run_and_done_and_the_time_left(tmp_path, capsys):
    """Without a terminal: a line when it starts, as it goes and when it ends; the time
    left comes from the run times recorded in the cache folder, which outlive the
    cached results."""
    import json

    from soilwater.studies.harness.progress import TIMES, signature

    run(JOBS, workers=1, cache_dir=tmp_path, progress=True, desc="column")
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == ("column: 2 runs: 0 cached, 2 to run, time left unknown "
                        "(2 runs never timed here)")
    assert lines[-1].startswith("column: 2/2 done, ") and lines[-1].endswith("nothing to run")
    times = json.loads((tmp_path / TIMES).read_text())
    assert set(times) == {signature(job) for job in JOBS}
    assert all(seconds > 0 for seconds in times.values())
    run(JOBS, workers=1, cache_dir=tmp_path, progress=True, desc="column")
    assert capsys.readouterr().err.splitlines()[0] == ("column: 2 runs: 2 cached, 0 to run, "
                                                       "nothing to run")
    for path in tmp_path.glob("*.pkl"):
        path.unlink()
    (tmp_path / TIMES).write_text(json.dumps({signature(JOBS[0]): 100.0,
                                              signature(JOBS[1]): 140.0}))
    run(JOBS, workers=2, cache_dir=tmp_path, progress=True, desc="column")
    assert capsys.readouterr().err.splitlines()[0] == ("column: 2 runs: 0 cached, 2 to run, "
                                                       "about 2 min 0 s left")
    run(JOBS, workers=1, cache_dir=tmp_path, progress=False)
    assert capsys.readouterr().err == ""
