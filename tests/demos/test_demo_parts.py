"""Quick checks of the demos' parts that need no rendering: geometry of the pixel regions, the
metamer design, the absorbed-power integral and the display filter."""

import numpy as np

from addon.tracer import spectra
from addon.tracer.lights import strength_scale
from addon.tracer.scene import Fluorescence
from demo_blends import display, metamers, metrics, scenes
from tests.support.scenes import box_grid, medium


def test_pixel_rays_follow_the_camera():
    camera = scenes.perspective((0.0, -5.0, 0.0), (0.0, 0.0, 0.0), 33, 21, 40.0)
    origins, rays = metrics.pixel_rays(camera)
    assert np.allclose(origins, (0.0, -5.0, 0.0))
    assert np.allclose(rays[10, 16], (0.0, 1.0, 0.0))  # the centre pixel looks at the target
    corner = np.degrees(np.arctan2(rays[10, -1, 0], rays[10, -1, 1]))
    assert np.isclose(corner, np.degrees(np.arctan(np.tan(np.radians(20.0)) * 32 / 33)))


def test_face_camera_sees_only_the_face_region():
    camera = scenes.metamer_camera(256, 160)
    crop = metamers.face_camera(camera, scenes.CUBE_CENTRES[0], 24)
    inside = metrics.face_mask(crop, scenes.CUBE_CENTRES[0], scenes.CUBE_EDGE)
    assert inside.mean() > 0.85  # the window hugs the averaged region


def test_designed_pair_matches_under_d65_and_differs_under_a():
    first, second = metamers.design_pair(0.7)
    d65, a = spectra.illuminant("D65").values, spectra.illuminant("A").values
    assert metamers.delta_e(first, second, d65) < 0.01
    assert metamers.delta_e(first, second, a) > 20.0
    assert first.min() >= 0.0 and second.max() <= 0.7 + 1e-9


def test_calibration_inverts_its_response():
    calibration = metamers.Calibration(np.array(metamers.CALIBRATION_ALBEDOS),
                                       0.4 * (1.0 - np.sqrt(1.0 - np.array(metamers.CALIBRATION_ALBEDOS))))
    albedo = np.array([0.1, 0.5, 0.9, 0.96])
    assert np.allclose(calibration.albedo_for(calibration.reflectance(albedo)), albedo, atol=1e-3)


def test_absorbed_power_of_an_opaque_box_is_its_shadow_times_the_irradiance():
    fluorescence = Fluorescence(excitation=spectra.constant(1.0), emission=spectra.gaussian(540.0, 20.0),
                                       quantum_yield=1.0)
    box = medium(box_grid(cells=(8, 8, 8), size=(1.0, 2.0, 1.0)), scale=500.0, extinction=0.0,
                 fluorescence=fluorescence)
    lamp = scenes.ENERGY_LAMP
    irradiance = metrics.light_xyz(lamp)  # checks the units path too: Y of the irradiance is the strength
    assert np.isclose(irradiance[1], lamp.strength)
    total = (lamp.spectrum.values * strength_scale(lamp)).sum()
    # The trilinear density falls to zero one cell beyond the outer cell centres, so an opaque box's
    # shadow is one cell wider than its nominal size on each axis: (1 + 1/8) × (2 + 2/8).
    assert np.isclose(metrics.absorbed_power(box, lamp), total * 1.125 * 2.25, rtol=0.01)


def test_the_display_image_is_denoised_keeping_a_flat_image_and_an_edge():
    xyz = np.ones((40, 60, 3))
    xyz[:, 30:] = 5.0
    noisy = xyz * (1.0 + 0.05 * np.random.default_rng(0).standard_normal(xyz.shape))
    variance = (0.05 * xyz) ** 2
    truth, raw, clean = display.display_rgb(xyz), display.display_rgb(noisy), display.display_rgb(noisy, variance)
    assert np.abs(clean - truth).mean() < np.abs(raw - truth).mean() / 2
    columns = np.median(clean @ [0.2126, 0.7152, 0.0722], axis=0)  # the edge stays sharp
    assert columns[:29].max() < 1.2 and columns[31:].min() > 4.5
