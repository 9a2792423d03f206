"""Cycles' black body for glows: Planck's law scaled to luminance σT⁴/π, tabulated for the kernels.

Blender's Cycles emits a black body as the colour of T at luminance 1 times the Stefan–Boltzmann radiance
σT⁴/π (all wavelengths). Spectrally that is Lbb(λ, T) = Planck(λ, T) · (σT⁴/π) / Y(Planck(·, T)), with Y
the luminance under the render's colour matching functions (`colorimetry`: a constant spectrum 1 has Y = 1),
so the film's luminance of Lbb is σT⁴/π whatever the matching functions. The scale spans hundreds of orders
of magnitude over T; the lowering tabulates its logarithm at temperatures evenly spaced in log T, which the
kernels interpolate (`kernels.media.blackbody_normalisation`).
"""

import numpy as np

from . import colorimetry
from .constants import STEFAN_BOLTZMANN
from .planck import planck_radiance
from .wavelengths import GRID

# The table's temperatures (K): beyond them the scale is held at its end value. Interpolating its logarithm
# linearly in log T errs by at most 1.2e-4 relative above 1000 K, 1e-3 at 100 K.
TABLE_KELVIN = (100.0, 100_000.0)
TABLE_NODES = 1024


def stefan_boltzmann_radiance(kelvin):
    """σT⁴/π: a black body's radiance over all wavelengths, W·m⁻²·sr⁻¹."""
    return STEFAN_BOLTZMANN * np.asarray(kelvin, dtype=np.float64) ** 4 / np.pi


def normalisation_table(cmf: str) -> tuple[np.ndarray, np.ndarray]:
    """(log T of the first node and the nodes' spacing, log((σT⁴/π) / Y(Planck(·, T))) at the nodes)."""
    log_kelvin = np.linspace(np.log(TABLE_KELVIN[0]), np.log(TABLE_KELVIN[1]), TABLE_NODES)
    kelvin = np.exp(log_kelvin)
    luminance = colorimetry.spectrum_to_xyz(planck_radiance(GRID[None, :], kelvin[:, None]), cmf)[:, 1]
    return (np.array([log_kelvin[0], log_kelvin[1] - log_kelvin[0]]),
            np.log(stefan_boltzmann_radiance(kelvin)) - np.log(luminance))
