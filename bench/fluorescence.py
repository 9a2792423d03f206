"""How the fluorescence estimator converges as the dye gets denser (issue 15, item 1): a wide slab whose
only extinction is a fluorophore (quantum yield 1, excitation in 300–340 nm, emission a Gaussian at
550 nm) under a uniform UV environment (280–350 nm, given in watts), seen face-on.

Its visible radiance has a closed form. The emission is not absorbed again (excitation and emission do
not overlap) and there is no scattering, so the face-on radiance is
    L(λ) = QY · emission_pdf(λ) · ∫ L_uv(λ') (1 − 2 E₃(τ(λ'))) / 2 dλ',
where τ(λ') is the slab's optical thickness at λ', E₃ the exponential integral of order 3, and
(1 − 2 E₃(τ))/2 = ∫₀¹ μ (1 − e^{−τ/μ}) dμ the absorbed share of isotropic light crossing one face.

Each row is one density, named by σ_fl·d, the optical thickness of the fluorescent source at the
emission peak. Every pixel sees the slab's uniform interior, so each pixel of a 1-spp pass is one
independent sample. The script prints the mean over all samples ÷ the exact value with its standard
error, the noise per sample (relative standard deviation), the share of the sum carried by the largest
0.1 % of samples, and the kernel time.

    python -m bench.fluorescence             # σ_fl·d 0.5 … 100, 64×64 pixels, 64 passes
    python -m bench.fluorescence --quick     # three densities, 32×32, 16 passes
"""

import argparse
import time

import numpy as np
from scipy.special import expn

from addon.tracer import colorimetry, spectra
from addon.tracer.builders import box_grid, medium, scene
from addon.tracer.lowering import compile_scene
from addon.tracer.render import render_unit
from addon.tracer.scene import Camera, Fluorescence, Light, Scene
from addon.tracer.wavelengths import GRID

from bench.measure import machine, warm_up

THICKNESS = 0.2  # slab thickness d (world units)
WIDTH = 40.0  # slab width: the camera sees its middle 0.5 × 0.5
UV_WATTS = 2.5  # the environment's radiance over the whole spectrum, W·m⁻²·sr⁻¹
QUANTUM_YIELD = 1.0
EXCITATION = spectra.window(spectra.constant(1.0), 300, 340)  # shape; scaled per row
EMISSION = spectra.gaussian(550, 20)
UV = spectra.window(spectra.constant(1.0), 280, 350)
SOURCE_THICKNESSES = (0.5, 2.0, 7.4, 18.5, 50.0, 100.0)


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--quick", action="store_true", help="σ_fl·d 0.5, 7.4, 18.5; 32×32 pixels, 16 passes")
    parser.add_argument("--thicknesses", type=float, nargs="+", help="σ_fl·d of each row")
    parser.add_argument("--pixels", type=int, help="image width and height (default 64; quick 32)")
    parser.add_argument("--passes", type=int, help="1-spp passes per row (default 64; quick 16)")
    args = parser.parse_args(argv)
    args.thicknesses = args.thicknesses or ([0.5, 7.4, 18.5] if args.quick else list(SOURCE_THICKNESSES))
    args.pixels = args.pixels or (32 if args.quick else 64)
    args.passes = args.passes or (16 if args.quick else 64)
    return args


def excitation_level(source_thickness: float) -> float:
    """The excitation coefficient that gives the slab a fluorescent source of optical thickness
    `source_thickness` at the emission peak: σ_fl = QY · ∫ excitation · max emission_pdf."""
    peak_pdf = EMISSION.values.max() / EMISSION.integral()
    return source_thickness / (THICKNESS * QUANTUM_YIELD * EXCITATION.integral() * peak_pdf)


def slab_scene(source_thickness: float, pixels: int) -> Scene:
    density = box_grid((16, 16, 4), (WIDTH, WIDTH, THICKNESS))
    excitation = spectra.Spectrum(EXCITATION.values * excitation_level(source_thickness))
    dye = medium(density, name="dye", extinction=0.0, fluorescence=Fluorescence(excitation, EMISSION, QUANTUM_YIELD))
    light = Light(kind="environment", spectrum=UV, strength=UV_WATTS, unit="radiant", name="uv")
    to_world = np.eye(4)
    to_world[2, 3] = 6.0  # looking down −z at the slab
    camera = Camera(to_world=to_world, width=pixels, height=pixels, kind="orthographic", ortho_scale=0.5)
    return scene(camera, (dye,), (light,), max_depth=64)


FINE = np.arange(GRID[0], GRID[-1], 0.01)  # the ∫ dλ' of the closed form, over the linearly interpolated spectra


def exact_y(source_thickness: float) -> float:
    """The closed form of the module docstring, as luminance Y (spectra interpolated linearly between grid
    points, as the tracer does: at the excitation window's edges τ changes within a nanometre)."""
    uv_radiance = np.interp(FINE, GRID, UV.values * UV_WATTS / UV.integral())
    tau = np.interp(FINE, GRID, EXCITATION.values * excitation_level(source_thickness) * THICKNESS)
    absorbed = float(np.sum(uv_radiance * (1.0 - 2.0 * expn(3, tau)) / 2.0) * (FINE[1] - FINE[0]))
    emitted = QUANTUM_YIELD * EMISSION.values / EMISSION.integral() * absorbed
    return float(colorimetry.spectrum_to_xyz(emitted)[1])


def measure(source_thickness: float, pixels: int, passes: int) -> dict:
    kernel_scene = compile_scene(slab_scene(source_thickness, pixels))
    warm_up(kernel_scene)
    samples, seconds = [], 0.0
    for index in range(passes):
        start = time.perf_counter()
        sums = render_unit(kernel_scene, 0, (index, index + 1), (0, 0, pixels, pixels), seed=3)[0]
        seconds += time.perf_counter() - start
        samples.append(sums[..., 1].ravel())
    y = np.concatenate(samples)
    exact = exact_y(source_thickness)
    top = np.sort(y)[-max(1, y.size // 1000):]
    return {"thickness": source_thickness, "ratio": y.mean() / exact, "error": y.std() / np.sqrt(y.size) / exact,
            "noise": y.std() / y.mean() if y.mean() > 0 else float("inf"), "top": top.sum() / y.sum(),
            "largest": y.max() / exact, "samples": y.size, "seconds": seconds}


def main(argv=None) -> int:
    args = parse(argv)
    print(machine())
    print(f"slab {WIDTH:g}×{WIDTH:g}×{THICKNESS:g}, quantum yield {QUANTUM_YIELD:g}, UV environment {UV_WATTS:g} W·m⁻²·sr⁻¹; "
          f"{args.pixels}×{args.pixels} pixels × {args.passes} passes of 1 spp per row")
    print(f"{'σ_fl·d':>7} {'mean ÷ exact':>16} {'noise/sample':>13} {'top 0.1 %':>10} {'largest ÷ exact':>16} "
          f"{'samples':>8} {'kernel s':>9}")
    for thickness in args.thicknesses:
        row = measure(thickness, args.pixels, args.passes)
        print(f"{row['thickness']:7.1f} {row['ratio']:8.3f} ± {row['error']:5.3f} {row['noise']:13.2f} "
              f"{100 * row['top']:9.1f}% {row['largest']:16.4g} {row['samples']:8d} {row['seconds']:9.2f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
