"""The whole export: an evaluated Blender scene (a depsgraph) → tracer Scene, plus warnings.

Which objects become what:
- Volume objects: their VDB grids (the object's Density Grid, and the material's temperature grid
  when it glows) with the first Spectral Volume material; no such material is an error.
- Meshes with a fluid domain modifier (smoke/fire): the domain's OpenVDB cache, same materials rule.
- Other meshes whose material has Spectral Volume enabled: voxelised at the object's Voxel Size.
- Sun, point and spot lights; the World (when its Spectral World is on); the scene camera.
Nothing is written to disk here and the Blender data is not changed. Spectral settings are read from
the original data blocks, geometry and transforms from the evaluated ones.
"""

from dataclasses import dataclass, field

from ..tracer.errors import SpectralError
from ..tracer.scene import RenderSettings, Scene
from .camera import export_camera
from .fluids import fluid_domain, fluid_grids
from .lights import export_light, export_world
from .media import export_medium, require_material, spectral_material
from .meshes import voxelise
from .volumes import volume_grids


@dataclass
class Export:
    scene: Scene
    warnings: list[str] = field(default_factory=list)


def render_settings(scene) -> RenderSettings:
    s = scene.original.spectral
    if s.lambda_min >= s.lambda_max:
        raise SpectralError(f"render settings: the wavelength range {s.lambda_min:g}–{s.lambda_max:g} nm is empty")
    return RenderSettings(spp=s.samples, seed=s.seed, max_depth=s.max_bounces,
                          wavelength_sampling=s.wavelength_sampling, wavelengths_per_path=int(s.wavelengths_per_path),
                          lambda_min=s.lambda_min, lambda_max=s.lambda_max, bands=s.bands, cmf=s.cmf,
                          backend=s.backend)


def _medium(obj, depsgraph):
    """The medium of one object, or None when the object is not a volume."""
    if obj.type == "VOLUME" or (obj.type == "MESH" and fluid_domain(obj) is not None):
        material = require_material(obj)
        names = [obj.original.spectral.density_grid]
        if material.spectral.use_blackbody:
            names.append(material.spectral.temperature_grid)
        read = volume_grids if obj.type == "VOLUME" else fluid_grids
        grids = read(obj, depsgraph, names)
        return export_medium(obj.name, material, grids[0], grids[1] if len(grids) > 1 else None)
    if obj.type == "MESH":
        material = spectral_material(obj)
        if material is not None:
            return export_medium(obj.name, material, voxelise(obj, obj.original.spectral.voxel_size), None)
    return None


def export_scene(depsgraph) -> Export:
    """Export the depsgraph's scene at its current frame. Raises SpectralError on bad input."""
    scene = depsgraph.scene
    warnings = []
    camera = export_camera(scene, scene.camera.evaluated_get(depsgraph) if scene.camera else None)
    media, lights = [], []
    for obj in depsgraph.objects:
        if obj.type == "LIGHT":
            light = export_light(obj)
            if light is None:
                warnings.append(f"light {obj.name!r}: {obj.data.type.lower()} lights are not supported, skipped")
            else:
                lights.append(light)
        else:
            medium = _medium(obj, depsgraph)
            if medium is not None:
                media.append(medium)
    world = export_world(scene.original.world)
    if world is not None:
        lights.append(world)
    if not lights and not any(medium.emission is not None for medium in media):
        raise SpectralError("the scene has no lights: add a sun, point or spot light, or turn on the "
                            "Spectral World in the World properties")
    return Export(Scene(camera=camera, media=tuple(media), lights=tuple(lights), settings=render_settings(scene)),
                  warnings)
