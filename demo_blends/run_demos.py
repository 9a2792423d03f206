"""The main job (`make demo`): renders every demo headless and prints the figures that prove each one.

The demos are tracer scenes built in code (`scenes`, `metamers`); rendering them as .blend files
through the add-on is a later step (issue 6). Written into the output folder:
- `<name>.exr`: the raw film, multilayer (R G B A linear Rec.709, spectral.X/Y/Z, variance.X/Y/Z);
- `<name>.png`: the display image, denoised (`display`), Standard view;
- `contact_sheet.png` (all demos, captioned) with `contact_sheet.txt` (the captions as text);
- `figures.json`: every printed figure, for scripts and tests.
Every figure is computed from the raw film (`metrics`), never from the denoised image.
"""

import argparse
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from addon.tracer import image_io
from addon.tracer.render import render
from addon.tracer.scene import Scene

from . import display, metamers, metrics, scenes

WIDTH, HEIGHT = 256, 160


@dataclass(frozen=True)
class Demo:
    name: str
    title: str
    build: Callable[[int, int, int], Scene]
    spp: int
    figures: Callable[[Scene, np.ndarray], dict]
    lines: Callable[[dict], list[str]]  # what to print; the first line is also the picture's caption
    exposure: float = 0.0


# ----------------------------------------------------------------------------- what each demo prints


def _nm(value: float) -> str:
    return "white" if not np.isfinite(value) else f"{value:.0f} nm"


def _sky_lines(f: dict) -> list[str]:
    return [f"dominant: sky {_nm(f['sky away']['dominant_nm'])}, around sun {_nm(f['around sun']['dominant_nm'])}, "
            f"sun {_nm(f['sun disc']['dominant_nm'])}"] + [
        metrics.format_colour(name, f[name]) for name in ("sky away", "around sun", "sun disc", "light")]


def _frog_lines(f: dict) -> list[str]:
    lines = [f"frog {_nm(f['frog']['dominant_nm'])} under a {_nm(f['lamp']['dominant_nm'])} lamp"]
    lines += [metrics.format_colour(name, f[name]) for name in ("frog", "pad", "lamp")]
    if "energy" in f:
        e = f["energy"]
        lines.append(f"energy: emitted {e['emitted_W']:.4g} W / absorbed UV {e['absorbed_W']:.4g} W = "
                     f"{e['ratio']:.3f} (quantum yield {e['quantum_yield']}); views' intensities "
                     f"{e['intensity_min']:.2f}–{e['intensity_max']:.2f} × their mean")
    return lines


def _cube_lines(f: dict) -> list[str]:
    return [f"dE00 = {f['delta_e']:.2f} between the cubes"] + [metrics.format_colour(f"{side} cube", f[side]) for side in ("left", "right")]


def _fire_lines(f: dict) -> list[str]:
    return [f"flame CCT {f['cct_p5']:.0f}-{f['cct_p95']:.0f} K (5th-95th percentile)",
            f"bright pixels: {f['pixels']}, CCT min {f['cct_min']:.0f} K, median {f['cct_median']:.0f} K, "
            f"max {f['cct_max']:.0f} K, |Duv| ≤ {f['duv_max']:.4f} (Ohno 2013); temperatures used "
            f"{scenes.FIRE_TEMPERATURES[0]:.0f}–{scenes.FIRE_TEMPERATURES[1]:.0f} K"]


def demo_list(pair: metamers.MetamerPair) -> list[Demo]:
    white = float(pair.calibration.g(1.0))

    def cubes(scene, xyz):
        return metrics.metamerism(scene, xyz, scenes.CUBE_CENTRES, scenes.CUBE_EDGE, white)

    return [
        Demo("rayleigh_report", "Rayleigh, the report's setup", scenes.rayleigh_report, 48, metrics.rayleigh,
             _sky_lines, exposure=-1.0),
        Demo("rayleigh_true", "Rayleigh: 1/lambda^4, Rayleigh phase", scenes.rayleigh_true, 48, metrics.rayleigh,
             _sky_lines, exposure=2.0),
        Demo("fluorescent_frog", "Fluorescent frog, 275-450 nm lamp", scenes.fluorescent_frog, 32, metrics.frog,
             _frog_lines),
        Demo("fire", "Fire: blackbody 1000-2000 K", scenes.fire, 48, metrics.fire, _fire_lines),
        Demo("metamers_simple_d65", "Report's cubes under D65", scenes.metamerism_simple("D65"), 24, cubes,
             _cube_lines, exposure=0.5),
        Demo("metamers_simple_lower_half", "Report's cubes, D65 below 570 nm", scenes.metamerism_simple("D65 lower half"),
             24, cubes, _cube_lines, exposure=0.5),
        Demo("metamers_d65", "Designed metamers under D65", metamers.metamerism_designed(pair, "D65"), 24, cubes,
             _cube_lines, exposure=1.0),
        Demo("metamers_a", "Designed metamers under A", metamers.metamerism_designed(pair, "A"), 24, cubes,
             _cube_lines, exposure=1.0),
    ]


# ----------------------------------------------------------------------------- running


@dataclass
class Result:
    demo: Demo
    scene: Scene
    xyz: np.ndarray
    variance: np.ndarray
    seconds: float
    figures: dict = field(default_factory=dict)


def frog_energy(size: int, spp: int, views: int) -> dict:
    """The frog's emitted power (from renders over the sphere) against the UV power it absorbs
    (computed from its grid and the lamp, `metrics.absorbed_power`)."""
    rendered = [(view, render(view).film.xyz) for view in scenes.frog_energy_views(size, spp, views)]
    emitted, intensities = metrics.emitted_power(rendered, scenes.FROG_EMISSION)
    absorbed = metrics.absorbed_power(scenes.frog_medium(), scenes.FROG_ENERGY_LAMP)
    return {"emitted_W": emitted, "absorbed_W": absorbed, "ratio": emitted / absorbed,
            "quantum_yield": scenes.FROG_QUANTUM_YIELD, "views": views,
            "intensity_min": float(intensities.min() / intensities.mean()),
            "intensity_max": float(intensities.max() / intensities.mean())}


def run(out: Path, scale: float = 1.0, quality: float = 1.0, only=None, denoise: bool = True, log=print) -> dict:
    """Render the demos (`only`: names to keep) at `scale` × 256×160 pixels and `quality` × their
    samples per pixel; write the files into `out`; return {name: Result} plus "metamer_design"."""
    width, height = max(16, int(round(WIDTH * scale))), max(10, int(round(HEIGHT * scale)))
    samples = lambda spp: max(2, int(round(spp * quality)))
    start = time.perf_counter()
    calibration = metamers.calibrate()  # never cut: its error would bias the pair, not just add noise
    pair = metamers.metamer_pair(calibration)
    design = {"seconds": time.perf_counter() - start, "response": calibration.response.tolist(),
              "albedos": list(metamers.CALIBRATION_ALBEDOS),
              "predicted_delta_e": {light: pair.predicted_delta_e(light) for light in ("D65", "A")}}
    log(f"metamer design: calibrated the cube's response at {len(calibration.albedos)} albedos and designed "
        f"the pair in {design['seconds']:.1f} s; predicted ΔE00 {design['predicted_delta_e']['D65']:.2f} under "
        f"D65, {design['predicted_delta_e']['A']:.1f} under A")
    results = {}
    for demo in demo_list(pair):
        if only and demo.name not in only:
            continue
        scene = demo.build(width, height, samples(demo.spp))
        rendered = render(scene)
        film = rendered.film
        result = Result(demo, scene, film.xyz, film.variance, rendered.seconds)
        result.figures = demo.figures(scene, result.xyz)
        if demo.name == "fluorescent_frog":
            energy_start = time.perf_counter()
            result.figures["energy"] = frog_energy(24, samples(64), 16)
            result.figures["energy"]["seconds"] = time.perf_counter() - energy_start
        image_io.write_exr(out / f"{demo.name}.exr", film.xyz, film.rgb(), film.variance)
        image_io.write_png(out / f"{demo.name}.png",
                           display.display_rgb(film.xyz, film.variance if denoise else None), demo.exposure)
        results[demo.name] = result
        extra = f" + energy views {result.figures['energy']['seconds']:.1f} s" if "energy" in result.figures else ""
        log(f"\n{demo.name}: {demo.title} — {width}×{height}, {samples(demo.spp)} spp, {rendered.seconds:.1f} s{extra}")
        for line in demo.lines(result.figures):
            log(f"  {line}")
    results["metamer_design"] = design
    return results


def write_summary(out: Path, results: dict, seconds: float) -> None:
    """The contact sheet, its captions as text, and figures.json."""
    demos = [r for name, r in results.items() if name != "metamer_design"]
    tiles, captions = [], []
    for r in demos:
        caption = [r.demo.title, r.demo.lines(r.figures)[0]]
        rgb = display.display_rgb(r.xyz, r.variance) * 2.0 ** r.demo.exposure
        tiles.append((rgb, caption))
        captions.append(f"{r.demo.name}.png: {caption[0]} — {caption[1]}")
    drawn = display.contact_sheet(out / "contact_sheet.png", tiles, f"Spectral volume demos — {seconds:.0f} s")
    (out / "contact_sheet.txt").write_text("\n".join(captions) + "\n", encoding="utf-8")
    figures = {r.demo.name: {"seconds": r.seconds, **r.figures} for r in demos}
    figures["metamer_design"] = results["metamer_design"]
    (out / "figures.json").write_text(json.dumps(figures, indent=2, default=float), encoding="utf-8")
    if not drawn:
        print("(captions could not be drawn on the sheet; they are in contact_sheet.txt)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default: out/)")
    parser.add_argument("--scale", type=float, default=1.0, help=f"resolution scale (1.0: {WIDTH}×{HEIGHT})")
    parser.add_argument("--quality", type=float, default=1.0, help="samples per pixel scale (1.0: each demo's own)")
    parser.add_argument("--only", nargs="*", help="render only these demos")
    parser.add_argument("--no-denoise", action="store_true", help="PNGs of the raw film (the sheet is always denoised)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    args.out.mkdir(parents=True, exist_ok=True)
    results = run(args.out, args.scale, args.quality, args.only, denoise=not args.no_denoise)
    seconds = time.perf_counter() - start
    write_summary(args.out, results, seconds)
    print(f"\nall demos rendered in {seconds:.1f} s; wrote {args.out}/*.exr, *.png, contact_sheet.png, figures.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
