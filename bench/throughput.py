"""Throughput of the tracer on the procedural cloud: pixel-samples and density look-ups per second, and
peak memory (issue 3, Performance).

For each grid resolution and each Henyey–Greenstein g, the benchmark scene (bench/scenes.py: albedo 0.8,
D65 sun + constant environment, 4 wavelengths per path) is lowered once, then rendered with the real
kernel; only the kernel's time counts. Density look-ups are not counted in the real kernel (that would
slow it): an instrumented copy of the kernel (bench/counting.py) runs the first `--count-spp` samples of
the same paths and counts its calls of `_density` (one trilinear look-up each), shadow rays and
majorant-DDA steps; look-ups per second = (look-ups per pixel-sample, counted) × (pixel-samples per
second, timed).

Memory: peak resident set size (Linux: VmHWM, reset between phases) while generating the grid (the
procedural generator, not the tracer; skipped when the grid comes from the cache) and while lowering and
rendering the scene (the tracer), checked against `--memory-limit-gib` (2 GiB, issue 3).

    python -m bench.throughput            # 64³, 128³, 512³ × g 0, 0.6 at 256×256, 16 spp
    python -m bench.throughput --quick    # 32³, 64³ × g 0, 0.6 at 64×64, 4 spp: proves it runs
"""

import argparse
import time

import numpy as np

from addon.tracer.lowering import compile_scene

from bench import counting
from bench.measure import PeakRSS, compile_timed, fmt_bytes, machine, render_ours, rss, warm_up
from bench.scenes import CACHE, CloudSpec, cloud_density, cloud_scene


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true",
                        help="small everything (32³ and 64³, 64×64, 4 spp, 1 counted spp)")
    parser.add_argument("--resolutions", type=int, nargs="+", help="grid resolutions (default 64 128 512)")
    parser.add_argument("--g", type=float, nargs="+", default=[0.0, 0.6], help="HG anisotropies (default 0 0.6)")
    parser.add_argument("--width", type=int, help="image width (default 256)")
    parser.add_argument("--height", type=int, help="image height (default 256)")
    parser.add_argument("--spp", type=int, help="timed samples per pixel (default 16)")
    parser.add_argument("--count-spp", type=int, help="samples per pixel run through the counting kernel "
                        "(default 4; 0 skips counting)")
    parser.add_argument("--repeats", type=int, help="timed renders of the same samples; the median rate is "
                        "reported with the range (default 3; quick 2)")
    parser.add_argument("--threads", type=int, help="Numba threads (default: all)")
    parser.add_argument("--memory-limit-gib", type=float, default=2.0,
                        help="peak RSS allowed while lowering and rendering (default 2)")
    parser.add_argument("--cache", default=str(CACHE), help=f"folder for generated grids and the counting "
                        f"kernel (default {CACHE.relative_to(CACHE.parents[1])}); 'none' disables the grid cache")
    args = parser.parse_args(argv)
    quick = args.quick
    args.resolutions = args.resolutions or ([32, 64] if quick else [64, 128, 512])
    args.width = args.width or (64 if quick else 256)
    args.height = args.height or (64 if quick else 256)
    args.spp = args.spp or (4 if quick else 16)
    args.repeats = max(1, args.repeats or (2 if quick else 3))
    args.count_spp = min(args.spp, args.count_spp if args.count_spp is not None else (1 if quick else 4))
    return args


def main(argv=None) -> int:
    args = parse(argv)
    if args.threads:
        import numba

        numba.set_num_threads(args.threads)
    cache = None if args.cache == "none" else args.cache
    peak = PeakRSS()
    print(f"machine: {machine()}")
    print(f"scene: procedural cloud (bench/scenes.py), albedo 0.8, D65 sun + environment, "
          f"{args.width}×{args.height}, 4 wavelengths per path, {args.spp} spp timed"
          + (" [QUICK MODE: tiny sizes, figures are not representative]" if args.quick else ""))
    if args.count_spp:
        print(f"density look-ups: COUNTED by an instrumented copy of the kernel (bench/counting.py) on the "
              f"first {args.count_spp} spp of the same paths; look-ups/s = counted look-ups per pixel-sample "
              f"× timed pixel-samples/s of the real kernel. One look-up = one trilinear interpolation "
              f"(8 voxel reads).")
    if not peak.resettable:
        print("memory: VmHWM cannot be reset here; peaks below are of the whole process so far")
    rows, warmed = [], False
    for resolution in args.resolutions:  # phase 1: time and memory, real kernel only
        peak.reset()
        before = rss()
        start = time.perf_counter()
        density, cached = cloud_density(resolution, cache=cache)
        generation = time.perf_counter() - start
        generation_peak = peak.peak() - before
        source = "loaded from cache" if cached else f"generated, peak +{fmt_bytes(generation_peak)} over the process"
        print(f"\n{resolution}³ grid ({fmt_bytes(density.values.nbytes)} float32): {source} in {generation:.1f} s")
        for g in args.g:
            scene = cloud_scene(CloudSpec(resolution=resolution, g=g, width=args.width, height=args.height),
                                density, seed=0)
            baseline = rss()
            peak.reset()
            kernel_scene, compile_seconds = compile_timed(scene)
            if not warmed:
                print(f"  kernel compiled or loaded from Numba's cache, and warmed up, in "
                      f"{warm_up(kernel_scene):.1f} s (not timed)")
                warmed = True
            images = [render_ours(kernel_scene, args.spp, seed=0) for _ in range(args.repeats)]
            seconds = sorted(image.seconds for image in images)
            pixel_samples = args.width * args.height * args.spp
            row = {"resolution": resolution, "g": g, "rate": pixel_samples / float(np.median(seconds)),
                   "range": (pixel_samples / seconds[-1], pixel_samples / seconds[0]), "seconds": float(np.median(seconds)),
                   "compile": compile_seconds, "peak": peak.peak(), "baseline": baseline,
                   "mean_y": float(images[0].y.mean())}
            rows.append(row)
            report(row)
            del kernel_scene, scene
        del density
    if args.count_spp:  # phase 2: counts, after the memory figures (compiling the copy takes memory too)
        count_lookups(rows, args, cache)
    summary(rows, args)
    return 0


def count_lookups(rows: list[dict], args, cache) -> None:
    """Fill in counts per pixel-sample for every row, running the counting copy of the kernel."""
    print(f"\ncounting (instrumented kernel copy, first {args.count_spp} spp of the same paths):")
    start = time.perf_counter()
    folder = cache or CACHE
    density = None
    for row in rows:
        if density is None or density.values.shape[0] != row["resolution"]:
            density, _ = cloud_density(row["resolution"], cache=cache)
        scene = cloud_scene(CloudSpec(resolution=row["resolution"], g=row["g"], width=args.width,
                                      height=args.height), density, seed=0)
        kernel_scene = compile_scene(scene)
        if start is not None:
            tiny = kernel_scene._replace(camera=kernel_scene.camera._replace(width=2, height=2))
            counting.count(tiny, 1, 0, folder)
            print(f"  counting kernel compiled or loaded in {time.perf_counter() - start:.1f} s")
            start = None
        counts = counting.count(kernel_scene, args.count_spp, 0, folder)
        counted_samples = args.width * args.height * args.count_spp
        row.update({name: value / counted_samples for name, value in counts.items()})
        row["lookups_per_second"] = row["density_lookups"] * row["rate"]
        print(f"  {row['resolution']}³ g={row['g']:<4g} {row['density_lookups']:7.1f} density look-ups, "
              f"{row['shadow_rays']:.2f} shadow rays, {row['dda_steps']:.1f} DDA steps per pixel-sample -> "
              f"{row['lookups_per_second'] / 1e6:.2f} M look-ups/s ({1e9 / row['lookups_per_second']:.0f} ns of "
              f"kernel time per look-up, all work included)")
        del kernel_scene, scene


def report(row: dict) -> None:
    low, high = row["range"]
    print(f"  g={row['g']:<4g} {row['rate'] / 1e3:9.1f} k pixel-samples/s (range {low / 1e3:.1f}–{high / 1e3:.1f}; "
          f"median {row['seconds']:.2f} s kernel, lowering "
          f"{row['compile']:.2f} s), mean Y {row['mean_y']:.4f}; peak RSS while lowering + rendering "
          f"{fmt_bytes(row['peak'])} (before: {fmt_bytes(row['baseline'])})")


def summary(rows: list[dict], args) -> None:
    print("\nsummary (ratios are within this run):")
    print(f"{'grid':>6} {'g':>4} {'kpix-samples/s':>15} {'M look-ups/s':>13} {'look-ups/px-sample':>19} "
          f"{'peak RSS':>10} {'vs first row':>13}")
    first = rows[0]["rate"] if rows else 1.0
    for row in rows:
        lookups = f"{row['lookups_per_second'] / 1e6:13.2f} {row['density_lookups']:19.1f}" if "density_lookups" in row \
            else f"{'-':>13} {'-':>19}"
        print(f"{row['resolution']:>5}³ {row['g']:>4g} {row['rate'] / 1e3:15.1f} {lookups} {fmt_bytes(row['peak']):>10} "
              f"{row['rate'] / first:12.2f}×")
    limit = args.memory_limit_gib * 2**30
    largest = max(rows, key=lambda row: (row["resolution"], row["peak"])) if rows else None
    if largest is not None:
        verdict = "within" if largest["peak"] <= limit else "OVER"
        print(f"memory: {largest['resolution']}³ peaks at {fmt_bytes(largest['peak'])} while lowering and rendering: "
              f"{verdict} the {args.memory_limit_gib:g} GiB limit")


if __name__ == "__main__":
    raise SystemExit(main())
