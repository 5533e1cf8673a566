"""Typed readers of case entries: one table, one key, one clear line on bad input.

Each reader takes the table, the key and ``where`` (the dotted section name the message
shows, e.g. ``"material"``) and raises :class:`~soilwater.errors.InputError` naming
``where.key``, the value and what it must be.
"""

import math
import re

from soilwater.errors import require

#: Seconds per time unit of :func:`duration` (a year is 365.25 days).
TIME_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0, "day": 86400.0,
              "days": 86400.0, "yr": 31_557_600.0, "year": 31_557_600.0,
              "years": 31_557_600.0}

#: Marks an entry without a default: it must be given.
REQUIRED = object()


def section(data, name, default=REQUIRED):
    """``data[name]`` as a table; required unless a default is given."""
    require(name in data or default is not REQUIRED,
            f"case: section [{name}] is missing: add it (see soilwater/case/schema.py)")
    table = data.get(name, default)
    require(isinstance(table, dict), f"{name} must be a section [{name}], not a value")
    return table


def check_keys(table, allowed, where, what="key"):
    """Reject keys of ``table`` outside ``allowed``."""
    for key in table:
        require(key in allowed, f"{where}: unknown {what} {key!r}: "
                f"allowed are {', '.join(allowed)}")


def number(table, key, where, default=REQUIRED):
    """A finite float entry (ints accepted, bools not)."""
    require(key in table or default is not REQUIRED, f"{where}.{key} is missing: set it")
    value = table.get(key, default)
    require(isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value), f"{where}.{key} = {value!r} must be a finite number")
    return float(value)


def duration(value, where):
    """A time [s]: a finite number of seconds or a string ``"NUMBER UNIT"``, UNIT one of
    :data:`TIME_UNITS`.

    Examples
    --------
    >>> duration("60 yr", "time.end"), duration("1e6 s", "t"), duration(30, "t")
    (1893456000.0, 1000000.0, 30.0)
    >>> duration("2 weeks", "time.end")
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: time.end = '2 weeks' must be seconds or "NUMBER UNIT" with UNIT one of s, min, h, d, day, days, yr, year, years (e.g. "60 yr")
    """
    seconds = math.nan
    if isinstance(value, str):
        match = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([A-Za-z]+)\s*", value)
        if match and match.group(2) in TIME_UNITS:
            try:
                seconds = float(match.group(1)) * TIME_UNITS[match.group(2)]
            except ValueError:
                pass
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        seconds = float(value)
    require(math.isfinite(seconds), f"{where} = {value!r} must be seconds or \"NUMBER "
            f"UNIT\" with UNIT one of {', '.join(TIME_UNITS)} (e.g. \"60 yr\")")
    return seconds


def integer(table, key, where):
    """A required integer entry."""
    require(key in table, f"{where}.{key} is missing: set it")
    value = table[key]
    require(isinstance(value, int) and not isinstance(value, bool),
            f"{where}.{key} = {value!r} must be an integer")
    return value


def string(table, key, where, default, choices=None):
    """A string entry, optionally one of ``choices``."""
    value = table.get(key, default)
    require(isinstance(value, str), f"{where}.{key} = {value!r} must be a string")
    if choices is not None:
        require(value in choices,
                f"{where}.{key} = {value!r} is unknown: use one of {', '.join(choices)}")
    return value


def pair(value, where):
    """Two numbers ``[a, b]`` as a tuple of floats."""
    require(isinstance(value, (list, tuple)) and len(value) == 2,
            f"{where} = {value!r} must be a pair of numbers [a, b]")
    return tuple(number({"v": v}, "v", where) for v in value)
