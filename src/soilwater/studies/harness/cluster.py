"""The Dask side of :func:`soilwater.studies.harness.runner.run`: jobs sent to the workers
of a distributed scheduler, which may share no file system with this process.

:func:`compute` is called by the client (the process running the sweep) with the jobs
its own cache does not hold. It sends, with them, its source hash of each method
(:func:`soilwater.studies.harness.runner.code_version`); a worker whose own hash differs
refuses, and the sweep stops with one :class:`soilwater.errors.SoilwaterError` line naming
the worker. Every connected worker is checked before any job is sent, and each job is
checked again on the worker that runs it (a worker may join later).

A worker runs a job with :func:`soilwater.studies.harness.runner.execute` and its own
cache, the folder of its own ``SOILWATER_CACHE`` setting
(:func:`soilwater.studies.harness.paths.cache_folder`, ``.cache/runs`` in the worker's
checkout when unset): a job another sweep left there is read, not rerun. The result
travels back to the client with the cache key the worker computed it under (it names
the worker's linear solver), and the client stores it in its own cache.
"""

from dataclasses import dataclass

from soilwater.errors import SoilwaterError
from soilwater.studies.harness.runner import SETTING, code_version, execute

#: What a refusing worker asks the user to do.
FIX = "install the same checkout on every worker"


@dataclass(frozen=True)
class Refusal:
    """A worker's answer in place of an outcome: its source differs from the client's."""

    message: str


def compute(jobs, address, cache=True):
    """Run ``jobs`` on the workers of the Dask scheduler at ``address``.

    Parameters
    ----------
    jobs : list of Job
    address : str
        The scheduler, e.g. ``tcp://HOST:8786``.
    cache : bool
        Whether the workers read and write their own cache (False: every job is solved).

    Yields
    ------
    index : int
        The job's position in ``jobs``; the jobs come in the order they finish.
    outcome : Outcome
        What the job gave (``cached`` when the worker read it from its own cache).
    key : str or None
        The cache key the worker computed the result under (None for a failed job).

    Raises
    ------
    SoilwaterError
        Dask is not installed, or a worker's source hash differs from this process's.
    """
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise SoilwaterError("a Dask sweep needs the optional extra: pip install "
                             "'soilwater[dask]'") from None
    if not jobs:
        return
    ours = {method: code_version(method) for method in sorted({job.method for job in jobs})}
    with Client(address) as client:
        answers = client.run(versions, sorted(ours), on_error="return")
        for worker, theirs in sorted(answers.items()):
            if isinstance(theirs, BaseException):
                raise SoilwaterError(f"Dask worker {worker}: cannot import soilwater "
                                     f"({type(theirs).__name__}: {theirs}): {FIX}")
            message = mismatch(worker, theirs, ours)
            if message:
                raise SoilwaterError(message)
        futures = client.map(_compute, jobs, ours=ours, cache=cache, pure=False)
        index = {future.key: k for k, future in enumerate(futures)}
        for future, answer in as_completed(futures, with_results=True):
            if isinstance(answer, Refusal):
                client.cancel(futures)
                raise SoilwaterError(answer.message)
            yield index[future.key], *answer


def versions(methods):
    """This process's source hash of each method (method -> hash), run on each worker."""
    return {method: code_version(method) for method in methods}


def mismatch(worker, theirs, ours):
    """The one-line refusal of ``worker`` when its hashes ``theirs`` differ from the
    client's ``ours`` (method -> hash) on a method the client sends, else None."""
    for method, expected in ours.items():
        if theirs.get(method) != expected:
            return (f"Dask worker {worker}: its soilwater source (hash "
                    f"{theirs.get(method)}, method {method}) differs from this client's "
                    f"({expected}): {FIX}")
    return None


def _compute(job, ours, cache):
    """On a worker: ``(outcome, key)`` of ``job``, or a :class:`Refusal` when this
    worker's source of ``job.method`` differs from the client's hash ``ours``."""
    from distributed import get_worker

    message = mismatch(get_worker().address, versions([job.method]),
                       {job.method: ours[job.method]})
    if message:
        return Refusal(message)
    outcome = execute(job, SETTING if cache else None)
    return outcome, job.key() if outcome.ok else None
