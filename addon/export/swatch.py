"""Swatch colours: a spectrum setting → XYZ → linear Rec.709 for a COLOR property to display.

Lights show their colour at full brightness (largest channel 1), reflectances their colour under D65,
absorbers the colour D65 light keeps after one unit of optical depth. Settings that are not colours
(anisotropy) and settings in error show black.
"""

import numpy as np

from ..tracer import colorimetry, spectra
from ..tracer.errors import SpectralError
from .spectra import to_spectrum


def spectrum_colour(spectrum: spectra.Spectrum, role: str) -> np.ndarray:
    """Linear Rec.709 colour of `spectrum` shown as `role` ("light", "reflectance", "absorption")."""
    if role == "light":
        rgb = colorimetry.xyz_to_rgb(colorimetry.spectrum_to_xyz(spectrum.values))
        rgb = np.maximum(rgb, 0.0)
        peak = rgb.max()
        return rgb / peak if peak > 0 else rgb
    d65 = spectra.illuminant("D65").values
    values = spectrum.values if role == "reflectance" else np.exp(-spectrum.values)
    xyz = colorimetry.spectrum_to_xyz(values * d65) / colorimetry.spectrum_to_xyz(d65)[1]
    return np.clip(colorimetry.xyz_to_rgb(xyz), 0.0, 1.0)


def preview_colour(settings) -> tuple[float, float, float]:
    if not settings.ROLE:
        return (0.0, 0.0, 0.0)
    try:
        return tuple(float(c) for c in spectrum_colour(to_spectrum(settings), settings.ROLE))
    except SpectralError:
        return (0.0, 0.0, 0.0)
