"""The firefly filter (RenderSettings.firefly_threshold): each pixel's brightest sample, clamped where it stands
out from what its neighbourhood's other samples make likely.

A firefly is a rare large sample: an event of probability p per path (a path that reaches a sunlit face through
the peak of the phase function, say) shows in a 16-sample pixel with probability about 16·p, yet leaves no trace
in a 1024-sample image while 1024·p ≪ 1 (bench/README.md, "Speckles of the sunlit Cloud preset"). An unbiased
estimator keeps them; this filter trades a little light at low sample counts for their removal, and the trade
vanishes as samples grow (it is consistent).

The film keeps, per pixel and band, the brightest sample (by luminance Y) whole: its XYZ, and its light
categories' and spectral bins' parts (`Peaks`; merged by maximum, so any split of the work keeps the same one).
When the render ends (`filtered`), each pixel's neighbourhood (3×3 pixels) gives the mean μ and per-sample
standard deviation σ of Y over its samples, leaving out each pixel's brightest one (so that two fireflies side by
side do not hide each other). A brightest sample above
T = μ + k·σ·√n (k the threshold, n the pixel's samples) would move its pixel's mean by more than k of the
neighbourhood's standard errors: it is scaled down to T, colour kept, as Light Paths ▸ Clamping scales a sample.
For an estimator of finite variance the largest of n samples grows slower than √n, so the chance that any
sample is clamped falls to 0 as samples grow.
"""

from dataclasses import dataclass

import numpy as np

NEIGHBOURHOOD = 1  # the neighbourhood's reach in pixels: 3×3


@dataclass
class Peaks:
    """The brightest sample of each pixel of a tile (height, width): its Y, XYZ (…, 3), light categories' XYZ
    (…, categories, 3) and spectral bins (…, bins). Y is −∞ where no sample has arrived."""

    y: np.ndarray
    xyz: np.ndarray
    light: np.ndarray
    spectrum: np.ndarray

    @classmethod
    def none(cls, height: int, width: int, light_categories: int = 0, bins: int = 0) -> "Peaks":
        return cls(np.full((height, width), -np.inf), np.zeros((height, width, 3)),
                   np.zeros((height, width, light_categories, 3)), np.zeros((height, width, bins)))

    def keep(self, xyz: np.ndarray, light: np.ndarray, spectrum: np.ndarray,
             region: tuple[slice, slice] = (slice(None), slice(None))) -> None:
        """Keep, in `region`, each pixel's sample (`xyz`, `light`, `spectrum` of one sample, or other peaks')
        where it is brighter than the one kept."""
        brighter = xyz[..., 1] > self.y[region]
        self.y[region] = np.where(brighter, xyz[..., 1], self.y[region])
        self.xyz[region] = np.where(brighter[..., None], xyz, self.xyz[region])
        if self.light.shape[-2]:
            self.light[region] = np.where(brighter[..., None, None], light, self.light[region])
        if self.spectrum.shape[-1]:
            self.spectrum[region] = np.where(brighter[..., None], spectrum, self.spectrum[region])


def _window_sum(image: np.ndarray) -> np.ndarray:
    """Σ over each pixel's neighbourhood (pixels outside the image count as 0)."""
    reach = NEIGHBOURHOOD
    padded = np.pad(image, reach)
    height, width = image.shape
    return sum(padded[dy:dy + height, dx:dx + width] for dy in range(2 * reach + 1) for dx in range(2 * reach + 1))


def limits(sum_y: np.ndarray, sum_y2: np.ndarray, samples: np.ndarray, peak_y: np.ndarray,
           threshold: float) -> np.ndarray:
    """T = μ + k·σ·√n per pixel of one band (module docstring): μ and σ over the neighbourhood's samples but each
    pixel's brightest; +∞ where fewer than two samples arrived or nothing else is known."""
    has_peak = samples > 0
    own_peak = np.where(has_peak, peak_y, 0.0)
    others = _window_sum(samples - has_peak.astype(np.float64))
    safe = np.maximum(others, 1)
    mean = _window_sum(sum_y - own_peak) / safe
    spread = np.maximum(_window_sum(sum_y2 - own_peak ** 2) / safe - mean ** 2, 0.0)
    limit = mean + threshold * np.sqrt(spread) * np.sqrt(samples)
    return np.where((samples >= 2) & (others >= 1), limit, np.inf)


def filtered(film, threshold: float):
    """`film` with each pixel's brightest sample of each band scaled down to its limit where it exceeds it
    (module docstring); the film itself is left as it is. Needs the film's peaks (`Film.peaks`)."""
    result = film.copy()
    for band, peaks in enumerate(film.peaks):
        limit = limits(film.sum_xyz[band, ..., 1], film.sum_sq[band, ..., 1], film.pixel_samples[band], peaks.y,
                       threshold)
        over = peaks.y > limit
        if not over.any():
            continue
        kept = np.where(over, limit / np.where(over, peaks.y, 1.0), 1.0)  # the peak's share that stays
        result.sum_xyz[band] -= (1.0 - kept)[..., None] * peaks.xyz
        result.sum_sq[band] -= (1.0 - kept ** 2)[..., None] * peaks.xyz ** 2
        result.sum_light[band] -= (1.0 - kept)[..., None, None] * peaks.light
        result.sum_spectrum[band] -= (1.0 - kept)[..., None] * peaks.spectrum
    return result
