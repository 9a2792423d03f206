"""The whole export: an evaluated Blender scene (a depsgraph) → tracer Scene, plus warnings.

Which objects become what (the first material with a volume shader or Spectral Volume enabled):
- Volume objects: their VDB grids; meshes with a fluid domain modifier (smoke/fire): the domain's OpenVDB
  cache; other meshes with such a material: voxelised at the object's Voxel Size.
- A material renders from its volume node tree as Cycles means it (`media.shader_media`), or, with its
  Spectral Volume on, from its spectral settings (the object's Density Grid, and the material's
  temperature grid when it glows).
- Sun, point, spot and area lights (`lights`); the World, an HDRI included (`world`); the scene camera.
- Every other object with faces (meshes, curves, text): opaque surfaces, mesh lights where they emit
  (`surfaces`, `nodes.surface`).
- What is not rendered as set (closures other than diffuse and emission, a Hosek / Wilkie Sky Texture,
  unconvertible node inputs) is named in one warning (`nodes.notes`); nothing is skipped silently.
  Problems name Blender's objects, lights and World, not the exported indices (`validated`).
Spectral materials are per metre, so the scene's Unit Scale scales them (addon.export.media); node
values are per Blender unit, as in Cycles. Motion blur and
non-square pixels cannot be rendered: each gives one warning.
Everything is read from the evaluated depsgraph, so animation and drivers are those of its frame (a
render's own depsgraph never writes them back to the original data), and the instances it lists count:
Geometry Nodes volumes (Mesh to Volume, Volume Cube, ...) and instanced collections, each at its
instance matrix. Nothing is written to disk here and the Blender data is not changed.

The add-on exports render depsgraphs (F12, and `addon.export.rendered` for everything else) and the
Rendered viewport's own (see `export_scene`); scripts may pass a viewport one. Setting an add-on property
does not tag its data block for re-evaluation, so a viewport depsgraph may hold stale copies of the
materials, lights, worlds and scene: those are tagged and re-evaluated first (the Rendered viewport
reads the originals instead). A render's depsgraph is built fresh and needs none of this. Objects are not
tagged (that would re-run their modifiers and simulations): their settings, the density grid's name and the
voxel size, are read from the original objects.
"""

import re
import dataclasses
from dataclasses import dataclass, field

import bpy

from ..tracer.errors import SpectralError
from ..tracer.scene import Camera, RenderSettings, Scene
from .camera import export_camera
from .fluids import fluid_domain, fluid_grids
from .lights import export_light
from .media import export_medium, materials, shader_media, volume_material
from .meshes import voxelise
from .passes import pass_settings, spectrum_settings, unmade_warning
from ..nodes.notes import Notes
from ..props.render import chosen_backend
from .volume_fields import VolumeFields
from .volumes import volume_grids
from .surfaces import export_surfaces, held_out, seen_by_camera
from .world import export_world
from ..tracer.validation import validate


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
                          backend=chosen_backend(s), noise_threshold=s.adaptive_threshold if s.use_adaptive_sampling else 0.0,
                          min_samples=s.adaptive_min_samples, transparent=bool(scene.render.film_transparent),
                          clamp_direct=s.clamp_direct, clamp_indirect=s.clamp_indirect,
                          firefly_threshold=s.firefly_threshold if s.use_firefly_filter else 0.0)


def unsupported_settings(scene) -> list[str]:
    """Warnings for the scene's render settings the tracer cannot follow."""
    render, warnings = scene.render, []
    if render.use_motion_blur:
        warnings.append("motion blur is not supported: rendered without it (Render Properties ▸ Motion Blur)")
    return warnings


def _object_parts(instance, depsgraph, volume_owners, originals: bool, notes: Notes) -> tuple[list, list]:
    """(media, surfaces) of one depsgraph instance: a volume's media, or an object's opaque surfaces. With
    `originals`, its material's settings are read from the original material (see `export_scene`)."""
    obj, matrix = instance.object, instance.matrix_world
    is_volume = obj.type == "VOLUME" or (obj.type == "MESH" and fluid_domain(obj) is not None)
    material = volume_material(obj, depsgraph) if is_volume or obj.type == "MESH" else None
    holdout, camera = held_out(instance, depsgraph.view_layer), seen_by_camera(instance, depsgraph.view_layer)
    if holdout and material is not None:
        notes.add(f"object {obj.name!r}: Holdout has no effect on a volume, in Cycles as here: the volume renders as "
                  "it is")
    if not camera and material is not None:
        notes.add(f"object {obj.name!r}: a volume hidden from the camera (Indirect Only, Ray Visibility ▸ Camera) is "
                  "rendered as seen by the camera too")
    if material is None:
        if is_volume:
            names = [material.name for material in materials(obj, depsgraph)]
            notes.leave_out("volume without a volume material", obj.name + (f" ({', '.join(names)})" if names else ""),
                            "volumes without a volume material")
            return [], []
        return [], export_surfaces(obj, matrix, depsgraph, notes, holdout, camera)
    if obj.type == "MESH" and not is_volume and obj.original in volume_owners and not obj.data.polygons:
        return [], []  # Geometry Nodes turned the mesh into a volume: only that volume renders
    material = material.original if originals else material
    metres_per_unit = depsgraph.scene_eval.unit_settings.scale_length
    if not material.spectral.enabled:
        return shader_media(obj.name, material, VolumeFields(obj, depsgraph, matrix), notes), []
    if is_volume:
        names = [obj.original.spectral.density_grid]
        if material.spectral.use_blackbody:
            names.append(material.spectral.temperature_grid)
        read = volume_grids if obj.type == "VOLUME" else fluid_grids
        grids = read(obj, depsgraph, names, matrix)
        medium = export_medium(obj.name, material, grids[0], grids[1] if len(grids) > 1 else None, metres_per_unit)
        return [medium], []
    return [export_medium(obj.name, material, voxelise(obj, obj.original.spectral.voxel_size, matrix), None,
                          metres_per_unit)], []


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
    warnings, notes = unsupported_settings(scene), Notes()
    camera = view or export_camera(scene, scene.camera.evaluated_get(depsgraph) if scene.camera else None)
    media, lights, surfaces = [], [], []
    volume_owners = {instance.object.original for instance in depsgraph.object_instances
                     if instance.is_instance and instance.object.type == "VOLUME"}
    for instance in depsgraph.object_instances:  # each instance's object lives only for this iteration
        obj = instance.object
        if obj.type == "LIGHT":
            light = export_light(obj.original if originals else obj, instance.matrix_world, notes)
            if light is not None:
                lights.append(light)
        else:
            object_media, object_surfaces = _object_parts(instance, depsgraph, volume_owners, originals, notes)
            media.extend(object_media)
            surfaces.extend(object_surfaces)
    lights.extend(export_world(settings_scene.world, notes))
    warning = notes.warning()
    if warning is not None:
        warnings.append(warning)
    if not lights and not any(medium.emits() for medium in media) and not any(surface.emission is not None for surface in surfaces):
        raise SpectralError("the scene has no lights: add a sun, point or spot light, give the World a colour, "
                            "or make a volume or a surface glow" + (f" ({warning})" if warning else ""))
    settings = render_settings(settings_scene)
    if not originals:  # F12 and the command lines: the view layer's data passes and the spectrum (the viewport: none)
        settings = dataclasses.replace(settings, **pass_settings(depsgraph.view_layer, settings_scene.world),
                                       **spectrum_settings(settings_scene))
        unmade = unmade_warning(depsgraph.view_layer)
        if unmade is not None:
            warnings.append(unmade)
    scene = Scene(camera=camera, media=tuple(media), lights=tuple(lights), surfaces=tuple(surfaces),
                  settings=settings)
    return Export(validated(scene), warnings)


def validated(scene: Scene) -> Scene:
    """`scene`, checked; a problem names the Blender object, light or World, not the exported index
    (`lights[0].strength: ...` becomes `light 'Sun' strength: ...`)."""
    try:
        return validate(scene)
    except SpectralError as problem:
        def name(match):
            kind, index, rest = match.group(1), int(match.group(2)), match.group(3) or ""
            owner = getattr(scene, kind)[index]
            if kind == "lights":
                noun = "World" if owner.kind in ("environment", "sky", "envmap") else "light"
            else:
                noun = "volume" if kind == "media" else "surface"
            return f"{noun} {owner.name!r}" + (f" {rest[1:]}" if rest else "")
        pattern = r"\b(lights|media|surfaces)\[(\d+)\](\.[\w.\[\]]+)?"
        message = re.sub(r"\brender\.spectrum_(start|end|step)\b",
                         lambda match: f"Spectral EXR {match.group(1).title()} (View Layer ▸ Passes)", str(problem))
        raise SpectralError(re.sub(pattern, name, message)) from None
