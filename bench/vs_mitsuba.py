"""Our tracer against Mitsuba 3 (llvm_ad_spectral, volpath) on the same cloud scenes: image means, and
equal-time error against a long reference render of ours (issue 3, Performance).

For each scene: (1) a long reference with our tracer; (2) each renderer's time per sample measured on a
short render after a warm-up (Numba and Dr.Jit compile their kernels on first use; that is not timed);
(3) each renderer renders for the same wall-clock budget, in interleaved passes so that a change in
machine load hits both alike; (4) the error of linear Y (and of XYZ) against the reference, with the
reference's own noise (its per-pixel variance of the mean) subtracted from the MSE; efficiency =
1 / (MSE · seconds), which does not depend on the budget for unbiased renderers; the ratio ours/Mitsuba
is the figure (target: ≥ 2 with 4 wavelengths per path). Both renderers' image means are printed next
to the reference's: a disagreement beyond the noise means the scene conversion (bench/mitsuba_scene.py)
is wrong, not that a renderer is faster.

`--check` first verifies the conversion on small images: the orientation of the grid and the camera
with an asymmetric test grid (the right conversion against deliberately wrong ones), and each light's
units alone (sun only, environment only).

    python -m bench.vs_mitsuba                 # 64³ and 128³, g 0 and 0.6, 256×256, 10 s per renderer
    python -m bench.vs_mitsuba --quick --check # small and short: proves it runs
"""

import argparse
import time

import numpy as np

from bench.measure import (Image, OurRenderer, at_time, compile_timed, corrected_mse, efficiency, equal_time, machine,
                           reference_noise, render_ours, rmse, warn_reference, warm_up)
from bench.mitsuba_scene import BLENDER_TO_MITSUBA_CAMERA, load_mitsuba, scene_dict, volume_data
from bench.scenes import CloudSpec, cloud_density, cloud_scene, orientation_grid

PASSES = 4  # interleaved passes per renderer in an equal-time render
CHUNK = 4  # samples per pixel in each call of mi.render


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true",
                        help="64³ only, 48×48, reference 256 spp, 2 s per renderer")
    parser.add_argument("--check", action="store_true", help="verify the scene conversion first (orientation, units)")
    parser.add_argument("--resolutions", type=int, nargs="+", help="grid resolutions (default 64 128)")
    parser.add_argument("--g", type=float, nargs="+", help="HG anisotropies (default 0 0.6; quick: 0.6)")
    parser.add_argument("--width", type=int, help="image width (default 256)")
    parser.add_argument("--height", type=int, help="image height (default 256)")
    parser.add_argument("--reference-spp", type=int, help="samples per pixel of our reference (default 512; quick 256)")
    parser.add_argument("--seconds", type=float, help="wall-clock budget per renderer and scene (default 10)")
    parser.add_argument("--integrator", default="volpath", choices=["volpath", "volpathmis"],
                        help="Mitsuba integrator (default volpath)")
    parser.add_argument("--threads", type=int, help="threads for both renderers (default: all cores)")
    args = parser.parse_args(argv)
    quick = args.quick
    args.resolutions = args.resolutions or ([64] if quick else [64, 128])
    args.g = args.g if args.g is not None else ([0.6] if quick else [0.0, 0.6])
    args.width = args.width or (48 if quick else 256)
    args.height = args.height or (48 if quick else 256)
    args.reference_spp = args.reference_spp or (256 if quick else 512)
    args.seconds = args.seconds or (2.0 if quick else 10.0)
    return args


# ----------------------------------------------------------------------------- Mitsuba renders

class MitsubaRenderer:
    def __init__(self, mi, scene, integrator: str = "volpath"):
        self.mi = mi
        description = scene_dict(mi, scene)
        description["integrator"]["type"] = integrator
        self.scene = mi.load_dict(description)
        self.seed = 1

    def render(self, spp: int) -> Image:
        """Mean XYZ of at least `spp` fresh samples per pixel, rendered CHUNK samples per call (each call
        with its own seed): every call then runs the same kernels, which the warm-up compiled."""
        calls = max(1, -(-spp // CHUNK))
        total, seconds = 0.0, 0.0
        for _ in range(calls):
            start = time.perf_counter()
            image = np.array(self.mi.render(self.scene, spp=CHUNK, seed=self.seed), dtype=np.float64)
            seconds += time.perf_counter() - start
            self.seed += 1
            total = total + image[..., :3]
        return Image(total / calls, None, calls * CHUNK, seconds)


# ----------------------------------------------------------------------------- conversion checks

def check_conversion(mi, args) -> None:
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
    density, _ = cloud_density(64)
    base = CloudSpec(resolution=64, width=width, height=height)
    for name, spec in (("sun only (irradiance)", base.with_(environment_strength=0.0)),
                       ("environment only (radiance)", base.with_(sun_strength=0.0))):
        scene = cloud_scene(spec, density, seed=0)
        kernel_scene, _ = compile_timed(scene)
        image = render_ours(kernel_scene, 128, seed=7)
        ours = image.xyz.reshape(-1, 3).mean(axis=0)
        relative_error = np.sqrt(image.variance[..., 1].sum()) / image.y.size / ours[1]
        theirs = MitsubaRenderer(mi, scene).render(128).xyz.reshape(-1, 3).mean(axis=0)
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

def compare(spec: CloudSpec, density, mi, args) -> dict:
    scene = cloud_scene(spec, density, seed=0)
    kernel_scene, _ = compile_timed(scene)
    warm_up(kernel_scene)
    start = time.perf_counter()
    mitsuba = MitsubaRenderer(mi, scene, args.integrator)
    mitsuba.render(CHUNK)  # Dr.Jit compiles (or loads from ~/.drjit) its kernels here
    setup_mi = time.perf_counter() - start
    reference = render_ours(kernel_scene, args.reference_spp, seed=1000)
    ours_renderer = OurRenderer(kernel_scene, seed=12)
    images = equal_time({"ours": ours_renderer, "mitsuba": mitsuba}, args.seconds, PASSES)
    ours, theirs = images["ours"], images["mitsuba"]
    warn_reference(reference, images.values())
    noise_y, noise_xyz = reference_noise(reference, 1), reference_noise(reference, None)
    result = {"spec": spec, "reference": reference, "ours": ours, "mitsuba": theirs, "setup_mi": setup_mi}
    for name, image in (("ours", ours), ("mitsuba", theirs)):
        mse_y = corrected_mse(image.y, reference.y, noise_y)
        mse_xyz = corrected_mse(image.xyz, reference.xyz, noise_xyz)
        result[name + "_mse_y"], result[name + "_mse_xyz"] = mse_y, mse_xyz
        result[name + "_eff_y"], result[name + "_eff_xyz"] = efficiency(mse_y, image.seconds), efficiency(mse_xyz, image.seconds)
    print_comparison(result, args)
    return result


def print_comparison(r: dict, args) -> None:
    reference, ours, theirs = r["reference"], r["ours"], r["mitsuba"]
    mean_ref = reference.xyz.reshape(-1, 3).mean(axis=0)
    # Standard error of the reference's image mean, from its per-pixel variances of the mean.
    se_ref = np.sqrt(reference.variance.reshape(-1, 3).sum(axis=0)) / reference.y.size
    print(f"\n{r['spec'].label()}: reference = ours at {reference.spp} spp ({reference.seconds:.1f} s); Mitsuba "
          f"{args.integrator} scene load + kernel compile {r['setup_mi']:.1f} s (not timed)")
    print(f"  image mean XYZ   reference {fmt3(mean_ref)} ± {se_ref[1]:.4f} (Y)")
    for name, image in (("ours", ours), ("Mitsuba", theirs)):
        mean = image.xyz.reshape(-1, 3).mean(axis=0)
        print(f"                   {name:9s} {fmt3(mean)}   Y {100 * (mean[1] / mean_ref[1] - 1):+.2f}% vs reference")
    mean_mi = theirs.xyz.reshape(-1, 3).mean(axis=0)
    if abs(mean_mi[1] / mean_ref[1] - 1) > 0.02:
        print("  WARNING: Mitsuba's image mean differs from ours by more than 2%: the scene conversion is suspect")
    for name, key, image in (("ours", "ours", ours), ("Mitsuba", "mitsuba", theirs)):
        print(f"  {name:8s} {image.spp:5d} spp in {image.seconds:6.2f} s ({image.seconds / image.spp * 1e3:7.1f} ms/spp)  "
              f"RMSE Y {np.sqrt(r[key + '_mse_y']):.5f} ({np.sqrt(at_time(r[key + '_mse_y'], image.seconds, args.seconds)):.5f} "
              f"at {args.seconds:g} s)  RMSE XYZ {np.sqrt(r[key + '_mse_xyz']):.5f}  efficiency Y {r[key + '_eff_y']:.4g}")
    per_spp = (theirs.seconds / theirs.spp) / (ours.seconds / ours.spp)
    print(f"  ours/Mitsuba: speed per sample {per_spp:.2f}×, efficiency Y {r['ours_eff_y'] / r['mitsuba_eff_y']:.2f}×, "
          f"efficiency XYZ {r['ours_eff_xyz'] / r['mitsuba_eff_xyz']:.2f}×  (target ≥ 2×)")


def main(argv=None) -> int:
    args = parse(argv)
    if args.threads:
        import numba

        numba.set_num_threads(args.threads)
    mi = load_mitsuba()
    import drjit as dr

    if args.threads:
        dr.set_thread_count(args.threads)
    print(f"machine: {machine()}; Dr.Jit {dr.__version__} with {dr.thread_count()} threads, Mitsuba {mi.__version__} "
          f"{mi.variant()}")
    print(f"ours: 4 wavelengths per path (hero + spectral MIS, colour-importance λ), majorant grid; Mitsuba: "
          f"{args.integrator}, 4 wavelengths per path, one majorant for the whole medium"
          + ("\n[QUICK MODE: tiny sizes and budgets, figures are not representative]" if args.quick else ""))
    if args.check:
        check_conversion(mi, args)
    results = []
    for resolution in args.resolutions:
        density, _ = cloud_density(resolution)
        for g in args.g:
            spec = CloudSpec(resolution=resolution, g=g, width=args.width, height=args.height)
            results.append(compare(spec, density, mi, args))
    print("\nsummary: efficiency = 1/(MSE·seconds), MSE of linear Y against our reference (its noise removed)")
    print(f"{'scene':40s} {'ours/Mitsuba Y':>15s} {'XYZ':>6s} {'mean Y ours':>12s} {'Mitsuba':>8s} {'reference':>10s}")
    for r in results:
        mean = lambda image: float(image.y.mean())
        print(f"{r['spec'].label():40s} {r['ours_eff_y'] / r['mitsuba_eff_y']:14.2f}× {r['ours_eff_xyz'] / r['mitsuba_eff_xyz']:5.2f}× "
              f"{mean(r['ours']):12.4f} {mean(r['mitsuba']):8.4f} {mean(r['reference']):10.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
