"""Volume material settings + grids → tracer Medium."""

import numpy as np

from ..tracer.errors import SpectralError
from ..tracer.scene import BlackbodyEmission, Fluorescence, Grid, Medium
from ..props.spectrum_values import to_spectrum


def materials(obj, depsgraph=None) -> list:
    """The materials of an object's slots, evaluated in `depsgraph` when given. A slot its evaluated
    geometry leaves empty (a Geometry Nodes volume without Set Material) falls back to the object's own
    slot, as Blender's renderers do."""
    own = obj.original.material_slots
    found = []
    for index, slot in enumerate(obj.material_slots):
        material = slot.material
        if material is None and index < len(own):
            material = own[index].material
        if material is not None:
            found.append(material if depsgraph is None else material.evaluated_get(depsgraph))
    return found


def spectral_material(obj, depsgraph=None):
    """The first material of `obj` with Spectral Volume enabled (evaluated in `depsgraph` when given), or None."""
    return next((material for material in materials(obj, depsgraph) if material.spectral.enabled), None)


def require_material(obj, depsgraph):
    material = spectral_material(obj, depsgraph)
    if material is None:
        names = [material.name for material in materials(obj, depsgraph)]
        found = f"its materials ({', '.join(names)}) are not spectral" if names else "it has no material"
        raise SpectralError(f"object {obj.name!r} is a volume but {found}: add a material and enable "
                            "Spectral Volume in it (Material Properties or the Spectral sidebar tab)")
    return material


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
