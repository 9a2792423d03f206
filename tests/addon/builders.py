"""Small Blender scenes for add-on tests: a camera, a sun, VDB files and volume objects."""

import math

import bpy
import numpy as np

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
    return sun


def add_volume(path, name="Cloud", material=None):
    volume = bpy.data.volumes.new(name)
    volume.filepath = str(path)
    obj = link(bpy.data.objects.new(name, volume))
    obj.data.materials.append(material or spectral_material())
    return obj


def tiny_render(scene, width=16, height=12, samples=2):
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.spectral.samples = samples


def basic_scene(tmp_path):
    """Camera, sun and a VDB cloud in front of the camera; 16×12 pixels, 2 samples."""
    scene = bpy.context.scene
    tiny_render(scene)
    add_camera()
    add_sun()
    cloud = add_volume(write_vdb(tmp_path / "cloud.vdb"))
    cloud.material_slots[0].material.spectral.density_scale = 4.0
    return scene, cloud
