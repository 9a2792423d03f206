"""Blender lights → tracer lights.

Brightness is Blender's own, converted so that the same light looks the same in Cycles:
- Sun: Strength is irradiance in W/m²; our sun's strength is its irradiance, so it is copied.
  Blender's sun shines along the object's −Z; our `direction` points towards the sun: the object's +Z.
- Point and spot: Power P in W radiates P / (4π) W/sr in every direction (Cycles: a spot is a point
  light masked to its cone, it does not concentrate its power), so our intensity is P / (4π) per sr.
- Area (Square, Rectangle, Disk, Ellipse): Power P in W is all it emits from its front (−Z), a
  Lambertian emitter of radiance P / (π A); the size is Blender's times the object's scale. Spread
  below 180° renders as 180° (named in the warning). As in Cycles, camera rays see its face where the
  object's Visibility ▸ Ray Visibility ▸ Camera is on (off by default for a light object), and rays after
  scattering find it (MIS).
All are scaled by 2^Exposure. The colour is Blender's: the light's Color (times the black body of its
Temperature when that is on, times the Color and Strength of an Emission node in its node tree) as an
emission spectrum (`tracer.spectra`), in the radiant unit so that the radiance is exactly Cycles' RGB as a
spectrum. With the light's Spectral Light on, its spectrum replaces the colour instead, in the unit its
settings choose (luminous: the number is luminance Y; radiant: watts over the whole spectrum, for UV
lamps).
"""

import math

import numpy as np

from ..props.spectrum_values import to_spectrum
from ..tracer import spectra
from ..tracer.scene import Light
from ..nodes.graph import colour, finite, number, output_source, reflectance_spectrum
from .world import radiant_light

SUPPORTED = ("SUN", "POINT", "SPOT", "AREA")
FULL_SPREAD = math.pi - 1e-4  # Blender's Spread of a Lambertian area light (180°), within float rounding


def point_intensity(power_watts: float) -> float:
    """Blender point/spot Power (W) → our intensity (per steradian)."""
    return power_watts / (4.0 * math.pi)


def _axis(matrix_world, column: int) -> np.ndarray:
    axis = np.array(matrix_world.col[column][:3], dtype=np.float64)
    return axis / np.linalg.norm(axis)


def light_colour(light, owner: str, notes) -> tuple[spectra.Spectrum, float]:
    """(emission spectrum, factor) of a Blender light's colour as Cycles combines it: Color × the
    Temperature's black body × an Emission node's Color and Strength."""
    rgb = np.maximum(np.array(finite(tuple(light.color[:3]), f"{owner} Color"), dtype=np.float64), 0.0)
    if light.use_temperature:
        temperature = finite(float(light.temperature), f"{owner} Temperature")
        spectrum = spectra.scaled_from_rgb(rgb) * spectra.blackbody_of_luminance_one(temperature)
    else:
        spectrum = spectra.emission_from_rgb(rgb)
    factor = 1.0
    found = output_source(light.node_tree, "Surface")
    if found is not None:
        node = found[0]
        if node.bl_idname == "ShaderNodeEmission":
            spectrum = spectrum * reflectance_spectrum(colour(node, "Color", owner, notes))
            factor *= max(float(number(node, "Strength", owner, notes)), 0.0)
        else:
            notes.add(f"{owner} ▸ {node.name}: only an Emission node sets a light's colour; its Color is used")
    return spectrum, factor


def _area(light, matrix, name: str, notes) -> dict:
    """An area light's geometry: its centre, its axes (normalised), its shape and world size (Blender's
    Size × the object's scale along each axis)."""
    columns = np.array([matrix.col[index][:3] for index in range(3)], dtype=np.float64)
    lengths = np.linalg.norm(columns, axis=1)
    square = light.shape in ("SQUARE", "DISK")
    if light.spread < FULL_SPREAD:
        notes.add(f"light {name!r}: Spread {math.degrees(light.spread):.0f}° rendered as 180°")
    return dict(position=np.array(matrix.translation, dtype=np.float64), area_axes=(columns / lengths[:, None]).T,
                area_shape="rectangle" if light.shape in ("SQUARE", "RECTANGLE") else "ellipse",
                size_x=light.size * lengths[0], size_y=(light.size if square else light.size_y) * lengths[1])


def export_light(obj, matrix, notes) -> Light | None:
    """The tracer light of an evaluated light object at world `matrix` (its own, or its instance's), or
    None when it gives no light, or when the tracer does not render its kind (named in `notes`)."""
    light = obj.data
    if light.type not in SUPPORTED:
        notes.leave_out(f"{light.type.lower()} light", obj.name)
        return None
    if light.type == "SUN":
        geometry = dict(direction=_axis(matrix, 2), angle=light.angle)
        strength = light.energy
    elif light.type == "AREA":
        geometry = dict(_area(light, matrix, obj.name, notes), camera_visible=bool(obj.visible_camera))
        strength = light.energy
    else:
        geometry = dict(position=np.array(matrix.translation, dtype=np.float64))
        strength = point_intensity(light.energy)
        if light.type == "SPOT":
            geometry.update(spot_direction=-_axis(matrix, 2), spot_size=light.spot_size, spot_blend=light.spot_blend)
    kind, strength = light.type.lower(), strength * 2.0 ** light.exposure
    if light.spectral.enabled:
        return Light(kind=kind, spectrum=to_spectrum(light.spectral.spectrum), strength=strength, name=obj.name,
                     unit=light.spectral.unit, **geometry)
    spectrum, factor = light_colour(light, f"light {obj.name!r}", notes)
    return radiant_light(kind, spectrum, strength * factor, name=obj.name, **geometry)
