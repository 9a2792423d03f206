"""The denoiser (addon/tracer/denoise.py): a noisy render, denoised, is closer to a converged one."""

import numpy as np
import pytest

from addon.tracer import denoise
from addon.tracer.errors import SpectralError
from addon.tracer.render import render
from tests.support import scenes as s


def lit_box(spp: int, seed: int):
    """A 40×40 view of a lit box of smoke over a dim environment, rendered at `spp` with `seed`."""
    camera = s.perspective_camera(40, 40, fov_degrees=30.0)
    box = s.medium(s.box_grid(size=(1.6, 1.6, 1.6), density=2.0), albedo=0.9)
    scene = s.scene(camera, [box], [s.sun((1.0, 0.5, 1.0), strength=3.0), s.environment(0.2)], spp=spp, seed=seed)
    return render(scene).film


@pytest.fixture(scope="module")
def reference():
    return lit_box(1024, seed=99).rgb()


def rmse(image, reference):
    return float(np.sqrt(np.mean((np.asarray(image, dtype=np.float64) - reference) ** 2)))


@pytest.mark.parametrize("spp", [4, 32])  # without the variance (below MIN_VARIANCE_SAMPLES) and with it
def test_a_denoised_render_is_closer_to_the_converged_one(reference, spp):
    film = lit_box(spp, seed=1)
    noisy, denoised = film.rgb(), denoise.denoised_rgb(film)
    assert denoised.shape == noisy.shape and denoised.dtype == np.float32
    assert rmse(denoised, reference) < 0.7 * rmse(noisy, reference)


def test_pixels_the_variance_calls_precise_are_mostly_kept():
    film = lit_box(32, seed=1)
    noisy, denoised = film.rgb(), denoise.denoised_rgb(film)
    weight = denoise.noisy_weight(noisy, film.variance)
    corner, smoke = (slice(0, 4), slice(0, 4)), (slice(16, 24), slice(16, 24))  # environment (precise), smoke
    assert np.all(weight[corner] > 0.5) and np.all(weight[smoke] == 0.0)
    change = lambda part: np.abs(denoised[part] - noisy[part]).mean() / noisy[part].mean()
    assert change(corner) < 0.2 * change(smoke)


def test_the_noisy_weight_follows_the_relative_error():
    rgb = np.ones((12, 12, 3))
    variance = np.zeros((12, 12, 3))
    variance[:, 6:] = 1.0  # standard error 1: 100 %
    weight = denoise.noisy_weight(rgb, variance)
    assert np.all(weight[:, :3] == 1.0) and np.all(weight[:, 9:] == 0.0)


def test_a_huge_variance_beside_zero_gives_no_nan():
    """A huge variance's rounding must not leak into a zero neighbourhood: summed areas made its mean
    negative (its square root NaN) on the Rayleigh demo."""
    rng = np.random.default_rng(3)
    variance = np.zeros((64, 64, 3))
    variance[:, :20] = 10.0 ** rng.uniform(-3, 9, (64, 20, 3))
    rgb = np.full((64, 64, 3), 0.3)
    weight = denoise.noisy_weight(rgb, variance)
    assert np.isfinite(weight).all() and np.all(weight[:, 30:] == 1.0)
    assert np.isfinite(denoise.denoise(rgb, variance)).all()


@pytest.mark.parametrize("rgb, variance, quality, message", [
    (np.ones((4, 4)), None, "high", "height × width × 3"),
    (np.full((4, 4, 3), np.nan), None, "high", "non-finite"),
    (np.ones((4, 4, 3)), np.ones((4, 5, 3)), "high", "variance image is (4, 5, 3)"),
    (np.ones((4, 4, 3)), None, "best", "not one of high"),
])
def test_bad_input_is_refused_with_a_clear_error(rgb, variance, quality, message):
    with pytest.raises(SpectralError, match=message.replace("(", r"\(").replace(")", r"\)")):
        denoise.denoise(rgb, variance, quality)


def test_without_oidn_it_says_so(monkeypatch):
    monkeypatch.setattr(denoise, "_loaded", (None, "Open Image Denoise is not available on this platform (test)"))
    assert not denoise.available()
    with pytest.raises(SpectralError, match="not available on this platform"):
        denoise.denoise(np.ones((4, 4, 3)))
