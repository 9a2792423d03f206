"""What the farm tests share (tests/tracer/test_farm.py, test_farm_plan.py, test_distributed.py): a small scene
and the film comparison that says a farm's image is the single-process one, bit for bit."""

import numpy as np

from addon.tracer.film import Film
from tests.support import scenes as s


def small_scene(spp=24, bands=2, seed=11):
    box = s.box_grid(cells=(6, 6, 6))
    return s.scene(s.perspective_camera(12, 10, fov_degrees=25.0),
                   [s.medium(box, extinction=s.smooth_ramp(3.0, 1.0), albedo=0.8, g=0.3)],
                   [s.environment(0.5), s.sun((1.0, 0.5, 2.0), strength=2.0)], spp=spp, bands=bands, seed=seed,
                   transparent=True)


def assert_same_film(expected: Film, actual: Film):
    assert np.array_equal(expected.samples, actual.samples)
    assert np.array_equal(expected.sum_xyz, actual.sum_xyz)
    assert np.array_equal(expected.sum_sq, actual.sum_sq)
    assert np.array_equal(expected.sum_transparent, actual.sum_transparent)
    assert np.array_equal(expected.sum_light, actual.sum_light)
    assert np.array_equal(expected.sum_spectrum, actual.sum_spectrum)
    assert np.array_equal(expected.xyz, actual.xyz)
    assert np.array_equal(expected.variance, actual.variance)
    assert len(expected.peaks) == len(actual.peaks)
    for ours, theirs in zip(expected.peaks, actual.peaks):
        for part in ("xyz", "sq", "light", "spectrum"):
            assert np.array_equal(getattr(ours, part), getattr(theirs, part))
