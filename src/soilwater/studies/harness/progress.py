"""Progress of a sweep: runs cached, to run and done, and an estimate of the time left.

Each finished run's wall time is recorded in the cache folder (``times.json``, by case,
method, overrides and linear solver, so that a record outlives the code change that made
its cached result stale); a sweep's estimate is the recorded times of the runs it has
left, shared by its workers. On a terminal the sweep shows a bar; without one (a batch
job, a log) it prints a plain line when it starts, about every tenth of its runs and when
it ends.
"""

import json
import os
import sys
import time
from pathlib import Path

from tqdm import tqdm

from soilwater.nonlinear.progress import _isatty, clock

#: The file of recorded run times in the cache folder.
TIMES = "times.json"
#: Plain lines per sweep without a terminal (about; the first and last always print).
LINES = 10


def signature(job):
    """What a run time is recorded under: case, method, overrides and linear solver."""
    return json.dumps([job.case, job.method, list(job.overrides), job.linear_solver])


def recorded(cache_dir):
    """The recorded run times [s] in ``cache_dir`` (signature -> seconds; empty without
    a cache or a readable record)."""
    try:
        return dict(json.loads((Path(cache_dir) / TIMES).read_text()))
    except (TypeError, OSError, ValueError):
        return {}


def record(cache_dir, outcomes):
    """Add the wall times of the outcomes that ran (not read from the cache) to the
    record in ``cache_dir``; a cache that cannot be written is skipped."""
    ran = {signature(o.job): round(o.seconds, 2) for o in outcomes if not o.cached}
    if cache_dir is None or not ran:
        return
    path = Path(cache_dir) / TIMES
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps({**recorded(cache_dir), **ran}, indent=0, sort_keys=True))
        os.replace(tmp, path)
    except OSError:
        pass


class Sweep:
    """Progress over a sweep's jobs.

    Parameters
    ----------
    jobs : list of Job
    cached : list of bool
        Whether each job's result is in the cache already.
    times : dict
        Recorded run times (:func:`recorded`).
    workers : int
        Runs at a time.
    desc : str
        What the sweep is, e.g. ``footing``.
    enabled : bool
        False: nothing is shown.
    stream : file, optional
        Where it shows (default: standard error).
    """

    def __init__(self, jobs, cached, times, workers, desc, enabled=True, stream=None):
        self.desc, self.workers = desc, max(1, workers)
        self.stream = sys.stderr if stream is None else stream
        self.left = {k: times.get(signature(job)) for k, (job, hit) in
                     enumerate(zip(jobs, cached)) if not hit}
        self.total, self.cached, self.done = len(jobs), sum(cached), 0
        self.start = time.perf_counter()
        terminal = enabled and _isatty(self.stream)
        self.every = max(1, -(-self.total // LINES)) if enabled and not terminal else 0
        self.bar = tqdm(total=self.total, desc=desc, unit="run", file=self.stream,
                        leave=False) if terminal else None
        if self.bar is not None:
            self.bar.set_postfix_str(self.estimate())
        elif self.every:
            self._line(f"{_runs(self.total)}: {self.cached} cached, {len(self.left)} to run"
                       f", {self.estimate()}")

    def estimate(self):
        """The time left by the recorded times of the runs left, shared by the workers:
        ``about 3 min 5 s left``, with the runs never timed counted apart."""
        known = [s for s in self.left.values() if s is not None]
        unknown = len(self.left) - len(known)
        if not self.left:
            return "nothing to run"
        if not known:
            return f"time left unknown ({_runs(unknown)} never timed here)"
        text = f"about {clock(sum(known) / min(self.workers, len(self.left)))} left"
        return text + (f" + {_runs(unknown)} never timed here" if unknown else "")

    def update(self, index=None):
        """Job ``index`` (its position in the sweep; None: one of those left) is done."""
        self.done += 1
        self.left.pop(next(iter(self.left), None) if index is None else index, None)
        if self.bar is not None:
            self.bar.update()
            self.bar.set_postfix_str(self.estimate())
        elif self.every and (self.done % self.every == 0 or self.done == self.total):
            self._line(f"{self.done}/{self.total} done, {clock(self._elapsed())} elapsed, "
                       f"{self.estimate()}")

    def close(self):
        if self.bar is not None:
            self.bar.close()

    def _elapsed(self):
        return time.perf_counter() - self.start

    def _line(self, text):
        print(f"{self.desc}: {text}", file=self.stream, flush=True)


def _runs(count):
    """``1 run``, ``2 runs``."""
    return f"{count} run" if count == 1 else f"{count} runs"
