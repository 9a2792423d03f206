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
(`held_out`: Object ▸ Visibility ▸ Holdout, or a collection set to Holdout), as in Cycles.
"""

import numpy as np

from ..nodes.notes import Notes
from ..nodes.surface import read_surface_shader
from ..props.spectrum_values import to_spectrum
from ..tracer.scene import Surface
from ..tracer.spectra import Spectrum
from .media import slot_materials

MESHED_TYPES = ("MESH", "CURVE", "SURFACE", "FONT", "META")
# Renderable geometry the tracer has no surfaces for (each named in the report).
UNRENDERED_TYPES = {"CURVES": ("hair curves object", "hair curves objects"), "POINTCLOUD": ("point cloud", None),
                    "GREASEPENCIL": ("Grease Pencil object", None)}


def _triangles(mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices (V, 3) in object space, triangles (T, 3), material index per triangle)."""
    mesh.calc_loop_triangles()
    vertices = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", vertices)
    triangles = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    slots = np.empty(len(mesh.loop_triangles), dtype=np.int32)
    mesh.loop_triangles.foreach_get("material_index", slots)
    return vertices.reshape(-1, 3).astype(np.float64), triangles.reshape(-1, 3), slots


def _reflectance(look, material) -> Spectrum:
    """The diffuse reflectance: the material's spectrum where its Spectral Surface is on, else its nodes'."""
    if material is not None and material.spectral.use_surface:
        return to_spectrum(material.spectral.reflectance)
    return Spectrum(look.reflectance)


def _surface(name, vertices, triangles, look, holdout: bool, obj, material) -> Surface:
    used, compact = np.unique(triangles, return_inverse=True)
    return Surface(name=name, vertices=vertices[used], triangles=compact.reshape(-1, 3).astype(np.int32),
                   reflectance=_reflectance(look, material),
                   emission=Spectrum(look.emission) if look.emits() else None, holdout=holdout or look.holdout,
                   object=obj.name, material=material.name if material is not None else "")


def held_out(instance, view_layer, notes: Notes) -> bool:
    """Whether Cycles renders a depsgraph instance as a holdout: its object's (or for an instance, its
    instancer's) Holdout property, or a collection of the view layer set to Holdout. A collection set to
    Indirect Only (hidden from the camera only) is named in `notes`: its objects render as ordinary ones."""
    owner = (instance.parent if instance.is_instance and instance.parent is not None else instance.object).original
    holdout = bool(owner.is_holdout or owner.holdout_get(view_layer=view_layer))
    if not holdout and owner.indirect_only_get(view_layer=view_layer):
        notes.add(f"object {owner.name!r}: Indirect Only (its collection's) rendered as seen by the camera too")
    return holdout


def export_surfaces(obj, matrix_world, depsgraph, notes: Notes, holdout: bool = False) -> list[Surface]:
    """The surfaces of one evaluated object instance at `matrix_world` ([] for a type with no faces); with
    `holdout` (`held_out`), all of them hold out."""
    if obj.type in UNRENDERED_TYPES:
        notes.leave_out(UNRENDERED_TYPES[obj.type][0], obj.name, UNRENDERED_TYPES[obj.type][1])
    if obj.type not in MESHED_TYPES:
        return []
    mesh = obj.data if obj.type == "MESH" else obj.to_mesh()
    try:
        if mesh is None or not mesh.polygons:
            return []
        vertices, triangles, slots = _triangles(mesh)
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
        surfaces.append(_surface(name, vertices, triangles[slots == index], look, holdout, obj, material))
    return surfaces
