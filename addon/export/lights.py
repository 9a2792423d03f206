"""Blender lights and World → tracer lights.

Brightness is Blender's own, converted so that the same light looks the same in Cycles, in the unit
the light's Spectral Light settings choose (luminous: the number is luminance Y; radiant: watts over
the whole spectrum, for UV lamps):
- Sun: Strength is irradiance in W/m²; our sun's strength is its irradiance, so it is copied.
  Blender's sun shines along the object's −Z; our `direction` points towards the sun: the object's +Z.
- Point and spot: Power P in W radiates P / (4π) W/sr in every direction (Cycles: a spot is a point
  light masked to its cone, it does not concentrate its power), so our intensity is P / (4π) per sr.
The spectrum replaces the light's colour. Area lights are not supported (skipped with a warning).
The World becomes a uniform environment or a sky of radiance `strength` in its unit.
"""

import math

import numpy as np

from ..tracer.scene import Light
from ..props.spectrum_values import to_spectrum

SUPPORTED = ("SUN", "POINT", "SPOT")


def point_intensity(power_watts: float) -> float:
    """Blender point/spot Power (W) → our intensity (per steradian)."""
    return power_watts / (4.0 * math.pi)


def _axis(matrix_world, column: int) -> np.ndarray:
    axis = np.array(matrix_world.col[column][:3], dtype=np.float64)
    return axis / np.linalg.norm(axis)


def export_light(obj, matrix) -> Light | None:
    """The tracer light of an evaluated light object at world `matrix` (its own, or its instance's), or
    None for unsupported types (area lights)."""
    light = obj.data
    if light.type not in SUPPORTED:
        return None
    spectrum, unit = to_spectrum(light.spectral.spectrum), light.spectral.unit
    if light.type == "SUN":
        return Light(kind="sun", spectrum=spectrum, strength=light.energy, direction=_axis(matrix, 2),
                     angle=light.angle, name=obj.name, unit=unit)
    position = np.array(matrix.translation, dtype=np.float64)
    strength = point_intensity(light.energy)
    if light.type == "POINT":
        return Light(kind="point", spectrum=spectrum, strength=strength, position=position, name=obj.name,
                     unit=unit)
    return Light(kind="spot", spectrum=spectrum, strength=strength, position=position,
                 spot_direction=-_axis(matrix, 2), spot_size=light.spot_size, spot_blend=light.spot_blend,
                 name=obj.name, unit=unit)


def export_world(world) -> Light | None:
    """The light of the evaluated scene's World, or None when its Spectral World is off."""
    if world is None or not world.spectral.enabled:
        return None
    settings = world.spectral
    horizon = to_spectrum(settings.horizon) if settings.kind == "sky" else None
    return Light(kind=settings.kind, spectrum=to_spectrum(settings.spectrum), strength=settings.strength,
                 horizon_spectrum=horizon, name=world.name, unit=settings.unit)
