"""The main job (`make demo`): renders every demo scene headless and prints what each one shows.

For now the demos are built directly as tracer scenes; the .blend demos rendered through the add-on
(issue 6) replace them as they land. Each demo writes `<name>.exr` (XYZ, RGB, variance) and
`<name>.png` (Standard view) into the output folder.
"""

import argparse
import time
from pathlib import Path

import numpy as np

from addon.tracer import colorimetry, image_io, spectra
from addon.tracer.procedural import cloud_grid
from addon.tracer.render import render
from addon.tracer.scene import Camera, Light, Medium, RenderSettings, Scene
from addon.tracer.wavelengths import GRID


def _look_at(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Blender camera matrix (looks along local −z, +y up) at `eye` looking at `target`."""
    eye, target, up = (np.asarray(v, dtype=np.float64) for v in (eye, target, up))
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = right, np.cross(back, right), back, eye
    return matrix


def sky_cloud(width: int, height: int, spp: int) -> Scene:
    """A procedural cumulus under a D65 sun and a blue-to-white sky: a first look at the tracer."""
    density = cloud_grid(resolution=64, size=2.0, seed=7)
    medium = Medium(name="cloud", density=density, density_scale=12.0, extinction=spectra.constant(1.0),
                    albedo_densities=np.array([0.0]), albedo_table=spectra.constant(0.95).values[None, :],
                    anisotropy=spectra.constant(0.6))
    sun = Light(kind="sun", spectrum=spectra.illuminant("D65"), strength=2.0,
                direction=np.array([0.5, -0.4, 0.75]) / np.linalg.norm([0.5, -0.4, 0.75]), angle=np.radians(0.5))
    daylight = spectra.illuminant("D65")
    rayleigh_blue = spectra.Spectrum(daylight.values * (550.0 / np.maximum(GRID, 300.0)) ** 4)
    sky = Light(kind="sky", spectrum=rayleigh_blue, strength=0.35, horizon_spectrum=daylight)
    camera = Camera(to_world=_look_at((0.0, -4.5, 0.6), (0.0, 0.0, 0.0)), width=width, height=height,
                    fov=np.radians(40.0))
    return Scene(camera=camera, media=(medium,), lights=(sun, sky), settings=RenderSettings(spp=spp, seed=1))


DEMOS = {"sky_cloud": sky_cloud}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default: out/)")
    parser.add_argument("--scale", type=float, default=1.0, help="resolution scale (1.0: 320×240)")
    parser.add_argument("--spp", type=int, default=64, help="samples per pixel")
    args = parser.parse_args(argv)
    width, height = max(8, int(320 * args.scale)), max(6, int(240 * args.scale))
    total = time.perf_counter()
    for name, build in DEMOS.items():
        result = render(build(width, height, args.spp))
        film = result.film
        image_io.write_exr(args.out / f"{name}.exr", film.xyz, film.rgb(), film.variance)
        image_io.write_png(args.out / f"{name}.png", film.rgb())
        x, y = colorimetry.xyz_to_xy(film.xyz.reshape(-1, 3).mean(axis=0))
        print(f"{name}: {width}×{height}, {args.spp} spp in {result.seconds:.1f} s "
              f"({result.stats['pixel_samples_per_second']:.0f} pixel-samples/s); mean chromaticity "
              f"x={x:.3f} y={y:.3f}; wrote {args.out / name}.exr and .png")
    print(f"all demos rendered in {time.perf_counter() - total:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
