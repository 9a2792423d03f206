"""The Sky Texture model's closed forms and symmetries (`tracer.sky_model`); its agreement with Cycles' own sky
is tested in tests/addon/test_sky_texture.py."""

import math

import numpy as np
import pytest

from addon.tracer import colorimetry
from addon.tracer.sky_model import LIMB_DARKENING, MODELS, Sky, SkyParameters, sun_direction, wrapped_sun


def test_the_sun_past_the_zenith_continues_on_the_other_side():
    elevation, rotation = wrapped_sun(math.radians(100.0), math.radians(30.0))
    assert (math.degrees(elevation), math.degrees(rotation)) == pytest.approx((80.0, 210.0))
    assert wrapped_sun(math.radians(-370.0), math.radians(-30.0)) == pytest.approx((math.radians(-10.0),
                                                                                    math.radians(330.0)))
    np.testing.assert_allclose(sun_direction(SkyParameters(sun_elevation=0.0, sun_rotation=math.pi / 2)),
                               [1.0, 0.0, 0.0], atol=1e-12)


def test_a_uniform_disc_irradiance_is_its_radiance_times_its_limb_darkened_solid_angle():
    """The limb darkening 1 − 0.6 (1 − √(1 − (α/α₀)²)) averages 1 − 0.6 / 3 over a small disc (flat to
    ~α₀² ≈ 2e-5 at the default size), so a disc of one colour gives 0.8 × its radiance × 2π (1 − cos α₀)."""
    sky = Sky(SkyParameters(sun_elevation=math.radians(40.0)))
    sky.sun_bottom = sky.sun_top = colorimetry.rgb_to_xyz([2.0, 1.0, 0.5])
    solid_angle = 2.0 * math.pi * (1.0 - math.cos(0.5 * sky.sun_size))
    np.testing.assert_allclose(sky.sun_irradiance_rgb(), np.array([2.0, 1.0, 0.5]) * solid_angle
                               * (1.0 - LIMB_DARKENING / 3.0), rtol=1e-4)


@pytest.mark.parametrize("model", MODELS)
def test_the_sky_is_mirror_symmetric_about_the_suns_azimuth(model):
    """Mirrored in the vertical plane through the sun (Single Scattering's table is mirrored about a longitude
    half a texel off the sun's, so it is symmetric to that texel's size, 2π / 512)."""
    parameters = SkyParameters(model, sun_elevation=math.radians(20.0), sun_rotation=math.radians(75.0),
                               sun_direction=tuple(sun_direction(SkyParameters(sun_elevation=math.radians(20.0),
                                                                               sun_rotation=math.radians(75.0)))))
    sky = Sky(parameters)
    sun = sky.sun
    normal = np.cross(sun, [0.0, 0.0, 1.0])
    normal /= np.linalg.norm(normal)
    rng = np.random.default_rng(1)
    directions = rng.normal(size=(200, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    directions = directions[directions[:, 2] > 0.05]
    mirrored = directions - 2.0 * (directions @ normal)[:, None] * normal
    rtol = 1e-9 if model != "SINGLE_SCATTERING" else 0.02
    np.testing.assert_allclose(sky.sky_rgb(mirrored), sky.sky_rgb(directions), rtol=rtol, atol=1e-9)
