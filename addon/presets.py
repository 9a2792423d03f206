"""Presets for light spectra and volume materials: plain data, and applying it to settings.

A preset is a dict of setting paths (relative to the settings it applies to) and values; a value
that is a list of (nm, value) pairs is a curve's points. Applying a preset first resets every other
setting to its default, so nothing of the previous look lingers; a light keeps its wavelength window.
"""

import numpy as np

from . import curves

LIGHT_PRESETS = {
    "DAYLIGHT": ("Daylight (D65)", {"source": "ILLUMINANT", "illuminant": "D65"}),
    "HORIZON": ("Horizon Daylight (D50)", {"source": "ILLUMINANT", "illuminant": "D50"}),
    "TUNGSTEN": ("Tungsten (A)", {"source": "ILLUMINANT", "illuminant": "A"}),
    "EQUAL": ("Equal Energy (E)", {"source": "ILLUMINANT", "illuminant": "E"}),
    "FLUORESCENT": ("Cool White Fluorescent (FL2)", {"source": "ILLUMINANT", "illuminant": "FL2"}),
    "TRIBAND": ("Triband Fluorescent (FL11)", {"source": "ILLUMINANT", "illuminant": "FL11"}),
    "LED_WHITE": ("White LED (LED-B3)", {"source": "ILLUMINANT", "illuminant": "LED-B3"}),
    "LED_RGB": ("RGB LED (LED-RGB1)", {"source": "ILLUMINANT", "illuminant": "LED-RGB1"}),
    "CANDLE": ("Candle (1900 K)", {"source": "BLACKBODY", "temperature": 1900.0}),
    "BLACKLIGHT": ("UV Blacklight (365 nm)", {"source": "BAND", "band": "UV365"}),
    "LASER_GREEN": ("Green Laser (532 nm)", {"source": "BAND", "band": "G532"}),
}

_RAYLEIGH_NM = np.array([360.0, 400.0, 450.0, 500.0, 550.0, 600.0, 700.0, 830.0])
_RAYLEIGH = [(float(lam), float((360.0 / lam) ** 4)) for lam in _RAYLEIGH_NM]

MATERIAL_PRESETS = {
    "SMOKE": ("Smoke", {"density_scale": 5.0, "albedo.value": 0.6, "anisotropy.value": 0.2}),
    "CLOUD": ("Cloud", {"density_scale": 20.0, "albedo.value": 0.99, "anisotropy.value": 0.8}),
    "FIRE": ("Fire", {"density_scale": 4.0, "albedo.value": 0.3, "use_blackbody": True,
                      "temperature_grid": "flame", "temperature_scale": 1500.0, "temperature_offset": 800.0,
                      "blackbody_intensity": 1.0}),
    "HAZE": ("Rayleigh Haze", {"density_scale": 2.0, "phase": "rayleigh", "albedo.value": 1.0,
                               "extinction.source": "CURVE", "extinction.curve": _RAYLEIGH}),
    "FLUORESCEIN": ("Fluorescein Dye", {"density_scale": 2.0, "extinction.value": 0.2, "albedo.value": 0.95,
                                        "use_fluorescence": True, "excitation.source": "GAUSSIAN",
                                        "excitation.peak": 490.0, "excitation.width": 15.0, "excitation.value": 3.0,
                                        "emission.peak": 515.0, "emission.width": 15.0, "quantum_yield": 0.93}),
    "QUININE": ("Quinine (UV)", {"density_scale": 2.0, "extinction.value": 0.1, "albedo.value": 0.98,
                                 "use_fluorescence": True, "excitation.source": "BAND", "excitation.band": "UV365",
                                 "excitation.value": 3.0, "emission.peak": 450.0, "emission.width": 30.0,
                                 "quantum_yield": 0.55}),
}

# Settings a preset never resets: the curve storage, the material's on/off switch, and a light's
# wavelength window (a filter in front of the lamp, not part of the spectrum's shape a preset sets).
_KEEP = {"curve_group", "curve", "enabled", "node", "use_window", "window_min", "window_max"}


def reset(settings) -> None:
    """Every setting of `settings` (and of its nested spectra) back to its default."""
    for prop in settings.bl_rna.properties:
        name = prop.identifier
        if name in _KEEP or name == "rna_type":
            continue
        if prop.type == "POINTER":
            reset(getattr(settings, name))
        elif prop.type == "COLLECTION":
            getattr(settings, name).clear()
        elif not prop.is_readonly:
            settings.property_unset(name)


def apply(settings, preset: dict) -> None:
    """Reset `settings`, then set each path of `preset` (curves get their points)."""
    reset(settings)
    for path, value in preset.items():
        owner, _, name = path.rpartition(".")
        target = settings.path_resolve(owner) if owner else settings
        if name == "curve":
            mapping = curves.ensure(target.curve, target.Y_RANGE)
            curves.set_points(mapping, *zip(*value))
        else:
            setattr(target, name, value)
