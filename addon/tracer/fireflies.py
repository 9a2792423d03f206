"""The firefly filter (RenderSettings.firefly_threshold): each pixel's brightest group of samples, scaled down where
it stands out from what its neighbourhood's other samples make likely.

A firefly is a rare large sample: an event of probability p per path (a path that reaches a sunlit face through
the peak of the phase function, say) shows in a 16-sample pixel with probability about 16·p, yet leaves no trace
in a 1024-sample image while 1024·p ≪ 1 (bench/README.md, "Speckles of the sunlit Cloud preset"). An unbiased
estimator keeps them; this filter trades a little light at low sample counts for their removal, and the trade
vanishes as samples grow (it is consistent).

A pixel's samples are taken in groups of g consecutive samples (`group_size`: 4 from 16 samples on, fewer below, so
that every pixel has at least 4 groups), one kernel call per group: a call of one sample per pixel runs 1.2–1.3×
slower per sample than one of 16, one of 4 about 1.05× (bench/README.md, "The firefly filter"), and on the sunlit
Cloud preset groups of 1, 2 and 4 at 16 samples removed the same fireflies. Larger groups would cost less still but
hold back the render's first whole image, which comes after one group of samples.

The film keeps, per pixel and band, the brightest group (by its Σ Y) whole: its Σ XYZ, Σ XYZ² and its light
categories' and spectral bins' sums (`Peaks`; merged by maximum, so any split of the work keeps the same one). When
the render ends (`filtered`), each pixel's neighbourhood (3×3 pixels) gives the mean μ and per-sample standard
deviation σ of Y over its samples, leaving out each pixel's brightest group (so that two fireflies side by side do
not hide each other). A group's sum has mean g·μ and standard deviation √g·σ over n/g groups: a brightest group
above T = g·μ + k·σ·√n (k the threshold, n the pixel's samples) would move its pixel's mean by more than k of the
neighbourhood's standard errors. It is scaled down to T, colour kept, as Light Paths ▸ Clamping scales a sample. For
an estimator of finite variance the largest of n/g group sums grows slower than √n, so the chance that any group is
scaled falls to 0 as samples grow.
"""

from dataclasses import dataclass

import numpy as np

NEIGHBOURHOOD = 1  # the neighbourhood's reach in pixels: 3×3
MIN_GROUPS = 4  # groups per pixel, at least, where the samples allow
MAX_GROUP = 4  # samples per group, at most


def group_size(spp: int) -> int:
    """Samples per group for a render of `spp`: the largest power of two up to MAX_GROUP that divides `spp` and
    leaves MIN_GROUPS groups (1 below 8 samples or for an odd count)."""
    size = 1
    while size * 2 <= MAX_GROUP and spp % (size * 2) == 0 and spp // (size * 2) >= MIN_GROUPS:
        size *= 2
    return size


@dataclass
class Peaks:
    """The brightest group of samples of each pixel of a tile (height, width): its Σ XYZ (…, 3), Σ XYZ² (…, 3),
    light categories' Σ XYZ (…, categories, 3) and spectral bins' Σ (…, bins); all 0 where no group has arrived."""

    xyz: np.ndarray
    sq: np.ndarray
    light: np.ndarray
    spectrum: np.ndarray

    @classmethod
    def none(cls, height: int, width: int, light_categories: int = 0, bins: int = 0) -> "Peaks":
        return cls(np.zeros((height, width, 3)), np.zeros((height, width, 3)),
                   np.zeros((height, width, light_categories, 3)), np.zeros((height, width, bins)))

    @classmethod
    def of(cls, sum_xyz, sum_sq, sum_light, sum_spectrum) -> "Peaks":
        """One group's sums (a unit's accumulators over the group's samples) as the peaks of its tile."""
        return cls(sum_xyz, sum_sq, sum_light, sum_spectrum)

    @property
    def y(self) -> np.ndarray:
        """Σ Y of each pixel's group: what "brightest" ranks by."""
        return self.xyz[..., 1]

    def keep(self, other: "Peaks", region: tuple[slice, slice] = (slice(None), slice(None))) -> None:
        """Keep, in `region`, each pixel's group of `other` where it is brighter than the one kept (a group of
        Y 0 changes nothing the filter uses: it is never above a limit)."""
        brighter = other.y > self.y[region]
        self.xyz[region] = np.where(brighter[..., None], other.xyz, self.xyz[region])
        self.sq[region] = np.where(brighter[..., None], other.sq, self.sq[region])
        self.light[region] = np.where(brighter[..., None, None], other.light, self.light[region])
        self.spectrum[region] = np.where(brighter[..., None], other.spectrum, self.spectrum[region])


def _window_sum(image: np.ndarray) -> np.ndarray:
    """Σ over each pixel's neighbourhood (pixels outside the image count as 0)."""
    reach = NEIGHBOURHOOD
    padded = np.pad(image, reach)
    height, width = image.shape
    return sum(padded[dy:dy + height, dx:dx + width] for dy in range(2 * reach + 1) for dx in range(2 * reach + 1))


def limits(sum_y: np.ndarray, sum_y2: np.ndarray, samples: np.ndarray, peaks: Peaks,
           group: int) -> tuple[np.ndarray, np.ndarray]:
    """(g·μ, σ·√n) per pixel of one band, whose limit is g·μ + k·σ·√n (module docstring): μ and σ over the
    neighbourhood's samples but each pixel's brightest group; σ·√n is +∞ where a pixel has fewer than two groups
    or its neighbourhood nothing else."""
    others = _window_sum(samples - group * (samples > 0).astype(np.float64))
    safe = np.maximum(others, 1)
    mean = _window_sum(sum_y - peaks.y) / safe
    spread = np.sqrt(np.maximum(_window_sum(sum_y2 - peaks.sq[..., 1]) / safe - mean**2, 0.0))
    scaled = np.where((samples >= 2 * group) & (others >= 1), spread * np.sqrt(samples), np.inf)
    return group * mean, scaled


def filtered(film, threshold: float):
    """`film` with each pixel's brightest group of each band scaled down to its limit where it exceeds it
    (module docstring); the film itself is left as it is. Needs the film's peaks (`Film.peaks`, `Film.group`)."""
    result = film.copy()
    for band, peaks in enumerate(film.peaks):
        base, scaled = limits(film.sum_xyz[band, ..., 1], film.sum_sq[band, ..., 1], film.pixel_samples[band], peaks,
                              film.group)
        limit = base + threshold * scaled
        over = peaks.y > limit
        if not over.any():
            continue
        kept = np.where(over, limit / np.where(over, peaks.y, 1.0), 1.0)  # the group's share that stays
        result.sum_xyz[band] -= (1.0 - kept)[..., None] * peaks.xyz
        result.sum_sq[band] -= (1.0 - kept**2)[..., None] * peaks.sq
        result.sum_light[band] -= (1.0 - kept)[..., None, None] * peaks.light
        result.sum_spectrum[band] -= (1.0 - kept)[..., None] * peaks.spectrum
    return result


def as_finished(film, threshold: float):
    """A film still rendering, as the finished render will show it: filtered where it keeps peaks (the fireflies
    would otherwise show in the progress images until the last sample, then vanish)."""
    return filtered(film, threshold) if film.peaks else film
