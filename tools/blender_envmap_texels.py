"""Which texel of an equirectangular Environment Texture Cycles shows along a few directions: the data of
tests/tracer/test_envmap.py's BLENDER_TEXELS (plain) and BLENDER_MAPPED_TEXELS (`--mapped`: a Mapping node,
Point, rotating the texture's vector by 90° about Z).

Run with Blender as a module (`python tools/blender_envmap_texels.py [--mapped]`); it renders one pixel per
direction with Cycles on the CPU, through a 0.5° camera, from an 8 × 4 map whose texels encode their column
and row in their red and green values (Closest interpolation).
"""

import math
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

COLUMNS, ROWS = 8, 4
DIRECTIONS = [(azimuth, elevation) for azimuth in (22.5, 112.5, 202.5, 292.5) for elevation in (-60.0, 60.0)]


def environment_texture(mapped: bool) -> None:
    """The world: an Environment Texture of texels (column / W, row / H, 0.5) (Blender stores rows bottom first)."""
    image = bpy.data.images.new("texels", COLUMNS, ROWS, float_buffer=True, alpha=False)
    pixels = np.zeros((ROWS, COLUMNS, 4), np.float32)
    for row_from_bottom in range(ROWS):
        for column in range(COLUMNS):
            pixels[row_from_bottom, column] = (column / COLUMNS + 0.01, row_from_bottom / ROWS + 0.01, 0.5, 1.0)
    image.pixels[:] = pixels.ravel().tolist()
    image.update()
    image.pack()
    image.colorspace_settings.name = "Non-Color"
    world = bpy.data.worlds.new("texels")
    bpy.context.scene.world = world
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    texture = nodes.new("ShaderNodeTexEnvironment")
    texture.image, texture.interpolation = image, "Closest"
    links.new(texture.outputs["Color"], nodes["Background"].inputs["Color"])
    if mapped:
        mapping = nodes.new("ShaderNodeMapping")
        mapping.vector_type = "POINT"
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(90.0))
        links.new(nodes.new("ShaderNodeTexCoord").outputs["Generated"], mapping.inputs["Vector"])
        links.new(mapping.outputs["Vector"], texture.inputs["Vector"])


def texel_seen(camera, azimuth: float, elevation: float, output: Path) -> tuple[int, int]:
    """(column, row from the top) that the camera sees looking along (azimuth from +X towards +Y, elevation)."""
    a, e = math.radians(azimuth), math.radians(elevation)
    camera.rotation_quaternion = Vector((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a),
                                         math.sin(e))).to_track_quat("-Z", "Y")
    bpy.ops.render.render(write_still=True)
    result = bpy.data.images.load(str(output), check_existing=False)
    red, green = result.pixels[0], result.pixels[1]
    bpy.data.images.remove(result)
    return int(red * COLUMNS), ROWS - 1 - int(green * ROWS)


def main() -> None:
    scene = bpy.context.scene
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    environment_texture("--mapped" in sys.argv)
    camera_data = bpy.data.cameras.new("camera")
    camera_data.angle = math.radians(0.5)
    camera = bpy.data.objects.new("camera", camera_data)
    camera.rotation_mode = "QUATERNION"
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 1, False
    scene.render.resolution_x = scene.render.resolution_y = 4
    scene.render.image_settings.file_format = "OPEN_EXR"
    with tempfile.TemporaryDirectory() as folder:
        scene.render.filepath = str(Path(folder) / "pixel.exr")
        print([((azimuth, elevation), texel_seen(camera, azimuth, elevation, Path(scene.render.filepath)))
               for azimuth, elevation in DIRECTIONS])


if __name__ == "__main__":
    main()
