"""Planck's law: spectral radiance of a black body, in W·sr⁻¹·m⁻²·nm⁻¹ (wavelength in nm, T in K).

Written once, as a plain function of NumPy-compatible arithmetic, so that spectra (tables, with
validated temperatures) and the kernels (per-voxel temperatures, compiled by Numba) share it.
"""

import numpy as np

from .constants import BOLTZMANN, PLANCK, SPEED_OF_LIGHT
from .shared_math import exp, log1p, shared

NANOMETRE = 1e-9  # metres
FIRST_RADIATION_CONSTANT = 2 * PLANCK * SPEED_OF_LIGHT**2  # 2hc², W·m²·sr⁻¹
SECOND_RADIATION_CONSTANT = PLANCK * SPEED_OF_LIGHT / BOLTZMANN  # hc/k, m·K


@shared
def planck_radiance(wavelength_nm, temperature):
    """Black-body spectral radiance per nanometre for T > 0 (0 for T ≤ 0); underflows to 0, never
    overflows (evaluated in log space: log(eˣ − 1) = x + log(1 − e⁻ˣ))."""
    metres = wavelength_nm * NANOMETRE
    x = SECOND_RADIATION_CONSTANT / (metres * np.maximum(temperature, 1e-3))
    log_expm1 = x + log1p(-exp(-x))
    per_metre = exp(np.log(FIRST_RADIATION_CONSTANT) - 5.0 * np.log(metres) - log_expm1)
    return per_metre * NANOMETRE * (temperature > 0)
