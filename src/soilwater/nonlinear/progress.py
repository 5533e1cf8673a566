"""Progress of a run's march: a bar on a terminal, plain lines without one.

A run in a batch job or piped into a log has no terminal, so tqdm's bar would be silent
for minutes; there :class:`Progress` prints a line every few steps on standard error
instead, with what a log reader needs to tell a slow run from a stuck one: the step,
the time reached, Newton's iterations and cut-backs so far, the time elapsed and an
estimate of the time left (the elapsed time per step so far times the steps left).
"""

import sys
import time

from tqdm import tqdm

#: Plain lines per run without a terminal (about; the first and last steps always print).
LINES = 20


def clock(seconds):
    """Seconds as a short duration: ``42 s``, ``3 min 5 s``, ``2 h 4 min``.

    Examples
    --------
    >>> clock(42.4), clock(185), clock(7440)
    ('42 s', '3 min 5 s', '2 h 4 min')
    """
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60} min"


class Progress:
    """Progress over ``total`` steps named ``desc``.

    Parameters
    ----------
    total : int
        Steps of the march.
    desc : str
        What runs, e.g. ``efg strip-footing``.
    enabled : bool
        False: nothing is shown (``soilwater run --quiet``, the report's runs).
    stream : file, optional
        Where it shows (default: standard error at the time of the call). A terminal
        gets tqdm's bar; anything else a line every ``total / LINES`` steps.
    """

    def __init__(self, total, desc, enabled=True, stream=None):
        self.total, self.desc, self.done = total, desc, 0
        self.stream = sys.stderr if stream is None else stream
        self.start = time.perf_counter()
        terminal = enabled and _isatty(self.stream)
        self.every = max(1, -(-total // LINES)) if enabled and not terminal else 0
        self.bar = tqdm(total=total, desc=desc, unit="step", file=self.stream,
                        leave=False) if terminal else None

    def update(self, t, stats):
        """One step done, at time ``t`` [s]; ``stats`` holds the march's counts
        (``newton_iterations``, ``cutbacks``)."""
        self.done += 1
        if self.bar is not None:
            self.bar.update()
        elif self.every and (self.done % self.every == 0 or self.done in (1, self.total)):
            elapsed = time.perf_counter() - self.start
            left = elapsed / self.done * (self.total - self.done)
            print(f"{self.desc}: step {self.done}/{self.total}, t = {t:.6g} s, "
                  f"{stats['newton_iterations']} Newton iterations, {stats['cutbacks']} "
                  f"cut-backs, {clock(elapsed)} elapsed, about {clock(left)} left",
                  file=self.stream, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _isatty(stream):
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
