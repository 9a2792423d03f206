"""The spectral image a render keeps beside its XYZ when the scene asks for it (`render.spectrum`): its bins from the
settings (`bin_edges`, checked by `check_bins`) and what its values are measured in (`radiance_units`).

Each pixel holds, per bin, the mean spectral radiance over the bin in the scene's radiance units per nm
(`kernels/spectrum_bins.py` estimates it; `Film.spectrum` sums the bands). Those units are W·m⁻²·sr⁻¹·nm⁻¹ where every
source of light in the scene is given in absolute terms (lengths in metres, one Blender unit each): lights with a
`"radiant"` strength (watts; Blender's lights, which the exporter writes so), envmaps, emissive surfaces, media's
thermal emission (Planck's law) and a glow's spectrum. A light with a `"luminous"` strength (scaled so that its
luminance Y, normalised so that a constant spectrum 1 has Y = 1, is the strength) or a glow's black body (Cycles'
normalisation to luminance σT⁴/π) makes them relative: the same numbers up to an unknown factor per source.
`image_io.spectral_exr` writes the image in the layout of Fichet et al. 2021.
"""

import numpy as np

from . import checks
from .errors import SpectralError

# The most bins a spectral image may have (1 nm bins over the whole grid, 250–830 nm, are 580).
MAX_BINS = 1000
ABSOLUTE_UNITS = "W.m^-2.sr^-1"  # the layout's `emissiveUnits` for spectral radiance (per nm, the channels' unit)
RELATIVE_UNITS = "relative"


def bin_count(settings) -> int:
    """The number of bins of the settings' spectral image (0 when it keeps none)."""
    if not settings.spectrum:
        return 0
    return int(round((settings.spectrum_end - settings.spectrum_start) / settings.spectrum_step))


def bin_edges(settings) -> np.ndarray:
    """The edges of the spectral image's bins in nm, (bins + 1,), uniform; empty when it keeps none."""
    count = bin_count(settings)
    if count == 0:
        return np.zeros(0)
    return np.linspace(float(settings.spectrum_start), float(settings.spectrum_end), count + 1)


def check_bins(settings, where: str = "render") -> None:
    """The spectral image's part of `validation.check_settings`: with `spectrum` on, bins from `spectrum_start` to
    `spectrum_end` in steps of `spectrum_step` nm, inside the wavelengths the camera samples."""
    if not isinstance(settings.spectrum, (bool, np.bool_)):
        raise SpectralError(f"{where}.spectrum: expected true or false, found {checks.shown(settings.spectrum)}")
    start, end, step = (checks.number(getattr(settings, key), f"{where}.{key}")
                        for key in ("spectrum_start", "spectrum_end", "spectrum_step"))
    if not settings.spectrum:
        return
    from .wavelength_modes import default_band  # the camera's range, where it is chosen

    lo, hi = default_band(settings)
    checks.within(start, f"{where}.spectrum_start", lo, hi)
    checks.within(end, f"{where}.spectrum_end", lo, hi)
    if not start < end:
        raise SpectralError(f"{where}.spectrum_end: must be above spectrum_start ({start:g} nm), found {end:g} nm")
    if not step > 0:
        raise SpectralError(f"{where}.spectrum_step: must be above 0 nm, found {step:g}")
    steps = (end - start) / step
    if abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        raise SpectralError(f"{where}.spectrum_step: {start:g}–{end:g} nm is not a whole number of {step:g} nm "
                            f"steps ({steps:.4g}): choose a step that divides it")
    if round(steps) > MAX_BINS:
        raise SpectralError(f"{where}.spectrum_step: {start:g}–{end:g} nm in {step:g} nm steps makes {round(steps)} "
                            f"bins, more than the {MAX_BINS} a spectral image may have")


def radiance_units(scene) -> str:
    """The layout's `emissiveUnits` for the scene's spectral image: `ABSOLUTE_UNITS` where every source of light is
    given in absolute units (the module docstring), else `RELATIVE_UNITS`."""
    absolute = all(light.unit == "radiant" for light in scene.lights)
    absolute = absolute and not any(medium.glow is not None and medium.glow.blackbody > 0 for medium in scene.media)
    return ABSOLUTE_UNITS if absolute else RELATIVE_UNITS


def channel_wavelength(centre: float) -> str:
    """A bin centre as the layout names it: in nm with at most three decimals, a comma for the decimal point (a
    dot separates an EXR channel's layers), e.g. `385`, `382,5`."""
    return f"{centre:.3f}".rstrip("0").rstrip(".").replace(".", ",")
