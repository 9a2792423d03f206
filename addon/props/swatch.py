"""Swatch colours: a spectrum setting → XYZ → linear Rec.709 for a COLOR property to display.

Lights show their colour at full brightness (largest channel 1), reflectances their colour under D65,
absorbers the colour D65 light keeps after one unit of optical depth. Settings that are not colours
(anisotropy) and settings in error show black.

Swatches are drawn on every redraw, so they never recover a spectrum from an RGB colour (a tenth of a
second or more): a Color spectrum not computed yet shows its colour, which is what the recovery matches
(before a light's wavelength window; the windowed colour shows once the spectrum has been computed,
by a render, an export or Edit as Curve).
"""

import numpy as np

from ..tracer import colorimetry, spectra
from ..tracer.errors import SpectralError
from .spectrum_values import cached, to_spectrum


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


def rgb_colour(rgb, role: str) -> np.ndarray:
    """The swatch of a spectrum recovered from `rgb` (a reflectance, or a light: reflectance × D65)."""
    rgb = np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0)
    peak = rgb.max()
    return rgb / peak if role == "light" and peak > 0 else rgb


def preview_colour(settings) -> tuple[float, float, float]:
    if not settings.ROLE:
        return (0.0, 0.0, 0.0)
    try:
        if settings.source == "COLOR" and cached(settings) is None:
            colour = rgb_colour(settings.color, settings.ROLE)
        else:
            colour = spectrum_colour(to_spectrum(settings), settings.ROLE)
    except SpectralError:
        return (0.0, 0.0, 0.0)
    return tuple(float(c) for c in colour)
