"""Run cases with several methods and settings: a sweep, in parallel, cached.

A :class:`Job` names a case (built-in or TOML file), a method and ``--set`` overrides.
:func:`run` executes jobs in a local process pool (one worker per core by default) or on a
Dask distributed scheduler (``dask=ADDRESS``, optional extra ``soilwater[dask]``; its
workers need not share this process's file system: their results come back and are cached
here, :mod:`soilwater.studies.harness.cluster`), and returns one :class:`Outcome` per job,
in order. A job that fails is an outcome with its error; the others complete.

Results are cached on disk under a key hashing the resolved case, the method, the linear
solver (name and version, :func:`soilwater.linalg.backends.identity`) and the source code
the method's solver can execute (:func:`code_version`: the modules its solver imports,
with ``efg/`` for EFG and ``fem/`` for the FEM pairs; a change of code there, not of
comments or docstrings, invalidates it):
rerunning a report only recomputes what changed, and a result made with one linear solver
is never reused for another.
"""

import hashlib
import json
import os
import pickle
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import pandas as pd
from soilwater.case.loader import load_case
from soilwater.errors import SoilwaterError
from soilwater.fem.spaces import PAIRS
from soilwater.linalg.backends import identity, linear_solver
from soilwater.methods import EFG_METHODS, solver

from soilwater.studies.harness import sources
from soilwater.studies.harness.paths import cache_folder
from soilwater.studies.harness.progress import Sweep, record, recorded

#: Scheduler address for every sweep of this process (``--dask ADDRESS``), or None.
DASK = {"address": None}
#: How sweeps show their progress when their caller does not say: ``show`` (the report
#: turns it on) and ``desc``, the sweep's name (the study being made).
PROGRESS = {"show": False, "desc": "sweep"}
#: Jobs run and jobs read from the cache in this process (the report states them).
COUNTS = {"runs": 0, "cached": 0}
#: Solver folders (``efg``, ``fem``) of the jobs run or read since last cleared: a
#: study's section depends on those and not on the others.
USED = set()


@dataclass(frozen=True)
class Job:
    """One run: a case, a method, overrides ``("section.key=value", ...)`` and the linear
    solver (``"pardiso"``, ``"superlu"`` or None for
    :func:`soilwater.linalg.backends.backend`'s choice)."""

    case: str
    method: str
    overrides: tuple = ()
    labels: tuple = field(default=(), compare=False)
    linear_solver: str | None = None

    def key(self):
        """Cache key: the resolved case without the other methods' settings (an EFG run
        does not read ``[fem]``, nor a FEM run ``[efg]``), the method, the linear solver
        and the code; on a mesh, its content (:attr:`soilwater.geometry.mesh.Mesh.digest`)."""
        with linear_solver(self.linear_solver):
            solver = identity()
        resolved = load_case(self.case, self.overrides)
        case = resolved.to_dict()
        case.pop("fem" if self.method in EFG_METHODS else "efg", None)
        spec = {"case": case,
                "method": self.method, "linear_solver": solver,
                "code": code_version(self.method)}
        if resolved.geometry.mesh is not None:
            spec["mesh"] = resolved.geometry.mesh.digest
        return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:24]


@dataclass
class Outcome:
    """What a job gave: its Result or its error, the wall time and whether it was cached."""

    job: Job
    result: object = None
    error: str | None = None
    seconds: float = 0.0
    cached: bool = False

    @property
    def ok(self):
        return self.error is None


#: The solver folder each method runs (its code and what it imports make its cache key).
SOURCES = {**{name: ("efg",) for name in EFG_METHODS}, **{name: ("fem",) for name in PAIRS}}


#: ``cache_dir`` of :func:`run` and :func:`execute` by default: the cache folder of
#: :func:`soilwater.studies.harness.paths.cache_folder`, read when the sweep starts.
SETTING = type("Setting", (), {"__repr__": lambda self: "the SOILWATER_CACHE setting"})()


def execute(job, cache_dir=SETTING):
    """Run one job (or read it from the cache); never raises for a failing case."""
    cache_dir = cache_folder() if cache_dir is SETTING else cache_dir
    tic = time.perf_counter()
    try:
        path = _cache_path(job.key(), cache_dir) if cache_dir else None
        cached = _read_cache(path)
        if cached is not None:
            return Outcome(job, cached, None, time.perf_counter() - tic, True)
        case = load_case(job.case, job.overrides)
        with linear_solver(job.linear_solver):
            result = solver(job.method)(case, progress=False)
        _write_cache(path, result)
        return Outcome(job, result, None, time.perf_counter() - tic, False)
    except (SoilwaterError, ArithmeticError, ValueError) as err:
        return Outcome(job, None, f"{type(err).__name__}: {err}", time.perf_counter() - tic)


def _is_cached(job, cache_dir):
    """Whether ``job``'s result is in ``cache_dir`` (False for a case that cannot be
    read: its run reports the error)."""
    try:
        return cache_dir is not None and (Path(cache_dir) / f"{job.key()}.pkl").exists()
    except (SoilwaterError, ArithmeticError, ValueError, OSError):
        return False


def _read_cache(path):
    """A cached Result, or None (no cache, no entry, or a cache this worker cannot read)."""
    try:
        with path.open("rb") as fh:
            return pickle.load(fh)
    except (AttributeError, OSError, pickle.UnpicklingError, EOFError):
        return None


def _write_cache(path, result):
    """Store a Result; a cache folder this process cannot write is skipped."""
    if path is None:
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        with tmp.open("wb") as fh:
            pickle.dump(result, fh)
        os.replace(tmp, path)
    except OSError:
        pass


def run(jobs, workers=None, dask=None, cache_dir=SETTING, progress=None, desc=None):
    """Execute jobs and return their outcomes in order.

    Parameters
    ----------
    jobs : list of Job
    workers : int, optional
        Local processes (default: the number of cores; 1 runs in this process).
    dask : str, optional
        Address of a Dask distributed scheduler; the same jobs go there instead
        (default: :data:`DASK`, which ``soilwater report --dask ADDRESS`` sets).
    cache_dir : path or None
        Where results are cached (None: no cache; by default
        :func:`soilwater.studies.harness.paths.cache_folder`, ``SOILWATER_CACHE`` or
        ``.cache/runs``, read here so that local processes and Dask workers get the
        folder, not the setting).
    progress : bool, optional
        Show the sweep's progress: runs cached, to run and done and the time left
        (:class:`soilwater.studies.harness.progress.Sweep`; a bar on a terminal, plain
        lines without one). Default: :data:`PROGRESS`, off unless the report runs.
    desc : str, optional
        The sweep's name in its progress (default: :data:`PROGRESS`).
    """
    jobs, dask = list(jobs), dask or DASK["address"]
    cache_dir = cache_folder() if cache_dir is SETTING else cache_dir
    workers = workers or os.cpu_count()
    bar = Sweep(jobs, [_is_cached(job, cache_dir) for job in jobs], recorded(cache_dir),
                workers, desc or PROGRESS["desc"],
                enabled=PROGRESS["show"] if progress is None else progress)
    if dask is not None:
        outcomes = _run_dask(jobs, dask, cache_dir, bar)
    elif workers == 1 or len(jobs) == 1:
        outcomes = []
        for k, job in enumerate(jobs):
            outcomes.append(execute(job, cache_dir))
            bar.update(k)
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(execute, job, cache_dir): k for k, job in enumerate(jobs)}
            for future in as_completed(futures):
                bar.update(futures[future])
            outcomes = [future.result() for future in futures]
    bar.close()
    record(cache_dir, outcomes)
    COUNTS["runs"] += len(outcomes)
    COUNTS["cached"] += sum(o.cached for o in outcomes)
    USED.update(folder for job in jobs for folder in SOURCES[job.method])
    return outcomes


def _run_dask(jobs, address, cache_dir, bar):
    """Outcomes of ``jobs`` in order, on the Dask scheduler at ``address``.

    Each job found in this process's cache ``cache_dir`` is read here (``cached``); only
    the others go to the workers (:func:`soilwater.studies.harness.cluster.compute`:
    the workers need not share a file system with this process, and one whose source
    differs from this process's is refused with a :class:`SoilwaterError`). Each
    successful result they send back is written to ``cache_dir`` under the key the
    worker computed it under. No connection is made when every job is cached here.
    """
    from soilwater.studies.harness import cluster

    outcomes = [_lookup(job, cache_dir) for job in jobs]
    missing = [k for k, outcome in enumerate(outcomes) if outcome is None]
    for k, outcome in enumerate(outcomes):
        if outcome is not None:
            bar.update(k)
    for i, outcome, key in cluster.compute([jobs[k] for k in missing], address,
                                           cache=bool(cache_dir)):
        outcomes[missing[i]] = outcome
        if key is not None and cache_dir:
            _write_cache(_cache_path(key, cache_dir), outcome.result)
        bar.update(missing[i])
    return outcomes


def _lookup(job, cache_dir):
    """``job``'s Outcome read from ``cache_dir`` (``cached``), or None: no cache, no
    entry, or a case this process cannot resolve (the worker that runs it reports it)."""
    tic = time.perf_counter()
    try:
        result = _read_cache(_cache_path(job.key(), cache_dir)) if cache_dir else None
    except (SoilwaterError, ArithmeticError, ValueError, OSError):
        return None
    return None if result is None else Outcome(job, result, None,
                                               time.perf_counter() - tic, True)


def _cache_path(key, cache_dir):
    """The cache file of the result under ``key`` in the folder ``cache_dir``."""
    return Path(cache_dir) / f"{key}.pkl"


def table(outcomes):
    """One row per outcome: labels, case, method, overrides, status, error, seconds."""
    rows = []
    for o in outcomes:
        summary = o.result.summary if o.ok else {}
        rows.append({**dict(o.job.labels), "case": o.job.case, "method": o.job.method,
                     "overrides": " ".join(o.job.overrides),
                     "status": "ok" if o.ok else "failed", "error": o.error or "",
                     "seconds": round(o.seconds, 3), "cached": o.cached,
                     "steps": summary.get("steps"),
                     "newton_iterations": summary.get("newton_iterations")})
    return pd.DataFrame(rows)


@cache
def code_version(method):
    """Hash of the package version and the code ``method``'s runs can execute
    (:func:`soilwater.studies.harness.sources.dependencies` of its solver, :data:`SOURCES`):
    a change to EFG's code leaves FEM's cached runs valid, and the reverse; a change of
    comments or docstrings leaves both."""
    from importlib.metadata import version

    folders = SOURCES[method]
    roots = ["soilwater.methods", *(f"soilwater.{f}.{m}" for f in folders
                                     for m in ("solver", "statics"))]
    return sources.digest({"version": version("soilwater"),
                           **sources.dependencies(roots, folders)})
