"""The demos' proof figures, asserted on a reduced run of `make demo`: the committed .blend files
rendered headless through the add-on.

One run of every demo at half the resolution (128×80) and half the samples per pixel, shared by all
tests here; the designed metamers again at full size and samples, since the faces' noise is of the
order of the ΔE00 < 1 asserted. Every render is seeded, so each figure is the same on every run;
bounds leave a margin for noise. In parentheses: the figures of the code-built tracer scenes with
seeds 1, 2 and 3, which show the noise, then "blend:" this run's.
"""

import numpy as np
import pytest

from demo_blends import run_demos, scenes

pytestmark = pytest.mark.slow
FULL_SIZE = ("metamers_d65", "metamers_a")


@pytest.fixture(scope="module")
def figures(tmp_path_factory):
    out = tmp_path_factory.mktemp("demos")
    results = run_demos.run(out, scale=0.5, quality=0.5, log=lambda *args: None)
    results.update(run_demos.run(out, only=FULL_SIZE, log=lambda *args: None))
    assert sorted(results) == sorted(demo.name for demo in run_demos.DEMOS)
    for name, result in results.items():
        assert (out / f"{name}.exr").is_file() and (out / f"{name}.png").is_file()
        expected = (256, 160) if name in FULL_SIZE else (128, 80)
        assert (result.scene.camera.width, result.scene.camera.height) == expected
    return {name: result.figures for name, result in results.items()}


@pytest.mark.parametrize("name", ["rayleigh_report", "rayleigh_true"])
def test_rayleigh_sky_is_blue_and_around_the_sun_reddish(figures, name):
    f = figures[name]
    light, sky, ring, disc = f["light"], f["sky away"], f["around sun"], f["sun disc"]
    # Bluer than the (white, flat-spectrum) light: both chromaticity coordinates below it, a blue
    # dominant wavelength (484–486 nm) and a blue CIELAB hue (236°–239°).
    assert sky["x"] < light["x"] - 0.02 and sky["y"] < light["y"] - 0.01
    assert 470.0 < sky["dominant_nm"] < 490.0  # blend: 484, 485 nm
    assert 200.0 < sky["hue"] < 280.0
    # Redder than the light around the sun: x above it, dominant wavelength yellow-orange or beyond
    # (report's setup 590–591 nm, true Rayleigh 577 nm).
    assert ring["x"] > light["x"] + 0.03
    assert ring["dominant_nm"] > 572.0  # blend: 591, 577 nm
    if name == "rayleigh_true":  # the sun itself is reddened by the long path through the air (582–585 nm)
        assert disc["dominant_nm"] > 575.0 and disc["x"] > light["x"] + 0.1  # blend: 585 nm


def test_frog_is_green_under_a_violet_lamp(figures):
    f = figures["fluorescent_frog"]
    assert 500.0 < f["frog"]["dominant_nm"] < 570.0  # 532–535 nm; blend: 533 nm
    assert f["lamp"]["dominant_nm"] < 450.0  # 437 nm: violet, and mostly UV besides
    assert f["pad"]["dominant_nm"] < 470.0 or f["pad"]["dominant_nm"] < 0  # the white pad shows the lamp: 459–460 nm


def test_frog_emits_at_most_its_quantum_yield_of_the_absorbed_uv(figures):
    energy = figures["fluorescent_frog"]["energy"]
    # Emitted / absorbed measured 0.453–0.514 for a quantum yield of 0.5 (0.476 at full samples): noise
    # of ±7 % at these samples, and a few per cent low on average (see scenes.FROG_DENSITY); blend: 0.445.
    assert 0.8 * energy["quantum_yield"] < energy["ratio"] < 1.1 * energy["quantum_yield"]
    # The frog is transparent to its own light, so it must send the same power in every direction.
    assert energy["intensity_min"] > 0.75 and energy["intensity_max"] < 1.3


def test_dense_highlighter_ink_glows_green_and_emits_its_quantum_yield(figures):
    f = figures["highlighter_ink"]
    assert 500.0 < f["ink"]["dominant_nm"] < 540.0  # 514 nm at full size and samples
    assert 490.0 < f["diluted ink"]["dominant_nm"] < 540.0  # 502 nm
    # Optically thick (72 at the excitation peak across the glass): every bit of the lamp's violet that
    # enters is absorbed, so the dense glass glows brighter than the diluted one (Y 0.48 against 0.18).
    assert f["ink"]["Y"] > 1.5 * f["diluted ink"]["Y"]
    energy = f["energy"]
    # Emitted / absorbed 0.886 for a quantum yield of 0.9 at full samples: the dense dye's estimator
    # converges (issue 15); the bound leaves the noise of these samples.
    assert 0.85 * energy["quantum_yield"] < energy["ratio"] < 1.1 * energy["quantum_yield"]
    assert energy["intensity_min"] > 0.75 and energy["intensity_max"] < 1.3


def test_fire_colour_temperatures_lie_within_the_blackbody_temperatures(figures):
    f = figures["fire"]
    low, high = scenes.FIRE_TEMPERATURES
    assert f["pixels"] > 100
    assert low < f["cct_median"] < high  # 1750–1766 K; blend: 1760 K
    # 5th–95th percentile: 1570–2053 K here (1606–1967 K at full samples; blend: 1576–1992 K); noise
    # spreads chromaticities.
    assert f["cct_p5"] > low and f["cct_p95"] < 1.1 * high


def test_report_cubes_match_under_the_lower_half_of_d65_only(figures):
    assert figures["metamers_simple_d65"]["delta_e"] > 10.0  # 14.1–14.7; blend: 14.1
    assert figures["metamers_simple_lower_half"]["delta_e"] < 1.0  # 0.39–0.81 (0.24 at full samples); blend: 0.19


def test_designed_metamers_match_under_d65_and_differ_under_a(figures):
    assert figures["metamers_d65"]["delta_e"] < 1.0  # full size: 0.36; blend: 0.32
    assert figures["metamers_a"]["delta_e"] > 25.0  # full size: 34.7; blend: 34.8
    left, right = figures["metamers_d65"]["left"], figures["metamers_d65"]["right"]
    assert np.hypot(left["x"] - right["x"], left["y"] - right["y"]) < 0.01


def test_cloud_casts_its_shadow_on_a_ground_lit_as_the_closed_form_says(figures):
    f = figures["cloud_shadow"]
    # The lit ground (its sun ray clear of the cloud, seen clear of it) is ρ (E cos θ + π L) / π: measured
    # 1.0036–1.0054 of it with seeds 1–3 (the cloud adds a little light it scatters down, and hides a little
    # sky); the shadow keeps only the sky and the cloud's scattered light: contrast 1.97–2.04.
    assert f["lit ground"]["Y"] == pytest.approx(f["lit_closed_form_Y"], rel=0.02)
    assert 1.7 < f["contrast"] < 2.4
    assert f["shadow_pixels"] > 100 and f["lit_pixels"] > 1000
    # Grass-green, in light and in shadow (dominant 561–562 nm).
    assert 540.0 < f["shadow"]["dominant_nm"] < 580.0 and 540.0 < f["lit ground"]["dominant_nm"] < 580.0


def test_cloud_demo_film_is_transparent_where_the_sky_shows(figures):
    a = figures["cloud_shadow"]["alpha"]
    # Through the grey cloud alpha is 1 − e^(−τ) along each pixel's ray: 0.781 against 0.777 at this size (0.775
    # against 0.773 at full size); the sky alone 0.010 (pixels at the cloud's edge see some of it), the ground 1.
    assert a["cloud_pixels"] > 200 and a["sky_pixels"] > 500
    assert a["cloud_alpha"] == pytest.approx(a["cloud_closed_form"], abs=0.02)
    assert a["sky_alpha"] < 0.03 and a["ground_alpha"] > 0.99
