"""The artist's own scene: volume shaders, lights and the World as Blender sets them render as Cycles shows
them (Cycles in the bpy module as the control, `tests/support/cycles.py`), and what is not rendered is named.

Grey media must agree with Cycles within noise: every 8×8 block within 4 standard deviations of the two
estimates (the tracer's film variance; Cycles' from two seeds) and the mean colour within CIEDE2000 0.5."""

import math

import numpy as np
import pytest

from addon.export.scene import export_scene
from addon.tracer import colorimetry
from addon.tracer.errors import SpectralError
from addon.tracer.sky_model import SkyParameters, sun_direction
from tests.support.cycles import NOISE_BOUND, compare, look_at

bpy = pytest.importorskip("bpy")

GREY_DELTA_E = 0.5


def _export():
    return export_scene(bpy.context.evaluated_depsgraph_get())


def factory_scene(width=48, height=32):
    """Blender's factory scene (cube, point light, grey World) small, with the add-on's engine chosen."""
    bpy.ops.wm.read_factory_settings(use_empty=False)
    scene = bpy.context.scene
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    bpy.data.objects["Light"].data.shadow_soft_size = 0.0  # the tracer's point lights are points
    return scene


def volume_shader(material, kind="ShaderNodeVolumePrincipled", keep_surface=False, **inputs):
    """Give `material` a volume shader node of `kind` with `inputs` (by socket name), in place of its surface."""
    tree = material.node_tree
    node = tree.nodes.new(kind)
    for name, value in inputs.items():
        socket = node.inputs[name]
        socket.default_value = (*value, 1.0) if isinstance(value, tuple) and len(socket.default_value) == 4 else value
    output = tree.get_output_node("ALL")
    tree.links.new(node.outputs[0], output.inputs["Volume"])
    if not keep_surface and output.inputs["Surface"].is_linked:
        tree.links.remove(output.inputs["Surface"].links[0])
    return node


def _cube_material():
    return bpy.data.objects["Cube"].active_material


@pytest.fixture
def factory(registered):
    scene = factory_scene()
    yield scene


def test_factory_scene_with_a_principled_volume_matches_cycles(factory, tmp_path):
    """The factory scene (point light 1000 W, World grey 0.05) with a grey Principled Volume on its cube."""
    volume_shader(_cube_material(), Color=(0.8, 0.8, 0.8), Density=1.0)
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.warnings == []
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND
    assert result.cycled.mean() > 0.02  # a lit image, not a flat or black frame


def test_volume_scatter_and_absorption_match_cycles(factory, tmp_path):
    material = _cube_material()
    scatter = volume_shader(material, "ShaderNodeVolumeScatter", Color=(0.7, 0.7, 0.7), Density=1.5, Anisotropy=0.5)
    absorb = material.node_tree.nodes.new("ShaderNodeVolumeAbsorption")
    absorb.inputs["Color"].default_value = (0.6, 0.6, 0.6, 1.0)
    absorb.inputs["Density"].default_value = 1.0
    add = material.node_tree.nodes.new("ShaderNodeAddShader")
    material.node_tree.links.new(scatter.outputs[0], add.inputs[0])
    material.node_tree.links.new(absorb.outputs[0], add.inputs[1])
    material.node_tree.links.new(add.outputs[0], material.node_tree.get_output_node("ALL").inputs["Volume"])
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND


def test_sun_and_world_colour_light_the_volume_as_in_cycles(factory, tmp_path):
    """A sun of 3 W/m² and a World of colour (0.2, 0.2, 0.2) × 2 light a grey cube; no point light."""
    bpy.data.objects.remove(bpy.data.objects["Light"])
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    factory.collection.objects.link(sun)
    sun.data.energy, sun.data.angle = 3.0, 0.0
    sun.rotation_euler = (math.radians(50), 0.0, math.radians(20))
    background = factory.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.2, 0.2, 0.2, 1.0)
    background.inputs["Strength"].default_value = 2.0
    volume_shader(_cube_material(), Color=(0.9, 0.9, 0.9), Density=2.0, Anisotropy=0.3)
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND


def test_spot_light_colour_and_temperature_as_in_cycles(factory, tmp_path):
    """A spot light's Color and Temperature (Blender multiplies them) and its Exposure."""
    light = bpy.data.objects["Light"]
    light.data.type = "SPOT"
    spot = light.data
    spot.spot_size, spot.spot_blend, spot.exposure = math.radians(60), 0.2, 1.0
    spot.color = (1.0, 0.8, 0.6)
    spot.use_temperature, spot.temperature = True, 4000.0
    light.rotation_euler = (0.0, 0.0, 0.0)
    light.location = (0.0, 0.0, 4.0)
    volume_shader(_cube_material(), Color=(0.8, 0.8, 0.8), Density=1.0)
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.delta_e < 1.0 and result.z < NOISE_BOUND  # a coloured light on a grey medium


def test_the_factory_scene_is_no_longer_silent(factory):
    """Its cube is a diffuse surface (its specular layer named as not rendered), lit by the point light and the
    World."""
    export = _export()
    assert export.warnings == ["material 'Material' ▸ Principled BSDF: rendered as its diffuse Base Color, "
                               "without specular"]
    kinds = sorted(light.kind for light in export.scene.lights)
    assert kinds == ["environment", "point"] and export.scene.media == ()
    assert [surface.name for surface in export.scene.surfaces] == ["Cube"]


def test_world_colour_is_blenders_by_default_and_the_spectral_world_starts_from_it(factory):
    background = factory.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.1, 0.2, 0.6, 1.0)
    background.inputs["Strength"].default_value = 1.5
    world = next(light for light in _export().scene.lights if light.kind == "environment")
    radiance = world.spectrum.values * world.strength / world.spectrum.integral()
    rgb = colorimetry.xyz_to_rgb(colorimetry.spectrum_to_xyz(radiance))
    np.testing.assert_allclose(rgb, np.array([0.1, 0.2, 0.6]) * 1.5, rtol=0.01, atol=0.002)
    factory.world.spectral.enabled = True
    settings = factory.world.spectral
    assert settings.spectrum.source == "COLOR" and settings.unit == "luminous"
    np.testing.assert_allclose(settings.spectrum.color, (1 / 6, 2 / 6, 1.0), rtol=1e-5)
    spectral = next(light for light in _export().scene.lights if light.kind == "environment")
    assert spectral.strength == pytest.approx(1.5 * (0.2126 * 0.1 + 0.7152 * 0.2 + 0.0722 * 0.6), rel=1e-5)


def test_what_is_not_rendered_is_named_in_one_warning(factory):
    bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0.0, 0.0, -1.0))
    area = bpy.data.objects.new("Area", bpy.data.lights.new("Area", "AREA"))
    factory.collection.objects.link(area)
    area.data.spread = math.radians(90.0)
    world = factory.world.node_tree
    sky = world.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "HOSEK_WILKIE"
    world.links.new(sky.outputs["Color"], world.nodes["Background"].inputs["Color"])
    fog = volume_shader(_cube_material(), "ShaderNodeVolumeScatter", Color=(0.8, 0.8, 0.8), Density=1.0)
    fog.phase = "MIE"
    texture = _cube_material().node_tree.nodes.new("ShaderNodeTexNoise")
    _cube_material().node_tree.links.new(texture.outputs["Fac"], fog.inputs["Density"])
    warnings = _export().warnings
    assert len(warnings) == 1
    warning = warnings[0]
    assert warning.startswith("not rendered: 1 World texture (Sky Texture of World 'World', Hosek / Wilkie model); ")
    assert "light 'Area': Spread 90° rendered as 180°" in warning
    assert "material 'Material' ▸ Volume Scatter: phase Mie rendered as Henyey–Greenstein" in warning
    assert "material 'Material' ▸ Volume Scatter ▸ Density is driven by 'Noise Texture'" in warning


def test_spectral_switch_chooses_the_spectral_settings_over_the_nodes(factory):
    material = _cube_material()
    volume_shader(material, Color=(0.8, 0.1, 0.1), Density=2.0)
    from_nodes = _export().scene.media[0]
    assert from_nodes.extinction.values.max() == pytest.approx(2.0)
    assert from_nodes.albedo_table[0, 650 - 250] > 0.6 > 0.2 > from_nodes.albedo_table[0, 530 - 250]
    material.spectral.enabled = True
    material.spectral.albedo.source, material.spectral.albedo.value = "CONSTANT", 0.5
    material.spectral.density_scale = 3.0
    spectral = _export().scene.media[0]
    np.testing.assert_allclose(spectral.albedo_table, 0.5)
    assert spectral.density_scale == pytest.approx(3.0)


def test_a_volume_without_a_volume_shader_is_named_not_an_error(factory):
    factory.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    bpy.data.objects.remove(bpy.data.objects["Light"])
    with pytest.raises(SpectralError, match=r"the scene has no lights.*'Material' ▸ Principled BSDF"):
        _export()


def test_turning_spectral_volume_on_starts_from_the_node_values(factory):
    """The exported medium barely changes: the same σ_t and g, the albedo through a curve (10 nm points)."""
    material = _cube_material()
    volume_shader(material, Color=(0.8, 0.1, 0.1), Density=2.0, Anisotropy=0.6, **{"Absorption Color": (0.2, 0.2, 0.2)})
    before = _export().scene.media[0]
    material.spectral.enabled = True
    after = _export().scene.media[0]
    visible = slice(380 - 250, 780 - 250)
    np.testing.assert_allclose((after.extinction.values * after.density_scale)[visible],
                               (before.extinction.values * before.density_scale)[visible], rtol=0.02)
    np.testing.assert_allclose(after.albedo_table[0][visible], before.albedo_table[0][visible], atol=0.02)
    assert after.anisotropy.values[0] == pytest.approx(0.6, abs=1e-6) and after.phase == "hg"


def test_vdb_volume_with_a_principled_volume_matches_cycles(registered, tmp_path):
    """A Volume object (a smooth ball in a VDB file) with an ordinary Principled Volume reading its
    "density" grid, under a sun: what Cycles renders, not an error."""
    from tests.addon.test_cycles_emulation import write_blob

    scene = factory_scene()
    for name in ("Cube", "Light"):
        bpy.data.objects.remove(bpy.data.objects[name])
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    scene.collection.objects.link(sun)
    sun.data.energy, sun.data.angle = 4.0, 0.0
    sun.rotation_euler = (math.radians(40), 0.0, math.radians(30))
    volume = bpy.data.volumes.new("Ball")
    volume.filepath = str(write_blob(tmp_path / "ball.vdb"))
    ball = bpy.data.objects.new("Ball", volume)
    scene.collection.objects.link(ball)
    ball.scale = (1.5, 1.5, 1.5)
    material = bpy.data.materials.new("Smoke")
    volume_shader(material, Color=(0.8, 0.8, 0.8), Density=4.0, Anisotropy=0.4)
    volume.materials.append(material)
    result = compare(scene, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.warnings == []
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND and result.cycled.mean() > 0.01


def test_principled_volume_emission_matches_cycles(factory, tmp_path):
    """Emission Color × Strength inside the cube, not scaled by the density (Cycles' meaning), seen through
    a grey scattering medium and lighting it."""
    volume_shader(_cube_material(), Color=(0.5, 0.5, 0.5), Density=1.0,
                  **{"Emission Color": (0.2, 0.9, 0.3), "Emission Strength": 0.5})
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND


def test_emission_shader_alone_glows_as_in_cycles(factory, tmp_path):
    """An Emission shader as the cube's only volume closure: a medium that emits and does not absorb."""
    bpy.data.objects.remove(bpy.data.objects["Light"])
    factory.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    volume_shader(_cube_material(), "ShaderNodeEmission", Color=(1.0, 0.5, 0.2), Strength=0.3)
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=16)
    print(result)
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND


@pytest.mark.parametrize("kelvin", [1500.0, 4000.0])
def test_principled_blackbody_at_a_constant_temperature_matches_cycles(factory, tmp_path, kelvin):
    """Blackbody Intensity 1 at a constant Temperature on a mesh (no grid): Cycles' σT⁴/π × 1e-6 of the
    black body's colour. The colour is Planck's spectrum here and Cycles' fitted RGB there: ΔE00 below 1."""
    bpy.data.objects.remove(bpy.data.objects["Light"])
    factory.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    volume_shader(_cube_material(), Color=(0.5, 0.5, 0.5), Density=0.5,
                  **{"Blackbody Intensity": 1.0, "Temperature": kelvin})
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.delta_e < 1.0
    luminance = np.array([0.2126, 0.7152, 0.0722])
    assert np.dot(luminance, result.traced) == pytest.approx(np.dot(luminance, result.cycled), rel=0.03)


@pytest.mark.parametrize("fire", [False, True])
def test_quick_smoke_and_quick_fire_materials_render_without_a_setting(registered, tmp_path, fire):
    """The material Blender's Quick Smoke (and Quick Fire: Blackbody Intensity 1) gives a domain: a Principled
    Volume of Density 5 reading the cache's density and, for fire, the temperature Cycles makes of the
    flame (ignition + flame × (max − ignition), in units of 1000 K at Temperature 1000)."""
    from tests.addon.builders import add_camera, add_fluid_domain, add_sun

    add_camera()
    add_sun()
    domain, density = add_fluid_domain(tmp_path)
    material = bpy.data.materials.new("Smoke Domain Material")
    volume_shader(material, Density=5.0, **({"Blackbody Intensity": 1.0} if fire else {}))
    domain.data.materials.clear()
    domain.data.materials.append(material)
    export = _export()
    assert export.warnings == []
    media = {medium.glow is None: medium for medium in export.scene.media}
    smoke = media[True]
    np.testing.assert_allclose(smoke.density.values, density, rtol=1e-6)
    np.testing.assert_allclose(smoke.extinction.values * smoke.density_scale, 5.0, rtol=1e-6)
    np.testing.assert_allclose(smoke.albedo_table[0][130:530], 0.5, atol=0.01)  # Color 0.5 grey, 380–780 nm
    if not fire:
        assert len(export.scene.media) == 1
        return
    glow = media[False].glow
    settings = domain.modifiers["Fluid"].domain_settings
    flame = density / 2  # the builder's flame grid
    expected = np.where(flame > 0.01, settings.flame_ignition + flame * (settings.flame_max_temp
                                                                         - settings.flame_ignition), 0.0)
    np.testing.assert_allclose(glow.temperature.values, expected, rtol=1e-6)
    assert glow.temperature_scale == pytest.approx(1000.0) and glow.blackbody == pytest.approx(1e-6)
    assert media[False].density.values.min() == 1.0  # the whole domain glows where it is hot, as in Cycles


@pytest.mark.slow
@pytest.mark.parametrize("colour, density, g", [((0.8, 0.1, 0.1), 2.0, 0.8), ((0.5, 0.7, 0.9), 1.0, 0.0),
                                                ((0.9, 0.6, 0.2), 4.0, 0.3)])
def test_coloured_principled_volume_matches_cycles_within_the_spectral_allowance(factory, tmp_path, colour, density,
                                                                                  g):
    """A coloured medium differs between spectral and RGB transport; Mitsuba 3's own RGB and spectral variants
    measure by how much on the same cube, light and camera (`tests/support/rgb_allowance.py`). The tracer must
    agree with Cycles within ΔE00 1.5 plus that difference, and every block within the noise plus it."""
    from addon.export.lights import point_intensity
    from tests.support.rgb_allowance import spectral_vs_rgb

    factory.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    volume_shader(_cube_material(), Color=colour, Density=density, Anisotropy=g)
    light = bpy.data.objects["Light"]
    mitsuba_rgb, mitsuba_spectral = spectral_vs_rgb(
        _export().scene, [(tuple(light.location), point_intensity(light.data.energy))], colour, density, g)
    allowance = np.abs(mitsuba_spectral / mitsuba_rgb - 1.0)
    result = compare(factory, tmp_path, tracer_spp=128, cycles_spp=128, allowance=allowance)
    measured = result.delta_e_of(mitsuba_spectral, mitsuba_rgb)
    print(result, f"| Mitsuba spectral vs RGB: ΔE00 {measured:.3f}, per channel {allowance}")
    assert result.delta_e < 1.5 + measured
    assert result.z < NOISE_BOUND


def test_errors_name_blender_objects(factory):
    bpy.data.objects["Light"].data.energy = float("inf")
    with pytest.raises(SpectralError, match=r"^light 'Light' strength: "):
        _export()


@pytest.mark.parametrize("shape, size, size_y, scale", [("SQUARE", 1.0, 1.0, (1.0, 1.0, 1.0)),
                                                        ("RECTANGLE", 1.5, 0.5, (1.0, 2.0, 1.0)),
                                                        ("DISK", 1.2, 1.2, (1.0, 1.0, 1.0)),
                                                        ("ELLIPSE", 0.6, 1.4, (1.5, 1.0, 1.0))])
def test_area_lights_match_cycles(factory, tmp_path, shape, size, size_y, scale):
    """An area light (Power in W, its shape, size and the object's scale) as the cube's only light."""
    factory.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    light = bpy.data.objects["Light"]
    light.data.type = "AREA"
    area = light.data
    area.shape, area.size, area.size_y, area.energy = shape, size, size_y, 300.0
    light.location, light.scale = (2.0, -1.0, 2.5), scale
    look_at(light)
    volume_shader(_cube_material(), Color=(0.8, 0.8, 0.8), Density=1.0, Anisotropy=0.2)
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.warnings == []
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND


@pytest.mark.parametrize("visible", [True, False])
def test_an_area_light_in_frame_is_seen_as_in_cycles(factory, tmp_path, visible):
    """A square area light beside the volume cube, facing the camera: its face is seen at its radiance
    P / (π A) (white: that in each of R, G, B) by both renderers where it is in frame, and the blocks agree; with
    the object's Ray Visibility ▸ Camera off neither shows it, while it still lights the cube."""
    factory.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    camera = bpy.data.objects["Camera"]
    light = bpy.data.objects["Light"]
    light.data.type = "AREA"
    area = light.data
    area.shape, area.size, area.energy = "SQUARE", 1.5, 40.0
    light.location = (-1.0, 2.5, 1.0)
    look_at(light, tuple(camera.location))
    light.visible_camera = visible
    volume_shader(_cube_material(), Color=(0.8, 0.8, 0.8), Density=1.0, Anisotropy=0.2)
    radiance = 40.0 / (math.pi * 1.5 * 1.5)
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.warnings == []
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND
    traced, cycled = (image.max(axis=-1) for image in result.images)
    face = np.abs(cycled - radiance) < 0.01 * radiance  # pixels wholly on the face, with no medium before it
    if visible:
        assert face.sum() >= 20
        np.testing.assert_allclose(traced[face].mean(), radiance, rtol=0.01)
    else:
        assert face.sum() == 0 and traced.max() < 0.5 * radiance
        assert result.traced.max() > 1e-3  # the cube is still lit


def test_mix_shader_of_rayleigh_scatter_and_volume_coefficients_matches_cycles(factory, tmp_path):
    """Mix Shader (Fac 0.3) of a Rayleigh Volume Scatter and a Volume Coefficients closure (grey σ_s 1.2,
    σ_a 0.3, g 0.5): two media on one grid, as Cycles adds two closures."""
    material = _cube_material()
    tree = material.node_tree
    rayleigh = volume_shader(material, "ShaderNodeVolumeScatter", Color=(0.9, 0.9, 0.9), Density=1.0)
    rayleigh.phase = "RAYLEIGH"
    coefficients = tree.nodes.new("ShaderNodeVolumeCoefficients")
    coefficients.inputs["Scatter Coefficients"].default_value = (1.2, 1.2, 1.2)
    coefficients.inputs["Absorption Coefficients"].default_value = (0.3, 0.3, 0.3)
    coefficients.inputs["Emission Coefficients"].default_value = (0.0, 0.0, 0.0)
    coefficients.inputs["Anisotropy"].default_value = 0.5
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = 0.3
    tree.links.new(rayleigh.outputs[0], mix.inputs[1])
    tree.links.new(coefficients.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.get_output_node("ALL").inputs["Volume"])
    assert sorted(medium.phase for medium in _export().scene.media) == ["hg", "rayleigh"]
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.warnings == []
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND


@pytest.mark.parametrize("vector_type", [None, "POINT", "TEXTURE"])
def test_an_hdri_world_lights_the_volume_as_in_cycles(factory, tmp_path, vector_type):
    """An Environment Texture (a 32×16 float image: a warm bright patch in a blue sky over a dark ground, read
    nearest-texel) as the only light, turned by a Mapping node (Point or Texture: inverse turns)."""
    bpy.data.objects.remove(bpy.data.objects["Light"])
    width, height = 32, 16
    rows = np.linspace(1.0, 0.0, height)[:, None, None]  # Blender's first row is the bottom: 1 − v
    pixels = np.where(rows > 0.5, [0.05, 0.04, 0.03], [0.2, 0.35, 0.8]) * np.ones((height, width, 3))
    pixels[10:13, 4:8] = (30.0, 20.0, 9.0)  # above the horizon, a quarter turn from the map's centre
    image = bpy.data.images.new("HDRI", width, height, float_buffer=True)
    image.pixels.foreach_set(np.concatenate([pixels, np.ones((height, width, 1))], axis=2).astype(np.float32).ravel())
    tree = factory.world.node_tree
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image, texture.interpolation = image, "Closest"
    tree.links.new(texture.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    if vector_type is not None:
        mapping = tree.nodes.new("ShaderNodeMapping")
        mapping.vector_type = vector_type
        mapping.inputs["Rotation"].default_value = (0.3, 0.0, math.radians(100.0))
        tree.links.new(tree.nodes.new("ShaderNodeTexCoord").outputs["Generated"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
    volume_shader(_cube_material(), Color=(0.8, 0.8, 0.8), Density=1.5, Anisotropy=0.3)
    assert [light.kind for light in _export().scene.lights] == ["envmap"]
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.warnings == []
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND


@pytest.mark.parametrize("model, elevation, rotation, mapped", [
    ("MULTIPLE_SCATTERING", 15.0, 60.0, False), ("MULTIPLE_SCATTERING", 50.0, 200.0, False),
    ("SINGLE_SCATTERING", 25.0, 120.0, False), ("MULTIPLE_SCATTERING", 10.0, 60.0, True),
    ("PREETHAM", 30.0, 60.0, False)],
    ids=["multiple-15°", "multiple-50°", "single-25°", "multiple-10°-mapped-no-disc", "preetham-30°"])
def test_a_sky_texture_lights_the_volume_as_in_cycles(factory, tmp_path, model, elevation, rotation, mapped):
    """A Sky Texture (Strength 0.1) as the only light of a grey cube: the sky as an envmap and its sun disc as
    a sun light (`tracer.sky_model`; Preetham's sky has no disc, its Sun Direction is the same sun's); without the disc, turned by a Mapping node (Point, 100° about Z). A grey
    medium transports every colour alike, so the sky's colour asks no spectral allowance. Under a single
    scattering sky the camera looks up from below the cube: Cycles' ground there (below the horizon) is darker
    than its source gives (`test_sky_texture.py`)."""
    bpy.data.objects.remove(bpy.data.objects["Light"])
    tree = factory.world.node_tree
    sky = tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type, sky.sun_elevation, sky.sun_rotation = model, math.radians(elevation), math.radians(rotation)
    sky.sun_direction = sun_direction(SkyParameters(sun_elevation=sky.sun_elevation, sun_rotation=sky.sun_rotation))
    background = tree.nodes["Background"]
    tree.links.new(sky.outputs["Color"], background.inputs["Color"])
    background.inputs["Strength"].default_value = 0.1
    if mapped:
        sky.sun_disc = False
        mapping = tree.nodes.new("ShaderNodeMapping")
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(100.0))
        tree.links.new(tree.nodes.new("ShaderNodeTexCoord").outputs["Generated"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], sky.inputs["Vector"])
    if model == "SINGLE_SCATTERING":  # look up at the cube, the frame all sky (see test_sky_texture.py)
        camera = bpy.data.objects["Camera"]
        camera.location.z = -4.0
        look_at(camera)
    volume_shader(_cube_material(), Color=(0.8, 0.8, 0.8), Density=1.5, Anisotropy=0.3)
    assert [light.kind for light in _export().scene.lights] == ["envmap"] + ["sun"] * (not mapped and model != "PREETHAM")
    result = compare(factory, tmp_path, tracer_spp=64, cycles_spp=64)
    print(result)
    assert result.warnings == []
    assert result.delta_e < GREY_DELTA_E and result.z < NOISE_BOUND
