"""A tracer Scene → a new Blender scene that exports back to it: camera and resolution, render settings,
media (Volume objects reading VDB files, Spectral Volume materials), sun, point, spot and area lights, and
the environment or sky as the World.

Blender's Volume objects read VDB files, so every medium's grids are written to a VDB file in a data
folder (and a spectrum no curve can hold, such as an extinction above 1, to a CSV file there). Those
files are written together, after the Blender data is made; when writing fails, the new scene and its
data are removed again and no file is left behind or changed.
"""

from pathlib import Path

import bpy

from ..tracer import image_io
from ..tracer.errors import SpectralError
from ..tracer.scene import RenderSettings, Scene
from . import parts

DENSITY, TEMPERATURE = "density", "temperature"  # grid names in the written VDB files
WORLD_KINDS = ("environment", "sky")
DATA = ("scenes", "objects", "cameras", "lights", "worlds", "materials", "volumes", "node_groups")


def _unique(stem: str, taken: set) -> str:
    name, i = stem, 1
    while name in taken:
        i += 1
        name = f"{stem}_{i}"
    taken.add(name)
    return name


def _all_data() -> set:
    return {block for collection in DATA for block in getattr(bpy.data, collection)}


def import_scene(scene: Scene, name: str, data_folder: Path) -> tuple[object, list[str]]:
    """Make the Blender scene `name` of the tracer `scene`, its files in `data_folder`; returns (the
    Blender scene, warnings about what Blender cannot hold). Raises SpectralError when a file cannot be
    written (then nothing is left of the import)."""
    data_folder = Path(data_folder)
    warnings = []
    if scene.settings.rr_depth != RenderSettings().rr_depth:
        warnings.append(f"Russian roulette depth {scene.settings.rr_depth} has no Blender setting: the add-on "
                        f"renders with {RenderSettings().rr_depth}")
    before = _all_data()
    try:
        blender_scene, files = _build(scene, name, data_folder, warnings)
        image_io.write_all(files)
    except (SpectralError, OSError) as problem:
        bpy.data.batch_remove(_all_data() - before)
        raise SpectralError(str(problem)) from None
    return blender_scene, warnings


def _build(scene: Scene, name: str, folder: Path, warnings: list) -> tuple[object, list]:
    camera = scene.camera
    blender_scene = parts.new_scene(name, camera.width, camera.height, scene.settings)
    parts.add_camera(blender_scene, camera)
    files, stems = [], set()
    collection = blender_scene.collection
    for medium in scene.media:
        stem = _unique(bpy.path.clean_name(medium.name), stems)
        named = {DENSITY: medium.density}
        if medium.emission is not None:
            named[TEMPERATURE] = medium.emission.temperature
        vdb = folder / f"{stem}.vdb"
        files.append(image_io.Output(vdb, lambda path, named=named: parts.write_vdb(Path(path), named)))

        def csv_file(role, values, stem=stem):
            path = folder / f"{stem}_{role}.csv"
            files.append(image_io.text(path, parts.csv_text(values)))
            return str(path)

        material = parts.volume_material(medium.name, medium, TEMPERATURE, csv_file)
        parts.add_vdb_volume(collection, medium.name, str(vdb), DENSITY, material)
    worlds = [light for light in scene.lights if light.kind in WORLD_KINDS]
    for light in scene.lights:
        if light.kind == "sun":
            parts.add_sun(collection, light, lambda settings, light=light: parts.set_light_spectrum(
                settings, light.spectrum), light.name or "Sun")
        elif light.kind in ("point", "spot"):
            parts.add_point_or_spot(collection, light, light.name or light.kind.title())
        elif light.kind == "area":
            parts.add_area(collection, light, light.name or "Area")
    if worlds:
        world = worlds[0]
        blender_scene.world = parts.new_world(world.name or name, world, lambda settings: parts.set_light_spectrum(
            settings, world.spectrum))
    else:
        blender_scene.world = parts.new_world(name)
    if len(worlds) > 1:
        warnings.append(f"a Blender scene has one World: {len(worlds) - 1} more environment or sky lights skipped")
    return blender_scene, files
