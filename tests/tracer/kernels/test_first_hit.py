"""The first-hit kernel (`kernels/first_hit.py`): the Numba kernel against its NumPy oracle (`numpy_backend.first_hits`),
and its depths and normals against closed forms."""

import numpy as np
import pytest

from addon.tracer.kernels import first_hit, numpy_backend
from addon.tracer.kernels.layout import FIRST_HIT_VALUES
from addon.tracer.lowering import compile_scene
from tests.support import scenes as s


def _scene(camera, surfaces):
    return s.scene(camera, lights=[s.environment()], surfaces=surfaces, spp=4)


def _hits(scene, find, samples=(0, 4), seed=3):
    ks = compile_scene(scene)
    width, height = scene.camera.width, scene.camera.height
    count = samples[1] - samples[0]
    values, triangles = np.empty((height, width, count, FIRST_HIT_VALUES)), np.empty((height, width, count), np.int64)
    find(ks.camera, ks.surfaces, np.int64(0), np.int64(0), np.int64(width), np.int64(height), np.int64(samples[0]),
         np.int64(samples[1]), np.uint64(seed), values, triangles)
    return values, triangles, ks


def tilted_plane(name="tilted"):
    """A square through the origin tilted 30° about the x axis (normal (0, −sin 30°, cos 30°))."""
    angle = np.radians(30.0)
    v = np.array([0.0, np.cos(angle), np.sin(angle)]) * 4.0
    return s.parallelogram(-np.array([2.0, 0.0, 0.0]) - v / 2, (4.0, 0.0, 0.0), v, 3, name=name)


@pytest.mark.parametrize("camera", [s.perspective_camera(9, 7, 40.0), s.ortho_camera(9, 7, scale=5.0)],
                         ids=["perspective", "orthographic"])
def test_numba_kernel_equals_its_numpy_oracle(camera):
    """Same rays, same triangles: the hierarchy walk and brute force find the same hits, to rounding."""
    scene = _scene(camera, [tilted_plane(), s.parallelogram((-0.5, -3.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))])
    fast, fast_triangles, _ = _hits(scene, first_hit.first_hits, (2, 7))
    slow, slow_triangles, _ = _hits(scene, numpy_backend.first_hits, (2, 7))
    np.testing.assert_array_equal(fast_triangles, slow_triangles)
    assert (fast_triangles >= 0).any() and (fast_triangles < 0).any()  # hits and misses both compared
    np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-12)


def test_depth_and_distance_of_a_plane_facing_the_camera_are_the_closed_forms():
    """A camera 6 above the plane z = 0, looking down: every hit's depth is 6, its distance 6 / cos of the ray's
    angle to the view axis (the ray's direction from the pixel's film point), and its normal faces up."""
    scene = _scene(s.perspective_camera(8, 6, 50.0), [s.parallelogram((-20, -20, 0), (40, 0, 0), (0, 40, 0))])
    values, triangles, ks = _hits(scene, first_hit.first_hits)
    assert (triangles >= 0).all()
    np.testing.assert_allclose(values[..., 0], 6.0, rtol=1e-12)
    # distance ≥ depth, equal on the axis only; depth / distance is the cosine: at most the corner ray's
    half = np.tan(np.radians(25.0))
    corner_cos = 1.0 / np.sqrt(1.0 + half**2 * (1.0 + (6 / 8) ** 2))
    cosine = values[..., 0] / values[..., 1]
    assert (cosine <= 1.0 + 1e-12).all() and (cosine >= corner_cos - 1e-12).all()
    np.testing.assert_allclose(values[..., 2:], np.broadcast_to([0.0, 0.0, 1.0], values[..., 2:].shape), atol=1e-12)


def test_normal_of_a_tilted_plane_faces_the_camera_and_misses_are_inf():
    angle = np.radians(30.0)
    scene = _scene(s.ortho_camera(10, 10, scale=6.0), [tilted_plane()])
    values, triangles, _ = _hits(scene, first_hit.first_hits)
    hit = triangles >= 0
    assert hit.any() and (~hit).any()
    np.testing.assert_allclose(values[hit][:, 2:], np.broadcast_to([0.0, -np.sin(angle), np.cos(angle)],
                                                                   (hit.sum(), 3)), atol=1e-12)
    assert np.isinf(values[~hit][:, :2]).all() and (values[~hit][:, 2:] == 0).all()
    # orthographic: the distance is the depth, the camera's height above the hit point
    np.testing.assert_allclose(values[hit][:, 0], values[hit][:, 1])
