"""Area lights: the next-event sampler against closed forms and quadrature (uniform over an ellipse's area,
uniform in a rectangle's solid angle, or over its area where that solid angle is too small or too large to
compute), the NumPy and Numba forms of it, what `strength` means, and how often next-event estimation
chooses one.

The sampler's estimate of the irradiance at a point is the mean over N samples of I₀ · falloff · cos θ_x / pdf
(I₀ = ∫ spd dλ, the light's intensity along its normal, P/π): each test uses a fixed seed and passes
within 4 standard errors of the samples' own spread (a correct sampler fails with probability 6e-5), and
checks the bound is tight (a biased sampler fails as soon as its bias exceeds it).
"""

import copy
import dataclasses

import numpy as np
import pytest
from numba import njit

from addon.tracer import colorimetry, spectra
from addon.tracer.errors import SpectralError
from addon.tracer.kernels.light_sampling import sample_light
from addon.tracer.lights import kernel_spectrum
from addon.tracer.lowering import compile_scene
from addon.tracer.render import render
from addon.tracer.scene import Light
from addon.tracer.scene_io import load_scene
from addon.tracer.spectra import Spectrum
from addon.tracer.wavelengths import GRID
from bench.area_lights import lamp_scene, luminance_figures
from tests.support import scenes as s
from tests.tracer.test_fuzz import JUNK
from tests.tracer.test_scene_io import leaf_paths, set_path

N = 100_000
SIGMAS = 4.0
POWER = 2.0  # watts


def _rotation(seed):
    """A fixed random rotation (columns: the light's local X, Y, Z in world space)."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.sign(np.linalg.det(q))


AXES = _rotation(5)
CENTRE = np.array([0.3, -0.2, 1.5])


def area_light(shape, size_x, size_y, axes=AXES, centre=CENTRE, **fields):
    fields = {"spectrum": spectra.constant(1.0), "strength": POWER, "unit": "radiant", **fields}
    return Light(kind="area", position=centre, area_axes=axes, area_shape=shape, size_x=size_x, size_y=size_y,
                 **fields)


def _compiled(*lights):
    return compile_scene(s.scene(s.ortho_camera(), [s.medium(s.box_grid())], list(lights)))


def _irradiance_estimate(light, point, normal, seed=1):
    """Mean and standard error of the sampler's irradiance estimate at `point` on a surface facing `normal`."""
    ks = _compiled(light)
    u1, u2 = np.random.default_rng(seed).random((2, N))
    px, py, pz = (np.full(N, c) for c in point)
    wx, wy, wz, pdf, _, falloff = sample_light(ks, 0, px, py, pz, u1, u2)
    intensity = np.trapezoid(ks.lights.spd[0], GRID)
    cos_x = np.maximum(wx * normal[0] + wy * normal[1] + wz * normal[2], 0.0)
    values = intensity * falloff * cos_x / pdf
    return values.mean(), values.std() / np.sqrt(N)


def _quadrature(light, point, normal, nodes=400):
    """∫ L cos θ_x cos θ_light / d² dA over the light's shape by the midpoint rule (polar for an ellipse),
    with L = P / (π · area), written independently of the kernels."""
    a, b = 0.5 * light.size_x, 0.5 * light.size_y
    mid = (np.arange(nodes) + 0.5) / nodes
    if light.area_shape == "ellipse":
        rho, phi = np.meshgrid(mid, 2 * np.pi * mid, indexing="ij")
        x, y, weight = rho * np.cos(phi), rho * np.sin(phi), rho * (2 * np.pi / nodes**2)
        area = np.pi * a * b
    else:
        x, y = np.meshgrid(2 * mid - 1, 2 * mid - 1, indexing="ij")
        weight, area = np.full(x.shape, 4.0 / nodes**2), 4 * a * b
    X, Y, Z = (light.area_axes[:, k] / np.linalg.norm(light.area_axes[:, k]) for k in range(3))
    q = light.position + (a * x)[..., None] * X + (b * y)[..., None] * Y
    v = q - point
    d = np.linalg.norm(v, axis=-1)
    cos_light = np.maximum(v @ Z / d, 0.0)  # the light emits along its local −Z, towards −v
    cos_x = np.maximum(v @ normal / d, 0.0)
    radiance = POWER / (np.pi * area)
    return float(np.sum(radiance * cos_x * cos_light / d**2 * weight * a * b))


def _assert_within(estimate, expected):
    mean, error = estimate
    assert abs(mean - expected) <= SIGMAS * error < 0.01 * expected, f"{mean:.6f} ± {error:.6f} vs {expected:.6f}"


def test_disk_irradiance_on_its_axis_is_the_closed_form():
    """A Lambertian disk of radius r and radiance L gives E = π L r² / (r² + h²) at height h on its axis."""
    r, h = 0.7, 1.3
    light = area_light("ellipse", 2 * r, 2 * r)
    point = CENTRE - h * AXES[:, 2]  # in front: the light emits along its local −Z
    radiance = POWER / (np.pi * np.pi * r * r)
    _assert_within(_irradiance_estimate(light, point, AXES[:, 2]), np.pi * radiance * r * r / (r * r + h * h))


@pytest.mark.parametrize("shape, size_x, size_y, offset", [
    ("rectangle", 1.2, 0.5, [0.4, -0.3, -0.9]), ("rectangle", 0.8, 0.8, [0.4, -0.3, -0.9]),
    ("ellipse", 1.5, 0.4, [0.4, -0.3, -0.9]),
    ("rectangle", 1.2, 0.5, [0.5, 0.2, -0.05]),  # close: a solid angle of 4.0
    ("rectangle", 0.1, 0.05, [1.0, 2.0, -5.0]),  # a solid angle of 1.5e-4: drawn over the area
])
def test_irradiance_off_axis_matches_quadrature(shape, size_x, size_y, offset):
    """A tilted receiver off the light's axis, under a rectangle, a square and an ellipse."""
    light = area_light(shape, size_x, size_y)
    point = CENTRE + AXES @ np.array(offset)
    normal = AXES @ np.array([-0.3, 0.2, 1.0])
    normal /= np.linalg.norm(normal)
    _assert_within(_irradiance_estimate(light, point, normal), _quadrature(light, point, normal))


def test_a_rectangle_in_front_is_sampled_in_its_solid_angle():
    """Every sample from a point on a rectangle's axis estimates its radiance times the solid angle, the
    closed form Ω = 4 arcsin(ab / √((a² + h²)(b² + h²))) of a 2a × 2b rectangle at distance h: no noise."""
    a, b, h = 0.6, 0.25, 0.8
    ks = _compiled(area_light("rectangle", 2 * a, 2 * b))
    u1, u2 = np.random.default_rng(6).random((2, 1000))
    point = CENTRE - h * AXES[:, 2]
    _, _, _, pdf, _, falloff = sample_light(ks, 0, *(np.full(1000, c) for c in point), u1, u2)
    solid_angle = 4 * np.arcsin(a * b / np.sqrt((a * a + h * h) * (b * b + h * h)))
    radiance = POWER / (np.pi * 4 * a * b)
    np.testing.assert_allclose(np.trapezoid(ks.lights.spd[0], GRID) * falloff / pdf, radiance * solid_angle,
                               rtol=1e-12)


@pytest.mark.parametrize("shape", ["rectangle", "ellipse"])
@pytest.mark.parametrize("side", [0.9, 0.0])
def test_nothing_arrives_behind_the_light_or_in_its_plane(shape, side):
    """Behind it the falloff (so the radiance) and the pdf are 0; in its plane, rounding may put a point a hair in
    front, whose radiance over its pdf (the estimate) is then vanishingly small."""
    light = area_light(shape, 1.0, 2.0)
    ks = _compiled(light)
    u1, u2 = np.random.default_rng(2).random((2, 1000))
    point = CENTRE + AXES @ np.array([0.2, 3.0, side])
    with np.errstate(divide="ignore", invalid="ignore"):  # as the NumPy backend: the plane is degenerate
        pdf, _, falloff = sample_light(ks, 0, *(np.full(1000, c) for c in point), u1, u2)[3:]
    front = pdf > 0.0
    assert np.all(falloff[~front] == 0.0)
    assert np.all(falloff[front] / pdf[front] < 1e-15)


@pytest.mark.parametrize("shape", ["rectangle", "ellipse"])
@pytest.mark.parametrize("offset", [[1.5, 2.0, -1.0], [0.59, 0.2, -0.01], [0.1, 0.1, -1e-3], [0.59, 0.2, -1e-7],
                                    [10.0, -20.0, -30.0]])
def test_the_distance_reaches_a_point_of_the_shape(shape, offset):
    """Shadow rays stop at the sampled point: it lies in the light's plane, within its shape, and its
    estimate is finite, from afar (a solid angle below the bounds) to very close (above them)."""
    light = area_light(shape, 1.2, 0.5)
    ks = _compiled(light)
    u1, u2 = np.random.default_rng(3).random((2, 1000))
    point = CENTRE + AXES @ np.array(offset)
    wx, wy, wz, _, distance, falloff = sample_light(ks, 0, *(np.full(1000, c) for c in point), u1, u2)
    local = (point + distance[:, None] * np.stack([wx, wy, wz], axis=1) - CENTRE) @ AXES
    x, y = local[:, 0] / 0.6, local[:, 1] / 0.25
    assert np.abs(local[:, 2]).max() < 1e-12 * max(1.0, np.linalg.norm(offset))
    inside = x * x + y * y if shape == "ellipse" else np.maximum(x * x, y * y)
    assert inside.max() <= 1.0 + 1e-9 and inside.max() > 0.9
    assert np.all(np.isfinite(falloff) & (falloff > 0.0))


@njit
def _sample_in_numba(ks, points, u1, u2):
    out = np.zeros((points.shape[0], 6))
    for k in range(points.shape[0]):
        wx, wy, wz, pdf, distance, falloff = sample_light(ks, 0, points[k, 0], points[k, 1], points[k, 2], u1[k], u2[k])
        out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4], out[k, 5] = wx, wy, wz, pdf, distance, falloff
    return out


@pytest.mark.parametrize("shape", ["rectangle", "ellipse"])
def test_numba_and_numpy_sample_alike(shape):
    ks = _compiled(area_light(shape, 1.2, 0.5))
    rng = np.random.default_rng(4)
    points, (u1, u2) = rng.normal(size=(200, 3)), rng.random((2, 200))
    expected = np.stack(np.broadcast_arrays(*sample_light(ks, 0, *points.T, u1, u2)), axis=1)
    # The same arithmetic, but NumPy's SIMD arccos, cos and sin may differ from the C library's in the last
    # bit, which the spherical rectangle's cancellations raise to about 1e-13.
    np.testing.assert_allclose(_sample_in_numba(ks, points, u1, u2), expected, rtol=1e-11, atol=1e-12)


def test_strength_is_the_power_in_its_unit():
    """Radiant: P = π ∫ spd dλ (the spectrum is the intensity P/π along the normal); luminous: π Y(spd)."""
    shape = spectra.gaussian(400, 30) + spectra.gaussian(650, 20, 0.3)
    radiant = area_light("rectangle", 1.0, 1.0, spectrum=shape, strength=2.5)
    luminous = area_light("ellipse", 1.0, 1.0, spectrum=shape, strength=2.5, unit="luminous")
    ks = _compiled(radiant, luminous)
    assert np.pi * np.trapezoid(ks.lights.spd[0], GRID) == pytest.approx(2.5, rel=1e-12)
    assert np.pi * colorimetry.spectrum_to_xyz(ks.lights.spd[1])[1] == pytest.approx(2.5, rel=1e-12)


def test_chosen_as_often_as_a_point_light_of_the_same_power():
    """The selection proxy is the light's power over its squared distance, for a point light (4π I) as for an
    area light (P), facing the media or not."""
    point = Light(kind="point", spectrum=spectra.constant(1.0), strength=POWER / (4 * np.pi), unit="radiant",
                  position=CENTRE)
    ks = _compiled(area_light("rectangle", 0.5, 0.5), point, area_light("ellipse", 0.5, 0.5, axes=-AXES))
    assert ks.lights.pmf == pytest.approx([1 / 3] * 3, rel=1e-12)


# Emits along (0, −1, −1) / √2, at the tiny scene's medium.
AREA_LIGHT_JSON = {"kind": "area", "spectrum": 1.0, "position": [0, 2, 2], "size_x": 1.0, "size_y": 0.5,
                   "area_axes": [[1, 0, 0], [0, 1, 1], [0, -1, 1]], "strength": 30, "camera_visible": True}


# A light 1e300 away overflows its selection power's distance (as a point light's does): its pmf is NaN, which
# the kernels never count (the pixels stay finite, which is what this test checks).
@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning", "ignore:invalid value:RuntimeWarning")
@pytest.mark.parametrize("shape", ["rectangle", "ellipse"])
def test_any_value_in_an_area_light_loads_or_is_refused_and_renders_without_nan(write_scene, scene_data, shape):
    """Every field of an area light (facing the tiny scene's medium) replaced in turn by each of the fuzzer's
    junk values: the scene is refused with a SpectralError, or it renders (NumPy backend, 4 × 3 pixels,
    1 sample) finite pixels."""
    light = {**AREA_LIGHT_JSON, "area_shape": shape}
    rendered = 0
    for path in leaf_paths(light):
        for junk in JUNK:
            data = copy.deepcopy(scene_data)
            data["lights"] = [copy.deepcopy(light)]
            set_path(data["lights"][0], path, copy.deepcopy(junk))
            try:
                scene = load_scene(write_scene(data))
            except SpectralError:
                continue
            camera = dataclasses.replace(scene.camera, width=4, height=3)
            film = render(dataclasses.replace(scene, camera=camera), spp=1, backend="numpy").film
            assert np.all(np.isfinite(film.xyz)), f"{path} = {junk!r}"
            rendered += 1
    assert rendered > 20


# The smoke under a large close lamp (bench/area_lights.py, 16 × 16 pixels) as next-event estimation alone rendered
# it, before rays found area lights (kernel fbc77b7): mean Y of four renders of 16384 spp (seeds 31–34) and its
# standard error (from each render's; the ellipse's has heavy tails: one render of the four read 0.466 ± 0.014).
NEE_ONLY = {"rectangle": (0.382776, 0.00043, 0.02), "ellipse": (0.456895, 0.0036, 0.04)}


@pytest.mark.parametrize("shape", ["rectangle", "ellipse"])
def test_a_close_lamp_lights_the_smoke_as_next_event_estimation_alone_did(shape):
    """MIS of light and phase sampling (rays that meet the lamp's face add it, weighted) against the image of
    next-event estimation alone: the means agree within 4 standard errors of both, a bound under 2 % of the
    mean for the rectangle (4 % for the ellipse, whose reference is noisier), so a lamp counted twice or missed
    by either strategy fails."""
    mean, error, _ = luminance_figures(render(lamp_scene(shape, 16, 2048, seed=5)).film)
    before, before_error, tight = NEE_ONLY[shape]
    bound = 4.0 * np.hypot(error, before_error)
    assert abs(mean - before) <= bound < tight * before, f"{mean:.5f} ± {error:.5f} vs {before:.5f} ± {before_error:.5f}"


def test_a_lamp_seen_through_the_smoke_renders_as_its_emissive_twin():
    """The rectangle lamp seen from below through the smoke (camera rays meet its face, scattered rays find it by
    MIS) against an emissive black square of the same radiance in its place (a mesh light: sampled over its
    triangles' area, hit as a surface): the image means agree within 4 standard errors, a bound under 2 %."""
    from_below = lamp_scene("rectangle", 16, 1024, seed=11)
    below = np.diag([1.0, -1.0, -1.0, 1.0])  # looking up (+z) from 6 units below
    below[2, 3] = -6.0
    from_below = dataclasses.replace(from_below, camera=dataclasses.replace(from_below.camera, to_world=below))
    lamp = dataclasses.replace(from_below.lights[0], camera_visible=True)
    from_below = dataclasses.replace(from_below, lights=(lamp,))
    radiance = Spectrum(kernel_spectrum(lamp) / (lamp.size_x * lamp.size_y))
    twin = s.parallelogram(lamp.position - [1.5, 1.5, 0.0], (3.0, 0.0, 0.0), (0.0, 3.0, 0.0), reflectance=0.0,
                           emission=radiance)
    twin_scene = dataclasses.replace(from_below, lights=(), surfaces=(twin,))
    (mean, error, _), (expected, twin_error, _) = (luminance_figures(render(scene).film)
                                                    for scene in (from_below, twin_scene))
    bound = 4.0 * np.hypot(error, twin_error)
    assert abs(mean - expected) <= bound < 0.02 * expected, f"{mean:.5f} ± {error:.5f} vs {expected:.5f}"
