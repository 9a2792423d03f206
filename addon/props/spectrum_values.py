"""Spectrum settings (addon.props.spectrum) → tracer Spectrum, remembered by content.

Every problem (a missing CSV file, a colour outside [0, 1], an empty window) is a SpectralError that
names the setting, so panels and the exporter can show it as is.

Panels redraw many times a second, so spectra (and their problems) are remembered by what they are
made of: the setting's values, a curve's points, a CSV file's path, modification time and size. A
redraw then costs a look-up; only a changed setting, curve or file is computed again.
"""

import os
from collections import OrderedDict

import bpy
import numpy as np

from . import curves
from ..tracer import spectra
from ..tracer.errors import SpectralError
from ..tracer.spectra import Spectrum


def describe(settings) -> str:
    """Where a spectrum setting lives, for messages: "Material 'Smoke' albedo_levels[0].spectrum"."""
    owner = settings.id_data
    return f"{type(owner).__name__} {owner.name!r} {settings.path_from_id().removeprefix('spectral.')}"


CACHE_SIZE = 512
_cache: OrderedDict = OrderedDict()  # content key → Spectrum or SpectralError
_SKIPPED = {"rna_type", "preview", "curve"}  # not content (preview is computed from the spectrum)


def _value(value):
    return tuple(value) if hasattr(value, "__len__") and not isinstance(value, str) else value


def csv_path(settings) -> str:
    """The absolute path of a setting's CSV file ("//" is the folder of the .blend file it lives in)."""
    return bpy.path.abspath(settings.filepath, library=settings.id_data.library)


def content_key(settings) -> tuple:
    """Everything the spectrum of `settings` depends on: equal keys give equal spectra."""
    values = tuple((name, _value(getattr(settings, name))) for name in settings.bl_rna.properties.keys()
                   if name not in _SKIPPED)
    extra = None
    if settings.source == "CURVE":
        mapping = curves.find_mapping(settings.curve)
        extra = None if mapping is None else (mapping.extend, tuple(
            (tuple(point.location), point.handle_type) for point in mapping.curves[0].points))
    elif settings.source == "CSV" and settings.filepath:
        path = csv_path(settings)
        try:
            status = os.stat(path)
            extra = (path, status.st_mtime_ns, status.st_size)
        except OSError:
            extra = (path, None, None)
    return type(settings).__name__, describe(settings), values, extra


def cached(settings) -> Spectrum | None:
    """The spectrum of `settings` when it has been computed for this content already, else None."""
    found = _cache.get(content_key(settings))
    return found if isinstance(found, Spectrum) else None


def to_spectrum(settings) -> Spectrum:
    """The tracer Spectrum a spectrum setting describes (a light's wavelength window applied)."""
    key = content_key(settings)
    found = _cache.get(key)
    if found is None:
        try:
            found = _compute(settings)
        except SpectralError as problem:
            found = problem
        _cache[key] = found
        if len(_cache) > CACHE_SIZE:
            _cache.popitem(last=False)
    else:
        _cache.move_to_end(key)
    if isinstance(found, SpectralError):
        raise found
    return found


def _compute(settings) -> Spectrum:
    try:
        spectrum = _shape(settings)
    except SpectralError as problem:
        raise SpectralError(f"{describe(settings)}: {problem}") from None
    if getattr(settings, "use_window", False):
        spectrum = spectra.window(spectrum, settings.window_min, settings.window_max)
    return spectrum


def problem(settings) -> str | None:
    """What is wrong with a spectrum setting, or None; never recovers a spectrum from RGB (slow), since
    a colour setting has nothing to go wrong but its window."""
    try:
        if settings.source == "COLOR":
            if getattr(settings, "use_window", False):
                spectra.window(spectra.constant(1.0), settings.window_min, settings.window_max)
        else:
            to_spectrum(settings)
    except SpectralError as error:
        return str(error)
    return None


def _shape(settings) -> Spectrum:
    source = settings.source
    if source == "CONSTANT":
        return spectra.constant(settings.value)
    if source == "ILLUMINANT":
        return spectra.illuminant(settings.illuminant)
    if source == "BLACKBODY":
        return spectra.blackbody(settings.temperature)
    if source == "BAND":
        _label, peak, width = spectra.BANDS[settings.band]
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
        return spectra.from_csv(csv_path(settings), settings.units)
    raise SpectralError(f"unknown spectrum source {source!r}")
