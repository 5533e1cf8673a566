"""The time line of a case: the load history (:class:`Loading`) and the time levels
(:class:`TimeStepping`), read from ``[loading]`` and ``[time]`` by
:mod:`soilwater.case.time_validation`. Times in seconds.
"""

from dataclasses import dataclass

import numpy as np

from soilwater.errors import require

#: What a step that fails after every halving does (:class:`TimeStepping`).
ON_FAILURE = ("error", "stop")
MAX_STEPS = 100_000
"""Largest number of time steps of a case (``time.steps``, or geometric steps to the end)."""


@dataclass(frozen=True)
class Loading:
    """Constant velocity gradient ``L_ij = dv_i/dx_j`` [1/s] and the load function.

    ``load`` is a float (step: 0 at t = 0, that factor for t > 0) or ``((t, f), ...)``
    interpolated linearly (constant outside the given times).
    """

    velocity_gradient: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0),
                                                                          (0.0, 0.0))
    load: float | tuple[tuple[float, float], ...] = 1.0

    @property
    def L(self):
        """The velocity gradient as a (2, 2) array."""
        return np.array(self.velocity_gradient)

    def factor(self, t):
        """Load factor at time(s) t (multiplies every edge traction)."""
        if isinstance(self.load, float):
            return np.where(np.asarray(t) > 0, self.load, 0.0)
        times, factors = np.array(self.load).T
        return np.interp(t, times, factors)

    def jump(self, t):
        """The jump of the load factor at time t [s], ``f(t+) - f(t)``: all of ``f(0+)``
        at t = 0 (the start is in equilibrium with no load: a step load, or a table
        whose factor at 0 is not 0), else 0 (tables are continuous).

        Examples
        --------
        >>> Loading(load=2.0).jump(0.0), Loading(load=2.0).jump(1.0)
        (2.0, 0.0)
        >>> Loading(load=((0.0, 0.0), (1.0, 1.0))).jump(0.0)
        0.0
        """
        if t > 0:
            return 0.0
        return float(self.load) if isinstance(self.load, float) else float(self.load[0][1])


@dataclass(frozen=True)
class TimeStepping:
    """End time [s] and either ``steps`` or geometric ``dt0``, ``growth``, ``dt_max``;
    ``output``: the times [s] at which fields are written (None: every level), each made
    a time level; ``on_failure`` is what a step that fails after every halving does:
    ``error`` (no result) or ``stop`` (the result ends at the last converged level)."""

    end: float
    steps: int | None = None
    dt0: float | None = None
    growth: float | None = None
    dt_max: float | None = None
    output: tuple | None = None
    on_failure: str = "error"

    def levels(self):
        """Time levels ``t_0 = 0, ..., t_end`` [s].

        ``steps`` gives equal steps; otherwise ``t_1 = dt0`` and
        ``t_{n+1} = t_n + min((growth - 1) t_n, dt_max)``, the last step cut to land on
        ``end``. The ``output`` times are added as levels; a level within ``1e-9 end``
        of one gives way to it. More than :data:`MAX_STEPS` steps raise
        :class:`~soilwater.errors.InputError`.

        Examples
        --------
        >>> TimeStepping(end=1.0, steps=4, output=(0.3, 0.5)).levels().tolist()
        [0.0, 0.25, 0.3, 0.5, 0.75, 1.0]
        """
        if self.steps is not None:
            t = np.linspace(0.0, self.end, self.steps + 1)
        else:
            t = [0.0, min(self.dt0, self.end)]
            while t[-1] < self.end:
                nxt = t[-1] + min((self.growth - 1.0) * t[-1], self.dt_max)
                t.append(self.end if nxt >= self.end * (1 - 1e-9) else nxt)
                require(len(t) <= MAX_STEPS + 1, f"time: more than {MAX_STEPS} steps to "
                        f"reach end = {self.end}: increase time.dt_max or time.growth")
            t = np.array(t)
        if not self.output:
            return t
        out = np.asarray(self.output, dtype=float)
        near = np.abs(t[:, None] - out[None, :]).min(axis=1) <= 1e-9 * self.end
        return np.union1d(t[~near | (t == 0.0) | (t == self.end)], out)

    def writes(self, t):
        """Whether fields are written at level ``t`` [s]: always at 0, and at every level
        without ``output``."""
        if not self.output or t == 0.0:
            return True
        return bool(np.abs(np.asarray(self.output) - t).min() <= 1e-9 * self.end)
