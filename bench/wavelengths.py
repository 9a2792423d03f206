"""The seminar report's wavelength sampling against ours, at equal time: colour error against a long
reference (issue 3, Performance).

Methods, all in our tracer on the same scene:
- report:        ONE wavelength per path, uniform over 380–700 nm (the report's §3.2), exact CIE 1931 CMFs;
- report+wyman1: the same with the Wyman–Sloan–Shirley single-lobe CMF fit (the report's §3.3 eq. 1–3);
- ours:          4 wavelengths per path (hero + 3 stratified companions, spectral MIS), colour-importance
                 sampling over 360–830 nm, exact CIE 1931 CMFs (the tracer's defaults).
`--ablation` adds "ours 1λ" (one colour-importance wavelength) and "4λ uniform" (4 wavelengths, uniform
over 380–700 nm) to show which change buys what.

The reference is ours with many samples. Each method renders for the same wall-clock budget (time per
sample from a calibration render, then interleaved passes); errors: RMSE of XYZ (with the reference's
own noise removed; "@budget" scales it to exactly the budget, MSE ∝ 1/time, the ratios use that) and
mean CIEDE2000 ΔE (CIELAB relative to D65 at the reference's 99th-percentile luminance; not scaled,
so compare it with the seconds actually taken in view). The report's method is biased as well as noisy (it ignores 360–380 and 700–830 nm, and
wyman1 is an approximation): the "bias" column is the part of its MSE its own noise does not explain.
Target: ours ≥ 3× lower equal-time colour error than the report's method.

Scenes: "cloud" (the benchmark cloud, flat medium spectra, g 0.6) and "chromatic" (the same cloud with
extinction, albedo and anisotropy varying with wavelength, where spectral MIS matters).

    python -m bench.wavelengths             # both scenes, 128³, 256×256, reference 512 spp, 10 s per method
    python -m bench.wavelengths --quick     # tiny: proves it runs
"""

import argparse

import numpy as np

from bench.measure import (OurRenderer, at_time, compile_timed, corrected_mse, equal_time, machine, mean_delta_e,
                           reference_noise, render_ours, warm_up, warn_reference, white_for)
from bench.scenes import CHROMATIC, CloudSpec, cloud_density, cloud_scene

REPORT = {"wavelengths_per_path": 1, "wavelength_sampling": "uniform", "lambda_min": 380.0, "lambda_max": 700.0}
METHODS = {
    "report": {**REPORT, "cmf": "cie1931"},
    "report+wyman1": {**REPORT, "cmf": "wyman1"},
    "ours": {"wavelengths_per_path": 4, "wavelength_sampling": "colour", "lambda_min": 360.0, "lambda_max": 830.0,
             "cmf": "cie1931"},
}
ABLATION = {
    "ours 1λ": {**METHODS["ours"], "wavelengths_per_path": 1},
    "4λ uniform": {**REPORT, "wavelengths_per_path": 4, "cmf": "cie1931"},
}
SCENES = {"cloud": {"g": 0.6}, "chromatic": CHROMATIC}


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="64³, 48×48, reference 256 spp, 2 s per method")
    parser.add_argument("--scenes", nargs="+", choices=list(SCENES), default=list(SCENES))
    parser.add_argument("--resolution", type=int, help="grid resolution (default 128)")
    parser.add_argument("--width", type=int, help="image width (default 256)")
    parser.add_argument("--height", type=int, help="image height (default 256)")
    parser.add_argument("--reference-spp", type=int, help="samples per pixel of the reference (default 512; quick 256)")
    parser.add_argument("--seconds", type=float, help="wall-clock budget per method and scene (default 10)")
    parser.add_argument("--ablation", action="store_true", help="also 'ours 1λ' and '4λ uniform'")
    parser.add_argument("--threads", type=int, help="Numba threads (default: all)")
    args = parser.parse_args(argv)
    quick = args.quick
    args.resolution = args.resolution or (64 if quick else 128)
    args.width = args.width or (48 if quick else 256)
    args.height = args.height or (48 if quick else 256)
    args.reference_spp = args.reference_spp or (256 if quick else 512)
    args.seconds = args.seconds or (2.0 if quick else 10.0)
    return args


def run_scene(name: str, density, args) -> dict:
    spec = CloudSpec(resolution=args.resolution, width=args.width, height=args.height).with_(**SCENES[name])
    methods = {**METHODS, **(ABLATION if args.ablation else {})}
    renderers = {}
    for index, (method, settings) in enumerate(methods.items()):
        kernel_scene, _ = compile_timed(cloud_scene(spec, density, seed=100 + index, **settings))
        warm_up(kernel_scene)
        renderers[method] = OurRenderer(kernel_scene, seed=100 + index)
    reference = render_ours(renderers["ours"].kernel_scene, args.reference_spp, seed=1000)
    images = equal_time(renderers, args.seconds)
    warn_reference(reference, images.values())
    noise = reference_noise(reference, None)
    white = white_for(reference)
    print(f"\n{spec.label()}: reference = ours at {reference.spp} spp ({reference.seconds:.1f} s); "
          f"budget {args.seconds:g} s per method")
    print(f"  {'method':14s} {'spp':>5s} {'s':>6s} {'ms/spp':>7s} {'RMSE XYZ':>9s} {'@budget':>8s} {'bias²/MSE':>10s} "
          f"{'mean ΔE00':>10s} {'mean XYZ':>26s}")
    rows = {}
    for method, image in images.items():
        mse = corrected_mse(image.xyz, reference.xyz, noise)
        own_noise = float(np.mean(image.variance))
        bias_share = max(0.0, mse - own_noise) / mse if mse > 0 else 0.0
        delta_e = mean_delta_e(image.xyz, reference.xyz, white)
        rmse_budget = float(np.sqrt(at_time(mse, image.seconds, args.seconds)))
        rows[method] = {"mse": mse, "rmse": rmse_budget, "delta_e": delta_e, "image": image}
        mean = image.xyz.reshape(-1, 3).mean(axis=0)
        print(f"  {method:14s} {image.spp:5d} {image.seconds:6.2f} {image.seconds / image.spp * 1e3:7.1f} "
              f"{np.sqrt(mse):9.5f} {rmse_budget:8.5f} {bias_share:10.2f} {delta_e:10.3f}   "
              f"({mean[0]:.4f}, {mean[1]:.4f}, {mean[2]:.4f})")
    mean_ref = reference.xyz.reshape(-1, 3).mean(axis=0)
    print(f"  {'reference':14s} {'':66s}   ({mean_ref[0]:.4f}, {mean_ref[1]:.4f}, {mean_ref[2]:.4f})")
    ours = rows["ours"]
    for method in rows:
        if method != "ours":
            print(f"  {method} / ours: RMSE XYZ at equal time {rows[method]['rmse'] / ours['rmse']:.2f}×, mean ΔE "
                  f"{rows[method]['delta_e'] / ours['delta_e']:.2f}× in {rows[method]['image'].seconds:.2f} s "
                  f"against {ours['image'].seconds:.2f} s  (target ≥ 3×)")
    return {"spec": spec, "rows": rows}


def main(argv=None) -> int:
    args = parse(argv)
    if args.threads:
        import numba

        numba.set_num_threads(args.threads)
    print(f"machine: {machine()}")
    if args.quick:
        print("[QUICK MODE: tiny sizes and budgets, figures are not representative]")
    density, _ = cloud_density(args.resolution)
    results = [run_scene(name, density, args) for name in args.scenes]
    print("\nsummary: equal-time colour error of each method relative to ours (higher = ours better)")
    for result in results:
        rows = result["rows"]
        ratios = ", ".join(f"{method}: RMSE XYZ {rows[method]['rmse'] / rows['ours']['rmse']:.2f}× "
                           f"ΔE {rows[method]['delta_e'] / rows['ours']['delta_e']:.2f}×"
                           for method in rows if method != "ours")
        print(f"  {result['spec'].label()}: {ratios}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
