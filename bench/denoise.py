"""Denoising (issue 17 item 2): how close a denoised render comes to a converged one, against the noisy
render given the same time, and what the denoiser costs.

For each scene (bench/scenes.py: the procedural cloud with grey or chromatic media, and the dense soft
sphere) a converged reference is rendered once (`--reference-spp`, another seed). Then, for each sample
count N of `--spp`, the scene is rendered at N spp (t_render seconds) and denoised as F12 does
(`addon.tracer.denoise.denoised_rgb`: OIDN "high", guided by the variance from 16 spp on; t_denoise);
the noisy render given the same total time is rendered too (N · (t_render + t_denoise) / t_render spp).
Printed: RMSE of the linear Rec.709 image against the reference for noisy, denoised and equal-time noisy,
and the ratio equal-time RMSE ÷ denoised RMSE (above 1: denoising wins at equal time). Then the
denoiser's own time at 256×160, 512×512 (the viewport's "fast" quality too) and 1920×1080.
Nothing is asserted. RMSE against a reference of finite samples includes the reference's own noise.
With `--png DIR`, each scene's images at the smallest N are written side by side as DIR/<scene>.png:
noisy, denoised, equal-time noisy, reference (Standard view).

    python -m bench.denoise                       # 256×160, N = 4 16 64, reference 1024 spp
    python -m bench.denoise --quick               # 128×80, N = 4 16, reference 256 spp
"""

import argparse
import time
from pathlib import Path

import numpy as np

from addon.tracer import image_io
from addon.tracer.denoise import denoise, denoised_rgb
from addon.tracer.render import render
from bench.measure import machine
from bench.scenes import CHROMATIC, SPHERE_DENSITY_SCALE, CloudSpec, cloud_scene

SCENES = {
    "cloud": CloudSpec(),
    "chromatic cloud": CloudSpec(**CHROMATIC),
    "dense sphere": CloudSpec(grid="sphere", density_scale=SPHERE_DENSITY_SCALE, g=0.6),
}
DENOISER_SIZES = ((256, 160), (512, 512), (1920, 1080))


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="128×80, N = 4 16, reference 256 spp")
    parser.add_argument("--scenes", nargs="+", choices=sorted(SCENES), default=sorted(SCENES))
    parser.add_argument("--width", type=int, default=256)
    parser.add_argument("--height", type=int, default=160)
    parser.add_argument("--spp", type=int, nargs="+", default=[4, 16, 64])
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--png", type=Path, help="folder for side-by-side images (noisy, denoised, equal time, "
                        "reference) at the smallest N")
    args = parser.parse_args(argv)
    if args.quick:
        args.width, args.height, args.spp, args.reference_spp = 128, 80, [4, 16], 256
    return args


def rmse(image, reference) -> float:
    return float(np.sqrt(np.mean((image - reference) ** 2)))


def timed(function, *args, **kwargs):
    start = time.perf_counter()
    value = function(*args, **kwargs)
    return value, time.perf_counter() - start


def compare(name: str, spec: CloudSpec, args) -> None:
    scene = cloud_scene(spec.with_(width=args.width, height=args.height))
    render(scene, spp=1)  # compile or load the kernel, untimed
    reference = render(scene, spp=args.reference_spp, seed=1_000_003).film.rgb()
    for spp in args.spp:
        film, render_seconds = timed(lambda: render(scene, spp=spp).film)
        denoised, denoise_seconds = timed(denoised_rgb, film)
        equal_spp = max(spp, round(spp * (render_seconds + denoise_seconds) / render_seconds))
        equal, equal_seconds = timed(lambda: render(scene, spp=equal_spp, seed=7).film.rgb())
        noisy_error, denoised_error, equal_error = (rmse(image, reference) for image in (film.rgb(), denoised, equal))
        print(f"{name:16} {spp:5d} {render_seconds:8.2f} {denoise_seconds:8.3f} {noisy_error:10.5f} "
              f"{denoised_error:10.5f} {equal_spp:5d} ({equal_seconds:6.2f} s) {equal_error:10.5f} "
              f"{equal_error / denoised_error:8.2f}×", flush=True)
        if args.png is not None and spp == min(args.spp):
            strip = np.concatenate([film.rgb(), denoised, equal, reference], axis=1)
            image_io.write_png(args.png / f"{name.replace(' ', '_')}.png", strip)


def denoiser_times() -> None:
    rng = np.random.default_rng(0)
    for width, height in DENOISER_SIZES:
        image = np.abs(0.5 + 0.2 * rng.standard_normal((height, width, 3))).astype(np.float32)
        qualities = ("high", "fast") if (width, height) == (512, 512) else ("high",)
        for quality in qualities:
            denoise(image[:16, :16], quality=quality)  # load the library and the filter, untimed
            seconds = min(timed(denoise, image, quality=quality)[1] for _ in range(3))
            print(f"denoiser {width}×{height} {quality:5}: {seconds:.3f} s (best of 3)", flush=True)


def main(argv=None) -> None:
    args = parse(argv)
    print(machine())
    print(f"{args.width}×{args.height}, reference {args.reference_spp} spp; RMSE of linear Rec.709 against it")
    print(f"{'scene':16} {'N':>5} {'render s':>8} {'denoise s':>8} {'noisy':>10} {'denoised':>10} "
          f"{'equal-time noisy (spp, s)':>26} {'equal/denoised':>14}")
    for name in args.scenes:
        compare(name, SCENES[name], args)
    denoiser_times()


if __name__ == "__main__":
    main()
