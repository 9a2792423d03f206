"""Light units: a luminous strength is the luminance Y with the render's colour matching functions, a
radiant one the radiometric quantity in watts over the whole spectrum (docs/scene-format.md)."""

import numpy as np
import pytest

from addon.tracer import colorimetry, spectra
from addon.tracer.lowering import compile_scene
from addon.tracer.errors import SpectralError
from addon.tracer.render import render
from addon.tracer.scene import Light
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s

UV_LAMP = spectra.window(spectra.constant(1.0), 300, 350)  # nothing visible (x̄, ȳ, z̄ start at 360 nm)


def _lights(unit):
    """One light of each kind, strength 2.5 in `unit`, with a violet-and-red spectrum."""
    shape = spectra.gaussian(400, 30) + spectra.gaussian(650, 20, 0.3)
    return [s.sun([0, 0, 1], 2.5, spectrum=shape),
            s.environment(2.5, shape),
            Light(kind="sky", spectrum=shape, strength=2.5, horizon_spectrum=spectra.constant(1.0)),
            Light(kind="point", spectrum=shape, strength=2.5, position=np.array([0.0, 0.0, 3.0])),
            Light(kind="spot", spectrum=shape, strength=2.5, position=np.array([0.0, 0.0, 3.0]),
                  spot_direction=np.array([0.0, 0.0, -1.0]))], shape


def _compiled(lights, **settings):
    return compile_scene(s.scene(s.ortho_camera(), [s.medium(s.box_grid())], lights, **settings))


def test_radiant_strength_is_the_integral_over_the_whole_spectrum():
    lights, _ = _lights("radiant")
    lights = [Light(**{**light.__dict__, "unit": "radiant"}) for light in lights]
    ks = _compiled(lights)
    assert np.allclose(np.trapezoid(ks.lights.spd, GRID, axis=1), 2.5, rtol=1e-12)
    assert np.trapezoid(ks.lights.spd_horizon[2], GRID) == pytest.approx(2.5, rel=1e-12)


@pytest.mark.parametrize("cmf", colorimetry.CMF_NAMES)
def test_luminous_strength_is_the_luminance_with_the_chosen_colour_matching_functions(cmf):
    lights, _ = _lights("luminous")
    ks = _compiled(lights, cmf=cmf)
    assert np.allclose(colorimetry.spectrum_to_xyz(ks.lights.spd, cmf)[:, 1], 2.5, rtol=1e-12)
    assert colorimetry.spectrum_to_xyz(ks.lights.spd_horizon[2], cmf)[1] == pytest.approx(2.5, rel=1e-12)


def test_strength_one_illuminant_a_renders_luminance_one_with_wyman1():
    """Seen directly, a strength-1 illuminant A environment has Y = 1 with `wyman1` (it was 1.0051, the
    CIE 1931 normalisation); the render's 4 standard errors are below 0.3 %."""
    lamp = s.environment(1.0, spectra.illuminant("A"))
    film = render(s.scene(s.perspective_camera(16, 16), [], [lamp], spp=256, seed=3, cmf="wyman1",
                          wavelength_sampling="light")).film
    mean = film.xyz[..., 1].mean()
    error = np.sqrt(film.variance[..., 1].sum()) / film.xyz[..., 1].size
    assert abs(mean - 1.0) <= 4 * error < 0.003, f"Y {mean:.5f} ± {error:.5f}"


def test_a_uv_lamp_in_watts_is_chosen_for_next_event_estimation():
    """The light-choice proxy of a lamp with no visible part is that of an equal-energy light of the same
    radiant power, not zero (a zero probability would lose its fluorescence)."""
    lamp = Light(kind="environment", spectrum=UV_LAMP, strength=580.0, unit="radiant")
    ks = _compiled([lamp, s.environment(1.0)])
    assert ks.lights.pmf == pytest.approx([0.5, 0.5], rel=1e-12)


def test_a_luminous_light_with_no_visible_part_is_refused_naming_the_light():
    lamp = Light(kind="environment", spectrum=UV_LAMP, strength=1.0)
    with pytest.raises(SpectralError, match=r'lights\[1\]\.spectrum: the spectrum has no visible part .*"unit": "radiant"'):
        _compiled([s.environment(1.0), lamp])
