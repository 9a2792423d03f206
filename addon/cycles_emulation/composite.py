"""Cycles renders → XYZ film: each render's R, G, B are three bands, weighted by their XYZ weights.

Each render is made twice with different seeds (two halves of the samples); their mean is the estimate
and (a − b)²/4 per pixel an unbiased estimate of its variance (one degree of freedom, so noisy per pixel,
but exact on average), summed over renders since they are independent. The film offers what the tracer's
Film offers to the outputs: `xyz`, `variance`, `rgb()` and `alpha`.
"""

import numpy as np

from ..tracer import colorimetry


class CompositeFilm:
    bins = 0  # no spectral image: the emulation makes none (`export.passes.without_light_passes`)

    def __init__(self, width: int, height: int):
        self.width, self.height = int(width), int(height)
        self.xyz = np.zeros((self.height, self.width, 3))
        self.variance = np.zeros_like(self.xyz)
        self.renders = 0

    def add(self, first: np.ndarray, second: np.ndarray, weights: np.ndarray) -> None:
        """Add a render's two halves (height, width, channels ≥ len(weights); top row first); `weights`
        (channels used, 3) maps each channel's band value to XYZ."""
        channels = len(weights)
        a = first[..., :channels] @ weights
        b = second[..., :channels] @ weights
        self.xyz += 0.5 * (a + b)
        self.variance += 0.25 * (a - b) ** 2
        self.renders += 1

    def rgb(self, space: str = "rec709") -> np.ndarray:
        return colorimetry.xyz_to_rgb(self.xyz, space)

    @property
    def alpha(self) -> np.ndarray:
        """1 everywhere: Cycles renders the bands with Film ▸ Transparent off (`setup.cycles_settings`)."""
        return np.ones((self.height, self.width))
