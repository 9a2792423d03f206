"""One Cycles render of the emulation set up on the user's scene: Cycles settings, the camera's clipping,
light and World colours, volume and surface materials for the render's bands; every change through
`state.Borrowed`.

Cycles is set to be unbiased and comparable with the tracer: CPU, no denoising, adaptive sampling, light
clamping, light threshold or path guiding; a 1-pixel box filter (the tracer's pixel); volume bounces = the
tracer's max bounces; compositing and the sequencer off; persistent data on (the two halves of a render
share Cycles' scene); output a 32-bit float EXR of the scene-linear
R, G, B (three bands, never mixed: Cycles keeps colour channels apart).
"""

import bpy

from ..export.media import spectral_material
from . import fluids, parameters, shaders, surfaces
from .parameters import Plan

LIGHT_TYPES = ("SUN", "POINT", "SPOT", "AREA")
CLIP_START, CLIP_END = 1e-6, 1e6  # the camera's range, as unlimited as Blender allows


def cycles_settings(borrowed, scene, *, samples: int, max_bounces: int, shader: str):
    """Everything but the seed and the output file, which change between the two halves."""
    render, cycles, image = scene.render, scene.cycles, scene.render.image_settings
    values = [
        (image, "color_depth", image.color_depth), (image, "color_mode", image.color_mode),  # restored last
        (render, "engine", "CYCLES"), (render, "use_persistent_data", True), (render, "use_compositing", False),
        (render, "use_sequencer", False), (render, "film_transparent", False), (render, "use_crop_to_border", True),
        (render, "use_multiview", False),
        (image, "file_format", "OPEN_EXR"), (image, "color_depth", "32"), (image, "color_mode", "RGB"),
        (cycles, "device", "CPU"), (cycles, "shading_system", shader == "OSL"), (cycles, "samples", samples),
        (cycles, "use_animated_seed", False), (cycles, "use_denoising", False),
        (cycles, "use_adaptive_sampling", False), (cycles, "pixel_filter_type", "BOX"), (cycles, "filter_width", 1.0),
        (cycles, "volume_bounces", max_bounces), (cycles, "max_bounces", max(cycles.max_bounces, max_bounces)),
        (cycles, "sample_clamp_direct", 0.0), (cycles, "sample_clamp_indirect", 0.0),
        (cycles, "light_sampling_threshold", 0.0), (cycles, "use_volume_guiding", False),
        (cycles, "volume_biased", False), (cycles, "blur_glossy", 0.0),
    ]
    for owner, attribute, value in values:
        borrowed.set(owner, attribute, value)


def camera(borrowed, scene) -> None:
    """The tracer does not clip camera rays; Cycles starts them at the camera's clip start (0.1 m by
    default), which skips the medium in front of a camera inside a volume (6 % darker in our test)."""
    if scene.camera is not None and scene.camera.type == "CAMERA":
        borrowed.set(scene.camera.data, "clip_start", CLIP_START)
        borrowed.set(scene.camera.data, "clip_end", max(scene.camera.data.clip_end, CLIP_END))


def _light_colour(borrowed, light, colour) -> None:
    """Cycles light colours are at most 1 in the UI: the brightest channel goes into the strength."""
    peak = float(max(colour))
    borrowed.set(light, "color", tuple(c / peak for c in colour) if peak > 0 else (0.0, 0.0, 0.0))
    if peak > 0:
        borrowed.set(light, "energy", light.energy * peak)


def _still(borrowed, datablock) -> None:
    """Animation and drivers would put a light's own colour and strength back when Cycles evaluates the
    frame: off while it renders (the values at this frame are the datablock's, which the export used)."""
    animation = datablock.animation_data
    if animation is None:
        return
    borrowed.set(animation, "action_slot", animation.action_slot)  # restored after the action
    borrowed.set(animation, "action", None)
    for driver in animation.drivers:
        borrowed.set(driver, "mute", True)


def lights(borrowed, objects, plan: Plan, members) -> None:
    for obj in objects:
        if obj.type != "LIGHT" or obj.data.type not in LIGHT_TYPES:
            continue
        light = obj.data
        _still(borrowed, light)
        colours = plan.light_colours.get(obj.name)
        if colours is None:  # a light the exported scene does not hold: its RGB colour upsampled
            colours = parameters.emitter_bands(light.color, plan.bands, plan.cmf)
        _light_colour(borrowed, light, shaders.channels(colours, members))


def world(borrowed, scene, plan: Plan, members) -> None:
    """The spectral World in the bands (a sky blends horizon to zenith by the direction's z), or black."""
    temporary = borrowed.keep(bpy.data.worlds.new(".spectral emulation world"))
    tree = temporary.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputWorld")
    background = tree.nodes.new("ShaderNodeBackground")
    tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    zenith, horizon = plan.world_colours
    if plan.world is None:
        background.inputs["Strength"].default_value = 0.0
    else:
        background.inputs["Strength"].default_value = plan.world.strength
        background.inputs["Color"].default_value = (*shaders.channels(zenith, members), 1.0)
        if horizon is not None:
            _sky(tree, background, shaders.channels(zenith, members), shaders.channels(horizon, members))
    borrowed.set(scene, "world", temporary)


def _sky(tree, background, zenith, horizon) -> None:
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    split = tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(coordinates.outputs["Generated"], split.inputs["Vector"])
    clamp = tree.nodes.new("ShaderNodeClamp")
    tree.links.new(split.outputs["Z"], clamp.inputs["Value"])
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    tree.links.new(clamp.outputs["Result"], mix.inputs["Factor"])
    mix.inputs["A"].default_value, mix.inputs["B"].default_value = (*horizon, 1.0), (*zenith, 1.0)
    tree.links.new(mix.outputs["Result"], background.inputs["Color"])


def _attribute(obj, grid: str) -> str | None:
    """The Cycles attribute of a grid of a Volume object (None for meshes)."""
    return grid if obj.type == "VOLUME" else None


def materials(borrowed, objects, plan: Plan, members, shader: str, warnings: list, stand_ins: dict) -> None:
    """Volume materials in the bands on volumes, meshes and the fluid domains' `stand_ins`
    (`fluids.stand_ins`); band copies of the RGB surface materials."""
    media = {medium.name: medium for medium in plan.media}
    text = shaders.osl_text(borrowed) if shader == "OSL" and media else None
    copies = {}
    for obj in objects:
        medium = media.get(obj.name)
        if obj.name in stand_ins:
            stand_ins[obj.name].data.materials.append(shaders.volume_material(
                borrowed, medium, members, fluids.DENSITY, shader, text, fluids.TEMPERATURE))
            continue
        volume = spectral_material(obj) if medium is not None else None
        for slot in getattr(obj, "material_slots", ()):
            material = slot.material
            if material is None:
                continue
            if material == volume:
                replacement = shaders.volume_material(
                    borrowed, medium, members, _attribute(obj, obj.spectral.density_grid), shader, text,
                    _attribute(obj, volume.spectral.temperature_grid))  # None for meshes: density 1 inside
            elif material.spectral.enabled:
                continue  # a spectral material on a non-volume: ignored by the tracer as well
            else:
                if material.name not in copies:
                    copies[material.name] = surfaces.band_material(borrowed, material, members, plan.bands, plan.cmf,
                                                                   warnings)
                replacement = copies[material.name]
            borrowed.set(slot, "material", replacement)
