"""soilwater's environment variables (``SOILWATER_LINEAR_SOLVER``, ``SOILWATER_THREADS``)
set for a block of code, and the memory the machine has left."""

import os
from contextlib import contextmanager


@contextmanager
def setting(name, value):
    """The environment variable ``name`` set to ``value`` inside the ``with`` block; the
    caller's value (or its absence) restored after.

    Examples
    --------
    >>> with setting("SOILWATER_EXAMPLE", "1"):
    ...     os.environ["SOILWATER_EXAMPLE"]
    '1'
    >>> "SOILWATER_EXAMPLE" in os.environ
    False
    """
    saved = os.environ.get(name)
    os.environ[name] = str(value)
    try:
        yield
    finally:
        if saved is None:
            del os.environ[name]
        else:
            os.environ[name] = saved


def available_memory():
    """The memory this process can still take [bytes]: ``MemAvailable`` of
    ``/proc/meminfo``, else the physical memory (``os.sysconf``).

    >>> available_memory() > 0
    True
    """
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
