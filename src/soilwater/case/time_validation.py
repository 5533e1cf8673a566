"""Readers of a case's ``[loading]`` and ``[time]``: the load history and the time levels,
every time in seconds or with a unit (:func:`soilwater.case.entries.duration`).

Each returns the model object (:class:`~soilwater.case.timeline.Loading`,
:class:`~soilwater.case.timeline.TimeStepping`) or raises
:class:`~soilwater.errors.InputError` naming the entry.
"""

import numpy as np

from soilwater.case.entries import check_keys, duration, integer, number, pair, string
from soilwater.case.timeline import MAX_STEPS, ON_FAILURE, Loading, TimeStepping
from soilwater.case.schema import GEOMETRIC, KEYS
from soilwater.errors import require


def read_loading(table):
    check_keys(table, KEYS["loading"], "loading")
    L = table.get("velocity_gradient", ((0.0, 0.0), (0.0, 0.0)))
    require(isinstance(L, (list, tuple)) and len(L) == 2, "loading.velocity_gradient "
            "must be [[L11, L12], [L21, L22]] (1/s)")
    L = tuple(pair(row, "loading.velocity_gradient row") for row in L)
    load = table.get("load", 1.0)
    if not isinstance(load, (list, tuple)):
        return Loading(L, number(table, "load", "loading", 1.0))
    points = tuple(_load_point(p) for p in load)
    times = [t for t, _ in points]
    require(len(points) >= 2 and all(np.diff(times) > 0), "loading.load: give two or "
            "more [t, factor] points with increasing times from t = 0, or one number (a "
            "step load)")
    require(times[0] == 0, f"loading.load starts at t = {times[0]:g} s: give the factor "
            f"at t = 0 too, e.g. [[0, 0], [{times[0]:g}, {points[0][1]:g}]] for a ramp or "
            f"[[0, {points[0][1]:g}], ...] for a step load")
    return Loading(L, points)


def _load_point(value):
    """A ``loading.load`` point ``[t, factor]``: the time [s] in any :func:`duration`
    form."""
    require(isinstance(value, (list, tuple)) and len(value) == 2, f"loading.load point "
            f"{value!r} must be [t, factor], e.g. [\"1 d\", 1.0]")
    return (duration(value[0], "loading.load point's time"),
            number({"factor": value[1]}, "factor", "loading.load point"))


def read_time(table):
    check_keys(table, KEYS["time"], "time")
    require("end" in table, "time.end is missing: set it (seconds or e.g. \"60 yr\")")
    end = duration(table["end"], "time.end")
    require(end > 0, f"time.end = {table['end']!r} must be positive")
    on_failure = string(table, "on_failure", "time", "error", ON_FAILURE)
    output = _output(table.get("output"), end)
    if "steps" in table:
        require(not set(GEOMETRIC) & set(table), "time: give either steps or dt0, "
                "growth, dt_max, not both")
        steps = integer(table, "steps", "time")
        require(1 <= steps <= MAX_STEPS, f"time.steps = {steps} must lie in 1..{MAX_STEPS}")
        return TimeStepping(end=end, steps=steps, output=output, on_failure=on_failure)
    require(set(GEOMETRIC) <= set(table), "time: give steps (equal steps) or all of dt0, "
            "growth, dt_max (geometric steps)")
    dt0, dt_max = (duration(table[key], f"time.{key}") for key in ("dt0", "dt_max"))
    growth = number(table, "growth", "time")
    require(0 < dt0 <= dt_max, f"time.dt0 = {table['dt0']!r} must be positive and at most "
            f"time.dt_max = {table['dt_max']!r}")
    require(growth > 1, f"time.growth = {growth} must exceed 1 (t_(n+1) = growth t_n)")
    return TimeStepping(end=end, dt0=dt0, growth=growth, dt_max=dt_max, output=output,
                        on_failure=on_failure)


def _output(value, end):
    """``time.output``: increasing times in (0, end] [s], or None."""
    if value is None:
        return None
    require(isinstance(value, (list, tuple)), f"time.output = {value!r} must be a list of "
            f"times, e.g. [{value!r}] or [\"0.1 yr\", \"1 yr\", \"10 yr\"]")
    require(value, "time.output = [] names no time: give one or more, e.g. [\"1 yr\"], or "
            "remove it to write every level")
    times = [duration(v, "time.output entry") for v in value]
    require(all(0 < t <= end * (1 + 1e-9) for t in times) and all(np.diff(times) > 0),
            f"time.output = {value!r}: give increasing times after 0 and at most time.end "
            "(the fields at t = 0 are always written)")
    return tuple(min(t, end) for t in times)
