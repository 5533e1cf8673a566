"""soilwater's environment variables (``SOILWATER_LINEAR_SOLVER``, ``SOILWATER_THREADS``)
set for a block of code."""

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
