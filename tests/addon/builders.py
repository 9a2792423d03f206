"""Small Blender scenes for add-on tests: a camera, a sun, VDB files, volume objects and fluid domains."""

import math

import bpy
import numpy as np

from addon.export.fluids import base_resolution
from addon.tracer import grids
from addon.tracer.scene import Grid

VOXEL = 0.25
# A 4×3×2 grid whose values all differ and are non-zero (so no voxel is trimmed as background).
PATTERN = (np.arange(24, dtype=np.float32).reshape(4, 3, 2) + 1.0) / 24.0


def vdb_index_to_world(voxel=VOXEL, offset=(-0.5, -0.25, 0.0)) -> np.ndarray:
    matrix = np.diag([voxel, voxel, voxel, 1.0])
    matrix[:3, 3] = offset
    return matrix


def write_vdb(path, scale=1.0, matrix=None, temperature=False):
    matrix = vdb_index_to_world() if matrix is None else matrix
    layers = [Grid(PATTERN * scale, matrix, "density")]
    if temperature:
        layers.append(Grid(PATTERN * 1000.0, matrix, "temperature"))
    grids.save_grid_vdb(path, *layers)
    return path


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def spectral_material(name="Smoke"):
    material = bpy.data.materials.new(name)
    material.spectral.enabled = True
    return material


def add_camera(location=(0.0, -6.0, 0.5), rotation=(math.radians(90), 0.0, 0.0)):
    camera = link(bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera")))
    camera.location, camera.rotation_euler = location, rotation
    bpy.context.scene.camera = camera
    return camera


def add_sun(rotation=(0.0, 0.0, 0.0), strength=3.0):
    sun = link(bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN")))
    sun.rotation_euler = rotation
    sun.data.energy = strength
    sun.data.spectral.enabled = True  # its spectrum (D65 by default) rather than its Color
    sun.data.spectral.spectrum.source = "ILLUMINANT"
    return sun


def add_volume(path, name="Cloud", material=None):
    volume = bpy.data.volumes.new(name)
    volume.filepath = str(path)
    obj = link(bpy.data.objects.new(name, volume))
    obj.data.materials.append(material or spectral_material())
    return obj


def add_fluid_domain(tmp_path, frames=(1,), density=None):
    """A 4 × 2 × 2 m smoke domain of 16 × 8 × 8 cells whose cache folder is written with OpenVDB (never
    baked, never evaluated: its modifier is hidden so Mantaflow does not start). Its cache holds `density`
    (default: uniform random in 0.1…1) × frame, temperature = 2 × density and flame = density / 2."""
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(0.0, 0.0, 1.0))
    domain = bpy.context.active_object
    domain.name = "Smoke Domain"
    domain.scale = (2.0, 1.0, 1.0)
    modifier = domain.modifiers.new("Fluid", "FLUID")
    modifier.show_viewport = modifier.show_render = False
    modifier.fluid_type = "DOMAIN"
    settings = modifier.domain_settings
    settings.resolution_max = 16
    settings.cache_type = "ALL"
    settings.cache_directory = str(tmp_path / "cache")
    cells = base_resolution((4.0, 2.0, 2.0), 16)
    assert tuple(cells) == (16, 8, 8)
    (tmp_path / "cache" / "data").mkdir(parents=True)
    if density is None:
        density = np.random.default_rng(1).uniform(0.1, 1.0, tuple(cells)).astype(np.float32)
    for frame in frames:
        grids.save_grid_vdb(tmp_path / "cache" / "data" / f"fluid_data_{frame:04d}.vdb",
                            Grid(density * frame, np.eye(4), "density"),
                            Grid(density * 2, np.eye(4), "temperature"), Grid(density / 2, np.eye(4), "flame"))
    domain.data.materials.append(spectral_material("Fire"))
    return domain, density


def tiny_render(scene, width=16, height=12, samples=2):
    """A small frame of `samples` per pixel, not denoised (so that F12's Combined is the raw film)."""
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.spectral.samples = samples
    scene.spectral.denoise = False


def basic_scene(tmp_path):
    """Camera, sun and a VDB cloud in front of the camera; 16×12 pixels, 2 samples."""
    scene = bpy.context.scene
    tiny_render(scene)
    add_camera()
    add_sun()
    cloud = add_volume(write_vdb(tmp_path / "cloud.vdb"))
    cloud.material_slots[0].material.spectral.density_scale = 4.0
    return scene, cloud


def geometry_nodes(obj, node_type):
    """Give `obj` a Geometry Nodes modifier whose tree is Group Input → `node_type` → Group Output."""
    tree = bpy.data.node_groups.new(node_type, "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    node = tree.nodes.new(node_type)
    if node.inputs and node.inputs[0].type == "GEOMETRY":
        tree.links.new(tree.nodes.new("NodeGroupInput").outputs[0], node.inputs[0])
    tree.links.new(node.outputs[0], tree.nodes.new("NodeGroupOutput").inputs[0])
    obj.modifiers.new("Geometry Nodes", "NODES").node_group = tree
    return node
