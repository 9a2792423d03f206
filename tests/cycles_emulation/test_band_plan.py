"""The Cycles emulation's automatic bands (`band_plan`), without Blender: the colour-error estimate is nil
where band means are exact and grows with the spectra's shape inside bands, and the plan reaches its target
within its render budget, or says it cannot."""

import numpy as np
import pytest

from addon.cycles_emulation import band_plan, bands
from addon.tracer import spectra
from addon.tracer.errors import SpectralError
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s


def comb(period=40.0, low=0.2, high=0.9) -> spectra.Spectrum:
    """An albedo that swings between `low` and `high` every `period` nm: the kind of spectrum whose
    colour hides inside wide bands (a metamer's)."""
    return spectra.Spectrum(low + (high - low) * 0.5 * (1.0 + np.sin(2.0 * np.pi * GRID / period)))


def cube_scene(albedo, light=None, g=0.0, scale=4.0):
    """A 2-unit box of optical thickness 2 × `scale` (thick by default) under a sun."""
    light_spectrum = spectra.illuminant(light) if light else None
    return s.scene(s.perspective_camera(8, 8), [s.medium(s.box_grid(), scale=scale, albedo=albedo, g=g)],
                   [s.sun([0.2, -0.3, 1.0], spectrum=light_spectrum)])


def test_grey_medium_under_one_light_needs_one_band():
    """Band weights shaped by the light render its colour exactly, and a grey albedo is the same in
    every band: one band, one Cycles render, no error."""
    plan = band_plan.plan_bands(cube_scene(0.8, "D65"))
    assert plan.bands.count == 1 and plan.renders == 1
    assert plan.estimate < 1e-6 and plan.warning is None


def test_estimate_is_nil_when_the_albedo_steps_at_a_band_edge_only():
    """A step at 500 nm under a flat light: exact with bands that have an edge at 500 nm, not with
    bands that have 500 nm inside one."""
    step = spectra.Spectrum(np.where(GRID < 500.0, 0.3, 0.9))
    scene = cube_scene(step)
    aligned = bands.Bands((360.0, 500.0, 830.0))
    straddling = bands.Bands((360.0, 450.0, 830.0))
    assert band_plan.estimate(scene, aligned) < 1e-6
    assert band_plan.estimate(scene, straddling) > 1.0


def knotted(seed=1, spacing=20.0) -> spectra.Spectrum:
    """A seeded random albedo with knots every `spacing` nm, as a designed metamer's (no period that
    a band width could alias with)."""
    knots = np.arange(360.0, 831.0, spacing)
    values = np.random.default_rng(seed).uniform(0.1, 0.95, knots.size)
    return spectra.Spectrum(np.interp(GRID, knots, values))


def test_estimate_falls_as_the_bands_narrow():
    scene = cube_scene(knotted(), "A")
    errors = [band_plan.estimate(scene, bands.split(360, 830, count)) for count in (3, 12, 48, 192)]
    assert errors[0] > band_plan.TARGET_DELTA_E
    assert all(wide > narrow for wide, narrow in zip(errors, errors[1:])), errors


def test_plan_reaches_the_target_within_the_budget():
    scene = cube_scene(comb(), "A")
    plan = band_plan.plan_bands(scene, max_renders=16)
    assert plan.estimate < band_plan.TARGET_DELTA_E and plan.warning is None
    assert plan.renders <= 16 and plan.renders == -(-plan.bands.count // 3)  # three bands per render
    assert band_plan.estimate(scene, plan.bands) == pytest.approx(plan.estimate)
    edges = np.array(plan.bands.edges)
    assert edges[0] == 360 and edges[-1] == 830 and np.all(np.diff(edges) >= 1) and np.all(edges == np.round(edges))
    # the fewest bands: one band less (either placement) misses the target
    fewer = plan.bands.count - 1
    assert band_plan.estimate(scene, bands.split(360, 830, fewer)) >= band_plan.TARGET_DELTA_E


def test_plan_says_when_the_budget_cannot_reach_the_target():
    plan = band_plan.plan_bands(cube_scene(comb(period=20.0), "A"), max_renders=1)
    assert plan.renders == 1 and plan.bands.count <= 3
    assert plan.estimate >= band_plan.TARGET_DELTA_E
    assert plan.warning and "Max Renders" in plan.warning and f"{plan.estimate:.2f}" in plan.warning


def test_bands_are_narrow_where_the_spectra_change():
    """An albedo that varies only between 500 and 580 nm gets narrower bands there than elsewhere."""
    varying = spectra.Spectrum(np.where((GRID >= 500) & (GRID < 580), comb(20.0).values, 0.6))
    plan = band_plan.plan_bands(cube_scene(varying, "D65"))
    edges = np.array(plan.bands.edges)
    widths, centres = np.diff(edges), 0.5 * (edges[1:] + edges[:-1])
    inside = (centres > 500) & (centres < 580)
    assert inside.any() and widths[inside].mean() < 0.5 * widths[~inside].mean()


def test_anisotropy_that_varies_with_wavelength_costs_one_render_per_band():
    scene = cube_scene(comb(), "A", g=s.smooth_ramp(0.0, 0.8))
    plan = band_plan.plan_bands(scene, max_renders=10)
    assert plan.renders == plan.bands.count <= 10


def test_a_budget_below_one_render_is_refused():
    with pytest.raises(SpectralError, match="at least 1 render"):
        band_plan.plan_bands(cube_scene(0.8), max_renders=0)


def test_anisotropy_and_extinction_that_vary_with_wavelength_colour_the_estimate():
    """Thin grey air under a flat light: exact with one band, unless the phase function (the report's sky:
    g rising with λ) or the extinction (Rayleigh's λ⁻⁴) changes the colour of scattered light."""
    assert band_plan.estimate(cube_scene(0.8, scale=0.2), bands.split(360, 830, 1)) < 1e-6
    by_phase = cube_scene(0.8, g=s.smooth_ramp(0.0, 0.9), scale=0.2)
    thin_blue = s.scene(s.perspective_camera(8, 8), [s.medium(s.box_grid(), scale=0.2, extinction=spectra.Spectrum(
        (GRID / 550.0) ** -4.0), albedo=1.0, phase="rayleigh")], [s.sun([0.2, -0.3, 1.0])])
    for scene in (by_phase, thin_blue):
        assert band_plan.estimate(scene, bands.split(360, 830, 1)) > 2.0
        assert band_plan.plan_bands(scene, max_renders=32).estimate < band_plan.TARGET_DELTA_E


def test_optical_thickness_picks_the_probes():
    """A thin box is judged by single scattering, a thick one by its diffuse reflectance: the thin one's
    estimate with equal bands is larger (single scattering keeps the albedo's full contrast)."""
    assert band_plan.optical_thickness(cube_scene(0.8, scale=0.2).media[0], GRID >= 360) == pytest.approx(0.4)
    equal = bands.split(360, 830, 6)
    thin, thick = (band_plan.estimate(cube_scene(knotted(), "D65", scale=scale), equal) for scale in (0.2, 10.0))
    assert thin > thick > 0.0
