"""The whole export: an evaluated Blender scene (a depsgraph) → tracer Scene, plus warnings.

Which objects become what:
- Volume objects: their VDB grids (the object's Density Grid, and the material's temperature grid
  when it glows) with the first Spectral Volume material; no such material is an error.
- Meshes with a fluid domain modifier (smoke/fire): the domain's OpenVDB cache, same materials rule.
- Other meshes whose material has Spectral Volume enabled: voxelised at the object's Voxel Size.
- Sun, point and spot lights; the World (when its Spectral World is on); the scene camera.
Materials are per metre, so the scene's Unit Scale scales them (addon.export.media). Motion blur and
non-square pixels cannot be rendered: each gives one warning.
Everything is read from the evaluated depsgraph, so animation and drivers are those of its frame (a
render's own depsgraph never writes them back to the original data), and the instances it lists count:
Geometry Nodes volumes (Mesh to Volume, Volume Cube, ...) and instanced collections, each at its
instance matrix. Nothing is written to disk here and the Blender data is not changed.

The add-on exports render depsgraphs (F12, and `addon.render_export` for everything else) and the
Rendered viewport's own (see `export_scene`); scripts may pass a viewport one. Setting an add-on property
does not tag its data block for re-evaluation, so a viewport depsgraph may hold stale copies of the
materials, lights, worlds and scene: those are tagged and re-evaluated first (the Rendered viewport
reads the originals instead). A render's depsgraph is built fresh and needs none of this. Objects are not
tagged (that would re-run their modifiers and simulations): their settings, the density grid's name and the
voxel size, are read from the original objects.
"""

from dataclasses import dataclass, field

import bpy

from ..tracer.errors import SpectralError
from ..tracer.scene import Camera, RenderSettings, Scene
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
    """The tracer settings of an (evaluated) scene."""
    s = scene.spectral
    if s.lambda_min >= s.lambda_max:
        raise SpectralError(f"render settings: the wavelength range {s.lambda_min:g}–{s.lambda_max:g} nm is empty")
    return RenderSettings(spp=s.samples, seed=s.seed, max_depth=s.max_bounces,
                          wavelength_sampling=s.wavelength_sampling, wavelengths_per_path=int(s.wavelengths_per_path),
                          lambda_min=s.lambda_min, lambda_max=s.lambda_max, bands=s.bands, cmf=s.cmf,
                          backend=s.backend)


def unsupported_settings(scene) -> list[str]:
    """Warnings for the scene's render settings the tracer cannot follow."""
    render, warnings = scene.render, []
    if render.use_motion_blur:
        warnings.append("motion blur is not supported: rendered without it (Render Properties ▸ Motion Blur)")
    return warnings


def _medium(instance, depsgraph, volume_owners, originals: bool):
    """The medium of one depsgraph instance, or None when it is not a volume. With `originals`, its
    material's settings are read from the original material (see `export_scene`)."""
    obj, matrix = instance.object, instance.matrix_world
    metres_per_unit = depsgraph.scene_eval.unit_settings.scale_length
    if obj.type == "VOLUME" or (obj.type == "MESH" and fluid_domain(obj) is not None):
        material = require_material(obj, depsgraph)
        material = material.original if originals else material
        names = [obj.original.spectral.density_grid]
        if material.spectral.use_blackbody:
            names.append(material.spectral.temperature_grid)
        read = volume_grids if obj.type == "VOLUME" else fluid_grids
        grids = read(obj, depsgraph, names, matrix)
        return export_medium(obj.name, material, grids[0], grids[1] if len(grids) > 1 else None, metres_per_unit)
    if obj.type == "MESH":
        material = spectral_material(obj, depsgraph)
        if material is None or (obj.original in volume_owners and not obj.data.polygons):
            return None  # Geometry Nodes turned the mesh into a volume: only that volume renders
        material = material.original if originals else material
        return export_medium(obj.name, material, voxelise(obj, obj.original.spectral.voxel_size, matrix), None,
                             metres_per_unit)
    return None


def _synchronise(depsgraph) -> None:
    """Re-evaluate the data blocks that hold spectral settings (see the module docstring)."""
    if depsgraph.mode == "RENDER":
        return
    depsgraph.scene.update_tag()
    for blocks in (bpy.data.materials, bpy.data.lights, bpy.data.worlds):
        for block in blocks:
            block.update_tag()
    depsgraph.update()


def export_scene(depsgraph, view: Camera | None = None) -> Export:
    """Export the depsgraph's scene at its current frame. Raises SpectralError on bad input.

    `view` is the Rendered viewport's camera, rendered instead of the scene camera. The viewport exports
    while Blender evaluates its depsgraph (`view_update`), when the depsgraph must not be updated: nothing
    is tagged, and the settings of materials, lights, the World and the scene are read from their
    original data blocks instead (the evaluated copies may be stale, see above; the viewport's depsgraph
    writes animated values back to the originals)."""
    originals = view is not None
    if not originals:
        _synchronise(depsgraph)
    scene = depsgraph.scene_eval
    settings_scene = depsgraph.scene.original if originals else scene
    warnings = unsupported_settings(scene)
    camera = view or export_camera(scene, scene.camera.evaluated_get(depsgraph) if scene.camera else None)
    media, lights = [], []
    volume_owners = {instance.object.original for instance in depsgraph.object_instances
                     if instance.is_instance and instance.object.type == "VOLUME"}
    for instance in depsgraph.object_instances:  # each instance's object lives only for this iteration
        obj = instance.object
        if obj.type == "LIGHT":
            light = export_light(obj.original if originals else obj, instance.matrix_world)
            if light is None:
                warnings.append(f"light {obj.name!r}: {obj.data.type.lower()} lights are not supported, skipped")
            else:
                lights.append(light)
        else:
            medium = _medium(instance, depsgraph, volume_owners, originals)
            if medium is not None:
                media.append(medium)
    world = export_world(settings_scene.world)
    if world is not None:
        lights.append(world)
    if not lights and not any(medium.emission is not None for medium in media):
        raise SpectralError("the scene has no lights: add a sun, point or spot light, or turn on the "
                            "Spectral World in the World properties")
    settings = render_settings(settings_scene)
    return Export(Scene(camera=camera, media=tuple(media), lights=tuple(lights), settings=settings), warnings)
