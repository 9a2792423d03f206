"""The demos' own Blender data: their scenes' view settings, light spectra from presets, mesh volumes and
fluid domains. The general builders (cameras, suns, worlds, volume materials, Volume objects, spectra)
are the add-on's importer's (`addon.importer.parts`).

`build_blends` describes each .blend with these; tests/demos/test_blends.py checks that the files export
back to the scenes of `scenes`. Needs `bpy` with the add-on registered.
"""

import bpy

from addon.props import curves
from addon.importer import parts
from addon.tracer.scene import RenderSettings
from addon.tracer.wavelengths import GRID


def new_scene(name: str, width: int, height: int, spp: int, seed: int, exposure: float = 0.0):
    """A Blender scene rendered by the Spectral Volume engine, shown through the Standard view."""
    scene = parts.new_scene(name, width, height, RenderSettings(spp=spp, seed=seed))
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.exposure = exposure
    return scene


# ----------------------------------------------------------------------------- light spectra


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


# ----------------------------------------------------------------------------- volumes


def box_mesh(name: str, low, high):
    """A closed box mesh spanning [low, high] (object at the origin)."""
    (x0, y0, z0), (x1, y1, z1) = low, high
    vertices = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    mesh.update()
    return mesh


def add_diffuse_surface(collection, surface, rgb):
    """A mesh object of the tracer surface's triangles (in world space) with a Diffuse BSDF of Color `rgb`
    (linear), as an artist makes a ground plane."""
    mesh = bpy.data.meshes.new(surface.name)
    mesh.from_pydata([tuple(v) for v in surface.vertices], [], [tuple(t) for t in surface.triangles])
    mesh.update()
    material = bpy.data.materials.new(surface.name)
    nodes = material.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*rgb, 1.0)
    material.node_tree.links.new(diffuse.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])
    mesh.materials.append(material)
    return parts.link(collection, bpy.data.objects.new(surface.name, mesh))


def add_mesh_volume(collection, name: str, low, high, voxel_size: float, material):
    """A box mesh filled with the volume material, voxelised by the add-on at `voxel_size`."""
    obj = parts.link(collection, bpy.data.objects.new(name, box_mesh(name, low, high)))
    obj.spectral.voxel_size = voxel_size
    obj.data.materials.append(material)
    return obj


def add_fluid_domain(collection, name: str, low, high, cache_directory: str, resolution_max: int, material,
                     density_grid: str = "density"):
    """A smoke/fire domain box over [low, high] whose OpenVDB cache lies in `cache_directory`. Its
    modifier is hidden, so Blender never simulates (Mantaflow would overwrite or abort); the add-on
    reads the cache files directly."""
    obj = parts.link(collection, bpy.data.objects.new(name, box_mesh(name, low, high)))
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
