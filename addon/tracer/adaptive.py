"""Adaptive sampling: a pixel stops receiving samples once its estimate is as quiet as the noise threshold asks.

The measure is Cycles' Noise Threshold's: a pixel's error is the sum of its R, G and B standard errors
divided by the square root of its R + G + B (so that dark pixels, where the eye forgives more noise, are
judged on a perceptual rather than a relative scale), and a pixel is done when that error is below the
threshold. The standard errors come from the film's own per-pixel variance (`Film.variance`, in XYZ,
taken to linear Rec.709 with the channels treated as independent). A pixel keeps sampling while any of its
eight neighbours does, so that a noisy region's edge is not left behind. No pixel is judged before it has
the minimum number of samples, so that a rare bright path has had its chance to show. Alpha (Film ▸
Transparent) is not judged, as in Cycles, whose measure is on the colour only: a pixel that stops early has
its alpha from the samples it took (it converges with them, and a noisy edge of a volume is noisy in colour too).
"""

import numpy as np

from . import colorimetry
from .film import Film

# The error's denominator floor: black pixels (R + G + B = 0) then need no noise at all, which they have.
ERROR_FLOOR = 1e-4


def minimum_samples(threshold: float, min_samples: int, spp: int) -> int:
    """Samples every pixel receives before it may stop: `min_samples`, or when that is 0, 16 / threshold^0.3
    (64 at the default threshold 0.01; more for stricter thresholds), never more than `spp`."""
    automatic = int(np.ceil(16.0 / threshold**0.3)) if threshold > 0 else spp
    return min(spp, int(min_samples) if min_samples > 0 else automatic)


def pixel_error(film: Film) -> np.ndarray:
    """Each pixel's error (height, width): Σ standard errors of R, G, B over √(R + G + B)."""
    to_rgb = colorimetry.xyz_to_rgb_matrix()
    rgb = film.xyz @ to_rgb.T
    standard_error = np.sqrt(np.maximum(film.variance @ (to_rgb**2).T, 0.0))
    return standard_error.sum(axis=-1) / (ERROR_FLOOR + np.sqrt(np.maximum(rgb.sum(axis=-1), 0.0)))


def active_pixels(film: Film, threshold: float) -> np.ndarray:
    """The pixels that still need samples (height, width, bool): above the threshold, or beside one that is."""
    noisy = pixel_error(film) >= threshold
    padded = np.pad(noisy, 1)
    height, width = noisy.shape
    spread = np.zeros_like(noisy)
    for dy in range(3):
        for dx in range(3):
            spread |= padded[dy:dy + height, dx:dx + width]
    return spread
