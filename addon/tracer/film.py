"""The film: per-pixel XYZ sums and squared sums, transparency sums and, for the light passes, each light
category's XYZ sums (`kernels/light_split.py`) for each wavelength band (and, for a spectral image, sums of each
wavelength bin's estimate), and what they estimate.

Each band is an independent estimator of its part of the spectrum; the pixel's XYZ is the sum over
bands of each band's sample mean, and its variance (of that estimate) the sum of the bands' variances
of the mean. Its alpha is 1 − the sum over bands of each band's mean transparency (`kernels/transparency.py`:
the share of the background its camera paths saw, 0 without Film ▸ Transparent, so alpha 1); the colour is
premultiplied by it, as Cycles' is. Its spectrum (with bins, `spectral_film`) is the sum over bands of each band's
mean per bin, as its XYZ is.
Accumulators merge by addition, so work split over passes, tiles or machines combines
exactly (up to floating-point summation order). Samples are counted per pixel, so a film that holds
part of a pass (some tiles done, others not) is still a consistent image. For the firefly filter a film may also
keep each pixel's brightest group of samples per band (`fireflies.Peaks`), merged by maximum.
"""

import numpy as np

from . import colorimetry
from .checks import byte_size, shown
from .errors import SpectralError
from .fireflies import Peaks
from .grids import available_memory

# float64 Σ XYZ, Σ XYZ² and Σ transparency and an int64 sample count per band, plus a tile's accumulators and
# the XYZ, RGB, variance and alpha images made at the end; for a spectral image, a float64 Σ per bin and band (and
# the tile's), and the spectrum made at the end.
ACCUMULATOR_BYTES = 2 * 3 * 8 + 8 + 8
OUTPUT_BYTES = 3 * 3 * 8 + 8
BIN_BYTES = 8


def film_bytes(width: int, height: int, bands: int = 1, bins: int = 0) -> int:
    """Memory a render of this size needs for its film (not counting the scene's grids)."""
    return int(width) * int(height) * ((ACCUMULATOR_BYTES + BIN_BYTES * bins) * (bands + 1) + OUTPUT_BYTES
                                       + BIN_BYTES * bins)


def check_film_memory(width: int, height: int, bands: int = 1, bins: int = 0) -> None:
    """Refuse a film larger than the memory available, saying how much it would need."""
    needed = film_bytes(width, height, bands, bins)
    available = available_memory()
    if available is not None and needed > available:
        spectral = f", {bins} spectral bins" if bins else ""
        raise SpectralError(f"a {shown(width, 24)}×{shown(height, 24)} film needs {byte_size(needed, 'GiB')} of "
                            f"memory ({bands} band(s){spectral}), but only {byte_size(available, 'GiB')} is available")


class Film:
    """`light_categories`: the light categories kept for the light passes (`kernels/light_split.py`; 0: none);
    `spectrum_edges`: the edges of the spectral image's bins in nm (`spectral_film.bin_edges`; empty: none)."""

    def __init__(self, width: int, height: int, bands: int = 1, light_categories: int = 0, spectrum_edges=(),
                 group: int = 0):
        self.spectrum_edges = np.asarray(spectrum_edges, dtype=np.float64)
        self.bins = max(self.spectrum_edges.size - 1, 0)
        check_film_memory(width, height, bands * (1 + light_categories + (group > 0)), self.bins)
        self.width, self.height, self.bands = int(width), int(height), int(bands)
        self.light_categories = int(light_categories)
        # Σ XYZ of each light category (`kernels/light_split.py`), for the light passes (`light_passes`)
        self.sum_light = np.zeros((self.bands, self.height, self.width, self.light_categories, 3))
        self.sum_xyz = np.zeros((self.bands, self.height, self.width, 3))
        self.sum_sq = np.zeros_like(self.sum_xyz)
        self.sum_transparent = np.zeros((self.bands, self.height, self.width))
        self.sum_spectrum = np.zeros((self.bands, self.height, self.width, self.bins))
        self.pixel_samples = np.zeros((self.bands, self.height, self.width), dtype=np.int64)
        # for the firefly filter (`fireflies`): the samples per group, and each band's brightest group per pixel
        # (none when `group` is 0)
        self.group = int(group)
        self.peaks = [Peaks.none(self.height, self.width, self.light_categories, self.bins)
                      for _ in range(self.bands)] if group else []

    def copy(self) -> "Film":
        """A film with copies of this one's sums (and the same peaks)."""
        film = Film.__new__(Film)
        film.__dict__.update(self.__dict__)
        for name in ("sum_light", "sum_xyz", "sum_sq", "sum_transparent", "sum_spectrum", "pixel_samples"):
            setattr(film, name, getattr(self, name).copy())
        return film

    def add(self, band: int, y0: int, x0: int, sum_xyz: np.ndarray, sum_sq: np.ndarray, samples: int,
            sum_transparent: np.ndarray | None = None, sum_light: np.ndarray | None = None,
            sum_spectrum: np.ndarray | None = None, peaks: Peaks | None = None) -> None:
        """Add a tile's accumulators (rows y0…, columns x0…) over `samples` samples per pixel of `band`
        (`sum_transparent` None: samples that saw no background; `sum_light` None: no light categories;
        `sum_spectrum` None: no spectrum; `peaks`: the tile's brightest groups, kept where the film keeps them)."""
        h, w = sum_xyz.shape[:2]
        self.sum_xyz[band, y0:y0 + h, x0:x0 + w] += sum_xyz
        self.sum_sq[band, y0:y0 + h, x0:x0 + w] += sum_sq
        if sum_transparent is not None:
            self.sum_transparent[band, y0:y0 + h, x0:x0 + w] += sum_transparent
        if sum_light is not None and self.light_categories:
            self.sum_light[band, y0:y0 + h, x0:x0 + w] += sum_light
        if sum_spectrum is not None and self.bins:
            self.sum_spectrum[band, y0:y0 + h, x0:x0 + w] += sum_spectrum
        self.pixel_samples[band, y0:y0 + h, x0:x0 + w] += samples
        if peaks is not None and self.peaks:
            self.peaks[band].keep(peaks, (slice(y0, y0 + h), slice(x0, x0 + w)))

    @property
    def samples(self) -> np.ndarray:
        """Samples per pixel that every pixel holds, per band (shape (bands,))."""
        return self.pixel_samples.reshape(self.bands, -1).min(axis=1)

    @property
    def xyz(self) -> np.ndarray:
        """Estimated XYZ per pixel, shape (height, width, 3)."""
        counts = np.maximum(self.pixel_samples, 1)[..., None]
        return (self.sum_xyz / counts).sum(axis=0)

    @property
    def spectrum(self) -> np.ndarray:
        """Estimated mean spectral radiance over each bin per pixel, shape (height, width, bins): the sum over bands
        of each band's mean (0 where no sample has arrived)."""
        return (self.sum_spectrum / np.maximum(self.pixel_samples, 1)[..., None]).sum(axis=0)

    @property
    def light_xyz(self) -> np.ndarray:
        """Estimated XYZ of each light category per pixel, shape (height, width, categories, 3); they sum to `xyz`."""
        counts = np.maximum(self.pixel_samples, 1)[..., None, None]
        return (self.sum_light / counts).sum(axis=0)

    @property
    def alpha(self) -> np.ndarray:
        """Estimated alpha per pixel, shape (height, width): 1 − the mean transparency, summed over bands (1
        where no sample has arrived). Not clipped: a stochastic estimate may stray past 0 or 1 by its noise."""
        return 1.0 - (self.sum_transparent / np.maximum(self.pixel_samples, 1)).sum(axis=0)

    @property
    def mean_xyz(self) -> np.ndarray:
        """Mean of `xyz` over the image, without forming `xyz` (quick at any size)."""
        weights = 1.0 / np.maximum(self.pixel_samples, 1)
        return np.einsum("bhwc,bhw->c", self.sum_xyz, weights) / (self.width * self.height)

    @property
    def variance(self) -> np.ndarray:
        """Variance of the XYZ estimate per pixel (sample variance / samples, summed over bands; 0 below two
        samples). Formed in place: a 1920×1080 film's temporaries are 50 MB each."""
        counts = self.pixel_samples[..., None].astype(np.float64)
        divisor = np.maximum(counts, 1)
        mean_squared = self.sum_xyz / divisor
        mean_squared *= mean_squared
        spread = self.sum_sq / divisor
        spread -= mean_squared
        np.maximum(spread, 0, out=spread)
        spread /= np.maximum(counts - 1, 1)  # E[x²] − mean² is the biased variance: n/(n − 1) of it, over n
        spread *= counts > 1
        return spread.sum(axis=0)

    def rgb(self, space: str = "rec709") -> np.ndarray:
        """Linear RGB in `space` (default Rec.709, Blender's scene-linear)."""
        return colorimetry.xyz_to_rgb(self.xyz, space)
