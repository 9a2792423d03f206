"""The Cycles emulation: it agrees with the tracer, packs bands by anisotropy, OSL and nodes give the same
image, the user's scene is left as it was, and it says what it cannot do (fluorescence).

Cross-checks compare 8×8-pixel block means: each block's difference must lie within 4 standard deviations
of the two estimates (the tracer's variance of the mean, and the emulation's from its two seeds; at least
10⁻⁴ of the white, for blocks that are black in both), and the mean colour within CIEDE2000 1 (white: D65
at the tracer's 99th-percentile luminance). Where the camera sees a light directly (a sky), noise is nil
and what remains is the band approximation (K band means stand in for each spectrum): there the bound
adds 1 % of the block's value."""

import math

import numpy as np
import pytest
from mathutils import Vector

from addon.cycles_emulation import parameters
from addon.cycles_emulation.job import EmulationJob
from addon.cycles_emulation.state import Borrowed
from addon.cycles_emulation.surfaces import band_material
from addon.export.scene import export_scene
from addon.tracer import colorimetry, grids, image_io
from addon.tracer.render import render
from addon.tracer.scene import Grid
from tests.addon.builders import add_camera, add_fluid_domain, add_sun, add_volume, link, tiny_render

bpy = pytest.importorskip("bpy")

BLOCK = 8
NOISE_BOUND = 4.0  # standard deviations per block


def write_blob(path, cells=16, edge=2.0, hot=False):
    """A smooth ball of density 1 − r² (0 at its edge, so the grid's border does not matter); `hot` adds a
    grid "temperature" of 1000 K + 1200 K × density."""
    x = (np.arange(cells) - (cells - 1) / 2) / (cells / 2)
    xx, yy, zz = np.meshgrid(x, x, x, indexing="ij")
    values = np.clip(1.0 - (xx**2 + yy**2 + zz**2), 0.0, None).astype(np.float32)
    voxel = edge / cells
    matrix = np.diag([voxel, voxel, voxel, 1.0])
    matrix[:3, 3] = -edge / 2 + voxel / 2
    layers = [Grid(values, matrix, "density")]
    if hot:
        layers.append(Grid(np.where(values > 0, 1000.0 + 1200.0 * values, 0.0).astype(np.float32), matrix,
                           "temperature"))
    grids.save_grid_vdb(path, *layers)
    return path


def blob_scene(tmp_path, width=48, height=32):
    scene = bpy.context.scene
    tiny_render(scene, width, height, 16)
    add_camera(location=(0.0, -5.0, 0.0))
    add_sun(rotation=(math.radians(40), 0.0, math.radians(30)), strength=3.0)
    cloud = add_volume(write_blob(tmp_path / "blob.vdb"))
    settings = cloud.material_slots[0].material.spectral
    settings.density_scale = 6.0
    settings.albedo.value = 0.8
    return scene, cloud


def emulate(scene, bands, shader="SVM", spp=None):
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    job = EmulationJob(scene, export.scene, export.warnings, band_count=bands, shader=shader, spp=spp)
    job.run()
    assert job.succeeded, job.error
    return job, export.scene


def _blocks(image):
    h, w = image.shape[0] // BLOCK, image.shape[1] // BLOCK
    return image[:h * BLOCK, :w * BLOCK].reshape(h, BLOCK, w, BLOCK, -1).mean(axis=(1, 3))


def agreement(emulated, traced, band_error=0.0):
    """(ΔE00 of the mean colours, largest block difference in standard deviations); `band_error`: a
    relative error of each block added to its noise."""
    white = colorimetry.rgb_to_xyz([1.0, 1.0, 1.0]) * np.percentile(traced.xyz[..., 1], 99)
    delta_e = float(colorimetry.delta_e_2000(emulated.xyz.mean(axis=(0, 1)), traced.xyz.mean(axis=(0, 1)), white))
    traced_blocks = _blocks(traced.xyz)
    sigma = np.sqrt((_blocks(emulated.variance) + _blocks(traced.variance)) / BLOCK**2
                    + (band_error * traced_blocks) ** 2)
    z = np.abs(_blocks(emulated.xyz) - traced_blocks) / np.maximum(sigma, 1e-4 * white.max())
    return delta_e, float(z.max())


def _cross_check(scene, bands, tracer_spp, cycles_spp, band_error=0.0):
    job, tracer_scene = emulate(scene, bands, spp=cycles_spp)
    traced = render(tracer_scene, spp=tracer_spp).film
    delta_e, z = agreement(job.film, traced, band_error)
    print(f"ΔE00 {delta_e:.3f}, largest block difference {z:.2f} σ, {job.cycles_renders} Cycles renders")
    assert delta_e < 1.0
    assert z < NOISE_BOUND
    return job


@pytest.mark.slow
@pytest.mark.parametrize("phase", ["hg", "rayleigh"])
def test_constant_albedo_agrees_with_the_tracer(registered, tmp_path, phase):
    scene, cloud = blob_scene(tmp_path)
    cloud.material_slots[0].material.spectral.phase = phase
    job = _cross_check(scene, bands=6, tracer_spp=256, cycles_spp=64)
    assert job.cycles_renders == 2  # ceil(6 / 3)


@pytest.mark.slow
def test_wavelength_dependent_albedo_agrees_with_the_tracer(registered, tmp_path):
    scene, cloud = blob_scene(tmp_path)
    settings = cloud.material_slots[0].material.spectral
    settings.albedo.source = "COLOR"
    settings.albedo.color = (0.9, 0.45, 0.15)
    scene.world = bpy.data.worlds.new("Sky")
    scene.world.spectral.enabled = True
    scene.world.spectral.enabled = True
    scene.world.spectral.strength = 0.3
    job = _cross_check(scene, bands=15, tracer_spp=256, cycles_spp=64)
    assert job.cycles_renders == 5


@pytest.mark.slow
def test_wavelength_dependent_anisotropy_agrees_with_the_tracer(registered, tmp_path):
    scene, cloud = blob_scene(tmp_path)
    table = tmp_path / "g.csv"
    table.write_text("250,0.0\n830,0.85\n")  # g rises over the whole range: no two bands alike
    anisotropy = cloud.material_slots[0].material.spectral.anisotropy
    anisotropy.source, anisotropy.filepath = "CSV", str(table)
    job = _cross_check(scene, bands=10, tracer_spp=256, cycles_spp=64)
    assert job.cycles_renders == 10  # g differs in every band: one band per render


@pytest.mark.slow
def test_camera_inside_the_volume_agrees_with_the_tracer(registered, tmp_path):
    """Cycles would skip the medium within the camera's clip start (0.1): the emulation sets it to ~0."""
    scene, _cloud = blob_scene(tmp_path)
    scene.camera.location = (0.0, -0.3, 0.0)
    job = _cross_check(scene, bands=3, tracer_spp=256, cycles_spp=64)
    assert job.cycles_renders == 1 and scene.camera.data.clip_start == pytest.approx(0.1)


@pytest.mark.slow
def test_blackbody_emission_agrees_with_the_tracer(registered, tmp_path):
    scene, cloud = blob_scene(tmp_path)
    bpy.data.objects.remove(bpy.data.objects["Sun"])  # lit by its own glow only
    cloud.data.filepath = str(write_blob(tmp_path / "hot.vdb", hot=True))
    settings = cloud.material_slots[0].material.spectral
    settings.use_blackbody, settings.blackbody_intensity, settings.albedo.value = True, 0.05, 0.5
    job = _cross_check(scene, bands=9, tracer_spp=256, cycles_spp=64)
    assert job.cycles_renders == 3 and job.film.xyz[..., 0].max() > 1.2 * job.film.xyz[..., 2].max()  # warm


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["POINT", "SPOT"])
def test_point_and_spot_lights_agree_with_the_tracer(registered, tmp_path, kind):
    """A 3000 K point light, or a spot whose blended cone edge crosses the blob (no sun). Radius 0: the
    tracer's lights are points."""
    scene, _cloud = blob_scene(tmp_path)
    bpy.data.objects.remove(bpy.data.objects["Sun"])
    light = link(bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", kind)))
    light.data.energy, light.data.shadow_soft_size = 150.0, 0.0
    light.data.spectral.enabled = True
    light.data.spectral.spectrum.source, light.data.spectral.spectrum.temperature = "BLACKBODY", 3000.0
    if kind == "POINT":
        light.location = (1.5, -1.5, 1.5)
    else:
        light.location = (0.0, -3.0, 2.0)
        light.rotation_euler = Vector((0.0, 3.0, -2.0)).to_track_quat("-Z", "Y").to_euler()
        light.data.spot_size, light.data.spot_blend = math.radians(25.0), 0.5
    job = _cross_check(scene, bands=6, tracer_spp=256, cycles_spp=64)
    rgb = job.film.rgb().mean(axis=(0, 1))
    assert rgb[0] > 1.5 * rgb[2]  # warm light


@pytest.mark.slow
def test_sky_world_agrees_with_the_tracer(registered, tmp_path):
    """Lit by a sky alone: a blue zenith over a white horizon (the emulation blends them by direction)."""
    scene, _cloud = blob_scene(tmp_path)
    bpy.data.objects.remove(bpy.data.objects["Sun"])
    scene.world = bpy.data.worlds.new("Sky")
    scene.world.spectral.enabled = True
    sky = scene.world.spectral
    sky.enabled, sky.kind, sky.strength = True, "sky", 1.0
    sky.spectrum.source, sky.spectrum.temperature = "BLACKBODY", 12000.0
    job = _cross_check(scene, bands=6, tracer_spp=256, cycles_spp=64, band_error=0.01)
    assert job.cycles_renders == 2


@pytest.mark.slow
def test_fluid_domain_agrees_with_the_tracer(registered, tmp_path):
    """A smoke domain whose cache holds an ellipsoid of density 1 − r², glowing by its temperature grid:
    Cycles cannot read the cache itself (its modifier is hidden), a stand-in Volume object does."""
    scene = bpy.context.scene
    tiny_render(scene, 48, 32, 16)
    add_camera(location=(0.0, -7.0, 1.0))
    add_sun(rotation=(math.radians(40), 0.0, math.radians(30)), strength=3.0)
    x, y, z = ((np.arange(n) - (n - 1) / 2) / (n / 2) for n in (16, 8, 8))
    xx, yy, zz = np.meshgrid(x, y, z, indexing="ij")
    blob = np.clip(1.0 - (xx**2 + yy**2 + zz**2), 0.0, None).astype(np.float32)
    domain, _density = add_fluid_domain(tmp_path, density=blob)
    settings = domain.material_slots[0].material.spectral
    settings.enabled, settings.density_scale, settings.albedo.value = True, 4.0, 0.7
    settings.use_blackbody, settings.temperature_grid, settings.blackbody_intensity = True, "heat", 0.02
    settings.temperature_scale, settings.temperature_offset = 600.0, 800.0
    before = _snapshot(scene)
    job = _cross_check(scene, bands=15, tracer_spp=256, cycles_spp=64)
    assert job.film.xyz[..., 1].max() > 0.05
    assert _snapshot(scene) == before and not domain.hide_render
    assert not bpy.data.volumes and len(bpy.data.objects) == 3


def _surface_scene(tmp_path):
    """The blob in front of a red Principled plane, lit by the sun and an area light, with a sky."""
    scene, cloud = blob_scene(tmp_path, width=24, height=16)
    bpy.ops.mesh.primitive_plane_add(size=8.0, location=(0.0, 2.0, 0.0), rotation=(math.radians(90), 0.0, 0.0))
    plane = bpy.context.object
    paint = bpy.data.materials.new("Paint")
    paint.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.1, 0.05, 1.0)
    plane.data.materials.append(paint)
    area = bpy.data.objects.new("Area", bpy.data.lights.new("Area", "AREA"))
    area.location = (0.0, -2.0, 3.0)
    area.data.color = (1.0, 0.9, 0.8)
    scene.collection.objects.link(area)
    scene.world = bpy.data.worlds.new("Sky")
    scene.world.spectral.enabled = True
    scene.world.spectral.enabled = True
    scene.world.spectral.kind = "sky"
    scene.world.spectral.strength = 0.2
    return scene, cloud, plane


def _snapshot(scene) -> dict:
    """What the emulation changes while it renders, as plain values."""
    cycles, render = scene.cycles, scene.render
    state = {name: getattr(cycles, name) for name in (
        "samples", "seed", "device", "shading_system", "volume_bounces", "max_bounces", "pixel_filter_type",
        "filter_width", "sample_clamp_direct", "sample_clamp_indirect", "light_sampling_threshold",
        "use_denoising", "use_adaptive_sampling", "use_volume_guiding", "blur_glossy")}
    state.update({name: getattr(render, name) for name in (
        "engine", "filepath", "use_persistent_data", "use_compositing", "film_transparent")})
    state["image"] = (render.image_settings.file_format, render.image_settings.color_depth)
    state["clipping"] = (scene.camera.data.clip_start, scene.camera.data.clip_end)
    state["world"] = scene.world.name if scene.world else None
    state["slots"] = {obj.name: [slot.material.name if slot.material else None for slot in obj.material_slots]
                      for obj in scene.objects}
    state["lights"] = {obj.name: (tuple(obj.data.color), obj.data.energy) for obj in scene.objects
                       if obj.type == "LIGHT"}
    state["colours"] = {material.name: [tuple(socket.default_value) for node in material.node_tree.nodes
                                        for socket in node.inputs if socket.type == "RGBA"]
                        for material in bpy.data.materials if material.node_tree}
    state["datablocks"] = (sorted(bpy.data.materials.keys()), sorted(bpy.data.worlds.keys()),
                           sorted(bpy.data.texts.keys()))
    return state


def test_scene_is_untouched_after_a_render_and_after_a_cancelled_one(registered, tmp_path):
    scene, _cloud, _plane = _surface_scene(tmp_path)
    scene.render.engine = "SPECTRAL_VOLUME"
    bpy.context.view_layer.update()  # the engine's Material Preview nodes are made now (`eevee_stand_in`), not by a render
    before = _snapshot(scene)
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    job = EmulationJob(scene, export.scene, export.warnings, band_count=6, spp=2)
    job.step()  # one of two renders, then cancelled
    assert _snapshot(scene) == before
    job.cancel()
    job.run()
    assert job.result.cancelled and not job.succeeded and job.film.renders == 1
    assert _snapshot(scene) == before
    done, _tracer_scene = emulate(scene, 9, spp=2)
    assert _snapshot(scene) == before
    # The red plane is red in the emulation too: its upsampled reflectance, band by band.
    rgb = done.film.rgb()
    corner = rgb[:3, :3].mean(axis=(0, 1))
    assert corner[0] > 2 * corner[1] and corner[0] > 2 * corner[2]


def test_failed_render_leaves_the_scene_untouched(registered, tmp_path):
    scene, cloud, _plane = _surface_scene(tmp_path)
    settings = cloud.material_slots[0].material.spectral
    for level in range(9):  # more albedo levels than the OSL shader takes: fails after the set-up began
        settings.albedo_levels.add().density = 0.1 * (level + 1)
    before = _snapshot(scene)
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    job = EmulationJob(scene, export.scene, band_count=3, shader="OSL", spp=2)
    job.run()
    assert not job.succeeded and "at most 8" in job.error and "Nodes (SVM)" in job.error
    assert _snapshot(scene) == before


@pytest.mark.parametrize("by_density", [False, True], ids=["constant albedo", "albedo by density"])
def test_osl_and_nodes_give_the_same_image(registered, tmp_path, by_density):
    scene, cloud = blob_scene(tmp_path, width=24, height=16)
    settings = cloud.material_slots[0].material.spectral
    settings.albedo.source = "COLOR"
    settings.albedo.color = (0.9, 0.5, 0.2)
    settings.anisotropy.value = 0.5
    if by_density:  # falls to 0.3 at the blob's centre: OSL's stochastic grid reads once made this 4 % darker
        level = settings.albedo_levels.add()
        level.density, level.spectrum.value = 1.0, 0.3
    nodes, _scene = emulate(scene, 3, "SVM", spp=64)
    osl, _scene = emulate(scene, 3, "OSL", spp=64)
    assert nodes.film.xyz.max() > 0.02
    # Cycles draws other random numbers with OSL than with its nodes: the same image within noise, not bit for
    # bit.
    delta_e, z = agreement(osl.film, nodes.film)
    print(f"OSL vs nodes: ΔE00 {delta_e:.3f}, largest block difference {z:.2f} σ")
    assert delta_e < 0.5 and z < NOISE_BOUND


def test_fluorescence_is_rendered_as_absorption_with_a_warning(registered, tmp_path):
    scene, cloud = blob_scene(tmp_path, width=8, height=6)
    cloud.material_slots[0].material.spectral.use_fluorescence = True
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    job = EmulationJob(scene, export.scene, export.warnings, band_count=3)
    assert any("fluoresces" in warning and "no fluorescent glow" in warning for warning in job.warnings)
    assert job.plan.media[0].excitation.max() > 0


def test_render_to_image_uses_the_emulation_when_chosen(registered, tmp_path, capfd):
    scene, _cloud = blob_scene(tmp_path, width=16, height=12)
    scene.spectral.renderer = "CYCLES"  # with the automatic bands: a grey cloud under one sun needs one
    scene.spectral.samples = 4
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.0, 3.0, -3.0))  # out of view: only its warning counts
    marble = bpy.data.materials.new("Marble")
    tree = marble.node_tree
    tree.links.new(tree.nodes.new("ShaderNodeTexNoise").outputs["Color"],
                   tree.nodes["Principled BSDF"].inputs["Base Color"])
    bpy.context.object.data.materials.append(marble)
    exr = tmp_path / "emulated.exr"
    assert bpy.ops.spectral.render_image(image_name="Emulated", exr_path=str(exr)) == {"FINISHED"}
    out = capfd.readouterr().out
    assert "Cycles emulation: 1 bands in 1 Cycles render(s), estimated color error ΔE00 0.00" in out
    # Found while rendering, shown when it ends.
    assert "Warning: material 'Marble': colours computed by nodes" in out
    image = bpy.data.images["Emulated"]
    assert image.is_float and tuple(image.size) == (16, 12)
    pixels = np.array(image.pixels[:], dtype=np.float32).reshape(12, 16, 4)[::-1]
    channels = image_io.read_exr(exr)
    assert {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B", "ViewLayer.Combined.A",
            "ViewLayer.XYZ.X", "ViewLayer.XYZ.Y", "ViewLayer.XYZ.Z", "ViewLayer.XYZ Variance.Y"} <= set(channels)
    xyz = np.stack([channels[f"ViewLayer.XYZ.{c}"] for c in "XYZ"], axis=-1)
    assert xyz[..., 1].max() > 0.05
    np.testing.assert_allclose(pixels[..., :3], colorimetry.xyz_to_rgb(xyz), rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(channels["ViewLayer.Combined.R"], pixels[..., 0], rtol=1e-5, atol=1e-6)
    assert scene.render.engine != "CYCLES"  # the user's engine came back


def test_animated_colours_do_not_replace_the_band_colours(registered, tmp_path):
    """Cycles evaluates the frame it renders: a keyframed light colour would override the band colours."""
    scene, _cloud = blob_scene(tmp_path, width=16, height=12)
    plain, _scene = emulate(scene, 3, spp=4)
    sun = bpy.data.objects["Sun"].data
    sun.color = (1.0, 0.0, 0.0)
    sun.keyframe_insert("color", frame=scene.frame_current)
    action = sun.animation_data.action
    animated, _scene = emulate(scene, 3, spp=4)
    np.testing.assert_allclose(animated.film.xyz, plain.film.xyz, rtol=1e-6, atol=1e-9)
    assert sun.animation_data.action == action and sun.animation_data.action_slot is not None
    # Surface copies lose their animation too (their colours at this frame are the material's).
    paint = bpy.data.materials.new("Paint")
    base = paint.node_tree.nodes["Principled BSDF"].inputs["Base Color"]
    base.default_value = (0.8, 0.1, 0.05, 1.0)
    base.keyframe_insert("default_value", frame=scene.frame_current)
    job = EmulationJob(scene, export_scene(bpy.context.evaluated_depsgraph_get()).scene, band_count=3, spp=2)
    with Borrowed() as borrowed:
        copy = band_material(borrowed, paint, (0, 1, 2), job.plan.bands, job.plan.cmf, [])
        assert copy.node_tree.animation_data is None
        assert tuple(copy.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value) != (0.8, 0.1, 0.05, 1.0)
    assert paint.node_tree.animation_data.action is not None


def test_a_spectral_surface_gives_its_spectrum_to_the_albedo_inputs(registered, tmp_path):
    """With Spectral Surface on, the band copy's albedo input holds the reflectance spectrum's band means, in
    place of its colour or its texture (as the tracer renders it); the other colours are upsampled as ever."""
    scene, _cloud = blob_scene(tmp_path, width=16, height=12)
    paint = bpy.data.materials.new("Paint")
    tree = paint.node_tree
    principled = tree.nodes["Principled BSDF"]
    tree.links.new(tree.nodes.new("ShaderNodeTexChecker").outputs["Color"], principled.inputs["Base Color"])
    principled.inputs["Emission Color"].default_value = (1.0, 0.5, 0.0, 1.0)
    paint.spectral.use_surface = True
    paint.spectral.reflectance.source, paint.spectral.reflectance.value = "CONSTANT", 0.3
    job = EmulationJob(scene, export_scene(bpy.context.evaluated_depsgraph_get()).scene, band_count=3, spp=2)
    warnings = []
    with Borrowed() as borrowed:
        copy = band_material(borrowed, paint, (0, 1, 2), job.plan.bands, job.plan.cmf, warnings)
        inputs = copy.node_tree.nodes["Principled BSDF"].inputs
        assert not inputs["Base Color"].is_linked and warnings == []
        np.testing.assert_allclose(tuple(inputs["Base Color"].default_value)[:3], 0.3, rtol=1e-6)
        orange = parameters.emitter_bands((1.0, 0.5, 0.0), job.plan.bands, job.plan.cmf)
        np.testing.assert_allclose(tuple(inputs["Emission Color"].default_value)[:3], orange, rtol=1e-5)
    assert principled.inputs["Base Color"].is_linked  # the user's material is untouched


def test_render_region_is_the_region_of_the_frame(registered, tmp_path):
    """The exported camera sees the region alone, so Cycles renders the region, cropped; Cycles samples a
    pixel alike whether it renders the frame or a region, so the region's pixels are the frame's (up to
    rounding: 1e-5 relative)."""
    scene, _cloud = blob_scene(tmp_path, width=16, height=12)
    full, _scene = emulate(scene, 3, spp=2)
    render = scene.render
    render.use_border, render.use_crop_to_border = True, False
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = 0.33, 0.77, 0.1, 0.55
    region, tracer_scene = emulate(scene, 3, spp=2)
    assert (tracer_scene.camera.width, tracer_scene.camera.height) == (7, 5)  # columns 5…11, rows 1…5 from below
    np.testing.assert_allclose(region.film.xyz, full.film.xyz[12 - 6:12 - 1, 5:12], rtol=1e-5, atol=1e-8)
    assert not render.use_crop_to_border  # the user's setting is back


def test_f12_refuses_the_emulation(registered, tmp_path):
    scene, _cloud = blob_scene(tmp_path, width=8, height=6)
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.spectral.renderer = "CYCLES"
    with pytest.raises(RuntimeError, match="Render to Image"):
        bpy.ops.render.render(write_still=False)


@pytest.mark.slow
def test_fluorescence_error_against_the_tracer(registered, tmp_path):
    """The emulation renders a fluorophore as the tracer does with quantum yield 0 (absorption, no glow); the
    difference from the fluorescent tracer render is the missing glow, printed as the stated error."""
    scene, cloud = blob_scene(tmp_path)
    settings = cloud.material_slots[0].material.spectral
    settings.use_fluorescence, settings.quantum_yield = True, 0.9
    settings.excitation.source, settings.excitation.peak, settings.excitation.width = "GAUSSIAN", 440.0, 40.0
    settings.excitation.value = 1.5
    settings.emission.source, settings.emission.peak, settings.emission.width = "GAUSSIAN", 560.0, 25.0
    job, fluorescent = emulate(scene, 15, spp=64)  # bands of 31 nm: the excitation peak is resolved
    assert any("fluoresces" in warning for warning in job.warnings)
    glowing = render(fluorescent, spp=256).film
    settings.quantum_yield = 0.0
    dark = render(export_scene(bpy.context.evaluated_depsgraph_get()).scene, spp=256).film
    delta_e, z = agreement(job.film, dark)
    missing_e, _z = agreement(job.film, glowing)
    missing_y = 1.0 - job.film.xyz[..., 1].mean() / glowing.xyz[..., 1].mean()
    print(f"fluorescence: vs tracer without re-emission ΔE00 {delta_e:.3f} ({z:.2f} σ); vs the fluorescent "
          f"tracer ΔE00 {missing_e:.2f}, luminance {100 * missing_y:.1f} % lower")
    assert delta_e < 1.0 and z < NOISE_BOUND
    assert missing_e > 2.0 and missing_y > 0.05  # the glow the emulation leaves out is visible


def test_panels_say_what_the_emulation_cannot_do(registered):
    from addon.ui import material as material_ui
    from addon.ui import render as render_ui
    from tests.addon.recording import RecordingLayout

    material = bpy.data.materials.new("Dye")
    material.spectral.enabled = material.spectral.use_fluorescence = True
    scene = bpy.context.scene
    for renderer, shown in (("TRACER", False), ("CYCLES", True)):
        scene.spectral.renderer = renderer
        fluorescence, settings = RecordingLayout(), RecordingLayout()
        material_ui.draw_fluorescence(fluorescence, material, scene.spectral.renderer)
        render_ui.draw_render_main(settings, scene)
        assert any("nothing is re-emitted" in text for text in fluorescence.texts()) == shown
        assert any("no re-emission" in text for text in settings.texts()) == shown
        assert (("prop", (scene.spectral, "emulation_band_mode"), {}) in settings.calls) == shown


def test_estimate_bands_shows_the_plan_in_the_panel(registered, tmp_path):
    """Automatic bands: the panel offers the budget and Estimate Bands, which shows the plan without
    rendering; Fixed bands: the count instead."""
    from addon.ui import render as render_ui
    from tests.addon.recording import RecordingLayout

    scene, cloud = blob_scene(tmp_path)
    scene.spectral.renderer = "CYCLES"
    settings = cloud.material_slots[0].material.spectral
    settings.albedo.source, settings.albedo.color = "COLOR", (0.9, 0.45, 0.15)
    assert bpy.ops.spectral.estimate_emulation_bands() == {"FINISHED"}
    panel = RecordingLayout()
    render_ui.draw_render_main(panel, scene)
    assert ("prop", (scene.spectral, "emulation_max_renders"), {}) in panel.calls
    assert any(call[0] == "operator" and call[1][0] == "spectral.estimate_emulation_bands" for call in panel.calls)
    assert any("Cycles render(s), estimated color error ΔE00" in text for text in panel.texts())
    scene.spectral.emulation_band_mode = "FIXED"
    panel = RecordingLayout()
    render_ui.draw_render_main(panel, scene)
    assert ("prop", (scene.spectral, "emulation_bands"), {}) in panel.calls
    assert ("prop", (scene.spectral, "emulation_max_renders"), {}) not in panel.calls


def test_cli_follows_the_scene_renderer(registered, tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    scene, _cloud = blob_scene(tmp_path, width=16, height=12)
    scene.spectral.renderer, scene.spectral.samples = "CYCLES", 2
    scene.spectral.emulation_band_mode, scene.spectral.emulation_bands = "FIXED", 3
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    out = tmp_path / "cli.exr"
    done = subprocess.run([sys.executable, "-m", "addon.cli", "render", str(blend), "--out", str(out), "--quiet"],
                          cwd=Path(__file__).resolve().parents[2], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "Cycles emulation: 3 equal bands in 1 Cycles render(s), each made twice" in done.stdout
    channels = image_io.read_exr(out)
    assert channels["ViewLayer.XYZ.Y"].shape == (12, 16) and channels["ViewLayer.XYZ.Y"].max() > 0.01
    assert "ViewLayer.XYZ Variance.Y" in channels
