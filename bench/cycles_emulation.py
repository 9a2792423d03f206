"""The Cycles emulation against the tracer at equal noise, on the same Blender scene (issue 5).

Scene: the benchmark cloud (bench/scenes.py, procedural, 32³ by default) as a Volume object read from a
VDB file, σ_t = 30 × density, albedo the smooth reflectance of RGB (0.9, 0.45, 0.15) (λ-dependent), g 0.3,
a D65 sun of strength 3; the camera of bench/scenes.py. Both engines render what `export_scene` makes of
it; the emulation with `--bands` bands (three per Cycles render) and plain nodes (SVM).

Noise is the mean over pixels of the variance of the luminance estimate (the tracer's film variance; the
emulation's from its two seeded halves). It falls as 1/spp, so each engine's time at the tracer's noise
follows from one render: the tracer's kernel time (scene lowered and kernel compiled beforehand), and for
the emulation a straight-line fit of time against samples over two renders, which separates Cycles'
per-render preparation (it builds an octree for every volume shader) from its per-sample cost.
The emulation with the OSL shader is timed at the first sample count too.

    python -m bench.cycles_emulation            # 96×64, tracer 256 spp, emulation 16 and 64 spp, 12 bands
    python -m bench.cycles_emulation --quick    # 48×32, small counts: proves it runs
"""

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="spectral_bench_user_"))

import bpy  # noqa: E402  (after BLENDER_USER_RESOURCES: Blender reads it at start-up)
import numpy as np  # noqa: E402

import addon  # noqa: E402
from addon.cycles_emulation.job import EmulationJob  # noqa: E402
from addon.export.scene import export_scene  # noqa: E402
from addon.tracer import colorimetry, grids  # noqa: E402
from addon.tracer.lowering import compile_scene  # noqa: E402
from addon.tracer.scene import Grid, look_at  # noqa: E402
from bench.measure import machine, render_ours, warm_up  # noqa: E402
from bench.scenes import EYE, SUN_DIRECTION, TARGET, cloud_density, cloud_transform  # noqa: E402


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="48×32, tracer 32 spp, emulation 4 and 16 spp")
    parser.add_argument("--width", type=int, help="image width (default 96)")
    parser.add_argument("--height", type=int, help="image height (default 64)")
    parser.add_argument("--resolution", type=int, default=32, help="cloud grid resolution (default 32)")
    parser.add_argument("--bands", type=int, default=12, help="emulation bands (default 12: 4 Cycles renders)")
    parser.add_argument("--tracer-spp", type=int, help="tracer samples per pixel (default 256)")
    parser.add_argument("--cycles-spp", type=int, nargs=2, help="emulation samples, two counts (default 16 64)")
    parser.add_argument("--no-osl", action="store_true", help="skip the OSL timing")
    args = parser.parse_args(argv)
    quick = args.quick
    args.width = args.width or (48 if quick else 96)
    args.height = args.height or (32 if quick else 64)
    args.tracer_spp = args.tracer_spp or (32 if quick else 256)
    args.cycles_spp = args.cycles_spp or ([4, 16] if quick else [16, 64])
    return args


def build_scene(args, folder: Path):
    """The cloud as a Blender scene: Volume object, spectral material, D65 sun, camera."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.height
    scene.render.resolution_percentage = 100
    density, _cached = cloud_density(args.resolution)
    path = folder / "cloud.vdb"
    grids.save_grid_vdb(path, Grid(density.values, cloud_transform(args.resolution), "density"))
    volume = bpy.data.volumes.new("Cloud")
    volume.filepath = str(path)
    cloud = bpy.data.objects.new("Cloud", volume)
    scene.collection.objects.link(cloud)
    material = bpy.data.materials.new("Cloud")
    settings = material.spectral
    settings.enabled, settings.density_scale, settings.anisotropy.value = True, 30.0, 0.3
    settings.albedo.source, settings.albedo.color = "COLOR", (0.9, 0.45, 0.15)
    volume.materials.append(material)
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    sun.data.spectral.spectrum.source, sun.data.spectral.spectrum.illuminant = "ILLUMINANT", "D65"
    towards = np.asarray(SUN_DIRECTION) / np.linalg.norm(SUN_DIRECTION)
    sun.rotation_euler = _z_towards(towards)
    scene.collection.objects.link(sun)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location, camera.rotation_euler = EYE, _euler(look_at(EYE, TARGET))
    camera.data.sensor_fit, camera.data.angle = "AUTO", math.radians(40.0)
    scene.camera = camera
    return scene


def _z_towards(direction):
    """Euler rotation turning the object's +Z (our sun's direction towards the sun) onto `direction`."""
    from mathutils import Vector

    return Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(direction)).to_euler()


def _euler(to_world):
    from mathutils import Matrix

    return Matrix([list(row) for row in to_world]).to_euler()


def emulate(scene, tracer_scene, bands: int, spp: int, shader: str = "SVM"):
    job = EmulationJob(scene, tracer_scene, band_count=bands, shader=shader, spp=spp)
    start = time.perf_counter()
    job.run()
    seconds = time.perf_counter() - start
    if not job.succeeded:
        raise SystemExit(f"emulation failed: {job.error}")
    return job, seconds


def noise(variance: np.ndarray) -> float:
    return float(variance[..., 1].mean())


def main(argv=None) -> int:
    args = parse(argv)
    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory(prefix="spectral_bench_") as folder:
        scene = build_scene(args, Path(folder))
        tracer_scene = export_scene(bpy.context.evaluated_depsgraph_get()).scene
        print(f"scene: cloud {args.resolution}³ (Volume object), λ-dependent albedo, g 0.3, D65 sun; "
              f"{args.width}×{args.height}; emulation {args.bands} bands" +
              (" [QUICK MODE: figures are not representative]" if args.quick else ""))
        kernel_scene = compile_scene(tracer_scene)
        warm_up(kernel_scene)
        traced = render_ours(kernel_scene, args.tracer_spp)
        target = noise(traced.variance)
        print(f"tracer: {args.tracer_spp} spp in {traced.seconds:.2f} s (kernel), luminance noise {target:.3g}")

        (low, high) = args.cycles_spp
        first, seconds_low = emulate(scene, tracer_scene, args.bands, low)
        second, seconds_high = emulate(scene, tracer_scene, args.bands, high)
        renders = first.cycles_renders
        per_spp = (seconds_high - seconds_low) / (high - low)
        overhead = seconds_low - per_spp * low
        constant = noise(second.film.variance) * high  # variance × spp
        needed = constant / target
        at_noise = overhead + per_spp * needed
        print(f"emulation: {renders} Cycles renders × 2 halves; {low} spp in {seconds_low:.2f} s, {high} spp in "
              f"{seconds_high:.2f} s → {overhead:.2f} s preparation + {per_spp:.3f} s per spp; "
              f"luminance noise {noise(second.film.variance):.3g} at {high} spp")
        print(f"at the tracer's noise: tracer {traced.seconds:.2f} s ({args.tracer_spp} spp), emulation "
              f"{at_noise:.2f} s ({needed:.0f} spp) → tracer {at_noise / traced.seconds:.1f}× faster "
              f"({(per_spp * needed) / traced.seconds:.1f}× without Cycles' preparation)")
        white = colorimetry.rgb_to_xyz([1.0, 1.0, 1.0]) * np.percentile(traced.xyz[..., 1], 99)
        delta_e = colorimetry.delta_e_2000(second.film.xyz.mean(axis=(0, 1)), traced.xyz.mean(axis=(0, 1)), white)
        print(f"mean colour, emulation vs tracer: ΔE00 {float(delta_e):.2f}")
        if not args.no_osl:
            osl, seconds_osl = emulate(scene, tracer_scene, args.bands, low, shader="OSL")
            print(f"OSL shader: {low} spp in {seconds_osl:.2f} s vs nodes {seconds_low:.2f} s "
                  f"({seconds_osl / seconds_low:.2f}×)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
