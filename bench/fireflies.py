"""Where the speckles of a sunlit Cloud come from at 16 spp (issue 31 item 4): per-pixel errors against a
long reference, and the path events behind the outliers.

The scene is the benchmark cloud (bench/scenes.py) with the optics of the built-in *Cloud* material preset
(addon/presets/spectral_volume/material/Cloud.py: density scale 20, albedo 0.99, HG g 0.8, grey) under the
D65 sun and a faint sky (`--sky`, radiance Y; the benchmark's sky is 0.5).

1. Numba: a reference of `--reference-spp` (seed 1 000 003) and `--seeds` images of 16 spp. The error
   measure is z = |Y₁₆ − Y_ref| / σ₁₆ per pixel, σ₁₆ = the reference's own per-sample standard deviation of
   Y (from its squared sums) over √16: the error in units of the noise a 16-spp pixel is expected to have.
   Printed: p50/p90/p99/max of z and the share of pixels above 3, 5 and 10, pooled over the seeds; then the
   same with the paths capped at `--depths` scattering events (same seeds, each cap against its own capped
   reference, so the figures compare noise, not the cap's bias).
2. The NumPy backend (the oracle: the same paths as Numba for the same seed) traces one 16-spp image with
   its functions wrapped here, not in the tracer, to record every contribution a path makes: next-event
   estimation towards the sun or the sky, or the sky reached by a phase-sampled (or camera) ray; with the
   path's depth, the largest β / mean r_u, the phase value at the event ÷ the isotropic 1/4π, and the
   shadow ray's transmittance estimate. Printed: how much of the image's variance each kind and depth band
   carries, what the largest contributions are made of, for the outlier pixels (z above `--k`) which
   single event makes their excess, and what clamping the contributions from depth 2 on (biased, as
   Cycles' Clamp Indirect; computed from the records, not in the tracer) would cost and gain.

3. Light Paths ▸ Clamping in the tracer (`kernels/light_split.py`): the relative RMSE of Y at 16 spp (`--seeds`
   images) against the `--reference-spp` reference, clamping off and at Blender's defaults (Direct 0, Indirect 10),
   and a tighter Indirect 1; each clamped image against the unclamped reference (error with the bias) and against
   its own clamped reference (noise alone), with the z figures of part 1 and the mean Y the clamp takes away.
   `--clamping` runs this part alone.

4. The firefly filter (`addon/tracer/fireflies.py`, docs/algorithm.md): the z figures of part 1 at 16 spp over
   `--seeds` images for firefly_threshold off, 1, 2 and 3, with the mean Y it takes at 16, 64 and 256 spp (one
   image each, against the unfiltered image of the same seed), and the render time with and without it (its
   passes run a group of samples at a time) at this size and at 4× the width and height. `--filter` runs this
   part alone.

Nothing is asserted. python -m bench.fireflies [--quick] [--clamping] [--filter]
"""

import dataclasses

import argparse
import time

import numpy as np

from addon.tracer.kernels import numpy_backend as nb
from addon.tracer.phase import INV_FOUR_PI
from addon.tracer.render import render
from bench.measure import machine
from bench.scenes import CloudSpec, cloud_scene

REFERENCE_SEED = 1_000_003
KINDS = ("sun NEE", "sky NEE", "sky by phase", "sky by camera")


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="reference 256 spp, 2 seeds, depths 8 only")
    parser.add_argument("--width", type=int, default=96)
    parser.add_argument("--height", type=int, default=60)
    parser.add_argument("--sky", type=float, default=0.05, help="sky radiance Y (sun irradiance Y 3)")
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--depths", type=int, nargs="*", default=[4, 8, 16])
    parser.add_argument("--k", type=float, default=5.0, help="z above which a pixel counts as an outlier")
    parser.add_argument("--max-depth", type=int, default=64)
    parser.add_argument("--clamping", action="store_true", help="part 3 only")
    parser.add_argument("--filter", action="store_true", help="part 4 only")
    args = parser.parse_args(argv)
    if args.quick:
        args.reference_spp, args.seeds, args.depths = 256, 2, [8]
    return args


def cloud_preset_scene(args, max_depth):
    spec = CloudSpec(density_scale=20.0, albedo=0.99, g=0.8, width=args.width, height=args.height,
                     environment_strength=args.sky)
    return cloud_scene(spec, max_depth=max_depth)


def luminance_and_sigma(film):
    """Y per pixel and the per-sample standard deviation of Y."""
    samples = film.pixel_samples.sum(axis=0) / film.bands
    return film.xyz[..., 1], np.sqrt(film.variance[..., 1] * samples)


def z_scores(scene, args, spp=16):
    """z of `args.seeds` images of `spp` (seeds 1, 2, …) against the scene's reference, the reference's Y and σ16."""
    reference, sigma = luminance_and_sigma(render(scene, spp=args.reference_spp, seed=REFERENCE_SEED).film)
    sigma_16 = np.maximum(sigma / np.sqrt(spp), 1e-12)
    zs = [np.abs(render(scene, spp=spp, seed=seed).film.xyz[..., 1] - reference) / sigma_16
          for seed in range(1, args.seeds + 1)]
    return np.stack(zs), reference, sigma_16


def describe(z) -> str:
    p50, p90, p99 = np.percentile(z, [50, 90, 99])
    shares = " ".join(f"{np.mean(z > k):7.2%}" for k in (3, 5, 10))
    return f"{p50:6.2f} {p90:6.2f} {p99:6.2f} {z.max():8.1f}  {shares}"


def part_numba(args):
    print(f"\n1. z = |Y16 − Yref| / σ16 over {args.width}×{args.height} pixels × {args.seeds} seeds, reference "
          f"{args.reference_spp} spp (its noise is 1/{np.sqrt(args.reference_spp / 16):.0f} of σ16)")
    print(f"{'paths':18} {'p50':>6} {'p90':>6} {'p99':>6} {'max':>8}  {'>3':>7} {'>5':>7} {'>10':>7}  "
          f"{'mean Y':>8} {'s/16spp':>7}")
    found = None
    for depth in [args.max_depth] + list(args.depths):
        scene = cloud_preset_scene(args, depth)
        start = time.perf_counter()
        render(scene, spp=16, seed=99)
        seconds = time.perf_counter() - start
        z, reference, sigma_16 = z_scores(scene, args)
        label = f"max_depth {depth}"
        print(f"{label:18} {describe(z)}  {reference.mean():8.5f} {seconds:7.2f}", flush=True)
        if found is None:
            found = z[0], reference, sigma_16
            worst = np.unravel_index(np.argmax(z), z.shape)
            image = render(scene, spp=16, seed=worst[0] + 1).film.xyz[..., 1]
            print(f"{'':18} worst pixel (seed {worst[0] + 1}, row {worst[1]}, column {worst[2]}): Y16 "
                  f"{image[worst[1:]]:.4f}, Yref {reference[worst[1:]]:.4f}, σ16 {sigma_16[worst[1:]]:.4f}")
    return found


# ----------------------------------------------------------------------------- the NumPy oracle, recorded

class Recorder:
    """Wraps numpy_backend's functions (restored by `close`) to record every contribution of every path."""

    NAMES = ("_trace", "_next_event", "_escape", "_sample_lights", "_mixture_phase", "_transmittance")

    def __init__(self):
        self.saved = {name: getattr(nb, name) for name in self.NAMES}
        self.events = {key: [] for key in ("path", "kind", "depth", "beta", "phase", "transmittance", "value")}
        self.path_pixel, self.path_y = [], []
        self.offset = 0
        self.capture = None
        for name in self.NAMES:
            setattr(nb, name, getattr(self, name))

    def close(self):
        for name, function in self.saved.items():
            setattr(nb, name, function)

    def _trace(self, ks, px, py, pixel_keys, samples, light_passes=False):
        traced = self.saved["_trace"](ks, px, py, pixel_keys, samples, light_passes)
        xyz = traced[0]
        self.path_pixel.append(np.stack(np.broadcast_arrays(py, px), axis=1))
        self.path_y.append(xyz[:, 1])
        self.offset += xyz.shape[0]
        return traced

    def _sample_lights(self, ks, lights, points, u1, u2, lams):
        out = self.saved["_sample_lights"](ks, lights, points, u1, u2, lams)
        if self.capture is not None:
            self.capture["light"] = lights.copy()
        return out

    def _mixture_phase(self, ks, medium_s, lams, cos_theta):
        values = self.saved["_mixture_phase"](ks, medium_s, lams, cos_theta)
        if self.capture is not None and "phase" not in self.capture:
            self.capture["phase"] = values[:, 0].copy()
        return values

    def _transmittance(self, ks, paths, rows, origins, directions, t_max, lams, residual):
        transmittance, survival = self.saved["_transmittance"](ks, paths, rows, origins, directions, t_max, lams,
                                                               residual)
        if self.capture is not None:
            self.capture["rows"], self.capture["transmittance"] = rows.copy(), transmittance.max(axis=1)
        return transmittance, survival

    def _record(self, paths, before, radiance, kind, phase=None, transmittance=None):
        value = radiance[paths.id].sum(axis=1) - before
        hit = np.flatnonzero(value != 0.0)
        if not hit.size:
            return
        largest = np.max(paths.beta / nb._mean(paths.r_u)[:, None], axis=1)
        e = self.events
        e["path"].append(self.offset + paths.id[hit])
        e["kind"].append(kind[hit] if np.ndim(kind) else np.full(hit.size, kind))
        e["depth"].append(paths.depth[hit].copy())
        e["beta"].append(largest[hit])
        e["phase"].append(np.full(hit.size, np.nan) if phase is None else phase[hit] / INV_FOUR_PI)
        e["transmittance"].append(np.full(hit.size, np.nan) if transmittance is None else transmittance[hit])
        e["value"].append(value[hit])

    def _next_event(self, ks, paths, vertex, isotropic, radiance, probing=False, held=None):
        before = radiance[paths.id].sum(axis=1)
        self.capture = {}
        try:
            self.saved["_next_event"](ks, paths, vertex, isotropic, radiance, probing, held)
            capture = self.capture
        finally:
            self.capture = None
        if "light" not in capture:
            return
        delta = np.array([nb.is_delta(ks, light) for light in range(ks.lights.kind.shape[0])])
        kind = np.where(delta[capture["light"]], 0, 1)
        transmittance = np.full(len(paths), np.nan)
        if "rows" in capture:
            transmittance[capture["rows"]] = capture["transmittance"]
        self._record(paths, before, radiance, kind, capture.get("phase"), transmittance)

    def _escape(self, ks, paths, radiance, survival):
        before = radiance[paths.id].sum(axis=1)
        self.saved["_escape"](ks, paths, radiance, survival)
        self._record(paths, before, radiance, np.where(paths.scattered, 2, 3))

    def table(self):
        e = {key: np.concatenate(value) for key, value in self.events.items()}
        path_y = np.concatenate(self.path_y)
        totals = np.bincount(e["path"], weights=e["value"], minlength=path_y.size)
        # each event's share of its path's Y (grey medium: the share of its radiance summed over wavelengths)
        e["y"] = np.where(totals[e["path"]] != 0, e["value"] / totals[e["path"]], 0.0) * path_y[e["path"]]
        return e, path_y


def part_oracle(args, found):
    z_numba, reference, sigma_16 = found
    scene = cloud_preset_scene(args, args.max_depth)
    recorder = Recorder()
    try:
        start = time.perf_counter()
        film = render(scene, spp=16, seed=1, backend="numpy").film
        seconds = time.perf_counter() - start
    finally:
        recorder.close()
    e, path_y = recorder.table()
    image = film.xyz[..., 1]
    z = np.abs(image - reference) / sigma_16
    print(f"\n2. NumPy oracle, seed 1, 16 spp ({seconds:.0f} s): {e['y'].size} contributions of {path_y.size} "
          f"paths; its z: {describe(z)}; pixels whose z differs from Numba's by > 0.1: "
          f"{np.mean(np.abs(z - z_numba) > 0.1):.2%}")
    mean_y = path_y.mean()
    second = np.mean(path_y ** 2)
    print(f"   a path's Y: mean {mean_y:.4f}, E[Y²] {second:.4f}, largest {path_y.max():.2f} "
          f"({path_y.max() / mean_y:.0f}× the mean); share of E[Y²] from the largest 0.1 % of paths "
          f"{np.sort(path_y ** 2)[-max(1, path_y.size // 1000):].sum() / (second * path_y.size):.1%}")
    # variance by kind and depth band: Σ over events of y² (cross terms ignored) as a share
    y2 = e["y"] ** 2
    print(f"\n   {'kind':14} {'share of Y':>10} {'share of Σy²':>12} {'largest y':>10} {'p99.9 y':>8}")
    for k, name in enumerate(KINDS):
        mine = e["kind"] == k
        if mine.any():
            print(f"   {name:14} {e['y'][mine].sum() / e['y'].sum():10.1%} {y2[mine].sum() / y2.sum():12.1%} "
                  f"{e['y'][mine].max():10.2f} {np.percentile(e['y'][mine], 99.9):8.3f}")
    bands = [(0, 0), (1, 1), (2, 2), (3, 4), (5, 8), (9, 16), (17, 32), (33, 64)]
    print(f"\n   {'depth':8} {'share of Y':>10} {'share of Σy²':>12} {'largest y':>10} {'mean β':>7} {'max β':>7}")
    for lo, hi in bands:
        mine = (e["depth"] >= lo) & (e["depth"] <= hi)
        if mine.any():
            print(f"   {f'{lo}–{hi}':8} {e['y'][mine].sum() / e['y'].sum():10.1%} {y2[mine].sum() / y2.sum():12.1%} "
                  f"{e['y'][mine].max():10.2f} {e['beta'][mine].mean():7.3f} {e['beta'][mine].max():7.3f}")
    sun = e["kind"] == 0
    top = sun & (e["y"] >= np.percentile(e["y"][sun], 99.9))
    print(f"\n   sun NEE: phase ÷ 1/4π mean {np.nanmean(e['phase'][sun]):.2f}, max {np.nanmax(e['phase'][sun]):.1f} "
          f"(HG g 0.8 peaks at 45.6); transmittance estimate max {np.nanmax(e['transmittance'][sun]):.4f}, share "
          f"above 1: {np.mean(e['transmittance'][sun] > 1.0):.4%}")
    print(f"   its largest 0.1 %: phase ÷ 1/4π median {np.median(e['phase'][top]):.1f}, transmittance median "
          f"{np.median(e['transmittance'][top]):.3f}, β median {np.median(e['beta'][top]):.3f} (max "
          f"{e['beta'][top].max():.3f}), depth median {np.median(e['depth'][top]):.0f} "
          f"(range {e['depth'][top].min()}–{e['depth'][top].max()})")
    # outlier pixels: the event behind each one's excess
    pixel_of_path = np.concatenate(recorder.path_pixel)
    pixel = pixel_of_path[:, 0] * args.width + pixel_of_path[:, 1]
    outliers = np.flatnonzero(z.ravel() > args.k)
    print(f"\n   {outliers.size} pixels with z > {args.k:g} ({outliers.size / z.size:.2%}); for each, the largest "
          f"event of its 16 paths and its share of the pixel's excess 16·(Y16 − Yref):")
    rows = []
    event_pixel = pixel[e["path"]]
    for p in outliers:
        mine = np.flatnonzero(event_pixel == p)
        if not mine.size:
            continue
        big = mine[np.argmax(e["y"][mine])]
        excess = 16 * (image.ravel()[p] - reference.ravel()[p])
        rows.append((e["kind"][big], e["depth"][big], e["phase"][big], e["transmittance"][big], e["beta"][big],
                     e["y"][big] / excess if excess else np.nan))
    if rows:
        kind, depth, phase, transmittance, beta, share = (np.array(column) for column in zip(*rows))
        print("   kinds: " + ", ".join(f"{name} {np.mean(kind == k):.0%}" for k, name in enumerate(KINDS)))
        print(f"   depth median {np.median(depth):.0f} (p10 {np.percentile(depth, 10):.0f}, p90 "
              f"{np.percentile(depth, 90):.0f}); phase ÷ 1/4π median {np.nanmedian(phase):.1f}; transmittance "
              f"median {np.nanmedian(transmittance):.3f}; β median {np.median(beta):.3f}, max {beta.max():.3f}; "
              f"share of the excess median {np.nanmedian(share):.0%}")
    # what a clamp of indirect light (biased, as Cycles' Clamp Indirect) would do: every contribution made
    # from the second vertex on
    print("\n   clamping every contribution at depth ≥ 2 to y ≤ c (BIASED; not in the tracer), z against the "
          "unclamped reference:")
    print(f"   {'c':>6} {'Y lost':>7}   {'p50':>6} {'p90':>6} {'p99':>6} {'max':>8}  {'>3':>7} {'>5':>7} {'>10':>7}")
    for c in (10.0, 3.0, 1.0, 0.3):
        cut = np.where(e["depth"] >= 2, np.maximum(e["y"] - c, 0.0), 0.0)
        lost = np.bincount(event_pixel, weights=cut, minlength=image.size).reshape(image.shape) / 16
        clamped = np.abs(image - lost - reference) / sigma_16
        print(f"   {c:6g} {cut.sum() / e['y'].sum():7.2%}   {describe(clamped)}")


def with_settings(scene, **changes):
    """`scene` with these RenderSettings fields changed."""
    return dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, **changes))


def part_clamping(args):
    scene = cloud_preset_scene(args, args.max_depth)
    unclamped_film = render(scene, spp=args.reference_spp, seed=REFERENCE_SEED).film
    reference, sigma = luminance_and_sigma(unclamped_film)
    sigma_16 = np.maximum(sigma / np.sqrt(16), 1e-12)
    print(f"\n3. Clamping in the tracer: Y at 16 spp ({args.seeds} seeds) against {args.reference_spp} spp, "
          f"relative RMSE = √mean((Y16 − Yref)²) / mean(Yref)")
    print(f"{'clamp (direct, indirect)':26} {'vs unclamped ref':>16} {'vs own ref':>10} {'mean Y lost':>11}   "
          f"z vs unclamped: {'p50':>6} {'p90':>6} {'p99':>6} {'max':>8}  {'>3':>7} {'>5':>7} {'>10':>7}")
    for direct, indirect in ((0.0, 0.0), (0.0, 10.0), (0.0, 1.0)):
        version = with_settings(scene, clamp_direct=direct, clamp_indirect=indirect)
        own = reference if indirect == 0.0 and direct == 0.0 else render(
            version, spp=args.reference_spp, seed=REFERENCE_SEED).film.xyz[..., 1]
        images = np.stack([render(version, spp=16, seed=seed).film.xyz[..., 1] for seed in range(1, args.seeds + 1)])
        rmse = np.sqrt(np.mean((images - reference) ** 2)) / reference.mean()
        rmse_own = np.sqrt(np.mean((images - own) ** 2)) / own.mean()
        lost = 1.0 - own.mean() / reference.mean()
        z = np.abs(images - reference) / sigma_16
        label = "off" if direct == indirect == 0.0 else f"{direct:g}, {indirect:g}"
        print(f"{label:26} {rmse:16.4f} {rmse_own:10.4f} {lost:11.2%}   {'':16}{describe(z)}", flush=True)


def seconds_to_render(scene, spp):
    """The median of three renders' wall-clock seconds."""
    times = []
    for _ in range(3):
        start = time.perf_counter()
        render(scene, spp=spp, seed=7)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def part_filter(args):
    scene = cloud_preset_scene(args, args.max_depth)
    reference, sigma = luminance_and_sigma(render(scene, spp=args.reference_spp, seed=REFERENCE_SEED).film)
    sigma_16 = np.maximum(sigma / np.sqrt(16), 1e-12)
    print(f"\n4. The firefly filter: z of {args.seeds} 16-spp images against the unfiltered {args.reference_spp}-spp "
          f"reference; mean Y taken at 16, 64, 256 spp (seed 7, against the unfiltered render of that seed); "
          f"wall-clock s per render (median of 3)")
    print(f"{'firefly_threshold':18} {'p50':>6} {'p90':>6} {'p99':>6} {'max':>8}  {'>3':>7} {'>5':>7} {'>10':>7}  "
          f"{'taken 16':>8} {'64':>7} {'256':>7}")
    for threshold in (0.0, 1.0, 2.0, 3.0):
        version = with_settings(scene, firefly_threshold=threshold)
        images = np.stack([render(version, spp=16, seed=seed).film.xyz[..., 1] for seed in range(1, args.seeds + 1)])
        z = np.abs(images - reference) / sigma_16
        taken = [1.0 - render(version, spp=spp, seed=7).film.xyz[..., 1].mean()
                 / render(scene, spp=spp, seed=7).film.xyz[..., 1].mean() for spp in (16, 64, 256)]
        label = "off" if threshold == 0.0 else f"{threshold:g}"
        print(f"{label:18} {describe(z)}  {taken[0]:8.2%} {taken[1]:7.2%} {taken[2]:7.2%}", flush=True)
    for scale in (1, 4):
        sized = argparse.Namespace(**{**vars(args), "width": args.width * scale, "height": args.height * scale})
        plain = cloud_preset_scene(sized, args.max_depth)
        for spp in (16, 256) if scale == 1 else (16,):
            off, on = seconds_to_render(plain, spp), seconds_to_render(with_settings(plain, firefly_threshold=2.0), spp)
            print(f"   {sized.width}×{sized.height}, {spp} spp: {off:.2f} s without the filter, {on:.2f} s with it "
                  f"({on / off:.2f}×)", flush=True)


def main(argv=None) -> None:
    args = parse(argv)
    print(machine())
    print(f"Cloud preset optics (σ_t 20 × density, albedo 0.99, g 0.8) on the benchmark cloud 64³, D65 sun "
          f"(irradiance Y 3), sky Y {args.sky:g}, {args.width}×{args.height}")
    render(cloud_preset_scene(args, args.max_depth), spp=1)  # compile or load the kernel, untimed
    if args.filter:
        part_filter(args)
        return
    if not args.clamping:
        found = part_numba(args)
        part_oracle(args, found)
    part_clamping(args)
    if not args.clamping:
        part_filter(args)


if __name__ == "__main__":
    main()
