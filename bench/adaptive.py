"""Adaptive sampling (issue 31 item 4): the time to reach a noise threshold against fixed samples per pixel.

For each scene (bench/scenes.py: the procedural cloud under a sun and a sky, and the dense soft sphere), a
converged reference is rendered once (`--reference-spp`, another seed). Then for each Noise Threshold of
`--thresholds` the scene is rendered adaptively with at most `--max-spp` samples (t_adaptive), and with
fixed samples per pixel given the same time (the spp that the fixed render's measured throughput affords in
t_adaptive). Printed: the adaptive render's mean and least samples per pixel, the share of pixels that
stopped early, its time, and for both renders two errors against the reference: the 95th percentile over
pixels of the threshold's own measure (Σ|RGB − reference| / √Σ reference, what the threshold bounds) and the
RMSE of linear Rec.709 (ratios above 1: adaptive sampling wins at equal time). Errors against a reference of
finite samples include the reference's own noise. Nothing is asserted.

    python -m bench.adaptive                  # 192×120, thresholds 0.05 0.02 0.01, reference 1024 spp
    python -m bench.adaptive --quick          # 96×60, thresholds 0.05 0.02, reference 256 spp
"""

import argparse
import dataclasses

import numpy as np

from addon.tracer.adaptive import ERROR_FLOOR
from addon.tracer.render import render
from bench.denoise import rmse, timed
from bench.measure import machine
from bench.scenes import SPHERE_DENSITY_SCALE, CloudSpec, cloud_scene

SCENES = {
    "cloud": CloudSpec(),
    "dense sphere": CloudSpec(grid="sphere", density_scale=SPHERE_DENSITY_SCALE, g=0.6),
}


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="96×60, thresholds 0.05 0.02, reference 256 spp")
    parser.add_argument("--scenes", nargs="+", choices=sorted(SCENES), default=sorted(SCENES))
    parser.add_argument("--width", type=int, default=192)
    parser.add_argument("--height", type=int, default=120)
    parser.add_argument("--thresholds", type=float, nargs="+", default=[0.05, 0.02, 0.01])
    parser.add_argument("--max-spp", type=int, default=512)
    parser.add_argument("--reference-spp", type=int, default=1024)
    args = parser.parse_args(argv)
    if args.quick:
        args.width, args.height, args.thresholds, args.reference_spp = 96, 60, [0.05, 0.02], 256
        args.max_spp = 256
    return args


def p95_error(image, reference) -> float:
    """The 95th percentile over pixels of Σ|image − reference| / √Σ reference (adaptive sampling's measure)."""
    error = np.abs(image - reference).sum(axis=-1) / (ERROR_FLOOR + np.sqrt(np.maximum(reference.sum(axis=-1), 0)))
    return float(np.percentile(error, 95))


def compare(name: str, spec: CloudSpec, args) -> None:
    scene = cloud_scene(spec.with_(width=args.width, height=args.height))
    render(scene, spp=1)  # compile or load the kernel, untimed
    reference = render(scene, spp=args.reference_spp, seed=1_000_003).film.rgb()
    fixed_spp = 16
    fixed_seconds = timed(lambda: render(scene, spp=fixed_spp, seed=5))[1]
    for threshold in args.thresholds:
        adaptive_scene = dataclasses.replace(scene, settings=dataclasses.replace(
            scene.settings, spp=args.max_spp, noise_threshold=threshold))
        result, seconds = timed(lambda: render(adaptive_scene))
        samples = result.film.pixel_samples.sum(axis=0)
        early = float(np.mean(samples < args.max_spp))
        equal_spp = max(1, round(fixed_spp * seconds / fixed_seconds))
        equal = render(scene, spp=equal_spp, seed=7).film.rgb()
        image = result.film.rgb()
        adaptive_p95, equal_p95 = p95_error(image, reference), p95_error(equal, reference)
        adaptive_rmse, equal_rmse = rmse(image, reference), rmse(equal, reference)
        print(f"{name:13} {threshold:9.3f} {samples.mean():8.1f} {samples.min():5d} {early:7.0%} {seconds:8.2f} "
              f"{equal_spp:9d} {adaptive_p95:8.4f} {equal_p95:8.4f} {equal_p95 / adaptive_p95:6.2f}× "
              f"{adaptive_rmse:9.5f} {equal_rmse:9.5f} {equal_rmse / adaptive_rmse:6.2f}×", flush=True)


def main(argv=None) -> None:
    args = parse(argv)
    print(machine())
    print(f"{args.width}×{args.height}, at most {args.max_spp} spp, reference {args.reference_spp} spp; RMSE of "
          "linear Rec.709 against it")
    print(f"{'scene':13} {'threshold':>9} {'mean spp':>8} {'least':>5} {'stopped':>7} {'seconds':>8} "
          f"{'fixed spp':>9} {'p95 adap':>8} {'p95 fixed':>8} {'ratio':>7} {'RMSE adap':>9} {'RMSE fixed':>9} "
          f"{'ratio':>7}")
    for name in args.scenes:
        compare(name, SCENES[name], args)


if __name__ == "__main__":
    main()
