"""Image textures on surfaces from Blender (`nodes.graph.image_texture`, `export.surfaces`, `export.textures`):
the export (pixels in linear Rec.709, UVs per triangle corner from the named or active render map through a
Mapping node, extension and interpolation), what is not rendered named in the report, and Cycles as the control;
and surfaces hidden from the camera (Indirect Only) against Cycles."""

import math

import numpy as np
import pytest

from addon.cycles_emulation.job import EmulationJob
from addon.cycles_emulation.surfaces import TEXTURED_WARNING
from tests.addon.test_blender_scene import factory_scene
from tests.addon.test_surfaces import COLOURED_DELTA_E, _export, _plane, _surface_shader, only_a_sun
from tests.support.cycles import NOISE_BOUND, compare

bpy = pytest.importorskip("bpy")

# An 8 × 4 image (rows top first) of sRGB-encoded bytes: a checker of colours and a grey ramp.
PIXELS = np.array([
    [[0.9, 0.2, 0.2], [0.2, 0.8, 0.3], [0.2, 0.3, 0.9], [0.95, 0.9, 0.2]] * 2,
    [[0.1, 0.1, 0.1], [0.3, 0.3, 0.3], [0.5, 0.5, 0.5], [0.7, 0.7, 0.7], [0.9, 0.9, 0.9], [1.0, 1.0, 1.0],
     [0.6, 0.4, 0.2], [0.2, 0.4, 0.6]],
    [[0.3, 0.6, 0.45], [0.7, 0.35, 0.6], [0.05, 0.05, 0.3], [0.62, 0.51, 0.33]] * 2,
    [[0.2, 0.9, 0.9], [0.9, 0.2, 0.9], [0.4, 0.4, 0.1], [0.13, 0.77, 0.58]] * 2])


@pytest.fixture
def factory(registered):
    return factory_scene()


def _image(name="Checker", pixels=PIXELS, is_float=False):
    """A generated image holding `pixels` (rows top first; 8-bit sRGB unless `is_float`)."""
    rows, columns = pixels.shape[:2]
    image = bpy.data.images.new(name, columns, rows, float_buffer=is_float)
    rgba = np.concatenate([pixels, np.ones((rows, columns, 1))], axis=-1)[::-1]  # Blender: bottom row first
    image.pixels.foreach_set(rgba.astype(np.float32).ravel())
    return image


def _textured(material_name="Textured", image=None, kind="ShaderNodeBsdfDiffuse", socket="Color", **texture):
    """A material whose BSDF's colour is an Image Texture node of `image` with `texture`'s settings (a Diffuse BSDF
    of roughness 0, Lambert as the tracer's, by default)."""
    material = bpy.data.materials.new(material_name)
    bsdf = _surface_shader(material, kind, **({"Roughness": 0.0} if kind == "ShaderNodeBsdfDiffuse" else {}))
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image if image is not None else _image()
    for key, value in texture.items():
        setattr(node, key, value)
    material.node_tree.links.new(node.outputs["Color"], bsdf.inputs[socket])
    return material, node


def test_a_textured_plane_exports_its_pixels_and_uvs(factory):
    """The default plane's UVs (0 … 1 over its face) per triangle corner, the image's bytes decoded from sRGB,
    extension and interpolation carried, and nothing named."""
    material, _node = _textured(extension="EXTEND", interpolation="Closest")
    plane = _plane("Plane", size=2.0, location=(0.0, 0.0, 3.0), material=material)
    export = _export()
    surface = next(surface for surface in export.scene.surfaces if surface.name == "Plane")
    texture = surface.texture
    assert (texture.extension, texture.interpolation) == ("EXTEND", "Closest")
    # the bytes each value was stored as (rounded either way at a half), left sRGB-encoded for the tracer to decode
    # after interpolation, as Cycles does
    assert texture.srgb is True
    bytes_ = texture.image * 255.0
    np.testing.assert_allclose(bytes_, np.round(bytes_), atol=1e-3)
    assert np.all((bytes_ >= np.floor(PIXELS * 255.0) - 1e-3) & (bytes_ <= np.ceil(PIXELS * 255.0) + 1e-3))
    # each corner's UV is the plane's local (x, y) mapped from [−1, 1] to [0, 1]
    local = surface.vertices[surface.triangles] - np.array(plane.location)
    np.testing.assert_allclose(texture.uv, (local[..., :2] + 1.0) / 2.0, atol=1e-6)
    assert not any("Textured" in warning for warning in export.warnings)


def test_a_uv_map_node_and_a_mapping_node_choose_and_transform_the_uvs(factory):
    """A UV Map node naming the second map, through a Mapping node (Point: scale 2, 3, then a turn of 90° about z,
    then a shift): the corners' UVs are the second map's, mapped as Cycles maps each point's."""
    material, node = _textured(image=_image(is_float=True))
    plane = _plane("Plane", material=material)
    second = plane.data.uv_layers.new(name="Second")
    for index, loop in enumerate(second.data):
        loop.uv = (0.1 * index, 0.3 + 0.05 * index)
    tree = material.node_tree
    uv_node, mapping = tree.nodes.new("ShaderNodeUVMap"), tree.nodes.new("ShaderNodeMapping")
    uv_node.uv_map = "Second"
    mapping.inputs["Scale"].default_value = (2.0, 3.0, 1.0)
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.pi / 2)
    mapping.inputs["Location"].default_value = (0.5, -0.25, 0.0)
    tree.links.new(uv_node.outputs["UV"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], node.inputs["Vector"])
    export = _export()
    surface = next(surface for surface in export.scene.surfaces if surface.name == "Plane")
    np.testing.assert_allclose(surface.texture.image, PIXELS, atol=1e-6)  # a float image as it is
    assert surface.texture.srgb is False
    mesh = plane.data
    mesh.calc_loop_triangles()
    corners = np.array([[tuple(second.data[loop].uv) for loop in triangle.loops] for triangle in mesh.loop_triangles])
    expected = np.stack([-3.0 * corners[..., 1] + 0.5, 2.0 * corners[..., 0] - 0.25], axis=-1)
    np.testing.assert_allclose(surface.texture.uv, expected, atol=1e-5)


def test_what_is_not_rendered_is_named(factory, tmp_path):
    """A Noise Texture on a Base Color, an Image Texture whose file is missing, a Box projection and a texture
    mixed with another colour render at their socket's value, each named in the report."""
    noise = bpy.data.materials.new("Noisy")
    principled = _surface_shader(noise, "ShaderNodeBsdfPrincipled")
    noise.node_tree.links.new(noise.node_tree.nodes.new("ShaderNodeTexNoise").outputs["Color"],
                              principled.inputs["Base Color"])
    _plane("Noise", location=(0.0, 0.0, 2.0), material=noise)
    path = tmp_path / "gone.png"
    saved = _image("Gone")
    saved.filepath_raw, saved.file_format = str(path), "PNG"
    saved.save()
    gone = bpy.data.images.load(str(path))
    path.unlink()
    gone.reload()
    _plane("Missing", location=(3.0, 0.0, 2.0), material=_textured("Missing file", image=gone)[0])
    _plane("Boxed", location=(6.0, 0.0, 2.0), material=_textured("Boxed", projection="BOX")[0])
    mixed, _node = _textured("Mixed")
    tree = mixed.node_tree
    mix = _surface_shader(mixed, "ShaderNodeMixShader", Fac=0.5)
    tree.links.new(tree.nodes["Diffuse BSDF"].outputs[0], mix.inputs[1])
    tree.links.new(tree.nodes.new("ShaderNodeBsdfDiffuse").outputs[0], mix.inputs[2])
    _plane("Mixed", location=(9.0, 0.0, 2.0), material=mixed)
    export = _export()
    assert all(surface.texture is None for surface in export.scene.surfaces)
    [warning] = export.warnings
    assert "▸ Base Color is driven by 'Noise Texture', which cannot be converted" in warning
    assert "material 'Missing file' ▸ Image Texture: image 'gone.png' has no pixels" in warning
    assert "material 'Boxed' ▸ Image Texture: Box projection is not a texture the tracer renders" in warning
    assert "material 'Mixed' ▸ Image Texture: an Image Texture mixed with other shaders' colours" in warning


def _textured_ground_under_a_sun(factory):
    """The 8 × 4 image repeated twice across a 4 × 4 plane (the Texture Coordinate node's UV through a Mapping node's
    scale 2, Repeat, Linear) on a Diffuse BSDF's Color, under a sun at 50°, no World, seen from above."""
    only_a_sun(factory, tilt_degrees=40)
    material, node = _textured()
    mapping = material.node_tree.nodes.new("ShaderNodeMapping")
    mapping.inputs["Scale"].default_value = (2.0, 2.0, 1.0)
    material.node_tree.links.new(material.node_tree.nodes.new("ShaderNodeTexCoord").outputs["UV"],
                                 mapping.inputs["Vector"])
    material.node_tree.links.new(mapping.outputs["Vector"], node.inputs["Vector"])
    _plane("Ground", size=4.0, material=material)
    camera = factory.camera
    camera.location, camera.rotation_euler = (0.0, 0.0, 5.0), (0.0, 0.0, 0.0)


@pytest.mark.slow
def test_a_textured_plane_under_a_sun_matches_cycles(factory, tmp_path):
    """`_textured_ground_under_a_sun` (8-bit sRGB texels, interpolated before they are decoded, as Cycles does): block
    means agree with Cycles within noise and the colour within the coloured bound."""
    _textured_ground_under_a_sun(factory)
    result = compare(factory, tmp_path, tracer_spp=16, cycles_spp=16)
    print(result)
    assert result.warnings == []
    assert result.delta_e < COLOURED_DELTA_E and result.z < NOISE_BOUND


@pytest.mark.slow
def test_the_cycles_emulation_renders_a_textured_plane_and_says_it_is_grey(factory):
    """The Cycles emulation cannot make texels spectral: it renders the textured plane with the texture's luminance
    and names it."""
    _textured_ground_under_a_sun(factory)
    export = _export()
    job = EmulationJob(factory, export.scene, export.warnings, band_count=3, spp=16)
    job.run()
    assert job.succeeded, job.error
    assert any(TEXTURED_WARNING.format(name="Textured") in warning for warning in job.warnings)


@pytest.mark.slow
def test_an_indirect_only_square_is_unseen_but_shades_the_ground_as_in_cycles(factory, tmp_path):
    """A red square in a collection set to Indirect Only, 0.5 above a grey ground, under a sun at 40° and the factory
    World: the camera above sees through it to the ground, where its shadow and the red light its underside reflects
    fall, as in Cycles (block means within noise)."""
    bpy.data.objects.remove(bpy.data.objects["Light"])
    bpy.data.objects.remove(bpy.data.objects["Cube"])
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    factory.collection.objects.link(sun)
    sun.data.energy, sun.data.angle = 3.0, 0.0
    sun.rotation_euler = (math.radians(50), 0.0, math.radians(30))
    grey, red = bpy.data.materials.new("Grey"), bpy.data.materials.new("Red")
    _surface_shader(grey, "ShaderNodeBsdfDiffuse", Color=(0.5, 0.5, 0.5), Roughness=0.0)
    _surface_shader(red, "ShaderNodeBsdfDiffuse", Color=(0.9, 0.1, 0.1), Roughness=0.0)
    _plane("Ground", size=10.0, material=grey)
    square = _plane("Square", size=1.5, location=(0.3, 0.0, 0.5), material=red)
    hidden = bpy.data.collections.new("Hidden")
    factory.collection.children.link(hidden)
    for owner in square.users_collection:
        owner.objects.unlink(square)
    hidden.objects.link(square)
    bpy.context.view_layer.layer_collection.children["Hidden"].indirect_only = True
    camera = factory.camera
    camera.location, camera.rotation_euler = (0.0, 0.0, 5.0), (0.0, 0.0, 0.0)
    result = compare(factory, tmp_path, tracer_spp=32, cycles_spp=32)
    print(result)
    assert result.warnings == []
    traced, _cycled = result.images
    assert traced[..., 1].min() < 0.5 * np.median(traced[..., 1])  # the shadow is in view
    assert result.delta_e < COLOURED_DELTA_E and result.z < NOISE_BOUND
