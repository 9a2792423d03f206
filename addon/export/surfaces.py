"""Blender geometry → the tracer's opaque surfaces: one `Surface` per object instance and material slot.

The triangles are the evaluated mesh's loop triangles (modifiers and Geometry Nodes applied) in world
space, at the depsgraph instance's matrix; curves, text, surfaces and metaballs are meshed as Blender's
renderers mesh them (`Object.to_mesh`); hair curves, point clouds and Grease Pencil are named as not
rendered. What a material renders as is `nodes.surface.read_surface_shader`, its reflectance the material's
spectrum where its Spectral Surface is on (`props.material`);
the triangles of a slot whose material has nothing linked to its Surface are see-through in Cycles and
are left out, as are meshes without faces. A surface is named after its object, and after its material too
where the object has several, so that errors and the report name Blender's data. A surface holds out
(`Surface.holdout`) where its material has a Holdout closure or its object is a holdout in the view layer
(`held_out`: Object ▸ Visibility ▸ Holdout, or a collection set to Holdout), as in Cycles; camera rays pass it
(`Surface.camera` off, `seen_by_camera`) where Cycles clears its camera visibility: Object ▸ Visibility ▸ Ray
Visibility ▸ Camera off (its own or its instancer's), or a collection set to Indirect Only (unless it holds out).
An albedo read from an Image Texture (`nodes.graph.image_texture`) becomes the surface's `Texture`: the image's
pixels as Cycles reads them (`textures.texture_image`) and each triangle corner's UV from the evaluated mesh's UV
map, through the Mapping node's affine map.
"""

import numpy as np

from ..nodes.notes import Notes
from ..nodes.surface import read_surface_shader
from ..props.spectrum_values import to_spectrum
from ..tracer.scene import Surface, Texture
from ..tracer.spectra import Spectrum
from .media import slot_materials
from .textures import texture_image

MESHED_TYPES = ("MESH", "CURVE", "SURFACE", "FONT", "META")
# Renderable geometry the tracer has no surfaces for (each named in the report).
UNRENDERED_TYPES = {"CURVES": ("hair curves object", "hair curves objects"), "POINTCLOUD": ("point cloud", None),
                    "GREASEPENCIL": ("Grease Pencil object", None)}


def _triangles(mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(vertices (V, 3) in object space, triangles (T, 3), material index per triangle, loops (T, 3): each
    corner's loop, where its UVs are)."""
    mesh.calc_loop_triangles()
    vertices = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", vertices)
    triangles = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    slots = np.empty(len(mesh.loop_triangles), dtype=np.int32)
    mesh.loop_triangles.foreach_get("material_index", slots)
    loops = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    return vertices.reshape(-1, 3).astype(np.float64), triangles.reshape(-1, 3), slots, loops.reshape(-1, 3)


def _uv_maps(mesh) -> dict:
    """Each UV map's UV per loop (L, 2), by name, and the active render map's under "" (none: no UV maps)."""
    maps = {}
    for layer in mesh.uv_layers:
        uv = np.empty(len(mesh.loops) * 2, dtype=np.float32)
        layer.data.foreach_get("uv", uv)
        maps[layer.name] = uv.reshape(-1, 2).astype(np.float64)
        if layer.active_render:
            maps[""] = maps[layer.name]
    return maps


def _texture(look, loops, uv_maps, owner: str, notes: Notes) -> Texture | None:
    """The tracer texture of a look's Image Texture on triangles of corner loops `loops`, or None (named) where its
    image has no pixels or the mesh lacks its UV map."""
    source = look.texture
    if source is None:
        return None
    pixels = texture_image(source.image, f"{owner} ▸ {source.node.name}", notes)
    if pixels is None:
        return None
    uv = uv_maps.get(source.uv_map)
    if uv is None:
        missing = f"UV map {source.uv_map!r}" if source.uv_map else "UV map"
        notes.add(f"{owner} ▸ {source.node.name}: the mesh has no {missing}: the texture is not rendered (its "
                  "socket's value is)")
        return None
    corners = uv[loops]  # (T, 3, 2)
    mapped = corners @ source.uv_transform[:, :2].T + source.uv_transform[:, 2]
    return Texture(image=pixels[0], uv=mapped, extension=source.extension, interpolation=source.interpolation,
                   srgb=pixels[1])


def _reflectance(look, material) -> Spectrum:
    """The diffuse reflectance: the material's spectrum where its Spectral Surface is on, else its nodes'."""
    if material is not None and material.spectral.use_surface:
        return to_spectrum(material.spectral.reflectance)
    return Spectrum(look.reflectance)


def _surface(name, vertices, triangles, look, holdout: bool, camera: bool, texture, obj, material) -> Surface:
    used, compact = np.unique(triangles, return_inverse=True)
    return Surface(name=name, vertices=vertices[used], triangles=compact.reshape(-1, 3).astype(np.int32),
                   reflectance=_reflectance(look, material),
                   emission=Spectrum(look.emission) if look.emits() else None, holdout=holdout or look.holdout,
                   camera=camera, texture=texture, object=obj.name,
                   material=material.name if material is not None else "")


def _owner(instance):
    """The object whose view-layer settings an instance takes: its instancer's for an instance, else its own."""
    return (instance.parent if instance.is_instance and instance.parent is not None else instance.object).original


def held_out(instance, view_layer) -> bool:
    """Whether Cycles renders a depsgraph instance as a holdout: its object's (or for an instance, its
    instancer's) Holdout property, or a collection of the view layer set to Holdout."""
    owner = _owner(instance)
    return bool(owner.is_holdout or owner.holdout_get(view_layer=view_layer))


def seen_by_camera(instance, view_layer) -> bool:
    """Whether Cycles lets camera rays see a depsgraph instance: Ray Visibility ▸ Camera on for its object and its
    instancer, and not in a collection set to Indirect Only (which a holdout ignores)."""
    owner = _owner(instance)
    visible = bool(instance.object.original.visible_camera and owner.visible_camera)
    indirect_only = not held_out(instance, view_layer) and owner.indirect_only_get(view_layer=view_layer)
    return visible and not indirect_only


def export_surfaces(obj, matrix_world, depsgraph, notes: Notes, holdout: bool = False,
                    camera: bool = True) -> list[Surface]:
    """The surfaces of one evaluated object instance at `matrix_world` ([] for a type with no faces); with
    `holdout` (`held_out`), all of them hold out; without `camera` (`seen_by_camera`), camera rays pass them."""
    if obj.type in UNRENDERED_TYPES:
        notes.leave_out(UNRENDERED_TYPES[obj.type][0], obj.name, UNRENDERED_TYPES[obj.type][1])
    if obj.type not in MESHED_TYPES:
        return []
    mesh = obj.data if obj.type == "MESH" else obj.to_mesh()
    try:
        if mesh is None or not mesh.polygons:
            return []
        vertices, triangles, slots, loops = _triangles(mesh)
        uv_maps = _uv_maps(mesh)
    finally:
        if obj.type != "MESH":
            obj.to_mesh_clear()
    matrix = np.array(matrix_world, dtype=np.float64)
    vertices = vertices @ matrix[:3, :3].T + matrix[:3, 3]
    materials = slot_materials(obj, depsgraph) or [None]
    slots = np.clip(slots, 0, len(materials) - 1)  # Blender renders an index past the slots with the last one
    several = len(set(materials)) > 1
    surfaces = []
    for index in np.unique(slots):
        material = materials[index]
        look = read_surface_shader(material, notes)
        if look is None:
            continue
        name = obj.name + (f" ▸ {material.name if material is not None else 'no material'}" if several else "")
        mine = slots == index
        texture = None
        if look.texture is not None and not material.spectral.use_surface:  # a look with a texture has a material
            texture = _texture(look, loops[mine], uv_maps, f"material {material.name!r}", notes)
        surfaces.append(_surface(name, vertices, triangles[mine], look, holdout, camera, texture, obj, material))
    return surfaces
