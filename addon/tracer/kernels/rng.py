"""Counter-based random numbers: every path draws from a stream keyed by (seed, band, pixel, sample).

A stream's i-th number is a hash of (key, i), so any split of the work over passes, tiles, threads
or machines draws exactly the same numbers for the same path. Plain functions of uint64 arithmetic
shared with both backends (`shared_math`).
"""

import numpy as np

from ..shared_math import shared

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MUL1 = np.uint64(0xBF58476D1CE4E5B9)
_MUL2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_UNIT = 1.0 / 9007199254740992.0  # 2⁻⁵³


@shared
def mix64(z):
    """SplitMix64's finaliser: a bijective 64-bit hash."""
    z = (z ^ (z >> _S30)) * _MUL1
    z = (z ^ (z >> _S27)) * _MUL2
    return z ^ (z >> _S31)


@shared
def path_key(seed, band, pixel, sample):
    """The stream key of one path (all arguments non-negative integers)."""
    key = mix64(np.uint64(seed) * _GOLDEN + np.uint64(band))
    key = mix64(key ^ (np.uint64(pixel) * _MUL1))
    return mix64(key ^ (np.uint64(sample) * _MUL2))


@shared
def uniform(key, counter):
    """The `counter`-th number of stream `key`, uniform in [0, 1)."""
    return (mix64(key + (np.uint64(counter) + np.uint64(1)) * _GOLDEN) >> _S11) * _UNIT
