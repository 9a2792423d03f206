"""Envmap lights: the map's orientation (checked against Blender's Environment Texture), the texel sampler and
its pdf against the map's exact integrals, renders against the uniform environment and from the bright side,
the scene file and `validation.validate`.

Statistical checks use fixed seeds and pass within 4 standard errors of the samples' own spread (a correct
estimator fails with probability ~6e-5 each), or a χ² bound stated at the test.
"""

import dataclasses

import numpy as np
import pytest
from scipy import stats

from addon.tracer import colorimetry, spectra
from addon.tracer.errors import SpectralError
from addon.tracer.kernels.envmap import row_solid_angle, texel_of
from addon.tracer.kernels.light_sampling import infinite_pdf, infinite_radiance, sample_light
from addon.tracer.kernels.lookups import on_grid
from addon.tracer.lowering import compile_scene
from addon.tracer.render import render
from addon.tracer.scene_io import load_scene, save_scene
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s
from addon.tracer.validation import validate

SIGMAS = 4.0


def random_map(rows=5, columns=7, seed=3):
    """A map of random colours with a black block (never to be sampled) and a black channel here and there."""
    rng = np.random.default_rng(seed)
    image = rng.uniform(0.0, 2.0, (rows, columns, 3)) * (rng.random((rows, columns, 3)) > 0.2)
    image[1:3, 2:4] = 0.0
    return image.astype(np.float32)


def rotation_about_z(degrees):
    c, s_ = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])


def compiled(*lights):
    return compile_scene(s.scene(s.perspective_camera(4, 4), [s.medium(s.box_grid(), extinction=1.0)], lights))


def direction(azimuth, elevation):
    """Unit vector at `azimuth` degrees from +X towards +Y, `elevation` degrees above the XY plane."""
    a, e = np.radians(azimuth), np.radians(elevation)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


# ----------------------------------------------------------------------------- orientation

# Rendered with Cycles (Blender 5.2, Environment Texture, Closest interpolation) on an 8 × 4 map: the texel
# (column, row from the top) that a camera looking along (azimuth, elevation) in degrees saw
# (tools/blender_envmap_texels.py).
BLENDER_TEXELS = [((22.5, -60.0), (3, 3)), ((22.5, 60.0), (3, 0)), ((112.5, -60.0), (1, 3)), ((112.5, 60.0), (1, 0)),
                  ((202.5, -60.0), (7, 3)), ((202.5, 60.0), (7, 0)), ((292.5, -60.0), (5, 3)), ((292.5, 60.0), (5, 0))]


@pytest.mark.parametrize("angles, texel", BLENDER_TEXELS)
def test_directions_fall_in_the_texels_blender_shows(angles, texel):
    ks = compiled(s.envmap(np.ones((4, 8, 3))))
    row, column = texel_of(ks, 0, *direction(*angles))
    assert (column, row) == texel


# The same with a Mapping node (Point) rotating the texture's vector by 90° about Z (`--mapped`): the
# Environment Texture reads the map at R · d, so `to_world` is Rᵀ.
BLENDER_MAPPED_TEXELS = [((22.5, -60.0), (1, 3)), ((22.5, 60.0), (1, 0)), ((112.5, -60.0), (7, 3)),
                         ((112.5, 60.0), (7, 0)), ((202.5, -60.0), (5, 3)), ((202.5, 60.0), (5, 0)),
                         ((292.5, -60.0), (3, 3)), ((292.5, 60.0), (3, 0))]


@pytest.mark.parametrize("angles, texel", BLENDER_MAPPED_TEXELS)
def test_to_world_is_the_transpose_of_blenders_mapping_rotation(angles, texel):
    ks = compiled(s.envmap(np.ones((4, 8, 3)), to_world=rotation_about_z(90.0).T))
    row, column = texel_of(ks, 0, *direction(*angles))
    assert (column, row) == texel


def test_to_world_turns_the_map():
    """A map turned by `to_world` shows along to_world · d what it showed along d."""
    turn = rotation_about_z(90.0) @ np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # about x, then about z
    ks = compiled(s.envmap(random_map()), s.envmap(random_map(), to_world=turn))
    rng = np.random.default_rng(2)
    d = rng.normal(size=(3, 200))
    d /= np.linalg.norm(d, axis=0)
    np.testing.assert_array_equal(np.array(texel_of(ks, 1, *(turn @ d))), np.array(texel_of(ks, 0, *d)))


# ----------------------------------------------------------------------------- the sampler

def _texel_directions(rows, columns):
    """The centre direction of every texel, in the map's frame, as (3, rows, columns)."""
    polar = np.pi * (np.arange(rows) + 0.5) / rows
    azimuth = np.pi * (1.0 - 2.0 * (np.arange(columns) + 0.5) / columns)
    p, a = np.meshgrid(polar, azimuth, indexing="ij")
    return np.array([np.sin(p) * np.cos(a), np.sin(p) * np.sin(a), np.cos(p)])


def test_the_pdf_integrates_to_one_and_is_zero_on_black_texels():
    """The pdf is constant over a texel: Σ pdf(texel) · Ω(texel) = 1 exactly, and on a uniform sphere of
    directions the mean of 4π · pdf is 1 (within 4 standard errors). The map is a scene's second envmap (its
    arrays start after the first's)."""
    image = random_map()
    ks = compiled(s.envmap(random_map(3, 4, seed=1)), s.envmap(image))
    rows, columns = image.shape[:2]
    pdf = infinite_pdf(ks, 1, *_texel_directions(rows, columns))
    solid_angle = row_solid_angle(rows, columns, np.arange(rows))[:, None]
    assert (pdf * solid_angle).sum() == pytest.approx(1.0, rel=1e-12)
    assert np.all(pdf[image.max(axis=2) == 0] == 0) and np.all(pdf[image.max(axis=2) > 0] > 0)
    d = np.random.default_rng(5).normal(size=(3, 400_000))
    values = 4 * np.pi * infinite_pdf(ks, 1, *(d / np.linalg.norm(d, axis=0)))
    assert abs(values.mean() - 1.0) <= SIGMAS * values.std() / np.sqrt(values.size)


@pytest.mark.parametrize("lam", [450.0, 550.0, 640.0])
def test_light_sampling_estimates_the_maps_integral(lam):
    """E[L(ω) / pdf(ω)] over the sampler's directions is ∫ L dω = Σ texel radiance × texel solid angle, and the
    pdf `sample_light` returns is the one `infinite_pdf` gives the same direction (MIS needs both alike)."""
    image = random_map()
    turn = rotation_about_z(30.0)
    ks = compiled(s.sun([0, 0, 1]), s.envmap(image, 1.7, to_world=turn))
    rows, columns = image.shape[:2]
    basis = 1.7 * s.envmap(image).basis_values()[:, int(lam - GRID[0])]  # λ on a grid node
    exact = ((image @ basis) * row_solid_angle(rows, columns, np.arange(rows))[:, None]).sum()
    rng = np.random.default_rng(int(lam))
    u1, u2 = rng.random(200_000), rng.random(200_000)
    wx, wy, wz, pdf, distance, falloff = sample_light(ks, 1, 0.0, 0.0, 0.0, u1, u2)
    assert np.all(pdf > 0) and distance == np.inf and falloff == 1.0
    np.testing.assert_allclose(infinite_pdf(ks, 1, wx, wy, wz), pdf, rtol=1e-12)
    estimate = infinite_radiance(ks, 1, on_grid(np.full(pdf.shape, lam)), wx, wy, wz) / pdf
    assert abs(estimate.mean() - exact) <= SIGMAS * estimate.std() / np.sqrt(estimate.size)
    assert estimate.std() / np.sqrt(estimate.size) < 0.01 * exact  # tight enough to see a bias


def test_texels_are_drawn_as_often_as_their_probability():
    """The histogram of 100 000 drawn texels against pdf × solid angle: χ² below its 1e-4 upper quantile, and
    no draw on a black texel. The map is a scene's second envmap."""
    image = random_map(rows=6, columns=9, seed=8)
    ks = compiled(s.envmap(random_map(3, 4, seed=1)), s.envmap(image))
    rows, columns = image.shape[:2]
    rng = np.random.default_rng(9)
    n = 100_000
    wx, wy, wz, _, _, _ = sample_light(ks, 1, 0.0, 0.0, 0.0, rng.random(n), rng.random(n))
    row, column = texel_of(ks, 1, wx, wy, wz)
    counts = np.bincount(row * columns + column, minlength=rows * columns).reshape(rows, columns)
    probability = infinite_pdf(ks, 1, *_texel_directions(rows, columns)) * row_solid_angle(
        rows, columns, np.arange(rows))[:, None]
    assert counts[probability == 0].sum() == 0
    expected = n * probability[probability > 0]
    chi2 = ((counts[probability > 0] - expected) ** 2 / expected).sum()
    assert chi2 < stats.chi2.ppf(1 - 1e-4, expected.size - 1)


def test_chosen_like_an_environment_of_its_mean_luminance():
    """The selection power is π × the mean luminance over the sphere, as an environment's: a constant map of
    is chosen as often as an environment of its luminance."""
    light = s.envmap(np.full((3, 4, 3), 2.0))
    ks = compiled(light, s.environment(colorimetry.spectrum_to_xyz(2.0 * light.basis_values().sum(axis=0))[1]))
    assert ks.lights.pmf == pytest.approx([0.5, 0.5], rel=1e-9)


# ----------------------------------------------------------------------------- renders

def _image_mean(film, channel):
    values = film.xyz[..., channel]
    return values.mean(), np.sqrt(film.variance[..., channel].sum()) / values.size


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_constant_map_renders_as_the_uniform_environment(backend):
    """A map of one colour everywhere is the environment of spectrum Σ rgb · basis: a scattering medium lit by
    either has the same image mean per channel (independent seeds, within 4 combined standard errors)."""
    rgb = np.array([0.8, 0.5, 0.3])
    light = s.envmap(np.tile(rgb, (4, 6, 1)), 1.5)
    spectrum = spectra.Spectrum(1.5 * rgb @ light.basis_values())
    uniform = s.environment(spectrum.integral(), spectrum=spectrum)
    uniform = dataclasses.replace(uniform, unit="radiant")
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(3.0, 1.0), albedo=0.9, g=0.4)
    films = [render(s.scene(s.perspective_camera(8, 8), [medium], [light_], spp=128, seed=seed),
                    backend=backend).film for light_, seed in ((light, 1), (uniform, 2))]
    for channel in range(3):
        (mean_a, error_a), (mean_b, error_b) = (_image_mean(film, channel) for film in films)
        assert abs(mean_a - mean_b) <= SIGMAS * np.hypot(error_a, error_b), f"{mean_a} ± {error_a}, {mean_b} ± {error_b}"


def test_a_bright_texel_block_lights_the_medium_from_its_side():
    """A map bright only around the map's +X (column centre, horizon rows) lights a dense cube from +X: seen
    from above (image x along world x) its right half is about twice as bright as its left half (far beyond
    the noise of 32 samples); turned by 180° about z, the left half is."""
    image = np.zeros((8, 16, 3), np.float32)
    image[3:5, 7:9] = 50.0
    medium = s.medium(s.box_grid(), extinction=6.0, albedo=0.9)
    halves = []
    for to_world in (None, rotation_about_z(180.0)):
        scene = s.scene(s.ortho_camera(8, 8, scale=1.2), [medium], [s.envmap(image, to_world=to_world)], spp=32)
        y = render(scene, backend="numpy").film.xyz[..., 1]
        halves.append((y[:, :4].mean(), y[:, 4:].mean()))
    (left, right), (turned_left, turned_right) = halves
    assert right > 1.5 * left and turned_left > 1.5 * turned_right  # twice as bright with this seed
    assert turned_left == pytest.approx(right, rel=0.2)


# ----------------------------------------------------------------------------- scene file and validation

def test_scene_file_round_trip(tmp_path):
    """save_scene writes the map beside scene.json (float32 .npy), and load_scene reads the same light."""
    image = random_map()
    turn = rotation_about_z(40.0)
    light = s.envmap(image, 2.5, to_world=turn, name="hdri")
    scene = s.scene(s.perspective_camera(4, 4), [s.medium(s.box_grid())], [light])
    save_scene(scene, tmp_path)
    assert (tmp_path / "lights0_image.npy").is_file()
    loaded = load_scene(tmp_path).lights[0]
    assert (loaded.kind, loaded.strength, loaded.unit, loaded.name, loaded.spectrum) == ("envmap", 2.5, "radiant",
                                                                                      "hdri", None)
    np.testing.assert_array_equal(loaded.image, image)
    np.testing.assert_array_equal(loaded.basis_values(), light.basis_values())
    np.testing.assert_array_equal(loaded.to_world, turn)
    a, b = compiled(light), compiled(loaded)
    for field in a.envmaps._fields:
        np.testing.assert_array_equal(getattr(a.envmaps, field), getattr(b.envmaps, field))


def _with(**fields):
    return dataclasses.replace(s.envmap(random_map()), **fields)


@pytest.mark.parametrize("light, message", [
    (_with(image=np.ones((4, 1, 3))), "lights[0].image: expected an array of H ≥ 1 rows, W ≥ 2 columns"),
    (_with(image=np.ones((4, 6))), "lights[0].image: expected an array"),
    (_with(image=np.ones((4, 6, 4))), "lights[0].image: expected an array"),
    (_with(image=np.full((2, 3, 3), np.nan)), "lights[0].image: must be finite and non-negative, found nan at"),
    (_with(image=-np.ones((2, 3, 3))), "lights[0].image: must be finite and non-negative, found -1"),
    (_with(image=np.zeros((2, 3, 3))), "lights[0].image: the map is black"),
    (_with(image="sky.exr"), "lights[0].image: expected an array of numbers"),
    (_with(basis=np.ones((2, GRID.size))), "lights[0].basis: expected 3 spectra"),
    (_with(basis=-np.ones((3, GRID.size))), "lights[0].basis: must be finite and non-negative"),
    (_with(basis=np.zeros((3, GRID.size))), "lights[0].image: the map is black"),
    (_with(to_world=2 * np.eye(3)), "lights[0].to_world: must be orthonormal"),
    (_with(to_world=[[1, 0], [0, 1]]), "lights[0].to_world: expected a 3 × 3 matrix"),
    (_with(unit="luminous"), "lights[0].unit: an envmap's strength multiplies its map"),
    (_with(spectrum=spectra.constant(1.0)), "lights[0].spectrum: an envmap's colour is its image and basis"),
])
def test_validate_refuses(light, message):
    with pytest.raises(SpectralError) as error:
        validate(s.scene(s.perspective_camera(4, 4), [s.medium(s.box_grid())], [light]))
    assert message in str(error.value)


def test_a_light_other_than_an_envmap_needs_a_spectrum():
    with pytest.raises(SpectralError, match=r"lights\[0\].spectrum: a sun light needs a spectrum"):
        validate(s.scene(s.perspective_camera(4, 4), [], [dataclasses.replace(s.sun([0, 0, 1]), spectrum=None)]))


def test_the_scene_file_names_a_missing_image(write_scene, scene_data):
    scene_data["lights"] = [{"kind": "envmap", "image": "missing.npy", "basis": [1.0, 1.0, 1.0]}]
    with pytest.raises(SpectralError, match=r"lights\[0\].image: image file .*missing.npy does not exist"):
        load_scene(write_scene(scene_data))
