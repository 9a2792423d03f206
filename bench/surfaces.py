"""Cost of surfaces: the benchmark cloud (bench/scenes.py) over a ground of N triangles (a subdivided square
under it, grey, reflectance 0.5), per pixel-sample, beside the same cloud without a ground; and the time to
lower the scene (the hierarchy's build). No assertions: it prints figures.

    python -m bench.surfaces                   # 10 k and 1 M triangles, 128×128, 16 spp, cloud 64³
    python -m bench.surfaces --quick           # 2 k and 20 k triangles, 32×32, 4 spp: proves it runs
"""

import argparse

import numpy as np

from addon.tracer.builders import parallelogram
from addon.tracer.scene import Scene

from bench.measure import compile_timed, machine, render_ours, warm_up
from bench.scenes import CloudSpec, cloud_scene

GROUND_SIZE = 8.0  # world units on a side, centred under the 2-unit cloud
GROUND_HEIGHT = -1.2


def ground_scene(spec: CloudSpec, triangles: int, **settings) -> Scene:
    """The cloud over a square ground of about `triangles` triangles (two per cell)."""
    cells = max(1, int(round(np.sqrt(triangles / 2))))
    half = GROUND_SIZE / 2
    ground = parallelogram((-half, -half, GROUND_HEIGHT), (GROUND_SIZE, 0, 0), (0, GROUND_SIZE, 0), cells,
                           reflectance=0.5, name="ground")
    scene = cloud_scene(spec, **settings)
    return Scene(camera=scene.camera, media=scene.media, lights=scene.lights, surfaces=(ground,),
                 settings=scene.settings)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--triangles", type=int, nargs="+")
    parser.add_argument("--size", type=int)
    parser.add_argument("--spp", type=int)
    args = parser.parse_args(argv)
    counts = args.triangles or ([2_000, 20_000] if args.quick else [10_000, 1_000_000])
    size = args.size or (32 if args.quick else 128)
    spp = args.spp or (4 if args.quick else 16)
    spec = CloudSpec(resolution=64, width=size, height=size)
    print(f"machine: {machine()}")
    print(f"cloud 64³ at {size}×{size}, {spp} spp; ground {GROUND_SIZE:g} units on a side")
    scenes = [("no ground", cloud_scene(spec))] + [(f"{n} triangles", ground_scene(spec, n)) for n in counts]
    for label, scene in scenes:
        kernel_scene, lowering = compile_timed(scene)
        warm_up(kernel_scene)
        image = render_ours(kernel_scene, spp)
        samples = size * size * spp
        triangles = kernel_scene.surfaces.corner.shape[0]
        print(f"{label:>20}: {triangles:>8} triangles, {kernel_scene.surfaces.node_count.shape[0]:>8} nodes, "
              f"lowering {lowering:6.2f} s, {1e6 * image.seconds / samples:7.2f} µs per pixel-sample, "
              f"mean Y {image.xyz[..., 1].mean():.4f}")


if __name__ == "__main__":
    main()
