"""Work on every core: numba kernels that release the GIL, each called on its own part
of the work from a pool of threads.

The parts are disjoint (rows of a matrix, subdomains of one colour), and each part's
result is computed in the same order whatever the number of threads, so results do not
depend on it. The pool is made once per process (a forked child makes its own: the
parent's threads do not survive a fork).
"""

import os
from concurrent.futures import ThreadPoolExecutor
from functools import cache

import numpy as np

#: Threads of the pool: the cores this process may run on.
THREADS = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def parts(start, stop, count=THREADS):
    """``count`` consecutive ranges ``(lo, hi)`` that split ``start:stop`` evenly.

    Examples
    --------
    >>> parts(0, 10, 3)
    [(0, 3), (3, 7), (7, 10)]
    """
    edges = np.linspace(start, stop, count + 1).round().astype(np.int64)
    return [(int(lo), int(hi)) for lo, hi in zip(edges[:-1], edges[1:])]


def run(kernel, ranges):
    """``kernel(lo, hi)`` for every range, concurrently; returns when all are done (an
    exception in any is raised here).

    Examples
    --------
    >>> out = np.zeros(10)
    >>> def fill(lo, hi):
    ...     out[lo:hi] = np.arange(lo, hi)
    >>> run(fill, parts(0, 10))
    >>> out.tolist() == list(range(10))
    True
    """
    if len(ranges) == 1:
        kernel(*ranges[0])
        return
    for _ in _pool(os.getpid()).map(lambda r: kernel(*r), ranges):
        pass


@cache
def _pool(pid):
    """The thread pool of the process ``pid``."""
    return ThreadPoolExecutor(THREADS, thread_name_prefix="soilwater")
