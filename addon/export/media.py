"""Volume materials → tracer media: from the material's Spectral Volume settings when they are on
(`export_medium`), else from its volume node tree as Cycles means it (`shader_media`).

Spectral settings are per metre (the scene's Unit Scale applies); node values are per Blender unit,
as in Cycles.
"""

import dataclasses

import numpy as np

from ..tracer import spectra
from ..tracer.wavelengths import GRID
from ..tracer.errors import SpectralError
from ..tracer.scene import BlackbodyEmission, Fluorescence, Glow, Grid, Medium
from ..tracer.spectra import Spectrum
from ..props.spectrum_values import to_spectrum
from ..nodes.volume import Scattering, has_volume_shader, read_volume_shader


def slot_materials(obj, depsgraph=None) -> list:
    """The material of each of an object's slots (None where empty), evaluated in `depsgraph` when given. A
    slot its evaluated geometry leaves empty (a Geometry Nodes volume without Set Material) falls back to
    the object's own slot, as Blender's renderers do."""
    own = obj.original.material_slots
    found = []
    for index, slot in enumerate(obj.material_slots):
        material = slot.material
        if material is None and index < len(own):
            material = own[index].material
        found.append(material if material is None or depsgraph is None else material.evaluated_get(depsgraph))
    return found


def materials(obj, depsgraph=None) -> list:
    """The materials of an object's slots (`slot_materials` without the empty ones)."""
    return [material for material in slot_materials(obj, depsgraph) if material is not None]


def spectral_material(obj, depsgraph=None):
    """The first material of `obj` with Spectral Volume enabled (evaluated in `depsgraph` when given), or None."""
    return next((material for material in materials(obj, depsgraph) if material.spectral.enabled), None)


def volume_material(obj, depsgraph=None):
    """The first material of `obj` that makes a volume (evaluated in `depsgraph` when given): Spectral
    Volume enabled, or a volume shader in its node tree; None when it has none."""
    return next((material for material in materials(obj, depsgraph)
                 if material.spectral.enabled or has_volume_shader(material)), None)


def albedo_table(settings) -> tuple[np.ndarray, np.ndarray]:
    """(densities, rows) from the base albedo at density 0 and the extra levels."""
    levels = [(0.0, settings.albedo)] + [(level.density, level.spectrum) for level in settings.albedo_levels]
    levels.sort(key=lambda level: level[0])
    densities = np.array([density for density, _spectrum in levels])
    if np.any(np.diff(densities) <= 0):
        raise SpectralError(f"material {settings.id_data.name!r}: albedo levels need different densities above 0, "
                            f"found {sorted(densities.tolist())}")
    return densities, np.stack([to_spectrum(spectrum).values for _density, spectrum in levels])


def export_medium(name: str, material, density: Grid, temperature: Grid | None, metres_per_unit: float = 1.0) -> Medium:
    """The medium of `material` over `density`; `temperature` is required when blackbody emission is on.
    The material's coefficients are per metre; the tracer's lengths are Blender units of `metres_per_unit`
    metres (the scene's Unit Scale), so the density scale (which scales absorption, scattering,
    fluorescence and glow alike) takes that factor."""
    settings = material.spectral
    densities, table = albedo_table(settings)
    fluorescence = None
    if settings.use_fluorescence:
        fluorescence = Fluorescence(excitation=to_spectrum(settings.excitation),
                                    emission=to_spectrum(settings.emission), quantum_yield=settings.quantum_yield)
    emission = None
    if settings.use_blackbody:
        if temperature is None:
            raise SpectralError(f"object {name!r}: material {material.name!r} glows by temperature, but the object "
                                "has no temperature grid (only Volume objects and fluid domains have one)")
        emission = BlackbodyEmission(temperature=temperature, intensity=settings.blackbody_intensity,
                                     temperature_scale=settings.temperature_scale,
                                     temperature_offset=settings.temperature_offset)
    return Medium(name=name, density=density, density_scale=settings.density_scale * metres_per_unit,
                  extinction=to_spectrum(settings.extinction), albedo_densities=densities, albedo_table=table,
                  anisotropy=to_spectrum(settings.anisotropy), phase=settings.phase, fluorescence=fluorescence,
                  emission=emission)


def _albedo(scattering: np.ndarray, extinction: np.ndarray) -> np.ndarray:
    return np.divide(scattering, extinction, out=np.zeros_like(extinction), where=extinction > 0)


def _scattering_media(name: str, parts, fields) -> dict:
    """One medium per (grid, phase function, anisotropy): the parts' coefficients added."""
    groups: dict = {}
    for part in parts:
        key = (part.grid, part.phase, part.anisotropy)
        scattering, absorption = groups.get(key, (0.0, 0.0))
        groups[key] = (scattering + part.scattering, absorption + part.absorption)
    media = {}
    for (grid, phase, anisotropy), (scattering, absorption) in groups.items():
        extinction = scattering + absorption
        if np.any(extinction > 0):
            media[(grid, phase, anisotropy)] = Medium(
                name=name, density=fields.grid(grid), density_scale=fields.density_scale,
                extinction=Spectrum(extinction),
                albedo_densities=np.zeros(1), albedo_table=_albedo(scattering, extinction)[None, :],
                anisotropy=spectra.constant(anisotropy), phase=phase)
    return media


def _glows(owner: str, parts, fields, notes) -> dict:
    """grid → tracer Glow, the parts on one grid added (one black body per grid: the first, others noted)."""
    glows: dict = {}
    for part in parts:
        found = glows.get(part.grid)
        temperature = fields.grid(part.temperature_grid) if part.temperature_grid else None
        blackbody = part.blackbody if temperature is not None or part.temperature > 0 else 0.0  # 0 K: dark
        glow = Glow(spectrum=Spectrum(part.spectrum), blackbody=blackbody, tint=Spectrum(part.tint),
                    temperature=temperature, temperature_scale=part.temperature if temperature else 1.0,
                    temperature_offset=0.0 if temperature else part.temperature)
        if found is not None:
            if glow.blackbody > 0 and found.blackbody > 0:
                notes.add(f"{owner}: only one black body per volume is rendered (the first)")
            keep = found if found.blackbody > 0 or glow.blackbody == 0 else glow
            glow = Glow(spectrum=Spectrum(found.spectrum.values + part.spectrum), blackbody=keep.blackbody,
                        tint=keep.tint, temperature=keep.temperature, temperature_scale=keep.temperature_scale,
                        temperature_offset=keep.temperature_offset)
        glows[part.grid] = glow
    return glows


def shader_media(name: str, material, fields, notes) -> list[Medium]:
    """The media of object `name` from `material`'s volume node tree (see `nodes.volume`), over the
    object's `fields` (`volume_fields.VolumeFields`). A glow goes with the scattering medium on its grid, or
    alone in an emission-only medium."""
    parts = read_volume_shader(material, fields.has, notes)
    owner = f"material {material.name!r}"
    media = _scattering_media(name, [part for part in parts if isinstance(part, Scattering)], fields)
    glows = _glows(owner, [part for part in parts if not isinstance(part, Scattering)], fields, notes)
    for grid, glow in glows.items():
        key = next((key for key in media if key[0] == grid), None)
        if key is not None:
            media[key] = dataclasses.replace(media[key], glow=glow)
        else:
            media[(grid, "glow", 0.0)] = Medium(
                name=name, density=fields.grid(grid), density_scale=fields.density_scale,
                extinction=spectra.constant(0.0),
                albedo_densities=np.zeros(1), albedo_table=np.zeros((1, GRID.size)),
                anisotropy=spectra.constant(0.0), glow=glow)
    return list(media.values())
