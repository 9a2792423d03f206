"""What a user is shown of a render's progress besides the fraction done: the time it has left, and how
often its picture is refreshed."""

import time
from contextlib import contextmanager


class TimeLeft:
    """Estimates the seconds a render has left from its progress fractions, at the rate of samples done
    since the first report (so that what came before rendering, e.g. compiling the kernel, does not count)."""

    def __init__(self):
        self.first = None  # (time, fraction) of the first report

    def __call__(self, fraction: float) -> float | None:
        now = time.perf_counter()
        if self.first is None:
            self.first = (now, fraction)
        start, begun = self.first
        return (now - start) * (1 - fraction) / (fraction - begun) if fraction > begun else None


class Throttle:
    """Says when a costly refresh of a render's picture (converting its film for display) is due: at most
    every `seconds`, and less often when refreshing takes over 1/`cost_ratio` of the time between
    refreshes (a large film takes a while to convert). The first is due `seconds` after its creation."""

    def __init__(self, seconds: float, cost_ratio: float):
        self.seconds, self.cost_ratio = seconds, cost_ratio
        self.last = time.perf_counter()  # when the last refresh ended
        self.cost = 0.0  # how long it took

    def due(self) -> bool:
        return time.perf_counter() - self.last >= max(self.seconds, self.cost_ratio * self.cost)

    @contextmanager
    def timed(self):
        """Time the refresh done inside."""
        start = time.perf_counter()
        yield
        self.last = time.perf_counter()
        self.cost = self.last - start
