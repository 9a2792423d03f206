"""Film ▸ Transparent and holdouts from Blender: the export (`render.film_transparent`, the Holdout shader, an
object's Holdout property, collections set to Holdout), the Render Result's alpha, Cycles as the control, and
compositing this engine's volume over a Cycles plate.

Alpha's noise is measured as Cycles' is in `tests/support/cycles.py`: from two renders with different seeds."""

import math

import numpy as np
import pytest

from addon.tracer import colorimetry, image_io
from addon.tracer.render import render
from tests.addon.builders import basic_scene
from tests.addon.test_blender_scene import factory_scene, volume_shader
from tests.addon.test_surfaces import _export, _plane, _surface_shader
from tests.support.cycles import BLOCK, NOISE_BOUND, blocks, cycles_rgb, look_at

bpy = pytest.importorskip("bpy")


@pytest.fixture
def factory(registered):
    return factory_scene()


def _material(name, kind, **inputs):
    material = bpy.data.materials.new(name)
    _surface_shader(material, kind, **inputs)
    return material


def test_film_transparent_and_every_kind_of_holdout_are_exported(factory):
    """Holdout by shader (black for indirect rays: reflectance 0), by the object's property, by a collection set
    to Holdout (the object keeps its material for indirect rays); a mixed Holdout named. A collection set to
    Indirect Only and an object's Ray Visibility ▸ Camera off hide a surface from camera rays only."""
    factory.render.film_transparent = True
    bpy.data.objects.remove(bpy.data.objects["Cube"])
    grey = _material("Grey", "ShaderNodeBsdfDiffuse", Color=(0.5, 0.5, 0.5))
    _plane("Shader", location=(-3.0, 0.0, 0.0), material=_material("Hole", "ShaderNodeHoldout"))
    _plane("Property", location=(0.0, 0.0, 0.0), material=grey).is_holdout = True
    mixed = _material("Half", "ShaderNodeMixShader", Fac=0.5)
    tree = mixed.node_tree
    tree.links.new(tree.nodes.new("ShaderNodeHoldout").outputs[0], tree.nodes["Mix Shader"].inputs[1])
    tree.links.new(tree.nodes.new("ShaderNodeBsdfDiffuse").outputs[0], tree.nodes["Mix Shader"].inputs[2])
    _plane("Mixed", location=(6.0, 0.0, 0.0), material=mixed)
    _plane("Plain", location=(9.0, 0.0, 0.0), material=grey)
    _plane("Unseen", location=(12.0, 0.0, 0.0), material=grey).visible_camera = False
    for name, flag in (("Held", "holdout"), ("Indirect", "indirect_only")):
        collection = bpy.data.collections.new(name)
        factory.collection.children.link(collection)
        plane = _plane(f"In {name}", location=(3.0, 3.0 * len(name), 0.0), material=grey)
        for owner in plane.users_collection:
            owner.objects.unlink(plane)
        collection.objects.link(plane)
        setattr(bpy.context.view_layer.layer_collection.children[name], flag, True)
    export = _export()
    assert export.scene.settings.transparent is True
    surfaces = {surface.name: surface for surface in export.scene.surfaces}
    assert {name for name, surface in surfaces.items() if surface.holdout} == {"Shader", "Property", "Mixed",
                                                                                "In Held"}
    assert not surfaces["Shader"].reflectance.values.any()
    np.testing.assert_allclose(surfaces["Property"].reflectance.values, surfaces["Plain"].reflectance.values)
    [warning] = export.warnings
    assert "material 'Half': Holdout mixed in at weight 0.5 rendered as a whole holdout" in warning
    assert "Indirect" not in warning
    assert {name for name, surface in surfaces.items() if not surface.camera} == {"In Indirect", "Unseen"}
    factory.render.film_transparent = False
    assert _export().scene.settings.transparent is False


@pytest.mark.slow
def test_f12_writes_the_films_alpha_into_combined(registered, tmp_path):
    scene, _cloud = basic_scene(tmp_path)
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.film_transparent = True
    scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    scene.render.filepath = str(tmp_path / "f12.exr")
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    channels = image_io.read_exr(tmp_path / "f12.exr")
    film = render(_export().scene).film  # the same scene and seed: the same image
    assert film.alpha.min() < 0.5 < film.alpha.max()  # the cloud over an empty background
    np.testing.assert_allclose(channels["ViewLayer.Combined.A"], film.alpha, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(channels["ViewLayer.Combined.R"], film.rgb()[..., 0], rtol=1e-4, atol=1e-6)


def _tracer_rgba(spp, seeds=(1, 2)):
    """This engine's premultiplied RGBA (height, width, 4) averaged over renders with `seeds`, and each
    channel's variance of that mean per pixel (RGB from the films' variance, alpha from the renders' spread)."""
    export = _export()
    films = [render(export.scene, spp=spp, seed=seed).film for seed in seeds]
    to_rgb = colorimetry.xyz_to_rgb_matrix()
    rgba = np.mean([np.concatenate([film.xyz @ to_rgb.T, film.alpha[..., None]], axis=-1) for film in films], axis=0)
    variance = np.concatenate([sum(film.variance for film in films) @ (to_rgb**2).T / len(films) ** 2,
                               (films[0].alpha - films[1].alpha)[..., None] ** 2 / 4], axis=-1)
    return rgba, variance, export.warnings


def _block_z(first, first_variance, second, second_variance):
    sigma = np.sqrt((blocks(first_variance) + blocks(second_variance)) / BLOCK**2)
    return np.abs(blocks(first) - blocks(second)) / np.maximum(sigma, 1e-4)


def _cycles_noise(halves):
    return (halves[0] - halves[1]) ** 2 / 4


@pytest.mark.slow
@pytest.mark.parametrize("holdout", [False, True])
def test_a_volume_cube_over_a_coloured_world_with_film_transparent_matches_cycles(factory, tmp_path, holdout):
    """A grey Principled Volume (extinction 1.5 per unit, 3 across the cube) over a blue World: Cycles and this
    engine agree on alpha and on the premultiplied colour, block by block, and on the mean alpha. With the cube's
    Holdout property on too: Cycles renders a volume's holdout as an ordinary volume, and so does this engine,
    saying so."""
    factory.render.film_transparent = True
    bpy.data.objects["Cube"].is_holdout = holdout
    background = factory.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.1, 0.3, 0.8, 1.0)
    background.inputs["Strength"].default_value = 1.0
    volume_shader(bpy.data.objects["Cube"].active_material, Color=(0.8, 0.8, 0.8), Density=1.5)
    traced, traced_variance, warnings = _tracer_rgba(spp=64)
    assert warnings == ([] if not holdout else [
        "object 'Cube': Holdout has no effect on a volume, in Cycles as here: the volume renders as it is"])
    halves = [cycles_rgb(factory, tmp_path, 64, seed, alpha=True) for seed in (1, 2)]
    cycled = (halves[0] + halves[1]) / 2
    z = _block_z(traced, traced_variance, cycled, _cycles_noise(halves))
    print(f"alpha: tracer {traced[..., 3].mean():.4f}, Cycles {cycled[..., 3].mean():.4f}; blocks within "
          f"{z.max():.2f} σ")
    assert z.max() < NOISE_BOUND
    alpha_error = np.sqrt(traced_variance[..., 3].sum() + _cycles_noise(halves)[..., 3].sum()) / traced[..., 3].size
    assert abs(traced[..., 3].mean() - cycled[..., 3].mean()) <= NOISE_BOUND * alpha_error
    assert 0.05 < cycled[..., 3].mean() < 0.9 and traced[..., 3].min() < 0.05  # the cube, and the World around it


@pytest.mark.slow
def test_the_volume_with_a_holdout_ground_composited_over_a_cycles_plate_is_the_full_render(factory, tmp_path):
    """An emissive, absorbing cube high above a grey ground under a low sun (its shadow falls off the ground),
    seen from above: this engine's render of it with the ground as holdout and Film ▸ Transparent, put "over"
    Cycles' render of the ground alone, is this engine's render of the whole scene. What the composite cannot
    have, the cube's own light on the ground (it subtends 0.03 sr there at a radiance of about Y 0.2, against the
    sun's irradiance of 1.5: about 0.5 % more light below it), is admitted as a relative allowance of 1 % per
    block."""
    factory.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    bpy.data.objects.remove(bpy.data.objects["Light"])
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    factory.collection.objects.link(sun)
    sun.data.energy, sun.data.angle = 3.0, 0.0
    sun.rotation_euler = (0.0, math.radians(60.0), 0.0)  # from +x, 30° above the horizon
    cube = bpy.data.objects["Cube"]
    cube.location = (0.0, 0.0, 12.0)
    volume_shader(cube.active_material, Color=(0.0, 0.0, 0.0), Density=0.6, **{
        "Emission Color": (1.0, 0.5, 0.2), "Emission Strength": 0.3})
    ground = _plane("Ground", size=6.0, material=_material("Ground", "ShaderNodeBsdfDiffuse", Color=(0.5, 0.5, 0.5)))
    camera = bpy.data.objects["Camera"]
    camera.location, camera.data.type, camera.data.ortho_scale = (0.0, 0.0, 30.0), "ORTHO", 8.0
    look_at(camera, (0.0, 0.0, 0.0))

    full, full_variance, _ = _tracer_rgba(spp=64, seeds=(3, 4))
    factory.render.film_transparent, ground.is_holdout = True, True
    front, front_variance, _ = _tracer_rgba(spp=64)
    factory.render.film_transparent, ground.is_holdout, cube.hide_render = False, False, True
    halves = [cycles_rgb(factory, tmp_path, 64, seed) for seed in (1, 2)]
    plate, plate_variance = (halves[0] + halves[1]) / 2, _cycles_noise(halves)

    alpha = front[..., 3:]
    composite = front[..., :3] + (1.0 - alpha) * plate
    composite_variance = front_variance[..., :3] + plate ** 2 * front_variance[..., 3:] + plate_variance
    z = _block_z(composite, composite_variance, full[..., :3], full_variance[..., :3])
    allowance = 0.01 * blocks(full[..., :3])
    z_allowed = np.abs(blocks(composite) - blocks(full[..., :3])) / np.maximum(
        np.sqrt((blocks(composite_variance) + blocks(full_variance[..., :3])) / BLOCK**2 + allowance**2), 1e-4)
    print(f"composite vs full: blocks within {z.max():.2f} σ ({z_allowed.max():.2f} σ with the allowance); "
          f"alpha {alpha.min():.3f}–{alpha.max():.3f}")
    assert z_allowed.max() < NOISE_BOUND
    assert alpha.max() > 0.3 and alpha.min() < 0.05  # the cube is seen, and the ground is a hole around it
    assert plate.mean() > 0.05  # the ground is lit in the plate
