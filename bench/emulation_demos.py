"""The Cycles emulation against the tracer on every demo but the fluorescent one (Cycles cannot re-emit), with
the automatic bands (the default) and with 12 equal bands (the default before them).

Each demo scene is the committed .blend, opened and exported through the add-on as `make demo` does,
rendered by the tracer and by the emulation at `--scale` × its resolution, both engines with `--quality` ×
the scene's samples. Objects of interest: the cubes' front faces (`metrics.face_mask`), the sky far from
the sun and the ring around it (`metrics.sky_regions`), the flame's bright pixels in the tracer's image
(`metrics.flame_mask`). For each, CIEDE2000 between the two engines' mean colours, the white being the
scene's sun (D65 for the glowing flame) at the tracer's 99th-percentile luminance. Beside the measured
error (largest over the objects), the band plan's estimate (`band_plan.estimate`), the Cycles renders
(each made twice) and the emulation's seconds.

    python -m bench.emulation_demos                 # half size, 2 × each scene's samples
    python -m bench.emulation_demos --only metamers_a --scale 0.25
"""

import argparse
import os
import tempfile
import time
from dataclasses import dataclass, replace

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="spectral_bench_user_"))

import bpy  # noqa: E402,F401  (after BLENDER_USER_RESOURCES: Blender reads it at start-up)
import numpy as np  # noqa: E402

from addon.cli import command as cli  # noqa: E402
from addon.cycles_emulation import band_plan  # noqa: E402
from addon.cycles_emulation.job import EmulationJob  # noqa: E402
from addon.tracer import colorimetry, spectra  # noqa: E402
from addon.tracer.render import render  # noqa: E402
from bench.measure import machine  # noqa: E402
from demo_blends import build_blends, metrics, run_demos, scenes  # noqa: E402

DEMOS = ("rayleigh_report", "rayleigh_true", "fire", "metamers_simple_d65", "metamers_simple_lower_half",
         "metamers_d65", "metamers_a")
EQUAL_BANDS = 12


def regions(name: str, scene, traced_xyz: np.ndarray) -> dict:
    """The demo's objects of interest as pixel masks."""
    if name.startswith("rayleigh"):
        sky = metrics.sky_regions(scene)
        return {key: sky[key] for key in ("sky away", "around sun")}
    if name == "fire":
        return {"flame": metrics.flame_mask(traced_xyz)}
    return {f"{side} cube": metrics.face_mask(scene.camera, centre, scenes.CUBE_EDGE)
            for side, centre in zip(("left", "right"), scenes.CUBE_CENTRES)}


def display_white(name: str, scene) -> np.ndarray:
    """The white's XYZ at Y = 1: the scene's sun, or D65 where the object glows (the fire's flame)."""
    white = colorimetry.spectrum_to_xyz(spectra.illuminant("D65").values) if name == "fire" else \
        metrics.light_xyz(metrics.sun(scene))
    return white / white[1]


@dataclass
class Emulated:
    label: str
    bands: int
    renders: int
    estimate: float
    delta_e: dict  # object → ΔE00 against the tracer
    seconds: float

    @property
    def worst(self) -> float:
        return max(self.delta_e.values())


def compare(name: str, scale: float, quality: float) -> tuple[dict, list[Emulated]]:
    """Open demo `name`, render it with the tracer and with the emulation (automatic and equal bands)."""
    where = build_blends.DEMO_SCENES[name]
    blender_scene = cli.open_scene(build_blends.HERE / where.blend, where.scene)
    blender_scene.render.resolution_percentage = max(1, round(100 * scale))
    spp = max(2, round(blender_scene.spectral.samples * quality))
    export = cli.export_context_scene()
    scene = replace(export.scene, settings=replace(export.scene.settings, spp=spp))
    traced = render(scene).film
    masks = regions(name, scene, traced.xyz)
    white = display_white(name, scene) * np.percentile(traced.xyz[..., 1], 99)
    rows = []
    for label, band_count in (("automatic", None), (f"{EQUAL_BANDS} equal", EQUAL_BANDS)):
        job = EmulationJob(blender_scene, scene, band_count=band_count, spp=spp)
        start = time.perf_counter()
        job.run()
        if not job.succeeded:
            raise SystemExit(f"{name}: emulation failed: {job.error}")
        seconds = time.perf_counter() - start
        delta_e = {key: float(colorimetry.delta_e_2000(metrics.region_xyz(job.film.xyz, mask),
                                                      metrics.region_xyz(traced.xyz, mask), white))
                   for key, mask in masks.items()}
        rows.append(Emulated(label, job.plan.bands.count, job.cycles_renders,
                             band_plan.estimate(scene, job.plan.bands), delta_e, seconds))
    return {"spp": spp, "size": (scene.camera.width, scene.camera.height)}, rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--scale", type=float, default=0.5, help="resolution scale (default 0.5: 128×80)")
    parser.add_argument("--quality", type=float, default=2.0, help="samples scale (default 2 × each scene's)")
    parser.add_argument("--only", nargs="+", choices=DEMOS, help="these demos only")
    args = parser.parse_args(argv)
    print(f"machine: {machine()}")
    print("| demo | bands | bands / Cycles renders | estimate ΔE00 | measured ΔE00 (objects) | emulation s |")
    print("| --- | --- | --- | --- | --- | --- |")
    with run_demos.addon_registered():
        for name in args.only or DEMOS:
            info, rows = compare(name, args.scale, args.quality)
            for row in rows:
                objects = ", ".join(f"{key} {value:.2f}" for key, value in row.delta_e.items())
                print(f"| {name} ({info['size'][0]}×{info['size'][1]}, {info['spp']} spp) | {row.label} | "
                      f"{row.bands} / {row.renders} | {row.estimate:.2f} | {row.worst:.2f} ({objects}) | "
                      f"{row.seconds:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
