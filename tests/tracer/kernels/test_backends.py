"""The NumPy backend against the Numba kernel, and the NumPy backend on its own (no Numba, determinism).

The two backends implement one algorithm, so on every scene below their images must estimate the same
values. Statistical comparisons use independent renders (different seeds) and bounds stated at each
test; with the same seed the backends trace the same paths (same random streams, same draw order, the
same arithmetic), so their images agree pixel by pixel, which is a far stronger check than any
statistical bound. For that the NumPy backend renders in a child process whose NumPy uses the C
library's elementary functions, as Numba does (`tests.support.libm_numpy`): NumPy's SIMD `cbrt`, `log`
or `exp` on AVX2/AVX-512 machines differ in the last bit, which sends some paths down other branches.

Images are tiny (8×8 pixels) and each film is rendered in one unit per band, so that the NumPy backend
traces all of a film's paths as one wavefront.
"""

import dataclasses
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from addon.tracer import colorimetry, spectra
from addon.tracer.lowering import compile_scene
from addon.tracer.film import Film
from addon.tracer.light_passes import light_categories
from addon.tracer.kernels import numpy_backend
from addon.tracer.render import band_scenes, render, render_unit
from addon.tracer.scene import BlackbodyEmission, Fluorescence, Glow, Grid, Light, Medium
from addon.tracer.wavelengths import GRID
from tests.support import libm_numpy
from tests.support import scenes as s

REPO = Path(__file__).resolve().parents[3]
SPP = 128
SIGMAS = 4.0


# ----------------------------------------------------------------------------- scenes

def blob_grid(cells=16, size=2.0, blobs=4, seed=1) -> Grid:
    """A cube of `cells`³ cells spanning `size` around the origin, holding a few Gaussian blobs (peak 1):
    strongly heterogeneous, so the majorant grid's blocks differ."""
    rng = np.random.default_rng(seed)
    x = ((np.arange(cells) + 0.5) / cells - 0.5) * size
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    values = np.zeros((cells,) * 3)
    for _ in range(blobs):
        centre = rng.uniform(-0.3, 0.3, 3) * size
        radius = rng.uniform(0.1, 0.25) * size
        values += np.exp(-((X - centre[0]) ** 2 + (Y - centre[1]) ** 2 + (Z - centre[2]) ** 2) / (2 * radius**2))
    index_to_world = s.box_grid(cells=(cells,) * 3, size=(size,) * 3).index_to_world
    return Grid((values / values.max()).astype(np.float32), index_to_world)


def grey_furnace():
    return s.scene(s.perspective_camera(8, 8), [s.medium(s.box_grid(), extinction=2.0)], [s.environment()])


def chromatic():
    """Chromatic extinction, albedo and anisotropy: the spectral MIS over 4 wavelengths at work."""
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(4.0, 0.4), albedo=s.smooth_ramp(0.95, 0.6),
                      g=s.smooth_ramp(-0.3, 0.8))
    return s.scene(s.perspective_camera(8, 8), [medium], [s.environment(0.5), s.sun([1, 0.5, 1], 2.0)])


def heterogeneous():
    """Gaussian blobs with a density-dependent albedo, a finite sun and an environment, in two bands, keeping the
    spectral image (20 nm bins; the bands split at 595 nm, inside a bin)."""
    albedo = np.stack([spectra.constant(value).values for value in (0.99, 0.9, 0.7)])
    medium = Medium(name="blobs", density=blob_grid(), density_scale=8.0, extinction=spectra.constant(1.0),
                    albedo_densities=np.array([0.0, 0.5, 1.0]), albedo_table=albedo,
                    anisotropy=spectra.constant(0.5))
    lights = [s.sun([0.3, 0.4, 1.0], 3.0, angle=0.3), s.environment(0.3)]
    return s.scene(s.ortho_camera(8, 8, scale=2.4), [medium], lights, bands=2, spectrum=True, spectrum_start=365.0,
                   spectrum_end=825.0, spectrum_step=20.0)


def fluorescence():
    """A forward-scattering slab with a UV-excited fluorophore under a UV environment and a weak visible sun, keeping
    the spectral image (the default bins): the camera paths and the fluorescent sub-paths send sunward probes."""
    slab = s.box_grid(cells=(16, 16, 4), size=(6.0, 6.0, 0.4))
    fluorophore = Fluorescence(spectra.window(spectra.constant(3.0), 300, 340), spectra.gaussian(550, 20), 0.8)
    medium = s.medium(slab, extinction=0.5, albedo=0.9, g=0.5, fluorescence=fluorophore)
    uv = Light(kind="environment", spectrum=spectra.window(spectra.constant(1.0), 280, 350), strength=580.0,
               unit="radiant")  # 580 W·m⁻²·sr⁻¹: the radiance of the old rule for a strength-1 UV light
    return s.scene(s.ortho_camera(8, 8, scale=2.0), [medium], [uv, s.sun([0, 0.3, 1], 0.3)], spectrum=True)


def blackbody():
    """A hot, scattering medium with a varying temperature (1500–2500 K) and no lights (so no next-event
    estimation)."""
    hot = BlackbodyEmission(temperature=blob_grid(seed=2), temperature_scale=1000.0, temperature_offset=1500.0)
    medium = s.medium(s.box_grid(), extinction=1.5, albedo=0.4, emission=hot)
    return s.scene(s.perspective_camera(8, 8), [medium], [])


def glow():
    """A thin, chromatic scattering medium glowing (a band and a tinted 1000–3000 K black body) under a delta sun:
    its majorant is the glow's floor, so most tentative collisions are null."""
    hot = Glow(spectrum=spectra.gaussian(620, 30, 0.3), blackbody=1e-6, tint=s.smooth_ramp(0.3, 1.0),
               temperature=blob_grid(seed=4), temperature_scale=2000.0, temperature_offset=1000.0)
    medium = s.medium(blob_grid(seed=5), extinction=s.smooth_ramp(0.6, 0.2), albedo=0.8, g=0.4, glow=hot)
    return s.scene(s.perspective_camera(8, 8), [medium], [s.sun([0.2, -0.5, 1.0], 0.5)])


def rayleigh():
    """Rayleigh phase under a sky, one wavelength per path drawn uniformly."""
    sky = Light(kind="sky", spectrum=s.smooth_ramp(2.0, 0.3), strength=1.0,
                horizon_spectrum=s.smooth_ramp(0.6, 1.0))
    medium = s.medium(s.box_grid(), extinction=1.5, albedo=0.95, phase="rayleigh")
    return s.scene(s.perspective_camera(8, 8), [medium], [sky], wavelengths_per_path=1,
                   wavelength_sampling="uniform")


def two_media():
    """A chromatic Henyey–Greenstein box overlapping a Rayleigh blob grid of another resolution."""
    box = s.medium(s.box_grid(), extinction=s.smooth_ramp(2.0, 1.0), albedo=0.9, g=0.6, name="box")
    blobs = s.medium(blob_grid(cells=12, size=1.6, seed=3), scale=3.0, albedo=0.8, phase="rayleigh", name="blobs")
    return s.scene(s.perspective_camera(8, 8), [box, blobs], [s.environment(0.5), s.sun([-1, 0.2, 1])])


def point_and_spot():
    """A point and a spot light outside the medium (inside it, the 1/d² of next-event estimation gives an
    estimator of infinite variance, and image means no statistical bound can hold)."""
    medium = s.medium(s.box_grid(), extinction=0.8, albedo=0.9, g=0.3)
    point = Light(kind="point", spectrum=spectra.constant(1.0), strength=10.0, position=np.array([0.0, -1.8, 1.6]))
    spot = Light(kind="spot", spectrum=s.smooth_ramp(0.2, 1.0), strength=20.0, position=np.array([2.0, 0.0, 2.0]),
                 spot_direction=np.array([-1.0, 0.0, -1.0]), spot_size=np.radians(40), spot_blend=0.3)
    return s.scene(s.perspective_camera(8, 8), [medium], [point, spot])


def area_lights():
    """A rectangle beside the medium, tilted towards it, a chromatic disk above it facing down (both outside it,
    for the reason `point_and_spot` gives), and a small square above it facing up, which the camera sees."""
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(1.2, 0.6), albedo=0.9, g=0.3)
    tilted = np.column_stack([[0.0, 1.0, 0.0], [0.6, 0.0, -0.8], [-0.8, 0.0, -0.6]])  # emits along (0.8, 0, 0.6)
    rectangle = Light(kind="area", spectrum=spectra.constant(1.0), strength=40.0, position=np.array([-2.0, 0.0, -0.5]),
                      area_axes=tilted, size_x=1.5, size_y=0.8)
    disk = Light(kind="area", spectrum=s.smooth_ramp(0.2, 1.0), strength=30.0, position=np.array([0.3, 0.0, 1.8]),
                 area_axes=np.eye(3), area_shape="ellipse", size_x=1.2, size_y=1.2)
    seen = Light(kind="area", spectrum=s.smooth_ramp(1.0, 0.3), strength=2.0, position=np.array([0.5, 0.4, 1.5]),
                 area_axes=np.diag([1.0, -1.0, -1.0]), size_x=0.5, size_y=0.4, camera_visible=True)
    return s.scene(s.perspective_camera(8, 8), [medium], [rectangle, disk, seen])


def envmap():
    """A turned envmap of random colours with a black block, beside a sun: grey extinction (MIS with residual
    tracking) and a chromatic albedo. Its basis is smooth ramps: `spectra.emission_from_rgb` fits its spectra
    with NumPy's elementary functions, whose last bits differ in the NumPy backend's child process."""
    rng = np.random.default_rng(6)
    image = rng.uniform(0.0, 3.0, (6, 10, 3))
    image[2:4, 3:6] = 0.0
    turn = np.array([[0.0, -0.6, 0.8], [1.0, 0.0, 0.0], [0.0, 0.8, 0.6]])
    medium = s.medium(s.box_grid(), extinction=2.5, albedo=s.smooth_ramp(0.95, 0.7), g=0.4)
    basis = (s.smooth_ramp(0.1, 1.0), spectra.constant(0.6), s.smooth_ramp(1.0, 0.05))
    light = s.envmap(image, 0.8, basis=basis, to_world=turn)
    return s.scene(s.perspective_camera(8, 8), [medium], [light, s.sun([1, 0, 1], 1.0)])


def surfaces():
    """A chromatic floor cutting through a chromatic medium, and a triangle above them casting a shadow, under a
    finite sun and an environment: free flights end at surfaces inside the medium's box, shadow rays stop at them,
    BRDF sampling finds the infinite lights (MIS)."""
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(1.5, 0.5), albedo=0.9, g=0.3)
    floor = s.parallelogram((-3.0, -3.0, -0.4), (6.0, 0.0, 0.0), (0.0, 6.0, 0.0), 3,
                            reflectance=s.smooth_ramp(0.8, 0.3), name="floor")
    blocker = s.parallelogram((-0.5, -2.0, 1.5), (1.2, 0.0, 0.3), (0.0, 1.5, 0.0), 1, reflectance=0.5,
                              name="blocker")
    lights = [s.sun([0.3, 0.2, 1.0], 2.0, angle=0.2), s.environment(0.4)]
    return s.scene(s.perspective_camera(8, 8, fov_degrees=50.0), [medium], lights, [floor, blocker])


def mesh_light():
    """An emissive, reflecting square above a grey medium and a floor, the only light: mesh-light sampling and
    BRDF and phase sampling finding the emitter, combined by MIS (grey paths: residual tracking)."""
    medium = s.medium(blob_grid(), scale=2.0, extinction=1.0, albedo=s.smooth_ramp(0.95, 0.6), g=0.2)
    floor = s.parallelogram((-3.0, -3.0, -1.2), (6.0, 0.0, 0.0), (0.0, 6.0, 0.0), 2, reflectance=0.7, name="floor")
    lamp = s.parallelogram((-1.5, 1.5, 2.0), (1.5, 0.0, 0.0), (0.0, -3.0, 0.4), 2, reflectance=0.3,
                           emission=s.smooth_ramp(1.0, 3.0), name="lamp")
    return s.scene(s.perspective_camera(8, 8, fov_degrees=50.0), [medium], [], [floor, lamp])


def transparent_holdout():
    """Film ▸ Transparent over a chromatic medium, a floor under half of it and a holdout under a quarter, under
    a finite sun and an environment: camera paths that escape or reach the holdout add their transparency."""
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(1.5, 0.5), albedo=0.9, g=0.3)
    floor = s.parallelogram((-3.0, -3.0, -0.4), (3.0, 0.0, 0.0), (0.0, 6.0, 0.0), 2, reflectance=0.6, name="floor")
    hole = s.parallelogram((0.0, -3.0, -0.6), (3.0, 0.0, 0.0), (0.0, 3.0, 0.0), 1, reflectance=0.5, holdout=True,
                           name="hole")
    lights = [s.sun([0.3, 0.2, 1.0], 2.0, angle=0.2), s.environment(0.4)]
    return s.scene(s.perspective_camera(8, 8, fov_degrees=50.0), [medium], lights, [floor, hole], transparent=True)


def textured_indirect_only():
    """A textured floor (Linear, Repeat, its image repeated twice across it) under a chromatic medium, and a square
    the camera does not see (Indirect Only) between them, under a finite sun and an environment."""
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(1.5, 0.5), albedo=0.9, g=0.3)
    rng = np.random.default_rng(5)
    floor = s.parallelogram((-3.0, -3.0, -0.4), (6.0, 0.0, 0.0), (0.0, 6.0, 0.0), 2, name="floor",
                            image=rng.uniform(0.0, 1.0, (5, 3, 3)))
    floor = dataclasses.replace(floor, texture=dataclasses.replace(floor.texture, uv=floor.texture.uv * 2.0))
    hidden = s.parallelogram((-2.0, -2.0, 0.8), (2.5, 0.0, 0.0), (0.0, 3.0, 0.0), 1, reflectance=0.7,
                             camera=False, name="hidden")
    lights = [s.sun([0.3, 0.2, 1.0], 2.0, angle=0.2), s.environment(0.4)]
    return s.scene(s.perspective_camera(8, 8, fov_degrees=50.0), [medium], lights, [floor, hidden])


LIGHT_PASSES = ("Emission", "Environment", "Volume Direct", "Volume Indirect")


def light_passes():
    """Every light pass and clamping (both limits low enough to scale many samples) over a chromatic medium, a floor,
    an emissive lamp the camera sees, a finite sun and an environment: the camera paths take their marks and split
    their light (`kernels/light_split.py`)."""
    medium = s.medium(s.box_grid(), extinction=s.smooth_ramp(1.5, 0.5), albedo=0.9, g=0.3)
    floor = s.parallelogram((-3.0, -3.0, -0.4), (6.0, 0.0, 0.0), (0.0, 6.0, 0.0), 2, reflectance=0.6, name="floor")
    lamp = s.parallelogram((-1.5, 1.5, 1.6), (1.5, 0.0, 0.0), (0.0, -3.0, 0.4), 1, reflectance=0.3,
                           emission=s.smooth_ramp(1.0, 3.0), name="lamp")
    lights = [s.sun([0.3, 0.2, 1.0], 2.0, angle=0.2), s.environment(0.4)]
    return s.scene(s.perspective_camera(8, 8, fov_degrees=60.0), [medium], lights, [floor, lamp],
                   passes=LIGHT_PASSES, clamp_direct=3.0, clamp_indirect=0.5)


def fluorescent_light_passes():
    """The fluorescent slab asking for every light pass: the sub-paths' light goes to the marks by the depth of
    their collisions."""
    return dataclasses.replace(fluorescence(), settings=dataclasses.replace(fluorescence().settings,
                                                                            passes=LIGHT_PASSES))


SCENES = {build.__name__: build for build in (grey_furnace, chromatic, heterogeneous, fluorescence, blackbody,
                                              glow, rayleigh, two_media, point_and_spot, area_lights, envmap,
                                              surfaces, mesh_light, transparent_holdout, light_passes,
                                              fluorescent_light_passes, textured_indirect_only)}


def render_film(scene, backend, seed, spp=SPP) -> Film:
    """All samples of every band in one `render_unit` call each (one wavefront for the NumPy backend), with the
    spectral image where the scene keeps one."""
    camera = scene.camera
    bands = band_scenes(scene)
    categories = light_categories(scene.settings)
    film = Film(camera.width, camera.height, len(bands), categories, bands[0].wavelengths.spectrum_edges)
    for band, kernel_scene in enumerate(bands):
        sums = render_unit(kernel_scene, band, (0, spp), (0, 0, camera.width, camera.height), seed, backend,
                           categories, film.bins > 0)
        film.add(band, 0, 0, *sums[:2], spp, *sums[2:])
    return film


# Renders every scene's NumPy film (seed 2) in the child process and pickles them.
NUMPY_FILMS = """
import pickle, sys
from tests.tracer.kernels.test_backends import SCENES, render_film
films = {name: render_film(build(), "numpy", 2) for name, build in SCENES.items()}
with open(sys.argv[1], "wb") as file:
    pickle.dump(films, file)
"""


def numpy_films(folder: Path) -> dict:
    """name -> the NumPy backend's film with seed 2, rendered with the C library's elementary functions."""
    path = folder / "numpy_films.pickle"
    libm_numpy.run(NUMPY_FILMS, str(path))
    with open(path, "rb") as file:
        return pickle.load(file)


@pytest.fixture(scope="module")
def films(tmp_path_factory):
    """name -> {(backend, seed): film}: Numba with seeds 1 and 2 rendered here on first use, NumPy with
    seed 2 (every scene at once, in the child process)."""
    from_numpy = numpy_films(tmp_path_factory.mktemp("numpy_films"))
    cache = {}

    def get(name):
        if name not in cache:
            scene = SCENES[name]()
            cache[name] = {("numba", seed): render_film(scene, "numba", seed) for seed in (1, 2)}
            cache[name]["numpy", 2] = from_numpy[name]
        return cache[name]

    return get


def image_mean_and_error(film, channel):
    """Mean of one XYZ channel over the image and the standard error of that mean."""
    values = film.xyz[..., channel]
    return values.mean(), np.sqrt(film.variance[..., channel].sum()) / values.size


# ----------------------------------------------------------------------------- agreement

@pytest.mark.parametrize("name", SCENES)
def test_image_means_agree(films, name):
    """Independent renders (Numba seed 1, NumPy seed 2) estimate the same image mean per channel:
    |Δ| ≤ 4·sqrt(se₁² + se₂²), the standard errors from each film's own per-pixel variance. For
    unbiased, roughly normal estimates a correct pair fails with probability ~6e-5 per channel."""
    numba_film, numpy_film = films(name)["numba", 1], films(name)["numpy", 2]
    for channel in range(3):
        mean_a, error_a = image_mean_and_error(numba_film, channel)
        mean_b, error_b = image_mean_and_error(numpy_film, channel)
        bound = SIGMAS * np.hypot(error_a, error_b)
        assert error_a > 0 and error_b > 0
        assert abs(mean_a - mean_b) <= bound, f"channel {channel}: {mean_a:.5f} ± {error_a:.5f} (numba) vs " \
                                              f"{mean_b:.5f} ± {error_b:.5f} (numpy)"


@pytest.mark.parametrize("name", SCENES)
def test_pixels_agree(films, name):
    """Per-pixel z-scores of independent renders, z = Δ / sqrt(var₁ + var₂): fewer than 1% of the pixel
    values beyond |z| > 4 (about 0.006% expected for normal estimates; the margin absorbs the heavy
    tails of 128-sample variance estimates). Pixels whose values are certain (variance 0 in both)
    must be equal."""
    numba_film, numpy_film = films(name)["numba", 1], films(name)["numpy", 2]
    difference = numba_film.xyz - numpy_film.xyz
    variance = numba_film.variance + numpy_film.variance
    certain = variance == 0
    np.testing.assert_allclose(difference[certain], 0.0, atol=1e-12)
    z = np.abs(difference[~certain]) / np.sqrt(variance[~certain])
    assert np.mean(z > SIGMAS) < 0.01, f"{np.sum(z > SIGMAS)} of {z.size} pixel values with |z| > 4"


@pytest.mark.parametrize("name", SCENES)
def test_same_seed_traces_the_same_paths(films, name):
    """With the same seed both backends draw the same numbers in the same order for every path and do
    the same arithmetic with the same elementary functions, so every pixel value agrees, up to
    rounding differences far below what one path traced differently would change (rtol 1e-12)."""
    numba_film, numpy_film = films(name)["numba", 2], films(name)["numpy", 2]
    np.testing.assert_array_equal(numpy_film.samples, numba_film.samples)
    close = np.isclose(numpy_film.sum_xyz, numba_film.sum_xyz, rtol=1e-12, atol=1e-300)
    assert close.all(), f"only {np.mean(close):.1%} of pixel values agree"
    close = np.isclose(numpy_film.sum_transparent, numba_film.sum_transparent, rtol=1e-12, atol=1e-300)
    assert close.all(), f"only {np.mean(close):.1%} of pixel transparencies agree"
    # the light categories (differences of marks: an absolute tolerance at the pixel's scale)
    scale = np.abs(numba_film.sum_xyz).max(initial=0.0)
    np.testing.assert_allclose(numpy_film.sum_light, numba_film.sum_light, rtol=1e-12, atol=1e-12 * scale)
    assert numba_film.sum_spectrum.shape == numpy_film.sum_spectrum.shape
    close = np.isclose(numpy_film.sum_spectrum, numba_film.sum_spectrum, rtol=1e-12, atol=1e-300)
    assert close.all(), f"only {np.mean(close):.1%} of spectral bins agree"


@pytest.mark.parametrize("name", [name for name, build in SCENES.items() if build().settings.spectrum])
def test_spectra_agree_and_integrate_to_the_films_xyz(films, name):
    """Independent renders (Numba seed 1, NumPy seed 2) estimate the same image mean per spectral bin within 4
    standard errors (from the spread of the two films' pixels; a correct pair fails a bin with probability ~6e-5),
    and each film's bins, integrated against the tracer's XYZ weights, give its image mean Y within 2 % (the bins'
    discretisation and the parts of the spectrum outside them, 360–365 and 825–830 nm or 360–380 and 780–830 nm)."""
    numba_film, numpy_film = films(name)["numba", 1], films(name)["numpy", 2]
    means = []
    for film in (numba_film, numpy_film):
        values = film.spectrum.reshape(-1, film.bins)
        means.append((values.mean(axis=0), values.std(axis=0, ddof=1) / np.sqrt(values.shape[0])))
        weights = colorimetry.xyz_weights()[1]
        per_bin = [np.trapezoid(weights[(GRID >= lo) & (GRID <= hi)], GRID[(GRID >= lo) & (GRID <= hi)])
                   for lo, hi in zip(film.spectrum_edges[:-1], film.spectrum_edges[1:])]
        assert abs(values.mean(axis=0) @ per_bin - film.mean_xyz[1]) <= 0.02 * film.mean_xyz[1]
    (mean_a, error_a), (mean_b, error_b) = means
    bound = SIGMAS * np.hypot(error_a, error_b)
    assert np.all((np.abs(mean_a - mean_b) <= bound) | (bound == 0)), np.max(np.abs(mean_a - mean_b) / bound)


def test_grey_furnace_returns_the_environment(films):
    """Albedo 1 in a uniform environment: each backend's image is the environment's XYZ (within 4 σ)."""
    expected = colorimetry.spectrum_to_xyz(np.ones(GRID.size))
    for key in (("numba", 1), ("numpy", 2)):
        for channel in range(3):
            mean, error = image_mean_and_error(films("grey_furnace")[key], channel)
            assert abs(mean - expected[channel]) <= SIGMAS * error, f"{key}: {mean:.5f} vs {expected[channel]:.5f}"


# ----------------------------------------------------------------------------- the NumPy backend alone

NO_NUMBA = """
import importlib.abc, json, sys

class NoNumba(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "numba" or name.startswith("numba."):
            raise ImportError(f"{name} is blocked for this test")

sys.meta_path.insert(0, NoNumba())
from addon.tracer.render import render
from tests.support.scenes import box_grid, environment, medium, perspective_camera, scene

tiny = scene(perspective_camera(4, 3), [medium(box_grid(), albedo=0.8, g=0.3)], [environment()], spp=3, seed=7)
result = render(tiny, backend="numpy", threads=2)
try:
    import addon.tracer.kernels.numba_backend
    blocked = False
except ImportError:
    blocked = True
print(json.dumps({"sum_xyz": result.film.sum_xyz.tolist(), "numba_loaded": "numba" in sys.modules,
                  "blocked": blocked}))
"""


def test_numpy_backend_runs_without_numba():
    """In a process where `import numba` fails, the NumPy backend renders, and gives the same image as
    here (where the shared math is compiled by Numba for the other backend, but called plainly here)."""
    done = subprocess.run([sys.executable, "-c", NO_NUMBA], cwd=REPO, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(REPO)})
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["blocked"] and not report["numba_loaded"]
    tiny = s.scene(s.perspective_camera(4, 3), [s.medium(s.box_grid(), albedo=0.8, g=0.3)], [s.environment()],
                   spp=3, seed=7)
    here = render(tiny, backend="numpy").film.sum_xyz
    np.testing.assert_allclose(report["sum_xyz"], here, rtol=1e-12)


@pytest.fixture(scope="module")
def kernel_scene():
    return compile_scene(heterogeneous())


def test_same_seed_gives_the_same_image(kernel_scene):
    first = render_unit(kernel_scene, 0, (0, 4), (0, 0, 8, 8), 3, "numpy")
    second = render_unit(kernel_scene, 0, (0, 4), (0, 0, 8, 8), 3, "numpy")
    np.testing.assert_array_equal(first[0], second[0])
    np.testing.assert_array_equal(first[1], second[1])
    assert np.any(first[0] != render_unit(kernel_scene, 0, (0, 4), (0, 0, 8, 8), 4, "numpy")[0])


def test_split_samples_and_tiles_sum_to_the_whole(kernel_scene):
    """Each path's numbers depend only on (seed, band, pixel, sample): any split of the work adds up."""
    whole = render_unit(kernel_scene, 0, (0, 6), (0, 0, 8, 8), 3, "numpy")
    first = render_unit(kernel_scene, 0, (0, 2), (0, 0, 8, 8), 3, "numpy")
    second = render_unit(kernel_scene, 0, (2, 6), (0, 0, 8, 8), 3, "numpy")
    right = render_unit(kernel_scene, 0, (0, 6), (5, 2, 3, 6), 3, "numpy")
    for index in range(2):
        np.testing.assert_allclose(first[index] + second[index], whole[index], rtol=1e-12)
        np.testing.assert_allclose(right[index], whole[index][2:, 5:], rtol=1e-12)


def test_chunks_do_not_change_the_image(kernel_scene, monkeypatch):
    """Tracing the tile's paths in many small chunks (boundaries inside pixels) gives the same sums."""
    whole = render_unit(kernel_scene, 0, (0, 6), (0, 0, 8, 8), 3, "numpy")
    monkeypatch.setattr(numpy_backend, "CHUNK_PATHS", 50)
    chunked = render_unit(kernel_scene, 0, (0, 6), (0, 0, 8, 8), 3, "numpy")
    for index in range(2):
        np.testing.assert_allclose(chunked[index], whole[index], rtol=1e-12)


def test_every_scene_gives_the_kernel_the_same_argument_types():
    """Media, lights, surfaces, textures, light passes and spectral bins change the kernel's arguments' values and
    shapes, never their Numba types (dtype, dimensions, layout, writeability): one compiled kernel renders every
    scene, where a second type would compile a second kernel of minutes (a textured surface's read-only RGB lattice
    once did)."""
    import numba

    from addon.tracer.backends import tile_arguments

    kinds = {}
    for name, build in SCENES.items():
        scene = build()
        arguments = tile_arguments(compile_scene(scene), 0, (0, 1), (0, 0, 1, 1), 1,
                                   light_categories(scene.settings), scene.settings.spectrum)
        kinds.setdefault(str(numba.typeof(arguments)), []).append(name)
    assert len(kinds) == 1, list(kinds.values())
