"""Noise of a medium lit by a large area light close to it: a 2-unit box of grey smoke (optical depth 4 across,
albedo 0.9, g 0.3) under a 3 × 3 square or a disk of diameter 3, 0.1 above its top and facing it, the camera
above looking down through the light's back. Prints the image's mean luminance Y with its standard error and
the noise per sample (the median over the lit pixels of the per-sample standard deviation of Y over Y), to
compare next-event estimation alone with its MIS against phase sampling; and the same for a small lamp far
above dense smoke (`far_lamp_scene`), where MIS gains little. No assertions: it prints figures.

    python -m bench.area_lights              # 32×32, 256 spp
    python -m bench.area_lights --quick      # 16×16, 16 spp: proves it runs
"""

import argparse
import dataclasses

import numpy as np

from addon.tracer import spectra
from addon.tracer.builders import box_grid, medium, scene
from addon.tracer.render import render
from addon.tracer.scene import Camera, Light

from bench.measure import machine

SHAPES = ("rectangle", "ellipse")


def lamp_scene(shape: str, size: int = 32, spp: int = 256, seed: int = 1):
    """The smoke under the lamp of `shape` (3 units across, of luminous power 100), seen from 6 units above at
    30°."""
    to_world = np.eye(4)
    to_world[2, 3] = 6.0
    camera = Camera(to_world=to_world, width=size, height=size, fov=np.radians(30.0))
    smoke = medium(box_grid(), extinction=2.0, albedo=0.9, g=0.3)
    lamp = Light(kind="area", spectrum=spectra.constant(1.0), strength=100.0, unit="luminous",
                 position=np.array([0.0, 0.0, 1.1]), area_axes=np.eye(3), area_shape=shape, size_x=3.0, size_y=3.0)
    return scene(camera, [smoke], [lamp], spp=spp, seed=seed)


def far_lamp_scene(shape: str, size: int = 32, spp: int = 256, seed: int = 1):
    """The lamp of `shape` 0.5 across, 3 units above smoke 4× as dense (optical depth 16 across)."""
    close = lamp_scene(shape, size, spp, seed)
    lamp = dataclasses.replace(close.lights[0], size_x=0.5, size_y=0.5, position=np.array([0.0, 0.0, 4.0]))
    smoke = medium(box_grid(), extinction=8.0, albedo=0.9, g=0.3)
    return dataclasses.replace(close, media=(smoke,), lights=(lamp,))


def luminance_figures(film) -> tuple[float, float, float]:
    """(mean Y of the image, its standard error, the median noise per sample of the lit pixels' Y)."""
    y, variance = film.xyz[..., 1], film.variance[..., 1]
    samples = film.pixel_samples.max()
    lit = y > 0.1 * y.max()
    noise = np.median(np.sqrt(variance[lit] * samples) / y[lit])
    return float(y.mean()), float(np.sqrt(variance.sum()) / y.size), float(noise)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    size, spp = (16, 16) if args.quick else (32, 256)
    print(f"machine: {machine()}")
    print(f"{size}×{size}, {spp} spp")
    for label, build in (("close lamp", lamp_scene), ("far lamp, dense", far_lamp_scene)):
        for shape in SHAPES:
            mean, error, noise = luminance_figures(render(build(shape, size, spp)).film)
            print(f"{label:>16}, {shape:>9}: mean Y {mean:.5f} ± {error:.5f}, noise per sample {noise:.3f}")


if __name__ == "__main__":
    main()
