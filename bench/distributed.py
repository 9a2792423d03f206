"""Benchmark of distributed rendering: speed-up of local Dask worker processes, and Dask's cost per task.

    .venv/bin/python bench/distributed.py            # a cloud that takes about 30 s on one core
    .venv/bin/python bench/distributed.py --quick    # the same in a few seconds (checks that it runs)

Every render uses one kernel thread per process, so the comparison is between processes:
- alone:     `render.render` in this process (whole-image passes), the reference image;
- in-process: the distributed task list (same tiles and passes) run one after another here with
             `render.render_unit` and merged by `PassMerger`, without Dask: the cost of tiling alone;
- 1 worker / N workers: `farm.RenderFarm` on a local cluster of 1 and N worker processes.
Speed-up = time(1 worker) / time(N workers) (target ≥ 1.8 for 2 workers on 2 idle cores);
overhead per task = (time(1 worker) − its set-up − time(in-process)) / tasks. Every image is checked to be
bit-identical with `alone`. Figures are printed, never asserted: run it on a quiet machine.
"""

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

# Run as a script, this folder would come first on sys.path and this file would shadow Dask's
# `distributed` package: put the repository root in its place.
sys.path[0] = str(Path(__file__).resolve().parents[1])

from addon.tracer import spectra  # noqa: E402
from addon.tracer import render as single  # noqa: E402
from addon.tracer.film import Film  # noqa: E402
from addon.tracer.procedural import cloud_grid  # noqa: E402
from addon.tracer.builders import environment, medium, scene, sun  # noqa: E402
from addon.tracer.farm import RenderFarm  # noqa: E402
from addon.tracer.farm_plan import PassMerger, plan  # noqa: E402
from addon.tracer.scene import Camera, Scene  # noqa: E402

FULL = {"width": 120, "height": 90, "spp": 128, "tile_size": 32}  # about 30 s on one core
QUICK = {"width": 32, "height": 24, "spp": 24, "tile_size": 8}


def cloud_scene(width: int, height: int, spp: int, bands: int = 1) -> Scene:
    """A procedural cumulus under a D65 sun and a uniform sky, seen from the side."""
    cloud = medium(cloud_grid(resolution=48, size=2.0, seed=7), 12.0, name="cloud", albedo=0.95, g=0.6)
    d65 = spectra.illuminant("D65")
    lights = (sun((0.5, -0.4, 0.75), 2.0, angle=np.radians(0.5), spectrum=d65), environment(0.3, d65))
    to_world = np.array([[1.0, 0, 0, 0], [0, 0, -1, -4.5], [0, 1, 0, 0], [0, 0, 0, 1]])  # at −y, looking +y
    camera = Camera(to_world=to_world, width=width, height=height, fov=np.radians(40.0))
    return scene(camera, (cloud,), lights, spp=spp, seed=1, bands=bands)


def timed(function):
    start = time.perf_counter()
    value = function()
    return time.perf_counter() - start, value


def in_process(scene: Scene, tile_size: int) -> Film:
    """The distributed task list, run here one task after another (no Dask)."""
    bands = single.band_scenes(scene)
    camera, settings = scene.camera, scene.settings
    film = Film(camera.width, camera.height, len(bands))
    sizes, tiles, units = plan(camera.width, camera.height, len(bands), settings.spp, tile_size)
    merger = PassMerger(film, sizes, tiles)
    for unit in units:
        merger.add(unit, *single.render_unit(bands[unit.band], unit.band, unit.samples, unit.tile,
                                             settings.seed, settings.backend)[:3])
    return film


def on_farm(scene: Scene, workers: int, tile_size: int):
    """(seconds of the render, film, tasks) on a fresh local cluster, after a warm-up render that
    makes every worker load the Numba kernels and receive a scene (not timed)."""
    with RenderFarm(workers=workers) as farm:
        farm.render(scene, spp=1, threads=1, tile_size=max(1, min(scene.camera.width, scene.camera.height) // 2))
        seconds, result = timed(lambda: farm.render(scene, threads=1, tile_size=tile_size))
        return seconds, result.film, result.stats


def same(a: Film, b: Film) -> str:
    identical = (np.array_equal(a.samples, b.samples) and np.array_equal(a.sum_xyz, b.sum_xyz)
                 and np.array_equal(a.sum_sq, b.sum_sq))
    return "bit-identical" if identical else "DIFFERENT (bug!)"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=f"a small scene ({QUICK}) to check the script runs")
    parser.add_argument("--workers", type=int, default=2, help="worker processes to compare with 1 (default 2)")
    parser.add_argument("--tile-size", type=int, help="tile edge of a task in pixels (default 32; quick: 8)")
    parser.add_argument("--width", type=int)
    parser.add_argument("--height", type=int)
    parser.add_argument("--spp", type=int)
    parser.add_argument("--bands", type=int, default=1)
    args = parser.parse_args(argv)
    size = dict(QUICK if args.quick else FULL)
    size.update({key: getattr(args, key) for key in size if getattr(args, key) is not None})
    tile_size = size.pop("tile_size")
    scene = cloud_scene(**size, bands=args.bands)

    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    load = ", ".join(f"{value:.2f}" for value in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    print(f"scene: cloud {size['width']}×{size['height']}, {size['spp']} spp, {args.bands} band(s); "
          f"tile {tile_size}; {cores} cores, load average {load}")

    warm = cloud_scene(8, 6, 1)
    seconds, _ = timed(lambda: single.render(warm, threads=1))
    print(f"Numba kernels ready in {seconds:.1f} s (compiled, or loaded from the cache)")

    alone_s, alone = timed(lambda: single.render(scene, threads=1).film)
    print(f"alone       (render.render, 1 thread):        {alone_s:7.2f} s")
    inline_s, inline = timed(lambda: in_process(scene, tile_size))
    print(f"in-process  (same tasks, no Dask, 1 thread):  {inline_s:7.2f} s   {same(alone, inline)}")
    one_s, one, stats = on_farm(scene, 1, tile_size)
    tasks, setup_s = stats["tasks"], stats["setup_seconds"]
    print(f"1 worker    (Dask, 1 process × 1 thread):     {one_s:7.2f} s   {same(alone, one)}; {tasks} tasks, "
          f"{setup_s:.2f} s of it before the first task (worker check, scene sent)")
    many_s, many, _ = on_farm(scene, args.workers, tile_size)
    print(f"{args.workers} workers   (Dask, {args.workers} processes × 1 thread):    {many_s:7.2f} s   "
          f"{same(alone, many)}")

    print(f"speed-up of {args.workers} workers over 1:  {one_s / many_s:5.2f}×  (target ≥ {0.9 * args.workers:.1f}× "
          f"on {args.workers} idle cores; efficiency {one_s / many_s / args.workers:.0%})")
    print(f"speed-up over alone:        {alone_s / many_s:5.2f}×")
    print(f"overhead per task:          {(one_s - setup_s - inline_s) / tasks * 1e3:6.1f} ms  "
          f"(1 worker − its set-up − in-process, over {tasks} tasks; mean task {inline_s / tasks * 1e3:.1f} ms "
          f"of rendering)")
    print(f"tiling cost:                {(inline_s - alone_s) / alone_s:+.1%}  (in-process − alone)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
