"""Material settings: what a material means to the spectral tracer when its Spectral Volume or Spectral
Surface is on.

Stored on the Material (`material.spectral`), used by every object the material is on: Volume
objects, fluid domains and meshes (voxelised). Mirrors the tracer's `Medium`: extinction, an albedo
table over density levels, anisotropy, phase function, fluorescence and blackbody emission. Off (the
default), the material renders from its volume nodes; turning it on starts the extinction, albedo and
anisotropy from those nodes (`start_from_nodes`), so the image does not jump. Emission does not carry
over: a spectral material's glow is thermal (by its absorption and a temperature grid).

Spectral Surface replaces the diffuse colour that a mesh's surface renders with (the Base Color of its
nodes, `nodes.surface`) by a reflectance spectrum, so that two paints that match under one light can
differ under another; turning it on starts the spectrum from the nodes' colour (`start_surface_from_nodes`).
The surface's emission and holdout stay the nodes'.
"""

import bpy
import numpy as np

from . import curves
from ..nodes.notes import Notes
from ..nodes.surface import read_surface_shader
from ..nodes.volume import Scattering, read_volume_shader
from ..tracer.wavelengths import GRID

from .spectrum import (SpectralAlbedoSpectrum, SpectralAnisotropySpectrum, SpectralEmissionSpectrum,
                       SpectralExcitationSpectrum, SpectralExtinctionSpectrum, SpectralReflectanceSpectrum)


class SpectralAlbedoLevel(bpy.types.PropertyGroup):
    """The albedo spectrum at one density level above 0; between levels the albedo is interpolated."""

    density: bpy.props.FloatProperty(name="Density", description="Grid density (before Density Scale) of this level",
                                     default=1.0, min=0.0, soft_max=10.0)
    spectrum: bpy.props.PointerProperty(type=SpectralAlbedoSpectrum, name="Albedo",
                                        description="Albedo spectrum at this density")


CURVE_STEP = 10  # nm between the points of a curve started from the nodes


def _set_spectrum(settings, values: np.ndarray) -> None:
    """A CONSTANT spectrum where `values` is flat, else a curve through them every CURVE_STEP nm."""
    if np.ptp(values) <= 1e-6 * max(float(np.abs(values).max()), 1e-12):
        settings.source, settings.value = "CONSTANT", float(values.mean())
        return
    settings.source = "CURVE"
    wavelengths = GRID[::CURVE_STEP]
    curves.set_points(curves.ensure(settings.curve, settings.Y_RANGE), wavelengths,
                      np.clip(values[::CURVE_STEP], *settings.Y_RANGE))


def start_from_nodes(settings, context) -> None:
    """Set a material's spectral extinction, albedo, anisotropy and phase from its volume nodes' scattering
    and absorption (Cycles' meaning, per Blender unit; the settings are per metre of the scene's Unit Scale)."""
    parts = [part for part in read_volume_shader(settings.id_data, lambda _name: True, Notes())
             if isinstance(part, Scattering)]
    if not parts:
        return
    scattering = sum(part.scattering for part in parts)
    extinction = scattering + sum(part.absorption for part in parts)
    peak = float(extinction.max())
    if not peak > 0:
        return
    metres_per_unit = context.scene.unit_settings.scale_length if getattr(context, "scene", None) else 1.0
    settings.density_scale = peak / metres_per_unit
    _set_spectrum(settings.extinction, extinction / peak)
    _set_spectrum(settings.albedo, np.divide(scattering, extinction, out=np.zeros_like(extinction),
                                             where=extinction > 0))
    weights = np.array([part.scattering.sum() for part in parts])
    anisotropy = float(np.dot(weights, [part.anisotropy for part in parts]) / max(weights.sum(), 1e-12))
    settings.anisotropy.source, settings.anisotropy.value = "CONSTANT", anisotropy
    settings.phase = "rayleigh" if all(part.phase == "rayleigh" for part in parts) else "hg"


def _enabled_changed(settings, context) -> None:
    if settings.enabled:
        start_from_nodes(settings, context)


def start_surface_from_nodes(settings) -> None:
    """Set a material's reflectance spectrum to the diffuse reflectance its surface nodes render with."""
    look = read_surface_shader(settings.id_data, Notes())
    if look is not None:
        _set_spectrum(settings.reflectance, look.reflectance)


def _surface_changed(settings, _context) -> None:
    if settings.use_surface:
        start_surface_from_nodes(settings)


class SpectralMaterialSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(name="Spectral Volume", default=False, update=_enabled_changed,
                                    description="Render this material's volume from the spectral settings "
                                                "instead of its volume nodes (starts from the nodes' values)")
    density_scale: bpy.props.FloatProperty(name="Density Scale", description="Multiplies the density grid",
                                           default=1.0, min=1e-6, soft_max=100.0)
    extinction: bpy.props.PointerProperty(type=SpectralExtinctionSpectrum, name="Extinction",
                                          description="Extinction per unit density and metre over wavelength")
    albedo: bpy.props.PointerProperty(type=SpectralAlbedoSpectrum, name="Albedo",
                                      description="Scattered fraction of the extinction at density 0")
    albedo_levels: bpy.props.CollectionProperty(type=SpectralAlbedoLevel,
                                                description="Albedo at higher densities (the first albedo is at 0)")
    albedo_index: bpy.props.IntProperty(name="Active Albedo Level", min=0,
                                        description="The albedo level selected in the list")
    anisotropy: bpy.props.PointerProperty(type=SpectralAnisotropySpectrum, name="Anisotropy",
                                          description="Henyey–Greenstein g over wavelength")
    phase: bpy.props.EnumProperty(name="Phase", description="Phase function", default="hg", items=[
        ("hg", "Henyey–Greenstein", "Forward or backward scattering by the anisotropy g"),
        ("rayleigh", "Rayleigh", "Scattering by particles much smaller than the wavelength")])
    use_fluorescence: bpy.props.BoolProperty(name="Fluorescence",
                                             description="Absorb the excitation band and re-emit at longer wavelengths")
    excitation: bpy.props.PointerProperty(type=SpectralExcitationSpectrum, name="Excitation",
                                          description="How strongly the fluorophore absorbs each wavelength")
    emission: bpy.props.PointerProperty(type=SpectralEmissionSpectrum, name="Emission",
                                        description="The color the fluorophore re-emits")
    quantum_yield: bpy.props.FloatProperty(name="Quantum Yield", description="Fraction of absorbed light re-emitted",
                                           default=0.9, min=0.0, max=1.0, subtype="FACTOR")
    use_blackbody: bpy.props.BoolProperty(name="Blackbody Emission", description="Glow by the temperature grid (fire)")
    temperature_grid: bpy.props.StringProperty(name="Temperature Grid", default="temperature",
                                               description="Grid holding the temperature (fluid domains: "
                                                           "'temperature' falls back to 'heat', or use 'flame')")
    blackbody_intensity: bpy.props.FloatProperty(name="Intensity", description="Brightness of the glow",
                                                 default=1.0, min=0.0, soft_max=100.0)
    temperature_scale: bpy.props.FloatProperty(name="Temperature Scale", default=1.0, soft_min=0.0, soft_max=10000.0,
                                               description="Kelvin per grid unit")
    temperature_offset: bpy.props.FloatProperty(name="Temperature Offset", default=0.0, soft_min=0.0,
                                                soft_max=10000.0, description="Kelvin added after scaling")
    use_surface: bpy.props.BoolProperty(name="Spectral Surface", default=False, update=_surface_changed,
                                        description="Render this material's surface with the reflectance spectrum "
                                                    "instead of its nodes' diffuse color (starts from that color)")
    reflectance: bpy.props.PointerProperty(type=SpectralReflectanceSpectrum, name="Reflectance",
                                           description="Diffuse reflectance of the surface over wavelength")
    curve_group: bpy.props.PointerProperty(type=bpy.types.NodeTree, name="Curves",
                                           description="Hidden node group holding this material's spectral curves")


CLASSES = (SpectralAlbedoLevel, SpectralMaterialSettings)
