"""Our tracer against Mitsuba 3 (llvm_ad_spectral) at its best, on a family of cloud scenes: speed per
sample, noise per sample and efficiency at equal time, against a long reference render of ours
(issue 3, Performance; issue 13 item 7).

The family (`FAMILY`; every scene is defined once in bench/scenes.py and converted for Mitsuba by
bench/mitsuba_scene.py): a smooth soft sphere (optical depth 8 through its centre) and the procedural
cloud (σ_t = 30 × density), each lit by the sun only and by the environment only, grey, albedo 0.8,
g 0; "albedo": the sphere with an albedo varying with wavelength, sun + environment; "chromatic": the
cloud with extinction and albedo varying with wavelength, g 0.6, sun + environment; "dense": the cloud,
grey, g 0.6, sun + environment.

Mitsuba is run as it runs best on each scene: a grey extinction is a `heterogeneous` medium with
`has_spectral_extinction` false and the `volpath` integrator; a varying extinction gets `volpathmis`
(spectral MIS); `--integrator` overrides. Each of its images is ONE `mi.render(scene, spp=N, seed=s)`
call with the image's whole sample count. Its fixed cost per call (tracing the kernel, launching it,
developing the film) is measured apart: overhead = 2·t(1 spp) − t(2 spp), medians of 3 calls each.
Mitsuba's images are divided by its Y for our equal-energy environment seen directly (about 1.001, the
scale of its colour matching; ours is exact), so that this scale does not count as its error.

For each scene: (1) a long reference with our tracer; (2) both renderers warmed up (Numba and Dr.Jit
compile their kernels on first use; that is not timed, nor is a Dr.Jit compile for a new sample count
later: its time is read from Dr.Jit's kernel history and taken off); (3) equal-time renders, the two
renderers alternating in 4 rounds so that a change in machine load hits both alike, each round sized
from the time per sample measured so far; (4) MSE of linear Y (and XYZ) against the reference, its own
noise subtracted. Printed: speed per sample (pixel-samples per second per thread), noise per sample
(MSE · spp), efficiency 1/(MSE · seconds) and its ratio ours/Mitsuba, Mitsuba's per-call overhead,
and the image means of ours, Mitsuba and the reference: they must agree within the noise, or the scene
conversion is wrong (not a renderer faster).

`--check` first verifies the conversion on small images: the orientation of the grid and the camera
with an asymmetric test grid (the right conversion against deliberately wrong ones), and each light's
units alone (sun only, environment only).

    python -m bench.vs_mitsuba                 # every scene, 64³, 256×256, 10 s per renderer and scene
    python -m bench.vs_mitsuba --quick --check # small and short: proves it runs (minutes)
"""

import argparse
import time

import numpy as np

from bench.measure import (Image, OurRenderer, compile_timed, corrected_mse, efficiency, equal_time, machine,
                           reference_noise, render_ours, rmse, warn_reference, warm_up)
from bench.mitsuba_scene import BLENDER_TO_MITSUBA_CAMERA, load_mitsuba, scene_dict, volume_data
from bench.scenes import SPHERE_DENSITY_SCALE, CloudSpec, cloud_scene, density_grid, orientation_grid

PASSES = 4  # interleaved rounds per renderer in an equal-time render
OVERHEAD_REPEATS = 3
MEAN_Z, MEAN_RELATIVE = 4.0, 0.0025  # an image mean this far from the reference's (both) flags the conversion

SUN, ENVIRONMENT = {"environment_strength": 0.0}, {"sun_strength": 0.0}
SPHERE = {"grid": "sphere", "density_scale": SPHERE_DENSITY_SCALE}
FAMILY = {  # name -> changes to CloudSpec's defaults (the cloud, σ_t = 30 × density, g 0, sun + environment)
    "sun-sphere": {**SPHERE, **SUN},
    "sun-cloud": SUN,
    "environment-sphere": {**SPHERE, **ENVIRONMENT},
    "environment-cloud": ENVIRONMENT,
    "albedo": {**SPHERE, "albedo_varies": True},
    "chromatic": {"extinction_varies": True, "albedo_varies": True, "g": 0.6},
    "dense": {"g": 0.6},
}


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="48×48, reference 256 spp, 2 s per renderer")
    parser.add_argument("--check", action="store_true", help="verify the scene conversion first (orientation, units)")
    parser.add_argument("--scenes", nargs="+", choices=list(FAMILY), default=list(FAMILY))
    parser.add_argument("--resolution", type=int, default=64, help="grid resolution (default 64)")
    parser.add_argument("--width", type=int, help="image width (default 256)")
    parser.add_argument("--height", type=int, help="image height (default 256)")
    parser.add_argument("--reference-spp", type=int, help="samples per pixel of our reference (default 512; quick 256)")
    parser.add_argument("--seconds", type=float, help="wall-clock budget per renderer and scene (default 10)")
    parser.add_argument("--integrator", choices=["volpath", "volpathmis"],
                        help="Mitsuba integrator for every scene (default: volpathmis where extinction varies "
                             "with wavelength, volpath elsewhere)")
    parser.add_argument("--threads", type=int, help="threads for both renderers (default: all cores)")
    args = parser.parse_args(argv)
    quick = args.quick
    args.width = args.width or (48 if quick else 256)
    args.height = args.height or (48 if quick else 256)
    args.reference_spp = args.reference_spp or (256 if quick else 512)
    args.seconds = args.seconds or (2.0 if quick else 10.0)
    return args


# ----------------------------------------------------------------------------- Mitsuba renders

class MitsubaRenderer:
    """Mitsuba on one converted scene; each image is one `mi.render` call with all its samples."""

    def __init__(self, mi, scene, integrator: str | None = None, white: float = 1.0):
        import drjit as dr

        self.mi, self.dr, self.white = mi, dr, white
        self.description = scene_dict(mi, scene, integrator)
        self.scene = mi.load_dict(self.description)
        self.seed = 1
        self.compile_seconds = 0.0  # Dr.Jit compiles met in timed calls, taken off their time
        dr.set_flag(dr.JitFlag.KernelHistory, True)

    def settings(self) -> str:
        """Integrator and medium as passed to Mitsuba."""
        integrator, interior = self.description["integrator"], self.description["medium_0"]["interior"]
        return (f"{integrator['type']} (max_depth {integrator['max_depth']}, rr_depth {integrator['rr_depth']}), "
                f"{interior['type']} medium, has_spectral_extinction="
                f"{interior.get('has_spectral_extinction', interior['type'] == 'gridspectrum')}")

    def _call(self, spp: int) -> tuple[np.ndarray, float]:
        """One `mi.render` call: the XYZ image and its seconds, less any kernel compile in them."""
        self.dr.kernel_history()  # empties the history
        start = time.perf_counter()
        image = np.array(self.mi.render(self.scene, spp=spp, seed=self.seed), dtype=np.float64)
        seconds = time.perf_counter() - start
        self.seed += 1
        image = image[..., :3] / self.white
        compiled = sum(kernel.get("codegen_time", 0.0) + kernel.get("backend_time", 0.0)
                       for kernel in self.dr.kernel_history() if not kernel.get("cache_hit", True)) / 1e3
        self.compile_seconds += compiled
        return image, seconds - compiled

    def render(self, spp: int) -> Image:
        image, seconds = self._call(spp)
        return Image(image, None, spp, seconds)

    def overhead(self) -> tuple[float, float]:
        """(seconds per call, seconds per sample per pixel) from 1- and 2-spp calls, medians of
        OVERHEAD_REPEATS each, alternating: overhead = 2·t(1) − t(2), per sample = t(2) − t(1)."""
        one, two = [], []
        for _ in range(OVERHEAD_REPEATS):
            one.append(self._call(1)[1])
            two.append(self._call(2)[1])
        t1, t2 = float(np.median(one)), float(np.median(two))
        return 2 * t1 - t2, t2 - t1


def mitsuba_white(mi) -> float:
    """Mitsuba's image Y for our equal-energy environment of luminance 1 with nothing in front of it.
    Ours is 1 by construction (exact CIE 1931); Mitsuba's colour matching gives about 1.001, for D65 as
    well: a scale of its own, which its images are divided by so that it does not count as error."""
    scene = cloud_scene(CloudSpec(width=32, height=32, sun_strength=0.0, environment_strength=1.0))
    description = scene_dict(mi, scene)
    del description["medium_0"]
    return float(np.array(mi.render(mi.load_dict(description), spp=1024, seed=0))[..., 1].mean())


# ----------------------------------------------------------------------------- conversion checks

def check_conversion(mi, white: float) -> None:
    """Orientation with an asymmetric grid, then each light alone; prints what it found."""
    print("\n== conversion check ==")
    width = height = 40
    spec = CloudSpec(width=width, height=height, g=0.3, density_scale=4.0, sun_strength=0.0)
    scene = cloud_scene(spec, orientation_grid(8), seed=0)
    kernel_scene, _ = compile_timed(scene)
    warm_up(kernel_scene)
    ours = render_ours(kernel_scene, 256, seed=3)
    variants = {"as converted": scene_dict(mi, scene)}
    wrong = scene_dict(mi, scene)  # grid passed in our [x, y, z] order, not transposed to [z, y, x]
    medium = wrong["medium_0"]["interior"]["sigma_t"]
    medium["grid"] = mi.VolumeGrid(np.ascontiguousarray(volume_data(scene.media[0].density)[..., 0]
                                                        .transpose(2, 1, 0))[..., None])
    variants["grid not transposed"] = wrong
    mirrored = scene_dict(mi, scene)  # camera matrix used as it is (no Blender → Mitsuba axis flip)
    mirrored["sensor"]["to_world"] = mi.ScalarTransform4f(
        (np.asarray(scene.camera.to_world) @ BLENDER_TO_MITSUBA_CAMERA @ np.diag([-1.0, 1, 1, 1])).tolist())
    variants["camera x not flipped"] = mirrored
    upside_down = scene_dict(mi, scene)  # camera's y axis flipped as well
    upside_down["sensor"]["to_world"] = mi.ScalarTransform4f(
        (np.asarray(scene.camera.to_world) @ BLENDER_TO_MITSUBA_CAMERA @ np.diag([1.0, -1, 1, 1])).tolist())
    variants["camera y flipped"] = upside_down
    background = float(np.median(ours.y))
    print(f"asymmetric 8³ grid, environment light, {width}×{height}: RMSE of Y against ours (256 spp each); "
          f"the conversion is right when 'as converted' is at the noise level and the wrong ones are not")
    for name, description in variants.items():
        image = np.array(mi.render(mi.load_dict(description), spp=256, seed=5), dtype=np.float64)[..., 1]
        shadow_ours, shadow_mi = background - ours.y, background - image
        print(f"  {name:22s} RMSE {rmse(image, ours.y):.4f}   correlation of the medium's footprint "
              f"{np.corrcoef(shadow_ours.ravel(), shadow_mi.ravel())[0, 1]:+.3f}")
    print(f"  (our own noise: RMSE {np.sqrt(np.mean(ours.variance[..., 1])) * np.sqrt(2):.4f} expected between "
          f"two independent 256-spp renders)")

    print("each light alone on the 64³ cloud, image mean XYZ, 128 spp each:")
    base = CloudSpec(resolution=64, width=width, height=height)
    density = density_grid(base)
    for name, spec in (("sun only (irradiance)", base.with_(**SUN)),
                       ("environment only (radiance)", base.with_(**ENVIRONMENT))):
        scene = cloud_scene(spec, density, seed=0)
        kernel_scene, _ = compile_timed(scene)
        image = render_ours(kernel_scene, 128, seed=7)
        ours = image.xyz.reshape(-1, 3).mean(axis=0)
        relative_error = np.sqrt(image.variance[..., 1].sum()) / image.y.size / ours[1]
        theirs = MitsubaRenderer(mi, scene, white=white).render(128).xyz.reshape(-1, 3).mean(axis=0)
        print(f"  {name:28s} ours {fmt3(ours)}  Mitsuba {fmt3(theirs)}  Mitsuba/ours Y {theirs[1] / ours[1]:.4f} "
              f"(ours alone ± {relative_error:.4f})")
        if spec.sun_strength > 0:  # the wrong sign of the sun's direction, to show the check would see it
            wrong = scene_dict(mi, scene)
            light = next(key for key in wrong if key.endswith("_sun"))
            wrong[light]["direction"] = [-v for v in wrong[light]["direction"]]
            image = np.array(mi.render(mi.load_dict(wrong), spp=128, seed=9), dtype=np.float64)
            print(f"  {'(sun direction not negated)':28s} {'':29s} Mitsuba/ours Y {image[..., 1].mean() / ours[1]:.4f}")


def fmt3(values) -> str:
    return "(" + ", ".join(f"{v:.4f}" for v in values) + ")"


# ----------------------------------------------------------------------------- equal time

def compare(name: str, spec: CloudSpec, mi, args, threads: dict, white: float) -> dict:
    scene = cloud_scene(spec, seed=0)
    kernel_scene, _ = compile_timed(scene)
    warm_up(kernel_scene)
    start = time.perf_counter()
    mitsuba = MitsubaRenderer(mi, scene, args.integrator, white)
    for spp in (1, 2):  # Dr.Jit compiles (or loads from ~/.drjit) its kernels here
        mitsuba.render(spp)
    setup_mi = time.perf_counter() - start
    overhead, per_sample = mitsuba.overhead()
    reference = render_ours(kernel_scene, args.reference_spp, seed=1000)
    images = equal_time({"ours": OurRenderer(kernel_scene, seed=12), "mitsuba": mitsuba}, args.seconds, PASSES)
    noise = {"y": reference_noise(reference, 1), "xyz": reference_noise(reference, None)}
    r = {"name": name, "spec": spec, "reference": reference, "setup_mi": setup_mi, "overhead": overhead,
         "per_sample_mi": per_sample, "settings": mitsuba.settings(), "compile_mi": mitsuba.compile_seconds}
    pixels = spec.width * spec.height
    for key, image in images.items():
        r[key] = image
        r[key + "_speed"] = image.spp * pixels / image.seconds / threads[key]
        r[key + "_z"] = mean_z(image, reference)
        for channel, values, reference_values in (("y", image.y, reference.y), ("xyz", image.xyz, reference.xyz)):
            mse = corrected_mse(values, reference_values, noise[channel])
            r[f"{key}_mse_{channel}"] = mse
            r[f"{key}_eff_{channel}"] = efficiency(mse, image.seconds)
    for channel in ("y", "xyz"):
        r["ratio_" + channel] = r["ours_eff_" + channel] / r["mitsuba_eff_" + channel]
    print_comparison(r)
    return r


def mean_z(image: Image, reference: Image) -> np.ndarray:
    """Distance of the image's mean X, Y, Z from the reference's, in standard errors of the difference:
    the image's error of the mean from its variance where it has one, else from its squared error
    against the reference less the reference's variance (as in `corrected_mse`)."""
    n = image.y.size
    reference_variance = reference.variance.reshape(-1, 3)
    if image.variance is not None:
        se2 = image.variance.reshape(-1, 3).sum(axis=0) / n**2
    else:
        squared = ((image.xyz - reference.xyz) ** 2).reshape(-1, 3).mean(axis=0)
        se2 = np.maximum(squared - reference_variance.mean(axis=0), 0.1 * squared) / n
    difference = image.xyz.reshape(-1, 3).mean(axis=0) - reference.xyz.reshape(-1, 3).mean(axis=0)
    return difference / np.sqrt(reference_variance.sum(axis=0) / n**2 + se2)


def print_comparison(r: dict) -> None:
    reference, ours, theirs = r["reference"], r["ours"], r["mitsuba"]
    mean_ref = reference.xyz.reshape(-1, 3).mean(axis=0)
    se_ref = np.sqrt(reference.variance[..., 1].sum()) / reference.y.size
    print(f"\n== {r['name']}: {r['spec'].label()}")
    print(f"  Mitsuba: {r['settings']}; scene load + kernel compile {r['setup_mi']:.1f} s (not timed)"
          + (f", {r['compile_mi']:.1f} s of compiles in timed calls taken off" if r["compile_mi"] else ""))
    print(f"  image mean XYZ  reference {fmt3(mean_ref)} ± {se_ref:.4f} (Y), ours at {reference.spp} spp "
          f"({reference.seconds:.1f} s)")
    for label, key in (("ours", "ours"), ("Mitsuba", "mitsuba")):
        image = r[key]
        print(f"                  {label:9s} {fmt3(image.xyz.reshape(-1, 3).mean(axis=0))}   Y "
              f"{100 * (image.y.mean() / mean_ref[1] - 1):+.2f}% vs reference; X, Y, Z off by "
              f"({', '.join(f'{z:+.1f}' for z in r[key + '_z'])}) standard errors")
    for label, key in (("ours", "ours"), ("Mitsuba", "mitsuba")):
        z = np.abs(r[key + "_z"]).max()
        relative = np.abs(r[key].xyz.reshape(-1, 3).mean(axis=0) / mean_ref - 1).max()
        if z > MEAN_Z and relative > MEAN_RELATIVE:
            print(f"  WARNING: {label}'s image mean is {z:.1f} standard errors and {100 * relative:.2f}% from the "
                  f"reference's: the scene conversion is suspect")
        elif z > MEAN_Z:
            print(f"  note: {label}'s image mean is {z:.1f} standard errors but only {100 * relative:.2f}% from the "
                  f"reference's: a small bias of one renderer, not a conversion error (see bench/README.md)")
    for label, key in (("ours", "ours"), ("Mitsuba", "mitsuba")):
        image = r[key]
        print(f"  {label:8s} {image.spp:5d} spp in {image.seconds:6.2f} s: {r[key + '_speed'] / 1e3:8.2f} k "
              f"pixel-samples/s per thread; noise per sample MSE·spp Y {r[key + '_mse_y'] * image.spp:.4g}, XYZ "
              f"{r[key + '_mse_xyz'] * image.spp:.4g}; efficiency Y {r[key + '_eff_y']:.4g}")
    print(f"  Mitsuba per call: overhead {r['overhead'] * 1e3:.0f} ms (2·t(1 spp) − t(2 spp), medians of "
          f"{OVERHEAD_REPEATS}), then {r['per_sample_mi'] * 1e3:.0f} ms per spp; its equal-time render was "
          f"{PASSES} calls, {100 * PASSES * r['overhead'] / theirs.seconds:.1f}% of its time")
    without_overhead = efficiency(r["mitsuba_mse_y"], theirs.seconds - PASSES * r["overhead"])
    print(f"  ours/Mitsuba: speed per sample {r['ours_speed'] / r['mitsuba_speed']:.2f}×, noise per sample "
          f"(Mitsuba/ours) Y {r['mitsuba_mse_y'] * theirs.spp / (r['ours_mse_y'] * ours.spp):.2f}×, "
          f"efficiency Y {r['ratio_y']:.2f}× ({r['ours_eff_y'] / without_overhead:.2f}× with Mitsuba's call overhead "
          f"taken off), XYZ {r['ratio_xyz']:.2f}×")
    warn_reference(reference, (ours, theirs))


def print_summary(results: list[dict]) -> None:
    print("\nsummary: ours/Mitsuba; speed = pixel-samples/s per thread; noise = MSE·spp of Y (Mitsuba's over ours); "
          "efficiency = 1/(MSE·seconds) against our reference, its noise removed; max |z|: the farthest image mean (X, Y "
          "or Z, ours or Mitsuba's) from the reference's, in standard errors")
    print(f"{'scene':20s} {'Mitsuba':11s} {'speed':>6s} {'noise':>6s} {'eff. Y':>7s} {'XYZ':>6s} "
          f"{'mean Y ours':>12s} {'Mitsuba':>8s} {'reference':>10s} {'max |z|':>8s}")
    for r in results:
        noise = r["mitsuba_mse_y"] * r["mitsuba"].spp / (r["ours_mse_y"] * r["ours"].spp)
        print(f"{r['name']:20s} {r['settings'].split()[0]:11s} {r['ours_speed'] / r['mitsuba_speed']:5.2f}× "
              f"{noise:5.2f}× {r['ratio_y']:6.2f}× {r['ratio_xyz']:5.2f}× {r['ours'].y.mean():12.4f} "
              f"{r['mitsuba'].y.mean():8.4f} {r['reference'].y.mean():10.4f} "
              f"{max(np.abs(r['ours_z']).max(), np.abs(r['mitsuba_z']).max()):8.1f}")
    geometric = {channel: float(np.exp(np.mean([np.log(r["ratio_" + channel]) for r in results])))
                 for channel in ("y", "xyz")}
    print(f"{'geometric mean':20s} {'':11s} {'':6s} {'':6s} {geometric['y']:6.2f}× {geometric['xyz']:5.2f}×")


def main(argv=None) -> int:
    args = parse(argv)
    import numba

    if args.threads:
        numba.set_num_threads(args.threads)
    mi = load_mitsuba()
    import drjit as dr

    if args.threads:
        dr.set_thread_count(args.threads)
    threads = {"ours": numba.get_num_threads(), "mitsuba": dr.thread_count()}
    print(f"machine: {machine()}; Dr.Jit {dr.__version__} with {dr.thread_count()} threads, Mitsuba {mi.__version__} "
          f"{mi.variant()}")
    print("ours: 4 wavelengths per path (hero + spectral MIS, colour-importance λ), majorant grid; Mitsuba: 4 "
          "wavelengths per path, one majorant for the whole medium, one mi.render call per image"
          + ("\n[QUICK MODE: tiny sizes and budgets, figures are not representative]" if args.quick else ""))
    white = mitsuba_white(mi)
    print(f"Mitsuba's Y for our equal-energy environment of Y 1 (ours: 1 exactly): {white:.5f}; Mitsuba's images "
          f"are divided by it")
    if args.check:
        check_conversion(mi, white)
    results = [compare(name, CloudSpec(resolution=args.resolution, width=args.width, height=args.height)
                       .with_(**FAMILY[name]), mi, args, threads, white)
               for name in args.scenes]
    print_summary(results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
