"""The data passes' cost (Depth, Mist, Normal, Cryptomatte Object and Material) beside the image's: a floor and
three boxes' worth of triangles under a sky, rendered at the same size and samples, the passes made by the Numba
first-hit kernel (and, with --quick, by its NumPy oracle). Prints seconds and the passes' share of the render."""

import argparse
import time

import numpy as np

from addon.tracer import builders as b
from addon.tracer.lowering import compile_scene
from addon.tracer.passes import DATA_PASSES, first_hit_ready, render_passes
from addon.tracer.render import render
from addon.tracer.scene import Camera


def scene(width: int, height: int, spp: int):
    camera = np.eye(4)
    camera[2, 3] = 6.0
    surfaces = [b.parallelogram((-10.0, -10.0, 0.0), (20.0, 0.0, 0.0), (0.0, 20.0, 0.0), 8, name="Floor")]
    for i, x in enumerate((-2.0, 0.0, 2.0)):
        surfaces.append(b.parallelogram((x - 0.5, -0.5, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 4, name=f"Box{i}"))
    return b.scene(Camera(to_world=camera, width=width, height=height, fov=np.radians(60.0)),
                   lights=[b.environment()], surfaces=surfaces, spp=spp, passes=DATA_PASSES)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="a small frame")
    args = parser.parse_args(argv)
    width, height, spp = (160, 90, 4) if args.quick else (640, 360, 16)
    data = scene(width, height, spp)
    kernel_scene = compile_scene(data)
    first_hit_ready(kernel_scene)
    render(scene(8, 8, 1))  # the path tracer's kernel loaded
    start = time.perf_counter()
    result = render(data)
    total = time.perf_counter() - start
    print(f"{width}×{height}, {spp} spp: render with passes {total:.2f} s")
    for backend in ("numba", "numpy") if args.quick else ("numba",):  # the oracle is slow: small frames only
        start = time.perf_counter()
        render_passes(data, kernel_scene, spp, 0, backend)
        seconds = time.perf_counter() - start
        rays = width * height * spp
        print(f"  passes ({backend}): {seconds:.3f} s, {rays / seconds / 1e6:.2f} M first hits/s, "
              f"{seconds / total:.1%} of the render")
    print(f"  passes written: {', '.join(result.passes.images)}")


if __name__ == "__main__":
    main()
