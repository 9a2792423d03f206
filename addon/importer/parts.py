"""Blender data from tracer values: scenes, cameras, lights, worlds, spectra, volume materials and Volume
objects. Each function takes a tracer Camera, Light, Medium or Spectrum and sets the add-on's settings so
that the exporter gives that value back (spectra drawn as curves: within Blender's curve table)."""

import math
from pathlib import Path

import bpy
import numpy as np
from mathutils import Matrix, Vector

from ..props import curves
from ..export.lights import point_intensity
from ..props.render import ENGINE_ID, GPU_BACKEND
from ..tracer import grids, spectra
from ..tracer.scene import Camera, Grid, Light, Medium, RenderSettings
from ..tracer.wavelengths import GRID

CURVE_STEP_NM = 5  # spectra drawn as curves get a point every this many nanometres
CLIP_END = 1000.0  # the tracer does not clip; Blender's viewport needs a clip end


def new_scene(name: str, width: int, height: int, settings: RenderSettings):
    """A Blender scene rendered by the Spectral Volume engine at `width` × `height` with the tracer's
    render settings (the scene's frame is 1)."""
    scene = bpy.data.scenes.new(name)
    scene.render.engine = ENGINE_ID
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    ours = scene.spectral
    ours.samples, ours.seed, ours.max_bounces = settings.spp, settings.seed, settings.max_depth
    ours.bands, ours.wavelength_sampling = settings.bands, settings.wavelength_sampling
    ours.wavelengths_per_path = str(settings.wavelengths_per_path)
    ours.lambda_min, ours.lambda_max = settings.lambda_min, settings.lambda_max
    ours.cmf = settings.cmf
    if settings.backend == GPU_BACKEND:
        ours.device = "GPU"
    else:
        ours.device, ours.backend = "CPU", settings.backend
    ours.use_adaptive_sampling = settings.noise_threshold > 0
    if settings.noise_threshold > 0:
        ours.adaptive_threshold = settings.noise_threshold
    ours.adaptive_min_samples = settings.min_samples
    ours.clamp_direct, ours.clamp_indirect = settings.clamp_direct, settings.clamp_indirect
    ours.use_firefly_filter = settings.firefly_threshold > 0
    if settings.firefly_threshold > 0:
        ours.firefly_threshold = settings.firefly_threshold
    scene.render.film_transparent = settings.transparent
    scene.frame_start = scene.frame_end = scene.frame_current = 1
    return scene


def link(collection, obj):
    collection.objects.link(obj)
    return obj


def add_camera(scene, camera: Camera, name: str = "Camera"):
    """The scene's camera, as the tracer camera (its size is the scene's resolution, `new_scene`)."""
    obj = link(scene.collection, bpy.data.objects.new(name, bpy.data.cameras.new(name)))
    scene.camera = obj
    obj.matrix_world = Matrix(np.asarray(camera.to_world).tolist())
    data = obj.data
    data.type = "PERSP" if camera.kind == "perspective" else "ORTHO"
    data.sensor_fit = camera.sensor_fit
    sensor = data.sensor_height if camera.sensor_fit == "VERTICAL" else data.sensor_width
    data.lens = sensor / (2.0 * math.tan(camera.fov / 2.0))
    data.ortho_scale = camera.ortho_scale
    data.shift_x, data.shift_y = camera.shift_x, camera.shift_y
    data.clip_end = CLIP_END
    return obj


# ----------------------------------------------------------------------------- spectra


def fits_curve(settings, values: np.ndarray) -> bool:
    """Whether a curve of this setting can hold `values` (curves are clipped to the setting's Y_RANGE)."""
    low, high = settings.Y_RANGE
    return bool(values.min() >= low and values.max() <= high)


def set_curve(settings, values: np.ndarray) -> None:
    """Draw `values` (on the wavelength grid) as the setting's curve, a point every CURVE_STEP_NM."""
    settings.source = "CURVE"
    mapping = curves.ensure(settings.curve, settings.Y_RANGE)
    curves.set_points(mapping, GRID[::CURVE_STEP_NM], values[::CURVE_STEP_NM])  # both ends included
    for point in mapping.curves[0].points:
        point.handle_type = "AUTO_CLAMPED"  # no overshoot between points
    mapping.update()


def csv_text(values: np.ndarray) -> str:
    """A spectrum on the wavelength grid as CSV lines `nm,value` (the add-on's CSV source reads them)."""
    return "".join(f"{lam:g},{value!r}\n" for lam, value in zip(GRID.tolist(), values.tolist()))


def set_spectrum(settings, spectrum: spectra.Spectrum, csv_file=None) -> None:
    """A material spectrum: Constant when it is one number, a Curve when a curve can hold it, else the CSV
    file `csv_file(values)` names (the caller writes it); without `csv_file`, a curve (clipped)."""
    values = spectrum.values
    if np.all(values == values[0]) and "CONSTANT" in _sources(settings):
        settings.source, settings.value = "CONSTANT", float(values[0])
    elif fits_curve(settings, values) or csv_file is None:
        set_curve(settings, values)
    else:
        settings.source, settings.filepath, settings.units = "CSV", csv_file(values), "nm"


def set_light_spectrum(settings, spectrum: spectra.Spectrum) -> None:
    """A light's spectrum as a curve of its shape (the strength sets the brightness)."""
    peak = spectrum.values.max()
    set_curve(settings, spectrum.values / peak if peak > 0 else spectrum.values)


def _sources(settings) -> set[str]:
    return {item.identifier for item in settings.bl_rna.properties["source"].enum_items}


# ----------------------------------------------------------------------------- lights


def _pointing(direction) -> Vector:
    """Euler rotation turning the object's +Z to `direction`."""
    return Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(direction)).to_euler()


def add_sun(collection, light: Light, spectrum, name: str | None = None):
    """A sun object shining from the tracer light's direction; `spectrum(settings)` sets its spectrum."""
    data = bpy.data.lights.new(name or light.name, "SUN")
    data.energy, data.angle = light.strength, light.angle
    data.spectral.enabled, data.spectral.unit = True, light.unit
    spectrum(data.spectral.spectrum)
    obj = link(collection, bpy.data.objects.new(name or light.name, data))
    obj.rotation_euler = _pointing(light.direction)
    return obj


def add_point_or_spot(collection, light: Light, name: str | None = None):
    """A point or spot light object of the tracer light (Power from its intensity, the spot along its
    direction); its spectrum as a curve."""
    data = bpy.data.lights.new(name or light.name, light.kind.upper())
    data.energy = light.strength / point_intensity(1.0)
    if light.kind == "spot":
        data.spot_size, data.spot_blend = light.spot_size, light.spot_blend
    data.spectral.enabled, data.spectral.unit = True, light.unit
    set_light_spectrum(data.spectral.spectrum, light.spectrum)
    obj = link(collection, bpy.data.objects.new(name or light.name, data))
    obj.location = Vector(light.position)
    if light.kind == "spot":  # a spot shines along its object's −Z
        obj.rotation_euler = _pointing(-np.asarray(light.spot_direction))
    return obj


def add_area(collection, light: Light, name: str | None = None):
    """An area light object of the tracer light: its power, shape and size, placed by its centre and axes
    (Blender's area light shines along its −Z, as the tracer's), seen by the camera where the light is; its
    spectrum as a curve."""
    equal = light.size_x == light.size_y
    shape = {("rectangle", True): "SQUARE", ("rectangle", False): "RECTANGLE", ("ellipse", True): "DISK",
             ("ellipse", False): "ELLIPSE"}[(light.area_shape, equal)]
    data = bpy.data.lights.new(name or light.name, "AREA")
    data.energy, data.shape, data.size, data.size_y = light.strength, shape, light.size_x, light.size_y
    data.spectral.enabled, data.spectral.unit = True, light.unit
    set_light_spectrum(data.spectral.spectrum, light.spectrum)
    obj = link(collection, bpy.data.objects.new(name or light.name, data))
    axes = np.asarray(light.area_axes, dtype=np.float64)
    matrix = np.eye(4)
    matrix[:3, :3], matrix[:3, 3] = axes / np.linalg.norm(axes, axis=0), light.position
    obj.matrix_world = Matrix(matrix.tolist())
    obj.visible_camera = bool(light.camera_visible)
    return obj


def new_world(name: str, light: Light | None = None, spectrum=None):
    """A World: dark, or the Spectral World of the environment or sky `light` with `spectrum(settings)` (a
    sky's horizon from the light)."""
    world = bpy.data.worlds.new(name)
    world.spectral.enabled = light is not None
    if light is None:  # Blender's own World (grey by default) would light the scene
        world.color = (0.0, 0.0, 0.0)
        for node in world.node_tree.nodes if world.node_tree else ():
            if "Strength" in node.inputs:
                node.inputs["Strength"].default_value = 0.0
    if light is not None:
        world.spectral.kind, world.spectral.strength = light.kind, light.strength
        spectrum(world.spectral.spectrum)
        if light.horizon_spectrum is not None:
            set_light_spectrum(world.spectral.horizon, light.horizon_spectrum)
    return world


# ----------------------------------------------------------------------------- volumes


def volume_material(name: str, medium: Medium, temperature_grid: str = "temperature", csv_file=None):
    """A Spectral Volume material with the tracer medium's optics; a glowing medium reads its temperature
    from the grid `temperature_grid`. A spectrum no curve can hold is read from the CSV file that
    `csv_file(role, values)` names (see `set_spectrum`)."""
    material = bpy.data.materials.new(name)
    settings = material.spectral
    settings.enabled = True
    settings.density_scale = medium.density_scale
    settings.phase = medium.phase

    def spectrum(target, value, role):
        set_spectrum(target, value, None if csv_file is None else lambda values: csv_file(role, values))

    spectrum(settings.extinction, medium.extinction, "extinction")
    albedo_levels = list(zip(medium.albedo_densities.tolist(), medium.albedo_table))
    if albedo_levels[0][0] > 0.0:  # the first level is at density 0: below the lowest, the albedo is clamped
        albedo_levels.insert(0, (0.0, albedo_levels[0][1]))
    spectrum(settings.albedo, spectra.Spectrum(albedo_levels[0][1]), "albedo")
    for i, (density, row) in enumerate(albedo_levels[1:], start=1):
        level = settings.albedo_levels.add()
        level.density = density
        spectrum(level.spectrum, spectra.Spectrum(row), f"albedo_{i}")
    spectrum(settings.anisotropy, medium.anisotropy, "anisotropy")
    if medium.fluorescence is not None:
        settings.use_fluorescence = True
        spectrum(settings.excitation, medium.fluorescence.excitation, "excitation")
        spectrum(settings.emission, medium.fluorescence.emission, "emission")
        settings.quantum_yield = medium.fluorescence.quantum_yield
    if medium.emission is not None:
        emission = medium.emission
        settings.use_blackbody, settings.temperature_grid = True, temperature_grid
        settings.blackbody_intensity = emission.intensity
        settings.temperature_scale = emission.temperature_scale
        settings.temperature_offset = emission.temperature_offset
    return material


def add_vdb_volume(collection, name: str, filepath: str, grid_name: str, material):
    """A Volume object reading grid `grid_name` of the VDB file `filepath`."""
    volume = bpy.data.volumes.new(name)
    volume.filepath = filepath
    obj = link(collection, bpy.data.objects.new(name, volume))
    obj.spectral.density_grid = grid_name
    obj.data.materials.append(material)
    return obj


def write_vdb(path: Path, named_grids: dict) -> None:
    """Write {name: tracer Grid} into one VDB file (each grid under its name here)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    grids.save_grid_vdb(path, *(Grid(grid.values, grid.index_to_world, name)
                                for name, grid in named_grids.items()))
