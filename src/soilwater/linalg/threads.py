"""Work on every core: numba kernels that release the GIL, each called on its own part
of the work from a pool of threads.

The parts are disjoint (rows of a matrix, points, subdomains that do not touch), and each
part's result is computed in the same order whatever the number of threads, so results do
not depend on it. ``SOILWATER_THREADS=N`` sets the number (default: the cores this process
may run on; 1 runs every kernel in the calling thread). The pool is made once per process
and size (a forked child makes its own: the parent's threads do not survive a fork).
"""

import os
from concurrent.futures import ThreadPoolExecutor
from functools import cache

import numpy as np

from soilwater.linalg.environment import setting
from soilwater.errors import InputError

#: The cores this process may run on.
CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def threads():
    """Threads of the pool: ``SOILWATER_THREADS`` (a whole number, at least 1) if it is
    set, else :data:`CORES`."""
    choice = os.environ.get("SOILWATER_THREADS", "").strip()
    if not choice:
        return CORES
    if not choice.isdigit() or int(choice) < 1:
        raise InputError(f"SOILWATER_THREADS={choice!r} is not a number of threads; set a "
                         f"whole number from 1, or unset it to use every core ({CORES})")
    return int(choice)


def using(count):
    """``SOILWATER_THREADS=count`` inside a ``with`` block (for measurements that compare
    thread counts in one process).

    Examples
    --------
    >>> with using(1):
    ...     threads()
    1
    """
    return setting("SOILWATER_THREADS", count)


def parts(start, stop, count=None):
    """``count`` (default :func:`threads`) consecutive ranges ``(lo, hi)`` that split
    ``start:stop`` evenly.

    Examples
    --------
    >>> parts(0, 10, 3)
    [(0, 3), (3, 7), (7, 10)]
    """
    edges = np.linspace(start, stop, (count or threads()) + 1).round().astype(np.int64)
    return [(int(lo), int(hi)) for lo, hi in zip(edges[:-1], edges[1:])]


def run(kernel, ranges):
    """``kernel(lo, hi)`` for every range, side by side on the pool; returns when all are
    done (an exception in any is raised here).

    Examples
    --------
    >>> out = np.zeros(10)
    >>> def fill(lo, hi):
    ...     out[lo:hi] = np.arange(lo, hi)
    >>> run(fill, parts(0, 10))
    >>> out.tolist() == list(range(10))
    True
    """
    count = threads()
    if len(ranges) == 1 or count == 1:
        for lo, hi in ranges:
            kernel(lo, hi)
        return
    for _ in _pool(os.getpid(), count).map(lambda r: kernel(*r), ranges):
        pass


@cache
def _pool(pid, count):
    """The pool of ``count`` threads of the process ``pid``."""
    return ThreadPoolExecutor(count, thread_name_prefix="soilwater")
