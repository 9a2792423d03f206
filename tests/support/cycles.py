"""Cycles as the control for the exporter: the same Blender scene rendered by Cycles (CPU, in the bpy
module) and by the tracer through the add-on's export, compared on block means.

Cycles renders as the Cycles emulation sets it up (its biased volume mode and light threshold off, a 1-pixel box
filter), clamping as the engine's Light Paths ▸ Clamping says (Blender's defaults on both sides; the engine's
firefly filter, which Cycles lacks, off), with its volume bounces raised to the tracer's depth (its default, 0, is
single scattering), denoising off, and its linear Rec.709 read from an EXR; the tracer's film gives linear Rec.709
and per-pixel variances. Block differences are judged against both estimates' noise: Cycles' from two renders with
different seeds."""

import dataclasses
import math
from pathlib import Path
from typing import NamedTuple

import bpy
import numpy as np

from addon.export.scene import export_scene
from addon.tracer import colorimetry, image_io
from addon.tracer.render import render

BLOCK = 8
NOISE_BOUND = 4.0  # standard deviations per block


def cycles_rgb(scene, folder: Path, spp: int, seed: int, bounces: int = 64, alpha: bool = False) -> np.ndarray:
    """Cycles' linear Rec.709 image of `scene` (height, width, 3), top row first; with `alpha`, RGBA (height,
    width, 4), the colour premultiplied (Film ▸ Transparent)."""
    engine = scene.render.engine
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device, cycles.samples, cycles.seed, cycles.use_denoising = "CPU", spp, seed, False
    cycles.use_adaptive_sampling = False
    cycles.max_bounces = cycles.volume_bounces = cycles.transparent_max_bounces = bounces
    cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transmission_bounces = bounces
    # the engine's Light Paths ▸ Clamping (Blender's defaults: direct off, indirect 10), so both sides clamp alike;
    # none where the add-on is not registered (tests of the tracer's own scenes, whose default is no clamping)
    spectral = getattr(scene, "spectral", None)
    cycles.sample_clamp_direct = spectral.clamp_direct if spectral is not None else 0.0
    cycles.sample_clamp_indirect = spectral.clamp_indirect if spectral is not None else 0.0
    cycles.volume_biased, cycles.light_sampling_threshold, cycles.use_volume_guiding = False, 0.0, False
    cycles.pixel_filter_type, cycles.filter_width = "BOX", 1.0  # the tracer's pixel
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth, settings.color_mode = "OPEN_EXR", "32", "RGBA" if alpha else "RGB"
    scene.render.filepath = str(folder / f"cycles_{seed}.exr")
    try:
        bpy.ops.render.render(write_still=True, scene=scene.name)
    finally:
        scene.render.engine = engine
    channels = image_io.read_exr(scene.render.filepath)
    letters = "RGBA" if alpha else "RGB"
    by_letter = {name.split(".")[-1]: channels[name] for name in channels if name.split(".")[-1] in tuple(letters)}
    return np.stack([by_letter[letter] for letter in letters], axis=-1).astype(np.float64)


def blocks(image: np.ndarray) -> np.ndarray:
    h, w = image.shape[0] // BLOCK, image.shape[1] // BLOCK
    return image[:h * BLOCK, :w * BLOCK].reshape(h, BLOCK, w, BLOCK, -1).mean(axis=(1, 3))


def tracer_rgb(scene, spp: int):
    """(linear Rec.709 image, per-pixel variance of each channel's mean, export warnings) of the tracer."""
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    # Cycles has no firefly filter (biased, on by default in Blender): the comparison renders without it
    settings = dataclasses.replace(export.scene.settings, firefly_threshold=0.0)
    film = render(dataclasses.replace(export.scene, settings=settings), spp=spp).film
    to_rgb = colorimetry.xyz_to_rgb_matrix()
    variance = film.variance @ (to_rgb**2).T  # channels treated as independent: a bound, not an estimate
    return film.xyz @ to_rgb.T, variance, export.warnings


class Comparison(NamedTuple):
    delta_e: float  # CIEDE2000 between the mean colours
    z: float  # the largest block difference, in standard deviations
    traced: np.ndarray  # the tracer's mean linear Rec.709
    cycled: np.ndarray  # Cycles' mean
    warnings: list
    white_y: float  # the luminance of the ΔE's white: the tracer's 99th percentile
    images: tuple  # (the tracer's, Cycles' mean) linear Rec.709 images, top row first

    def delta_e_of(self, rgb_a, rgb_b) -> float:
        """CIEDE2000 between two linear Rec.709 colours against this comparison's white."""
        white = colorimetry.rgb_to_xyz([1.0, 1.0, 1.0]) * self.white_y
        return float(colorimetry.delta_e_2000(colorimetry.rgb_to_xyz(rgb_a), colorimetry.rgb_to_xyz(rgb_b), white))

    def __str__(self) -> str:
        return (f"ΔE00 {self.delta_e:.3f}, blocks within {self.z:.2f} σ, tracer {self.traced}, "
                f"Cycles {self.cycled}")


def compare(scene, folder: Path, tracer_spp: int, cycles_spp: int, allowance=0.0) -> Comparison:
    """Render both and compare. `allowance`: a relative difference of each block (per channel, or one
    number) admitted beside the noise (the spectral-versus-RGB difference of coloured media)."""
    traced, variance, warnings = tracer_rgb(scene, tracer_spp)
    halves = [cycles_rgb(scene, folder, cycles_spp, seed) for seed in (1, 2)]
    cycled = (halves[0] + halves[1]) / 2
    cycles_variance = blocks((halves[0] - halves[1]) ** 2 / 4)  # of the mean of two, per block of pixels
    sigma = np.sqrt(blocks(variance) / BLOCK**2 + cycles_variance / BLOCK**2
                    + (np.asarray(allowance) * blocks(traced)) ** 2)
    white_y = max(float(np.percentile(traced @ colorimetry.rgb_to_xyz_matrix()[1], 99)), 1e-6)
    z = np.abs(blocks(cycled) - blocks(traced)) / np.maximum(sigma, 1e-4 * white_y)
    result = Comparison(0.0, float(z.max()), traced.mean(axis=(0, 1)), cycled.mean(axis=(0, 1)), warnings, white_y,
                        (traced, cycled))
    return result._replace(delta_e=result.delta_e_of(result.cycled, result.traced))


def look_at(obj, target=(0.0, 0.0, 0.0)) -> None:
    """Turn a Blender object (a camera, a light: both face their local −Z) towards `target`."""
    direction = np.subtract(target, tuple(obj.location))
    obj.rotation_euler = (math.atan2(math.hypot(direction[0], direction[1]), -direction[2]), 0.0,
                          math.atan2(direction[1], direction[0]) - math.pi / 2)
