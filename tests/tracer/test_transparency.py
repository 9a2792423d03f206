"""Film ▸ Transparent and holdouts (`kernels/transparency.py`) against closed forms.

An orthographic camera looks straight down through a slab 1 unit thick (a box much wider than the view) of
extinction σ: a camera path reaches the background with probability T = exp(−σ), so alpha = 1 − T for a grey
slab, and for a chromatic one 1 − ∫ T(λ) ȳ(λ) dλ / ∫ ȳ(λ) dλ (the luminance-weighted mean the film uses).
Alpha's standard error comes from the spread of the pixels' alphas (independent pixels, the same expectation);
every statistical bound is 4 standard errors (a correct renderer fails one with probability about 6e-5).
"""

import dataclasses
import json

import numpy as np
import pytest

from addon.tracer import colorimetry
from addon.tracer.errors import SpectralError
from addon.tracer.render import render
from addon.tracer.scene_io import load_scene, save_scene
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s
from tests.tracer.test_transport import assert_within
from addon.tracer.validation import validate

SIGMAS = 4.0
SIGMA = 0.7  # the grey slab's extinction (its optical depth: it is 1 unit thick)
CHROMATIC = s.smooth_ramp(1.5, 0.3, 400.0, 700.0)
BACKGROUND = 1.0  # the environment's radiance (Y)


def camera():
    return s.ortho_camera(8, 8, scale=1.0, distance=2.0)  # at z = 2 looking down −z


def slab(extinction=SIGMA, albedo=0.5):
    return s.medium(s.box_grid(cells=(4, 4, 4), size=(6.0, 6.0, 1.0)), extinction=extinction, albedo=albedo)


def floor(**fields):
    """A plane under the slab, wider than the view."""
    return s.parallelogram((-4.0, -4.0, -1.5), (8.0, 0.0, 0.0), (0.0, 8.0, 0.0), 2, **fields)


def scene(media=(), surfaces=(), lights=None, **settings):
    settings = {"spp": 64, "seed": 5, "transparent": True} | settings
    lights = [s.environment(BACKGROUND)] if lights is None else lights
    return s.scene(camera(), media, lights, surfaces, **settings)


def alpha_mean_and_error(film):
    alpha = film.alpha.ravel()
    return alpha.mean(), alpha.std(ddof=1) / np.sqrt(alpha.size)


def assert_alpha(film, expected):
    mean, error = alpha_mean_and_error(film)
    assert error > 0
    assert abs(mean - expected) <= SIGMAS * error, f"alpha {mean:.5f} vs expected {expected:.5f} ± {error:.5f}"


def luminance_mean(values_on_grid):
    """∫ values ȳ dλ / ∫ ȳ dλ (the camera's 360–830 nm hold all of ȳ)."""
    return colorimetry.spectrum_to_xyz(values_on_grid)[1] / colorimetry.spectrum_to_xyz(np.ones(GRID.size))[1]


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_alpha_of_a_grey_slab_is_one_minus_its_transmittance(backend):
    assert_alpha(render(scene([slab()], backend=backend)).film, 1.0 - np.exp(-SIGMA))


@pytest.mark.parametrize("bands", [1, 2])
def test_alpha_of_a_chromatic_slab_is_one_minus_its_luminance_weighted_transmittance(bands):
    """Each band estimates its part of the spectrum; the bands' transparencies add up to the whole."""
    expected = 1.0 - luminance_mean(np.exp(-CHROMATIC.values))
    uniform = 1.0 - np.exp(-CHROMATIC.values)[GRID >= 360.0].mean()  # a plain mean over the camera's 360–830 nm
    assert abs(expected - uniform) > 0.05  # the weighting matters here
    assert_alpha(render(scene([slab(CHROMATIC)], bands=bands)).film, expected)


def test_the_colour_is_premultiplied_and_composites_over_the_background():
    """The slab rendered with Film ▸ Transparent, put "over" its background (colour + (1 − alpha) · background),
    is the slab rendered in front of it: the infinite lights still light the slab."""
    transparent = render(scene([slab()], spp=128)).film
    opaque = render(scene([slab()], spp=128, seed=6, transparent=False)).film
    background = colorimetry.spectrum_to_xyz(np.ones(GRID.size))[1] * BACKGROUND
    alpha, alpha_error = alpha_mean_and_error(transparent)
    for film in (transparent, opaque):
        assert film.variance[..., 1].sum() > 0
    composite = transparent.xyz[..., 1].mean() + (1.0 - alpha) * background
    error = (np.sqrt(transparent.variance[..., 1].sum()) / transparent.alpha.size + background * alpha_error
             + np.sqrt(opaque.variance[..., 1].sum()) / opaque.alpha.size)
    assert abs(composite - opaque.xyz[..., 1].mean()) <= SIGMAS * error
    assert transparent.xyz[..., 1].mean() < 0.8 * opaque.xyz[..., 1].mean()  # the background is gone


def test_a_surface_behind_makes_alpha_one_and_is_lit_as_without_transparency():
    """A plane of albedo ρ in a uniform environment reflects ρ L, with Film ▸ Transparent as without."""
    film = render(scene(surfaces=[floor(reflectance=0.6)])).film
    np.testing.assert_allclose(film.alpha, 1.0, atol=1e-12)
    assert_within(film, 0.6 * colorimetry.spectrum_to_xyz(np.ones(GRID.size))[1] * BACKGROUND)


def test_transparent_off_gives_alpha_one_everywhere():
    film = render(scene([slab()], transparent=False)).film
    np.testing.assert_allclose(film.alpha, 1.0, atol=1e-12)


def test_every_infinite_light_is_hidden_from_camera_rays_a_suns_disc_too():
    """Looking straight at a finite sun and the environment: nothing with Film ▸ Transparent, alpha 0."""
    lights = [s.environment(BACKGROUND), s.sun((0.0, 0.0, -1.0), 5.0, angle=0.3)]
    seen = render(scene(lights=lights, transparent=False)).film
    assert seen.xyz[..., 1].min() > 1.0  # the disc covers the view
    hidden = render(scene(lights=lights)).film
    np.testing.assert_allclose(hidden.xyz, 0.0, atol=1e-12)
    assert_alpha(hidden, 0.0)


def test_a_holdout_seen_directly_is_a_hole_of_zero_colour_and_alpha():
    film = render(scene(surfaces=[floor(reflectance=0.6, emission=2.0, holdout=True)])).film
    np.testing.assert_allclose(film.xyz, 0.0, atol=1e-12)
    assert_alpha(film, 0.0)


def test_a_holdout_without_film_transparent_is_black_and_opaque():
    film = render(scene(surfaces=[floor(reflectance=0.6, holdout=True)], transparent=False)).film
    np.testing.assert_allclose(film.xyz, 0.0, atol=1e-12)
    np.testing.assert_allclose(film.alpha, 1.0, atol=1e-12)


def test_a_holdout_behind_a_volume_leaves_the_volumes_alpha_and_light():
    """Behind the slab, a holdout cuts the hole the background would: alpha 1 − exp(−σ), and the slab's own
    scattered light stays (premultiplied colour)."""
    film = render(scene([slab()], [floor(reflectance=0.0, holdout=True)])).film
    assert_alpha(film, 1.0 - np.exp(-SIGMA))
    assert film.xyz[..., 1].mean() > 0.05


def test_holdouts_are_seen_by_indirect_rays_as_their_surface():
    """As in Cycles, a holdout is a hole for camera rays only: light scattered in the slab still reflects off the
    holdout plane below it (albedo 1) and comes back, so the slab is brighter than over a black holdout."""
    white = render(scene([slab()], [floor(reflectance=1.0, holdout=True)])).film
    black = render(scene([slab()], [floor(reflectance=0.0, holdout=True)])).film
    difference = white.xyz[..., 1].mean() - black.xyz[..., 1].mean()
    error = np.sqrt(white.variance[..., 1].sum() + black.variance[..., 1].sum()) / white.alpha.size
    assert difference > SIGMAS * error


def test_transparent_and_holdout_round_trip_through_the_scene_file(tmp_path):
    original = scene([slab()], [floor(holdout=True), floor(name="plain")])
    save_scene(original, tmp_path)
    loaded = load_scene(tmp_path)
    assert loaded.settings.transparent is True
    assert [surface.holdout for surface in loaded.surfaces] == [True, False]
    data = json.loads((tmp_path / "scene.json").read_text())
    del data["render"]["transparent"], data["surfaces"][0]["holdout"]  # a scene written before these fields
    (tmp_path / "scene.json").write_text(json.dumps(data))
    old = load_scene(tmp_path)
    assert old.settings.transparent is False and not any(surface.holdout for surface in old.surfaces)


@pytest.mark.parametrize("change, message", [
    (lambda sc: dataclasses.replace(sc, settings=dataclasses.replace(sc.settings, transparent="yes")),
     "render.transparent: expected true or false, found 'yes'"),
    (lambda sc: dataclasses.replace(sc, surfaces=(dataclasses.replace(sc.surfaces[0], holdout=1),)),
     "surfaces[0].holdout: expected true or false, found 1"),
])
def test_bad_transparent_and_holdout_values_are_refused_naming_the_field(change, message):
    with pytest.raises(SpectralError, match=message.replace("[", r"\[").replace("]", r"\]")):
        validate(change(scene(surfaces=[floor()])))
