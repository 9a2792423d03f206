"""Wavelength bands of the Cycles emulation: their edges, their XYZ weights, band means of spectra, and how
bands are packed into Cycles renders.

Band k covers the grid nodes lo_k ≤ λ < hi_k (the last band includes its upper edge), so the bands
partition the rendered range and their XYZ weights w_k = Σ_band c (the tracer's quadrature, node by node:
`colorimetry.integration_weights`) add up to the XYZ of a constant spectrum of 1: Y = 1 over the
visible range. Shaped by a reference spectrum (the scene's lights), the weights make that spectrum's XYZ
exact however wide the bands: the light's colour is not distorted by the band approximation. A spectrum
enters a band as its mean weighted by x̄ + ȳ + z̄ (what the eye sees of the band), or its plain mean where
the band lies outside the colour matching functions.

Cycles renders three bands at once in its R, G and B channels, but its phase functions do not vary per
channel (three Henyey–Greenstein lobes weighted pure R, G and B render grey): bands share a render only
when every medium has the same phase function in all of them.
"""

from dataclasses import dataclass

import numpy as np

from ..tracer import colorimetry
from ..tracer.errors import SpectralError
from ..tracer.sampling import band_ranges
from ..tracer.wavelengths import GRID

CHANNELS = 3  # R, G, B of one Cycles render


@dataclass(frozen=True)
class Bands:
    """K contiguous bands over [edges[0], edges[-1]] nm; `masks[k]` selects band k's grid nodes."""

    edges: tuple[float, ...]

    @property
    def count(self) -> int:
        return len(self.edges) - 1

    @property
    def masks(self) -> np.ndarray:
        """(K, GRID.size) booleans."""
        lo, hi = np.array(self.edges[:-1])[:, None], np.array(self.edges[1:])[:, None]
        masks = (GRID >= lo) & (GRID < hi)
        masks[-1] |= GRID == self.edges[-1]
        return masks

    def label(self, k: int) -> str:
        return f"{self.edges[k]:g}–{self.edges[k + 1]:g} nm"


def split(lo: float, hi: float, count: int) -> Bands:
    """`count` bands of whole nanometres over [lo, hi] (widths differ by at most 1 nm)."""
    ranges = band_ranges(int(round(lo)), int(round(hi)), count)
    return Bands(tuple(float(edge) for edge in [ranges[0][0]] + [band_hi for _lo, band_hi in ranges]))


def xyz_weights(bands: Bands, cmf: str = "cie1931", reference=None) -> np.ndarray:
    """(K, 3): XYZ = Σ_k value_k · weights[k] for a spectrum with band means value_k shaped within each band
    like `reference` (default flat): weights[k] = Σ_band c · reference / band mean of reference.
    Exact for the reference itself (and any multiple of it per band), so for a light of that spectrum."""
    masks = bands.masks.astype(np.float64)
    if reference is None:
        return masks @ colorimetry.integration_weights(cmf).T
    reference = np.asarray(reference, dtype=np.float64)
    means = band_means(reference, bands, cmf)
    flat = xyz_weights(bands, cmf)
    shaped = masks @ (colorimetry.integration_weights(cmf) * reference).T
    usable = means > 1e-12 * max(float(means.max()), 1e-300)
    return np.where(usable[:, None], shaped / np.where(usable, means, 1.0)[:, None], flat)


def band_means(values, bands: Bands, cmf: str = "cie1931") -> np.ndarray:
    """Band means of spectra tabulated on GRID: (..., GRID.size) → (..., K)."""
    values = np.asarray(values, dtype=np.float64)
    importance = colorimetry.cmf(cmf).sum(axis=0)
    weights = bands.masks * importance
    empty = weights.sum(axis=1) <= 0
    weights[empty] = bands.masks[empty]  # a band the eye does not see: plain mean
    weights /= weights.sum(axis=1, keepdims=True)
    return values @ weights.T


def pack(keys) -> tuple[tuple[int, ...], ...]:
    """Band indices grouped into Cycles renders of at most three bands, only bands with equal keys (their
    phase functions) together; in band order. Constant keys give ceil(K/3) renders, all different K."""
    groups: dict = {}
    for k, key in enumerate(keys):
        groups.setdefault(key, []).append(k)
    renders = [tuple(members[i:i + CHANNELS]) for members in groups.values()
               for i in range(0, len(members), CHANNELS)]
    if not renders:
        raise SpectralError("the Cycles emulation needs at least one wavelength band")
    return tuple(sorted(renders))
