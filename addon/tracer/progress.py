"""What a user is shown of a render's progress besides the fraction done: the time it has left."""

import time


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
