"""Builds the demo .blend files from factory settings with the add-on's settings (reproducibly):

    python -m demo_blends.build_blends [--out demo_blends/] [--only rayleigh fire ...]

Every number comes from the tracer scenes in `scenes` (and the metamer design in `metamers`), so each
Blender scene exports to the same tracer scene that `scenes` builds in code. Written into `--out`:
- `rayleigh.blend`: scenes "Report" (grey air, anisotropy rising with λ) and "True Rayleigh"
  (extinction ∝ λ⁻⁴, Rayleigh phase), sharing the ground;
- `fluorescent_frog.blend`: a fluorescent frog on a white pad under a 275–450 nm lamp;
- `highlighter_ink.blend`: two glasses of highlighter ink (optically thick, and diluted 50×) under that lamp;
- `metamerism.blend`: the light switch: scenes "Simple D65", "Simple D65 lower half" (the report's
  cubes), "Designed D65", "Designed A" (a pair designed with colour-science), each a cube pair
  collection with a light collection and World;
- `fire.blend`: fire and smoke domains reading one fluid cache (never simulated);
- `cloud_shadow.blend`: a cloud over a ground plane (a mesh with a Diffuse BSDF), its shadow on it, Film ▸
  Transparent on;
- `volumes/`: the VDB files they read (`//volumes/...`): the air and ground, the frog, the inks, the fire's
  cache `fire_cache/data/fluid_data_0001.vdb`, the cloud.
Rebuilding writes the same content in different bytes (Blender and OpenVDB stamp their files), so
tests/demos/test_blends.py compares the exported scenes, not the files.
"""

import argparse
import functools
from dataclasses import dataclass
from pathlib import Path

import bpy
import numpy as np

import addon
from addon.importer import parts

from . import blend_parts as demo_parts
from . import metamers, scenes

HERE = Path(__file__).resolve().parent
WIDTH, HEIGHT = 256, 160
VOLUMES = "volumes"


@dataclass(frozen=True)
class DemoScene:
    """Where a demo lives: Blender scene `scene` of `blend`, rendered at `spp` samples per pixel;
    `exposure` is the scene's view exposure (stops) for display."""

    blend: str
    scene: str
    spp: int
    exposure: float = 0.0


DEMO_SCENES = {
    "rayleigh_report": DemoScene("rayleigh.blend", "Report", 48, -1.0),
    "rayleigh_true": DemoScene("rayleigh.blend", "True Rayleigh", 48, 2.0),
    "fluorescent_frog": DemoScene("fluorescent_frog.blend", "Frog", 32),
    "highlighter_ink": DemoScene("highlighter_ink.blend", "Ink", 32),
    "fire": DemoScene("fire.blend", "Fire", 48),
    "metamers_simple_d65": DemoScene("metamerism.blend", "Simple D65", 24, 0.5),
    "metamers_simple_lower_half": DemoScene("metamerism.blend", "Simple D65 lower half", 24, 0.5),
    "metamers_d65": DemoScene("metamerism.blend", "Designed D65", 24, 1.0),
    "metamers_a": DemoScene("metamerism.blend", "Designed A", 24, 1.0),
    "cloud_shadow": DemoScene("cloud_shadow.blend", "Cloud", 32),
}


def _scene(demo: str):
    d = DEMO_SCENES[demo]
    return demo_parts.new_scene(d.scene, WIDTH, HEIGHT, d.spp, scenes.SEED, d.exposure)


def _vdb(out: Path, name: str, named_grids: dict) -> str:
    """Write the grids to `out/volumes/name` and return the path the .blend uses."""
    parts.write_vdb(out / VOLUMES / name, named_grids)
    return f"//{VOLUMES}/{name}"


def _volumes(collection, media, filepath: str, names=None) -> None:
    """A Volume object per tracer medium, reading the grid named after it from `filepath`."""
    for medium in media:
        name = (names or {}).get(medium.name, medium.name)
        parts.add_vdb_volume(collection, name, filepath, medium.name, parts.volume_material(name, medium))


# ----------------------------------------------------------------------------- the files


def build_rayleigh(out: Path) -> list:
    report = scenes.rayleigh_report(WIDTH, HEIGHT, 1)
    true = scenes.rayleigh_true(WIDTH, HEIGHT, 1)
    air, ground = report.media
    path = _vdb(out, "atmosphere.vdb", {"air": air.density, "ground": ground.density})
    built, ground_object = [], None
    for demo, tracer, label in (("rayleigh_report", report, "Report"), ("rayleigh_true", true, "Rayleigh")):
        scene = _scene(demo)
        collection = scene.collection
        parts.add_camera(scene, tracer.camera, f"{label} camera")
        parts.add_sun(collection, tracer.lights[0], lambda s: demo_parts.set_preset(s, "E"), f"{label} sun")
        scene.world = parts.new_world(f"{label} (no world light)")
        _volumes(collection, tracer.media[:1], path, {"air": f"{label} air"})
        if ground_object is None:
            ground_object = parts.add_vdb_volume(collection, "ground", path, "ground",
                                                 parts.volume_material("ground", ground))
        else:
            parts.link(collection, ground_object)
        built.append(scene)
    return built


def _under_uv_lamp(out: Path, demo: str, tracer, vdb: str) -> list:
    """A demo scene lit like the frog (the UV lamp and its fill), its media read from `volumes/<vdb>`."""
    scene = _scene(demo)
    collection = scene.collection
    parts.add_camera(scene, tracer.camera)
    lamp, fill = tracer.lights
    uv = lambda settings: demo_parts.set_flat(settings, scenes.UV_WINDOW)
    parts.add_sun(collection, lamp, uv)
    scene.world = parts.new_world("UV fill", fill, uv)
    _volumes(collection, tracer.media, _vdb(out, vdb, {m.name: m.density for m in tracer.media}))
    return [scene]


def build_frog(out: Path) -> list:
    return _under_uv_lamp(out, "fluorescent_frog", scenes.fluorescent_frog(WIDTH, HEIGHT, 1), "frog.vdb")


def build_highlighter_ink(out: Path) -> list:
    return _under_uv_lamp(out, "highlighter_ink", scenes.highlighter_ink(WIDTH, HEIGHT, 1), "ink.vdb")


LIGHT_PRESETS = {"D65": ("D65", None), "D65 lower half": ("D65", scenes.LOWER_HALF), "A": ("A", None)}


def build_metamerism(pair: metamers.MetamerPair) -> list:
    """Cube pairs and lights as collections; each scene links one of each (the light switch). The
    cubes are meshes, voxelised by the add-on: nothing is written beside the .blend."""
    camera = None
    cube_sets = {}
    for label, albedos in (("Simple", scenes.SIMPLE_ALBEDOS), ("Designed", pair.albedos)):
        collection = bpy.data.collections.new(f"{label} cubes")
        tracer = scenes.two_cubes(*albedos, scenes.LIGHTS["D65"], WIDTH, HEIGHT, 1)
        for medium in tracer.media:
            grid = medium.density
            voxel = float(grid.index_to_world[0, 0])
            low = grid.index_to_world[:3, 3] - voxel / 2
            high = low + voxel * np.array(grid.values.shape)
            name = f"{label} {medium.name}"
            demo_parts.add_mesh_volume(collection, name, low, high, voxel, parts.volume_material(name, medium))
        cube_sets[label] = collection
        camera = camera or tracer.camera
    light_sets = {}
    for label, (illuminant, window) in LIGHT_PRESETS.items():
        collection = bpy.data.collections.new(f"Light {label}")
        sun, fill = scenes.two_cubes(1.0, 1.0, scenes.LIGHTS[label], WIDTH, HEIGHT, 1).lights
        spectrum = lambda settings, illuminant=illuminant, window=window: demo_parts.set_preset(settings, illuminant,
                                                                                                window)
        parts.add_sun(collection, sun, spectrum, f"Sun {label}")
        light_sets[label] = (collection, parts.new_world(f"Fill {label}", fill, spectrum))
    camera_object = None
    built = []
    for demo, cubes, light in (("metamers_simple_d65", "Simple", "D65"),
                               ("metamers_simple_lower_half", "Simple", "D65 lower half"),
                               ("metamers_d65", "Designed", "D65"), ("metamers_a", "Designed", "A")):
        scene = _scene(demo)
        if camera_object is None:
            camera_object = parts.add_camera(scene, camera)
        else:
            scene.camera = parts.link(scene.collection, camera_object)
        lights, scene.world = light_sets[light]
        scene.collection.children.link(cube_sets[cubes])
        scene.collection.children.link(lights)
        built.append(scene)
    return built


def build_fire(out: Path) -> list:
    fire = scenes.fire(WIDTH, HEIGHT, 1)
    flame, smoke = fire.media
    parts.write_vdb(out / VOLUMES / "fire_cache" / "data" / "fluid_data_0001.vdb",
                    {"density": smoke.density, "flame": flame.density, "temperature": flame.emission.temperature})
    scene = _scene("fire")
    collection = scene.collection
    parts.add_camera(scene, fire.camera)
    parts.add_sun(collection, fire.lights[0],
                  lambda settings: demo_parts.set_blackbody(settings, scenes.MOON_TEMPERATURE))
    scene.world = parts.new_world("Night (no world light)")
    cache, cells = f"//{VOLUMES}/fire_cache", max(scenes.FIRE_CELLS)
    for medium, grid in ((flame, "flame"), (smoke, "density")):
        demo_parts.add_fluid_domain(collection, medium.name, *scenes.FIRE_BOX, cache, cells,
                               parts.volume_material(medium.name, medium), density_grid=grid)
    return [scene]


def build_cloud_shadow(out: Path) -> list:
    tracer = scenes.cloud_shadow(WIDTH, HEIGHT, 1)
    scene = _scene("cloud_shadow")
    collection = scene.collection
    parts.add_camera(scene, tracer.camera)
    sun, sky = tracer.lights
    d65 = lambda settings: demo_parts.set_preset(settings, "D65")
    parts.add_sun(collection, sun, d65)
    scene.world = parts.new_world("Sky", sky, d65)
    _volumes(collection, tracer.media, _vdb(out, "cloud.vdb", {m.name: m.density for m in tracer.media}))
    demo_parts.add_diffuse_surface(collection, tracer.surfaces[0], scenes.GROUND_RGB)
    scene.render.film_transparent = True
    return [scene]


# ----------------------------------------------------------------------------- writing


@functools.cache
def designed_pair() -> metamers.MetamerPair:
    """The designed metamers (calibrated on the code-built cubes, which the .blend's cubes equal);
    designed once per process."""
    return metamers.metamer_pair(metamers.calibrate())


def write_blend(path: Path, build) -> None:
    """Start from factory settings with the add-on registered, build, and save `path` compressed."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        empty = bpy.context.scene
        built = build()
        bpy.context.window.scene = built[0]
        bpy.data.scenes.remove(empty)
        path.parent.mkdir(parents=True, exist_ok=True)
        bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True, relative_remap=False)
    finally:
        addon.unregister()


BUILDERS = {"rayleigh": build_rayleigh, "fluorescent_frog": build_frog, "highlighter_ink": build_highlighter_ink,
            "metamerism": lambda _out: build_metamerism(designed_pair()), "fire": build_fire,
            "cloud_shadow": build_cloud_shadow}


def build(out: Path = HERE, only=None, log=print) -> list[Path]:
    """Write the .blend files (`only`: names among BUILDERS) and their volumes into `out`."""
    written = []
    for name, builder in BUILDERS.items():
        if only and name not in only:
            continue
        path = out / f"{name}.blend"
        write_blend(path, lambda builder=builder: builder(out))
        log(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB)")
        written.append(path)
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE, help="folder for the .blend files (default: demo_blends/)")
    parser.add_argument("--only", nargs="*", choices=sorted(BUILDERS), help="build only these files")
    args = parser.parse_args(argv)
    build(args.out, args.only)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
