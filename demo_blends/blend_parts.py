"""Blender data from the demos' tracer values: scenes, cameras, suns, worlds, volume materials and objects.

`build_blends` describes each .blend with these; the numbers come from the tracer scenes in `scenes`
(a tracer Camera, Light or Medium in, the add-on's settings out); tests/demos/test_blends.py checks
that the files export back to those scenes. Needs `bpy` with the add-on registered.
"""

import bpy
import numpy as np
from mathutils import Matrix, Vector

from addon import curves
from addon.props.render import ENGINE_ID
from addon.tracer import grids, spectra
from addon.tracer.scene import Camera, Grid, Light, Medium
from addon.tracer.wavelengths import GRID

CURVE_STEP_NM = 5  # spectra drawn as curves get a point every this many nanometres


def new_scene(name: str, width: int, height: int, spp: int, seed: int, exposure: float = 0.0):
    """A Blender scene rendered by the Spectral Volume engine."""
    scene = bpy.data.scenes.new(name)
    scene.render.engine = ENGINE_ID
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    scene.spectral.samples, scene.spectral.seed = spp, seed
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.exposure = exposure
    scene.frame_start = scene.frame_end = scene.frame_current = 1
    return scene


def link(collection, obj):
    collection.objects.link(obj)
    return obj


def add_camera(scene, camera: Camera, name: str = "Camera"):
    """The scene's camera: a perspective camera object matching a tracer camera (field of view
    across the wider axis)."""
    obj = link(scene.collection, bpy.data.objects.new(name, bpy.data.cameras.new(name)))
    scene.camera = obj
    obj.matrix_world = Matrix(np.asarray(camera.to_world).tolist())
    obj.data.sensor_fit = "AUTO"
    obj.data.angle = camera.fov
    obj.data.clip_end = 1000.0
    return obj


# ----------------------------------------------------------------------------- spectra


def set_curve(settings, values: np.ndarray) -> None:
    """Draw `values` (on the wavelength grid) as the setting's curve, a point every CURVE_STEP_NM."""
    settings.source = "CURVE"
    mapping = curves.ensure(settings.curve, settings.Y_RANGE)
    curves.set_points(mapping, GRID[::CURVE_STEP_NM], values[::CURVE_STEP_NM])  # both ends included
    for point in mapping.curves[0].points:
        point.handle_type = "AUTO_CLAMPED"  # no overshoot between points
    mapping.update()


def set_spectrum(settings, spectrum: spectra.Spectrum) -> None:
    """A material spectrum: Constant when it is one number, otherwise a Curve."""
    values = spectrum.values
    if np.all(values == values[0]) and "CONSTANT" in _sources(settings):
        settings.source, settings.value = "CONSTANT", float(values[0])
    else:
        set_curve(settings, values)


def _sources(settings) -> set[str]:
    return {item.identifier for item in settings.bl_rna.properties["source"].enum_items}


def set_preset(settings, illuminant: str, window=None) -> None:
    """A light spectrum from a CIE illuminant preset, optionally cut to a (min, max) nm window."""
    settings.source, settings.illuminant = "ILLUMINANT", illuminant
    _window(settings, window)


def set_flat(settings, window=None) -> None:
    """A light spectrum of equal energy at every wavelength (down to 250 nm, unlike illuminant E): a
    flat curve."""
    settings.source = "CURVE"
    curves.set_points(curves.ensure(settings.curve, settings.Y_RANGE), (GRID[0], GRID[-1]), (1.0, 1.0))
    _window(settings, window)


def set_blackbody(settings, kelvin: float) -> None:
    """A light spectrum of a black body at `kelvin`."""
    settings.source, settings.temperature = "BLACKBODY", kelvin


def _window(settings, window) -> None:
    settings.use_window = window is not None
    if window is not None:
        settings.window_min, settings.window_max = window


# ----------------------------------------------------------------------------- lights


def add_sun(collection, light: Light, spectrum, name: str | None = None):
    """A sun object shining from the tracer light's direction; `spectrum(settings)` sets its spectrum."""
    data = bpy.data.lights.new(name or light.name, "SUN")
    data.energy, data.angle = light.strength, light.angle
    spectrum(data.spectral.spectrum)
    obj = link(collection, bpy.data.objects.new(name or light.name, data))
    obj.rotation_euler = Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(light.direction)).to_euler()
    return obj


def new_world(name: str, light: Light | None = None, spectrum=None):
    """A World: off, or the uniform environment `light` with `spectrum(settings)`."""
    world = bpy.data.worlds.new(name)
    world.spectral.enabled = light is not None
    if light is not None:
        world.spectral.kind, world.spectral.strength = light.kind, light.strength
        spectrum(world.spectral.spectrum)
    return world


# ----------------------------------------------------------------------------- volumes


def volume_material(name: str, medium: Medium, temperature_grid: str = "temperature"):
    """A Spectral Volume material with the tracer medium's optics (one albedo for every density); a
    glowing medium reads its temperature from the grid `temperature_grid`."""
    material = bpy.data.materials.new(name)
    settings = material.spectral
    settings.enabled = True
    settings.density_scale = medium.density_scale
    settings.phase = medium.phase
    set_spectrum(settings.extinction, medium.extinction)
    set_spectrum(settings.albedo, spectra.Spectrum(medium.albedo_table[0]))
    set_spectrum(settings.anisotropy, medium.anisotropy)
    if medium.fluorescence is not None:
        settings.use_fluorescence = True
        set_spectrum(settings.excitation, medium.fluorescence.excitation)
        set_spectrum(settings.emission, medium.fluorescence.emission)
        settings.quantum_yield = medium.fluorescence.quantum_yield
    if medium.emission is not None:
        emission = medium.emission
        settings.use_blackbody, settings.temperature_grid = True, temperature_grid
        settings.blackbody_intensity = emission.intensity
        settings.temperature_scale = emission.temperature_scale
        settings.temperature_offset = emission.temperature_offset
    return material


def add_vdb_volume(collection, name: str, filepath: str, grid_name: str, material):
    """A Volume object reading grid `grid_name` of the VDB file `filepath` (a `//` relative path)."""
    volume = bpy.data.volumes.new(name)
    volume.filepath = filepath
    obj = link(collection, bpy.data.objects.new(name, volume))
    obj.spectral.density_grid = grid_name
    obj.data.materials.append(material)
    return obj


def write_vdb(path, named_grids: dict) -> None:
    """Write {name: tracer Grid} into one VDB file (each grid under its name here)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    grids.save_grid_vdb(path, *(Grid(grid.values, grid.index_to_world, name)
                                for name, grid in named_grids.items()))


def box_mesh(name: str, low, high):
    """A closed box mesh spanning [low, high] (object at the origin)."""
    (x0, y0, z0), (x1, y1, z1) = low, high
    vertices = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    mesh.update()
    return mesh


def add_mesh_volume(collection, name: str, low, high, voxel_size: float, material):
    """A box mesh filled with the volume material, voxelised by the add-on at `voxel_size`."""
    obj = link(collection, bpy.data.objects.new(name, box_mesh(name, low, high)))
    obj.spectral.voxel_size = voxel_size
    obj.data.materials.append(material)
    return obj


def add_fluid_domain(collection, name: str, low, high, cache_directory: str, resolution_max: int, material,
                     density_grid: str = "density"):
    """A smoke/fire domain box over [low, high] whose OpenVDB cache lies in `cache_directory`. Its
    modifier is hidden, so Blender never simulates (Mantaflow would overwrite or abort); the add-on
    reads the cache files directly."""
    obj = link(collection, bpy.data.objects.new(name, box_mesh(name, low, high)))
    modifier = obj.modifiers.new("Fluid", "FLUID")
    modifier.show_viewport = modifier.show_render = False
    modifier.fluid_type = "DOMAIN"
    domain = modifier.domain_settings
    domain.domain_type, domain.cache_type, domain.cache_data_format = "GAS", "ALL", "OPENVDB"
    domain.resolution_max = resolution_max
    domain.cache_directory = cache_directory
    obj.spectral.density_grid = density_grid
    obj.data.materials.append(material)
    return obj
