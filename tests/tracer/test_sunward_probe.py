"""The sunward probe (docs/algorithm.md, "The sunward probe"): its chance against Beer–Lambert's law, which sun it
aims at, and the Numba kernel's images with and without probes, which must have the same expectation, with less
variance where the sun's forward peak matters. (That the NumPy backend traces the same probes, draw for draw, is
`tests/tracer/kernels/test_backends.py`'s: its scenes under a sun send them.)"""

import numpy as np
import pytest

from addon.tracer.kernels import numba_backend
from addon.tracer.kernels.lookups import probe_chance
from addon.tracer.lowering import compile_scene
from addon.tracer.probe_grid import FORWARD_G, PROBE_STRENGTH
from addon.tracer.backends import tile_arguments
from tests.support import scenes as s

EXTINCTION = 1.5


def cube_under(towards, lights=()):
    """A cube of constant density 1 (2 units wide around the origin, σ_t = EXTINCTION, HG g 0.8) under a sun from
    `towards`."""
    medium = s.medium(s.box_grid(), extinction=EXTINCTION, g=0.8)
    return s.scene(s.perspective_camera(4, 4), [medium], [s.sun(towards, 1.0), *lights])


@pytest.mark.parametrize("towards", [(0.0, 0.0, 1.0), (1.0, 0.0, 2.0)])
def test_the_chance_is_the_strength_times_the_suns_transmittance(towards):
    """At the grid's cell centres inside the cube, where the path to the sun leaves by the top face away from the
    others: −ln(a / A) = σ_t × the distance to the top along the sun's direction (Beer–Lambert; the cube's density
    is exactly 1 up to its faces' half cell, whose ramp integrates to the same). Bound: 0.01 in optical depth, the
    march's midpoint rule."""
    ks = compile_scene(cube_under(towards, [s.environment(0.1)]))
    lower, cells_per_unit = ks.lights.probe_box
    centres = lower[0] + (np.arange(ks.lights.probe_chance.shape[0]) + 0.5) / cells_per_unit[0]
    inner = centres[np.abs(centres) < 0.8]
    x, y, z = np.meshgrid(inner, inner, inner, indexing="ij")
    sun = np.asarray(towards) / np.linalg.norm(towards)
    distance = (1.0 - z) / sun[2]
    away = x + distance * sun[0] < 0.75  # leaves by the top, away from the +x face
    depth = -np.log(probe_chance(ks, x, y, z) / PROBE_STRENGTH)
    assert away.sum() > 1000
    assert np.abs(depth - EXTINCTION * distance)[away].max() < 0.01


def test_the_probe_aims_at_the_sun_chosen_most_often():
    """Two suns: the probe aims at the brighter (next-event estimation's likelier choice)."""
    scene = cube_under((0.0, 0.0, 1.0), [s.sun((1.0, 0.0, 0.0), 5.0)])
    ks = compile_scene(scene)
    assert ks.lights.probe[0] == 1
    assert ks.lights.pmf[1] > ks.lights.pmf[0]


def test_no_probe_without_a_sun_or_a_medium_that_scatters_forward():
    """No sun, no medium, or media whose phase functions have no forward peak (isotropic, backward, Rayleigh, HG g
    below FORWARD_G at every wavelength): no probe. A medium forward at some wavelengths sends them."""
    sun = s.sun((0.0, 0.0, 1.0))
    without_sun = s.scene(s.perspective_camera(4, 4), [s.medium(s.box_grid(), g=0.8)], [s.environment()])
    without_medium = s.scene(s.perspective_camera(4, 4), [], [sun])
    flat = [s.medium(s.box_grid(), g=g, name=str(g)) for g in (0.0, -0.8, FORWARD_G - 0.01)]
    rayleigh = s.medium(s.box_grid(), phase="rayleigh", name="air")
    without_peak = s.scene(s.perspective_camera(4, 4), [*flat[:3], rayleigh], [sun])
    for scene in (without_sun, without_medium, without_peak):
        assert compile_scene(scene).lights.probe[0] == -1
    partly = s.medium(s.box_grid(), g=s.smooth_ramp(0.0, FORWARD_G), name="partly")
    assert compile_scene(s.scene(s.perspective_camera(4, 4), [flat[0], partly], [sun])).lights.probe[0] == 0


# ----------------------------------------------------------------------------- the kernel with and without probes

def sunlit_cloud(chromatic=False, angle=0.0):
    """A dense cube of forward-scattering droplets (σ_t 6, albedo 0.99, HG g 0.8: the Cloud preset's optics) lit
    from the side by a sun and a faint sky, seen from above; `chromatic`: the extinction and anisotropy vary with
    the wavelength (the spectral MIS over wavelengths and strategies); `angle`: the sun's diameter (radians)."""
    if chromatic:
        medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(7.0, 5.0), albedo=0.99, g=s.smooth_ramp(0.85, 0.7))
    else:
        medium = s.medium(s.box_grid(), extinction=6.0, albedo=0.99, g=0.8)
    lights = [s.sun((1.0, 0.3, 0.4), 3.0, angle=angle), s.environment(0.05)]
    return s.scene(s.perspective_camera(12, 12, fov_degrees=24.0), [medium], lights)


def render(ks, spp, seed):
    """Per-sample mean and standard error of the image's mean Y, and the mean per-pixel variance of Y (one
    sample's)."""
    args = tile_arguments(ks, 0, (0, spp), (0, 0, ks.camera.width, ks.camera.height), seed)
    numba_backend.render_tile(*args)
    sum_y, sum_sq = args[9][..., 1], args[10][..., 1]
    pixel_mean = sum_y / spp
    pixel_variance = sum_sq / spp - pixel_mean**2
    return pixel_mean.mean(), np.sqrt(pixel_variance.mean() / (spp * pixel_mean.size)), pixel_variance.mean()


def without_probes(ks):
    return ks._replace(lights=ks.lights._replace(probe=np.full(1, -1, dtype=np.int64)))


@pytest.mark.parametrize("chromatic, angle", [(False, 0.0), (True, 0.0), (False, 0.05)],
                         ids=["grey", "chromatic", "finite-sun"])
def test_probes_leave_the_image_unbiased_and_lower_its_variance(chromatic, angle):
    """The image's mean Y with probes equals that without (independent seeds; bound: 4 combined standard errors),
    on a grey cloud, a chromatic one (MIS over wavelengths and strategies) and under a sun with a diameter (its
    estimate MIS-weighted against phase sampling at both vertices), and the mean per-pixel variance falls by more
    than 15 % (measured: by 29–40 %, three seeds for each scene)."""
    ks = compile_scene(sunlit_cloud(chromatic, angle))
    assert ks.lights.probe[0] == 0
    probed, probed_error, probed_variance = render(ks, 1024, seed=11)
    plain, plain_error, plain_variance = render(without_probes(ks), 1024, seed=12)
    assert abs(probed - plain) < 4.0 * np.hypot(probed_error, plain_error), (probed, plain)
    assert probed_variance < 0.85 * plain_variance, (probed_variance, plain_variance)
