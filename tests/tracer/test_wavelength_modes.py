"""Every wavelength-sampling mode renders the same image (in expectation) for every scene.

Each scene is rendered with a fixed seed in every mode; the image means of X, Y and Z of every pair of
modes must agree within 4.5 standard errors of their difference (the errors from the films' own per-pixel
variance). With 15 pairs × 3 channels per scene, an unbiased renderer fails a scene with probability
about 3e-4; a mode that misses light (zero density where light reaches the camera) fails at once.
"""

import itertools

import numpy as np
import pytest

from addon.tracer import colorimetry, spectra
from addon.tracer.glow import stefan_boltzmann_radiance
from addon.tracer.render import render
from addon.tracer.lowering import compile_scene
from addon.tracer.scene import WAVELENGTH_SAMPLINGS, BlackbodyEmission, Fluorescence, Glow, Light
from addon.tracer.planck import planck_radiance
from addon.tracer.wavelength_modes import light_mode_sources
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s

SIGMAS = 4.5


def _blue_light_on_a_hot_slab():
    """A blue-only sun on a 1500 K emitting slab: the red glow is outside the light's spectrum."""
    box = s.box_grid(cells=(8, 8, 8), size=(4.0, 4.0, 1.0))
    hot = BlackbodyEmission(temperature=s.box_grid(size=(6.0, 6.0, 3.0), density=1500.0), intensity=30.0)
    blue = s.sun([0, 0, 1], spectrum=spectra.gaussian(450, 15))
    return [s.medium(box, extinction=0.5, albedo=0.5, emission=hot)], [blue]


def _blue_light_on_a_glowing_slab():
    """A blue-only sun on a slab glowing red (a band and a 1200 K black body) that hardly attenuates."""
    box = s.box_grid(cells=(8, 8, 8), size=(4.0, 4.0, 1.0))
    red = Glow(spectrum=spectra.gaussian(650, 15, 0.2), blackbody=1e-4, temperature_offset=1200.0)
    blue = s.sun([0, 0, 1], spectrum=spectra.gaussian(450, 15))
    return [s.medium(box, extinction=0.05, albedo=0.5, glow=red)], [blue]


def _sky_below_the_horizon():
    """A sky with a blue zenith and a white horizon, seen looking down (below the horizon: all horizon)."""
    sky = Light(kind="sky", spectrum=spectra.gaussian(450, 15), strength=1.0, horizon_spectrum=spectra.constant(1.0))
    return [], [sky]


def _fluorophore(box):
    excitation = spectra.window(spectra.constant(2.0), 300, 360)
    return s.medium(box, extinction=0.2, albedo=0.5,
                    fluorescence=Fluorescence(excitation, spectra.gaussian(550, 20), 1.0))


def _lamp(spectrum):
    """A UV environment of 10 W·m⁻²·sr⁻¹."""
    return Light(kind="environment", spectrum=spectrum, strength=10.0, unit="radiant")


def _uv_lamp_with_a_visible_tail():
    """A UV lamp with a weak violet tail on a fluorophore emitting green: the green is in no light's spectrum."""
    lamp = spectra.window(spectra.constant(1.0), 300, 360) + spectra.window(spectra.constant(0.01), 360, 400)
    return [_fluorophore(s.box_grid(size=(4.0, 4.0, 1.0)))], [_lamp(lamp)]


def _uv_lamp_zero_from_359_nm():
    """A UV lamp with nothing in the camera's 360–830 nm range: only the fluorescence is visible."""
    lamp = spectra.window(spectra.constant(1.0), 300, 359)
    return [_fluorophore(s.box_grid(size=(4.0, 4.0, 1.0)))], [_lamp(lamp)]


SCENES = {
    "blue light on a 1500 K slab": _blue_light_on_a_hot_slab,
    "blue light on a glowing slab": _blue_light_on_a_glowing_slab,
    "sky below the horizon": _sky_below_the_horizon,
    "UV lamp with a visible tail and a fluorophore": _uv_lamp_with_a_visible_tail,
    "UV lamp zero from 359 nm and a fluorophore": _uv_lamp_zero_from_359_nm,
}


def _mean_and_error(film):
    """Image mean of X, Y, Z and the standard error of each."""
    pixels = film.xyz.shape[0] * film.xyz.shape[1]
    return film.xyz.mean(axis=(0, 1)), np.sqrt(film.variance.sum(axis=(0, 1))) / pixels


@pytest.mark.parametrize("name", SCENES)
def test_every_wavelength_sampling_mode_agrees_with_every_other(name):
    media, lights = SCENES[name]()
    results = {}
    for mode in WAVELENGTH_SAMPLINGS:
        scene = s.scene(s.ortho_camera(8, 8, scale=2.0), media, lights, spp=128, seed=7, wavelength_sampling=mode)
        results[mode] = _mean_and_error(render(scene).film)
    assert results["colour"][0][1] > 10 * results["colour"][1][1], "the scene must be visibly lit"
    for (a, (mean_a, error_a)), (b, (mean_b, error_b)) in itertools.combinations(results.items(), 2):
        bound = SIGMAS * np.hypot(error_a, error_b)
        assert np.all(np.abs(mean_a - mean_b) <= bound), (
            f"{a} {mean_a} ± {error_a} vs {b} {mean_b} ± {error_b} (XYZ)")


def test_the_light_mode_follows_a_glow():
    """A glowing medium is a source of the `light` mode: its glow at its hottest temperature, here its band
    plus Cycles' black body (Planck's law at luminance blackbody · σT⁴/π)."""
    media, lights = _blue_light_on_a_glowing_slab()
    sources = light_mode_sources(compile_scene(s.scene(s.ortho_camera(), media, lights)))
    assert len(sources) == 2 and sources[1][1] == 1.0
    planck = planck_radiance(GRID, 1200.0)
    blackbody = planck * stefan_boltzmann_radiance(1200.0) / colorimetry.spectrum_to_xyz(planck)[1]
    expected = spectra.gaussian(650, 15, 0.2).values + 1e-4 * blackbody
    np.testing.assert_allclose(sources[1][0].values, expected, rtol=2e-4)
