"""Spectrum settings (addon.props.spectrum) → tracer Spectrum.

Every problem (a missing CSV file, a colour outside [0, 1], an empty window) is a SpectralError that
names the setting, so panels and the exporter can show it as is.
"""

import bpy
import numpy as np

from .. import curves
from ..props.spectrum import BANDS
from ..tracer import spectra
from ..tracer.errors import SpectralError
from ..tracer.spectra import Spectrum


def describe(settings) -> str:
    """Where a spectrum setting lives, for messages: "Material 'Smoke' albedo_levels[0].spectrum"."""
    owner = settings.id_data
    return f"{type(owner).__name__} {owner.name!r} {settings.path_from_id().removeprefix('spectral.')}"


def to_spectrum(settings) -> Spectrum:
    """The tracer Spectrum a spectrum setting describes (a light's wavelength window applied)."""
    try:
        spectrum = _shape(settings)
    except SpectralError as problem:
        raise SpectralError(f"{describe(settings)}: {problem}") from None
    if getattr(settings, "use_window", False):
        spectrum = spectra.window(spectrum, settings.window_min, settings.window_max)
    return spectrum


def _shape(settings) -> Spectrum:
    source = settings.source
    if source == "CONSTANT":
        return spectra.constant(settings.value)
    if source == "ILLUMINANT":
        return spectra.illuminant(settings.illuminant)
    if source == "BLACKBODY":
        return spectra.blackbody(settings.temperature)
    if source == "BAND":
        _label, peak, width = BANDS[settings.band]
        return spectra.gaussian(peak, width, getattr(settings, "value", 1.0))
    if source == "GAUSSIAN":
        return spectra.gaussian(settings.peak, settings.width, getattr(settings, "value", 1.0))
    if source == "COLOR":
        reflectance = spectra.from_rgb(tuple(settings.color), settings.rgb_method)
        return reflectance * spectra.illuminant("D65") if settings.ROLE == "light" else reflectance
    if source == "CURVE":
        mapping = curves.find_mapping(settings.curve)
        if mapping is None:
            raise SpectralError("the curve is missing: choose the Curve source again to create it")
        return Spectrum(np.clip(curves.sample(mapping), *settings.Y_RANGE))
    if source == "CSV":
        if not settings.filepath:
            raise SpectralError("no CSV file chosen")
        return spectra.from_csv(bpy.path.abspath(settings.filepath), settings.units)
    raise SpectralError(f"unknown spectrum source {source!r}")
