"""A diffuse floor under a small scattering box lit by a sun, rendered by our tracer and by Mitsuba 3
(`volpath`, llvm_ad_spectral; the conversion is bench/mitsuba_scene.py's, surfaces as two-sided diffuse meshes).

Mitsuba's film gives no variance, so it renders the image several times with different seeds and its per-pixel
error comes from their spread; ours comes from the film's variance. Bounds: the image mean per XYZ channel within
4.5 combined standard errors plus 0.3 % (Mitsuba's colour matching normalises XYZ about 0.1 % differently from
ours: bench/vs_mitsuba.py, `mitsuba_white`), and fewer than 5 % of the 4×4-pixel block means beyond 4 combined
standard errors (a converted scene with the shadow misplaced, the floor one-sided or the reflectance lost fails
both by far).
"""

import numpy as np
import pytest

from addon.tracer.builders import perspective
from addon.tracer.render import render
from tests.support import scenes as s

pytest.importorskip("mitsuba")

MITSUBA_RENDERS, MITSUBA_SPP, OUR_SPP = 16, 32, 512
BLOCK = 4


def floor_under_a_box():
    medium = s.medium(s.box_grid(cells=(8, 8, 8), size=(1.0, 1.0, 1.0), centre=(0.0, 0.0, 0.9)), extinction=3.0,
                      albedo=0.85, g=0.3)
    floor = s.parallelogram((-4.0, -4.0, 0.0), (8.0, 0.0, 0.0), (0.0, 8.0, 0.0), 4,
                            reflectance=s.smooth_ramp(0.3, 0.7), name="floor")
    camera = perspective(eye=(0.0, -3.5, 2.5), target=(0.0, 0.0, 0.3), width=24, height=24, fov_degrees=45.0)
    return s.scene(camera, [medium], [s.sun([0.5, -0.3, 1.0], 2.0)], [floor], spp=OUR_SPP, seed=11)


def _blocks(image):
    height, width = image.shape[:2]
    return image.reshape(height // BLOCK, BLOCK, width // BLOCK, BLOCK, -1).mean(axis=(1, 3))


@pytest.mark.slow
def test_floor_under_a_box_agrees_with_mitsuba():
    from bench.mitsuba_scene import load_mitsuba, scene_dict

    try:
        mi = load_mitsuba()
    except SystemExit as problem:
        pytest.skip(str(problem))
    scene = floor_under_a_box()
    film = render(scene).film
    ours, our_variance = film.xyz, film.variance  # variance of each pixel's mean
    mitsuba_scene = mi.load_dict(scene_dict(mi, scene, "volpath", MITSUBA_SPP))
    images = np.array([np.array(mi.render(mitsuba_scene, spp=MITSUBA_SPP, seed=seed), dtype=np.float64)
                       for seed in range(MITSUBA_RENDERS)])
    for channel in range(3):
        mean_ours = ours[..., channel].mean()
        error_ours = np.sqrt(our_variance[..., channel].sum()) / ours[..., channel].size
        per_image = images[..., channel].mean(axis=(1, 2))
        mean_theirs, error_theirs = per_image.mean(), per_image.std(ddof=1) / np.sqrt(MITSUBA_RENDERS)
        bound = 4.5 * np.hypot(error_ours, error_theirs) + 0.003 * mean_ours
        assert abs(mean_ours - mean_theirs) <= bound, (channel, mean_ours, mean_theirs, bound)
    block_ours = _blocks(ours)
    block_error_ours = np.sqrt(_blocks(our_variance)) / BLOCK
    block_images = np.array([_blocks(image) for image in images])
    block_error_theirs = block_images.std(axis=0, ddof=1) / np.sqrt(MITSUBA_RENDERS)
    difference, error = block_ours - block_images.mean(axis=0), np.hypot(block_error_ours, block_error_theirs)
    certain = error == 0  # the sky beside the floor: black in both
    np.testing.assert_array_equal(difference[certain], 0.0)
    z = np.abs(difference[~certain]) / error[~certain]
    assert np.mean(z > 4.0) < 0.05, f"{np.sum(z > 4.0)} of {z.size} block means beyond 4 standard errors"
