"""The film: per-pixel XYZ sums and squared sums for each wavelength band, and what they estimate.

Each band is an independent estimator of its part of the spectrum; the pixel's XYZ is the sum over
bands of each band's sample mean, and its variance (of that estimate) the sum of the bands' variances
of the mean. Accumulators merge by addition, so work split over passes, tiles or machines combines
exactly (up to floating-point summation order).
"""

import numpy as np

from . import colorimetry
from .checks import byte_size, shown
from .errors import SpectralError
from .grids import available_memory

# float64 Σ XYZ and Σ XYZ² per band, plus a tile's pair of accumulators and the XYZ, RGB and
# variance images made at the end.
ACCUMULATOR_BYTES = 2 * 3 * 8
OUTPUT_BYTES = 3 * 3 * 8


def film_bytes(width: int, height: int, bands: int = 1) -> int:
    """Memory a render of this size needs for its film (not counting the scene's grids)."""
    return int(width) * int(height) * (ACCUMULATOR_BYTES * (bands + 1) + OUTPUT_BYTES)


def check_film_memory(width: int, height: int, bands: int = 1) -> None:
    """Refuse a film larger than the memory available, saying how much it would need."""
    needed = film_bytes(width, height, bands)
    available = available_memory()
    if available is not None and needed > available:
        raise SpectralError(f"a {shown(width, 24)}×{shown(height, 24)} film needs {byte_size(needed, 'GiB')} of "
                            f"memory ({bands} band(s)), but only {byte_size(available, 'GiB')} is available")


class Film:
    def __init__(self, width: int, height: int, bands: int = 1):
        check_film_memory(width, height, bands)
        self.width, self.height, self.bands = int(width), int(height), int(bands)
        self.sum_xyz = np.zeros((self.bands, self.height, self.width, 3))
        self.sum_sq = np.zeros_like(self.sum_xyz)
        self.samples = np.zeros(self.bands, dtype=np.int64)

    def add(self, band: int, y0: int, x0: int, sum_xyz: np.ndarray, sum_sq: np.ndarray) -> None:
        """Add a tile's accumulators (rows y0…, columns x0…) for `band`."""
        h, w = sum_xyz.shape[:2]
        self.sum_xyz[band, y0:y0 + h, x0:x0 + w] += sum_xyz
        self.sum_sq[band, y0:y0 + h, x0:x0 + w] += sum_sq

    def count(self, band: int, samples: int) -> None:
        """Record that `samples` more samples per pixel of `band` have been added (whole film)."""
        self.samples[band] += samples

    @property
    def xyz(self) -> np.ndarray:
        """Estimated XYZ per pixel, shape (height, width, 3)."""
        counts = np.maximum(self.samples, 1)[:, None, None, None]
        return (self.sum_xyz / counts).sum(axis=0)

    @property
    def variance(self) -> np.ndarray:
        """Variance of the XYZ estimate per pixel (sample variance / samples, summed over bands)."""
        counts = self.samples[:, None, None, None].astype(np.float64)
        safe = np.maximum(counts, 2)
        mean = self.sum_xyz / np.maximum(counts, 1)
        sample_variance = np.maximum(self.sum_sq / np.maximum(counts, 1) - mean**2, 0) * safe / (safe - 1)
        return np.where(counts > 1, sample_variance / safe, 0.0).sum(axis=0)

    def rgb(self, space: str = "rec709") -> np.ndarray:
        """Linear RGB in `space` (default Rec.709, Blender's scene-linear)."""
        return colorimetry.xyz_to_rgb(self.xyz, space)
