"""The main job (`make demo`): renders every demo's .blend file headless through the add-on and prints
the figures that prove each one.

Each demo is a scene of a .blend file in `demo_blends/` (`build_blends.DEMO_SCENES`; files that are
missing are built first). It is opened in Blender-as-a-module, exported by the add-on (`addon.cli`)
and rendered by the add-on's tracer job (`render_tracer`). Written into the output folder:
- `<name>.exr`: the raw film, multilayer (passes Combined: linear Rec.709, XYZ and XYZ Variance, named as F12's:
  `ViewLayer.XYZ.X`, ...);
- `<name>.png`: the display image, denoised with Open Image Denoise (`display`), Standard view at the scene's exposure;
- `contact_sheet.png` (all demos, captioned) with `contact_sheet.txt` (the captions as text);
- `figures.json`: every printed figure, for scripts and tests.
Every figure is computed from the raw film and the exported scene (`metrics`), never from the
denoised image.
"""

import argparse
import json
import time
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

import addon
from addon.cli import command as cli
from addon.jobs.tracer_job import render_tracer
from addon.tracer import colorimetry, image_io
from addon.tracer.render import render
from addon.tracer.scene import Scene

from . import build_blends, display, metamers, metrics, scenes


@dataclass(frozen=True)
class Demo:
    """A demo: its Blender scene is `build_blends.DEMO_SCENES[name]` (file, scene, samples, exposure)."""

    name: str
    title: str
    figures: Callable[[Scene, np.ndarray], dict]
    lines: Callable[[dict], list[str]]  # what to print; the first line is also the picture's caption


# ----------------------------------------------------------------------------- what each demo prints


def _nm(value: float) -> str:
    return "white" if not np.isfinite(value) else f"{value:.0f} nm"


def _sky_lines(f: dict) -> list[str]:
    return [f"dominant: sky {_nm(f['sky away']['dominant_nm'])}, around sun {_nm(f['around sun']['dominant_nm'])}, "
            f"sun {_nm(f['sun disc']['dominant_nm'])}"] + [
        metrics.format_colour(name, f[name]) for name in ("sky away", "around sun", "sun disc", "light")]


def _energy_lines(f: dict) -> list[str]:
    if "energy" not in f:
        return []
    e = f["energy"]
    return [f"energy: emitted {e['emitted_W']:.4g} W / absorbed UV {e['absorbed_W']:.4g} W = "
            f"{e['ratio']:.3f} (quantum yield {e['quantum_yield']:.3g}); views' intensities "
            f"{e['intensity_min']:.2f}–{e['intensity_max']:.2f} × their mean"]


def _frog_lines(f: dict) -> list[str]:
    lines = [f"frog {_nm(f['frog']['dominant_nm'])} under a {_nm(f['lamp']['dominant_nm'])} lamp"]
    return lines + [metrics.format_colour(name, f[name]) for name in ("frog", "pad", "lamp")] + _energy_lines(f)


def _ink_lines(f: dict) -> list[str]:
    caption = f"ink {_nm(f['ink']['dominant_nm'])}"
    if "energy" in f:
        caption += f", emitted/absorbed {f['energy']['ratio']:.3f} (QY {f['energy']['quantum_yield']:.3g})"
    names = ("ink", "diluted ink", "pad", "lamp")
    return [caption] + [metrics.format_colour(name, f[name]) for name in names] + _energy_lines(f)


def _cube_lines(f: dict) -> list[str]:
    return [f"dE00 = {f['delta_e']:.2f} between the cubes"] + [metrics.format_colour(f"{side} cube", f[side]) for side in ("left", "right")]


def _fire_lines(f: dict) -> list[str]:
    return [f"flame CCT {f['cct_p5']:.0f}-{f['cct_p95']:.0f} K (5th-95th percentile)",
            f"bright pixels: {f['pixels']}, CCT min {f['cct_min']:.0f} K, median {f['cct_median']:.0f} K, "
            f"max {f['cct_max']:.0f} K, |Duv| ≤ {f['duv_max']:.4f} (Ohno 2013); temperatures used "
            f"{scenes.FIRE_TEMPERATURES[0]:.0f}–{scenes.FIRE_TEMPERATURES[1]:.0f} K"]


def _shadow_lines(f: dict) -> list[str]:
    return [f"shadow contrast {f['contrast']:.1f}:1 on the ground; lit ground Y {f['lit ground']['Y']:.4f}, "
            f"closed form {f['lit_closed_form_Y']:.4f}",
            f"Film Transparent: alpha through the cloud {f['alpha']['cloud_alpha']:.3f}, closed form 1 - e^-tau "
            f"{f['alpha']['cloud_closed_form']:.3f}; sky alone {f['alpha']['sky_alpha']:.4f}; ground "
            f"{f['alpha']['ground_alpha']:.4f}"] + [
        metrics.format_colour(name, f[name]) for name in ("lit ground", "shadow")]


def _cubes(scene, xyz) -> dict:
    """ΔE00 between the cubes against the white of an albedo-1 cube in this very scene."""
    white, _ = metamers.face_response(scene, 1.0)
    return metrics.metamerism(scene, xyz, scenes.CUBE_CENTRES, scenes.CUBE_EDGE, white)


DEMOS = [
    Demo("rayleigh_report", "Rayleigh, the report's setup", metrics.rayleigh, _sky_lines),
    Demo("rayleigh_true", "Rayleigh: 1/lambda^4, Rayleigh phase", metrics.rayleigh, _sky_lines),
    Demo("fluorescent_frog", "Fluorescent frog, 275-450 nm lamp", metrics.frog, _frog_lines),
    Demo("highlighter_ink", "Highlighter ink, dense and diluted 50x", metrics.ink, _ink_lines),
    Demo("fire", "Fire: blackbody 1000-2000 K", metrics.fire, _fire_lines),
    Demo("metamers_simple_d65", "Report's cubes under D65", _cubes, _cube_lines),
    Demo("metamers_simple_lower_half", "Report's cubes, D65 below 570 nm", _cubes, _cube_lines),
    Demo("metamers_d65", "Designed metamers under D65", _cubes, _cube_lines),
    Demo("metamers_a", "Designed metamers under A", _cubes, _cube_lines),
    Demo("cloud_shadow", "A cloud's shadow on a ground plane", metrics.cloud_shadow, _shadow_lines),
]


# ----------------------------------------------------------------------------- running


@dataclass
class Result:
    demo: Demo
    scene: Scene  # the tracer scene the add-on exported from the .blend
    xyz: np.ndarray
    variance: np.ndarray
    alpha: np.ndarray  # 1 everywhere unless the scene's film is transparent
    seconds: float
    exposure: float
    figures: dict = field(default_factory=dict)


def fluorescence_energy(body, box, size: int, spp: int, views: int) -> dict:
    """A fluorescent body's emitted power (from renders of `body`, an exported medium inside `box`, over
    the sphere) against the UV power it absorbs (from its grid and the lamp, `metrics.absorbed_power`)."""
    rendered = [(view, render(view).film.xyz) for view in scenes.energy_views(body, box, size, spp, views)]
    emitted, intensities = metrics.emitted_power(rendered, body.fluorescence.emission)
    absorbed = metrics.absorbed_power(body, scenes.ENERGY_LAMP)
    return {"emitted_W": emitted, "absorbed_W": absorbed, "ratio": emitted / absorbed,
            "quantum_yield": body.fluorescence.quantum_yield, "views": views,
            "intensity_min": float(intensities.min() / intensities.mean()),
            "intensity_max": float(intensities.max() / intensities.mean())}


# The fluorescent body whose energy balance each fluorescent demo proves: demo → (medium, its box).
ENERGY_BODIES = {"fluorescent_frog": ("frog", scenes.FROG_BOX),
                 "highlighter_ink": ("ink", scenes.ink_box(scenes.INK_CENTRES[0]))}


@contextmanager
def addon_registered():
    """The add-on registered in this `bpy` for the duration (its settings are read from the files)."""
    addon.register()
    try:
        yield
    finally:
        addon.unregister()


def render_demo(demo: Demo, blends: Path, scale: float, quality: float) -> Result:
    """Open the demo's .blend, export its scene through the add-on at `scale` × its resolution and
    render it at `quality` × its samples per pixel."""
    where = build_blends.DEMO_SCENES[demo.name]
    blender_scene = cli.open_scene(blends / where.blend, where.scene)
    blender_scene.render.resolution_percentage = max(1, round(100 * scale))
    spp = max(2, round(blender_scene.spectral.samples * quality))
    export = cli.export_context_scene()
    for warning in export.warnings:
        print(f"warning: {warning}")
    scene = replace(export.scene, settings=replace(export.scene.settings, spp=spp))
    rendered = render_tracer(scene)
    film = rendered.film
    return Result(demo, scene, film.xyz, film.variance, film.alpha, rendered.seconds,
                  blender_scene.view_settings.exposure)


def run(out: Path, scale: float = 1.0, quality: float = 1.0, only=None, denoise: bool = True,
        blends: Path = build_blends.HERE, log=print) -> dict:
    """Render the demos' .blend files in `blends` (`only`: demo names to keep) at `scale` × their
    resolution and `quality` × their samples per pixel; write the files into `out`; return
    {name: Result}. Missing .blend files are built first."""
    wanted = [demo for demo in DEMOS if not only or demo.name in only]
    needed = {build_blends.DEMO_SCENES[demo.name].blend for demo in wanted}
    missing = sorted(needed - {path.name for path in blends.glob("*.blend")})
    if missing:
        log(f"building {', '.join(missing)} (python -m demo_blends.build_blends)")
        build_blends.build(blends, [name.removesuffix(".blend") for name in missing], log=log)
    results = {}
    with addon_registered():
        for demo in wanted:
            result = render_demo(demo, blends, scale, quality)
            figures_start = time.perf_counter()
            result.figures = demo.figures(result.scene, result.xyz)
            if demo.name in ENERGY_BODIES:
                body, box = ENERGY_BODIES[demo.name]
                result.figures["energy"] = fluorescence_energy(metrics.medium(result.scene, body), box, 24,
                                                               max(2, round(64 * quality)), 16)
            if result.scene.settings.transparent:
                result.figures["alpha"] = metrics.alpha_coverage(result.scene, result.alpha)
            figures_seconds = time.perf_counter() - figures_start
            film_rgb = colorimetry.xyz_to_rgb(result.xyz)
            image_io.write_exr(out / f"{demo.name}.exr", result.xyz, film_rgb, result.variance, result.alpha)
            image_io.write_png(out / f"{demo.name}.png",
                               display.display_rgb(result.xyz, result.variance if denoise else None), result.exposure)
            results[demo.name] = result
            camera = result.scene.camera
            log(f"\n{demo.name}: {demo.title} — {build_blends.DEMO_SCENES[demo.name].blend} "
                f"scene {build_blends.DEMO_SCENES[demo.name].scene!r}, {camera.width}×{camera.height}, "
                f"{result.scene.settings.spp} spp, render {result.seconds:.1f} s, figures {figures_seconds:.1f} s")
            for line in demo.lines(result.figures):
                log(f"  {line}")
    return results


def write_summary(out: Path, results: dict, seconds: float) -> None:
    """The contact sheet, its captions as text, and figures.json."""
    demos = list(results.values())
    tiles, captions = [], []
    for r in demos:
        caption = [r.demo.title, r.demo.lines(r.figures)[0]]
        rgb = display.display_rgb(r.xyz, r.variance) * 2.0 ** r.exposure
        tiles.append((rgb, caption))
        captions.append(f"{r.demo.name}.png: {caption[0]} — {caption[1]}")
    drawn = display.contact_sheet(out / "contact_sheet.png", tiles, f"Spectral volume demos — {seconds:.0f} s")
    (out / "contact_sheet.txt").write_text("\n".join(captions) + "\n", encoding="utf-8")
    figures = {r.demo.name: {"seconds": r.seconds, **r.figures} for r in demos}
    (out / "figures.json").write_text(json.dumps(figures, indent=2, default=float), encoding="utf-8")
    if not drawn:
        print("(captions could not be drawn on the sheet; they are in contact_sheet.txt)")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default: out/)")
    parser.add_argument("--scale", type=float, default=1.0, help="resolution scale (1.0: each scene's, 256×160)")
    parser.add_argument("--quality", type=float, default=1.0, help="samples per pixel scale (1.0: each scene's own)")
    parser.add_argument("--only", nargs="*", choices=[demo.name for demo in DEMOS], help="render only these demos")
    parser.add_argument("--no-denoise", action="store_true", help="PNGs of the raw film (the sheet is always denoised)")
    parser.add_argument("--blends", type=Path, default=build_blends.HERE,
                        help="folder of the .blend files (default: demo_blends/)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    args.out.mkdir(parents=True, exist_ok=True)
    results = run(args.out, args.scale, args.quality, args.only, denoise=not args.no_denoise, blends=args.blends)
    seconds = time.perf_counter() - start
    write_summary(args.out, results, seconds)
    rendering = sum(result.seconds for result in results.values())
    print(f"\nall demos done in {seconds:.1f} s (rendering {rendering:.1f} s of it); wrote {args.out}/*.exr, *.png, "
          "contact_sheet.png, figures.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
