"""The spectral image (`spectral_film`, `kernels/spectrum_bins.py`, `Film.spectrum`) and the spectral EXR
(`image_io.spectral_exr`): its bins and their checks, a known emitter's spectral radiance per bin, the same XYZ as the
film's through the CIE colour matching functions, any number of bands, and the file read back by OpenImageIO and by
colour-science's reader of the layout of Fichet et al. 2021.

Statistical bounds are stated at each test; pixels are independent estimates, so the standard error of an image mean is
the spread of its pixels over √pixels. Renders use the NumPy backend (the Numba kernel's agreement with it, path by
path, is tests/tracer/kernels/test_backends.py's).
"""

import dataclasses

import colour
import numpy as np
import pytest

from addon.tracer import image_io, spectral_film
from addon.tracer.errors import SpectralError
from addon.tracer.film import Film
from addon.tracer.lowering import compile_scene
from addon.tracer.render import render
from addon.tracer.scene import Light
from addon.tracer.validation import check_settings
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s

SIGMAS = 5.0  # per bin and channel; with ~40 bins, a correct render fails one with probability ~2e-5
# A smooth emitter spectrum, given in watts (absolute units): a broad Gaussian on a floor.
SMOOTH = {"type": "table", "wavelengths": GRID.tolist(),
          "values": (0.3 + np.exp(-0.5 * ((GRID - 560.0) / 70.0) ** 2)).tolist()}


def with_settings(scene, **settings):
    return dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, **settings))


def emitter_scene(**settings):
    """An 8×8 camera seeing only a radiant environment of the smooth spectrum (2 W·m⁻²·sr⁻¹ over the grid)."""
    from addon.tracer.spectra import from_spec

    light = Light(kind="environment", spectrum=from_spec(SMOOTH), strength=2.0, unit="radiant")
    return s.scene(s.perspective_camera(8, 8), [], [light], spp=64, seed=5, wavelength_sampling="uniform",
                   spectrum=True, **settings)


def bin_means(values_on_grid: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The mean over each bin of a spectrum linear between the 1 nm grid's nodes (edges on whole nm)."""
    means = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = (GRID >= lo) & (GRID <= hi)
        means.append(np.trapezoid(values_on_grid[inside], GRID[inside]) / (hi - lo))
    return np.array(means)


def image_mean_and_error(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean over the pixels of each channel of (height, width, channels) and its standard error."""
    values = image.reshape(-1, image.shape[-1])
    return values.mean(axis=0), values.std(axis=0, ddof=1) / np.sqrt(values.shape[0])


# ----------------------------------------------------------------------------- bins and their checks


def test_bins_default_to_380_780_nm_in_10_nm_steps_and_none_when_off():
    settings = s.scene(s.perspective_camera(2, 2), spectrum=True).settings
    np.testing.assert_allclose(spectral_film.bin_edges(settings), np.arange(380.0, 781.0, 10.0))
    assert spectral_film.bin_edges(dataclasses.replace(settings, spectrum=False)).size == 0
    assert image_io.spectral_channel_names([380.0, 385.0, 390.0]) == ["S0.382,5nm", "S0.387,5nm"]
    assert image_io.spectral_channel_names([380.0, 390.0, 400.0]) == ["S0.385nm", "S0.395nm"]


@pytest.mark.parametrize("settings, message", [
    (dict(spectrum_step=0.0), "render.spectrum_step: must be above 0 nm"),
    (dict(spectrum_step=-5.0), "render.spectrum_step: must be above 0 nm"),
    (dict(spectrum_step=7.0), "render.spectrum_step: 380–780 nm is not a whole number of 7 nm steps"),
    (dict(spectrum_start=350.0), "render.spectrum_start"),
    (dict(spectrum_end=800.0, lambda_max=790.0), "render.spectrum_end"),
    (dict(spectrum_start=600.0, spectrum_end=500.0), "render.spectrum_end: must be above spectrum_start"),
    (dict(spectrum_step=0.1), "makes 4000 bins"),
    (dict(spectrum="yes"), "render.spectrum: expected true or false"),
    (dict(spectrum_step="ten"), "render.spectrum_step"),
])
def test_bad_bins_are_refused_naming_the_field(settings, message):
    scene = s.scene(s.perspective_camera(2, 2), **{"spectrum": True, **settings})
    with pytest.raises(SpectralError, match=message):
        check_settings(scene.settings)


def test_bins_are_checked_only_when_the_spectrum_is_kept():
    check_settings(s.scene(s.perspective_camera(2, 2), lambda_min=400.0).settings)  # 380 nm start, but off
    with pytest.raises(SpectralError, match="render.spectrum_start"):
        check_settings(s.scene(s.perspective_camera(2, 2), lambda_min=400.0, spectrum=True).settings)


def test_the_film_sums_each_bands_mean_per_bin():
    """Two bands with different sample counts (one tile of a later pass in band 0): each pixel's spectrum is the
    sum over bands of each band's mean, as its XYZ is."""
    rng = np.random.default_rng(4)
    film = Film(5, 4, bands=2, spectrum_edges=np.linspace(400.0, 700.0, 4))
    first, second = rng.random((2, 2, 4, 5, 3))
    zeros = np.zeros((4, 5, 3))
    for band in range(2):
        film.add(band, 0, 0, zeros, zeros, 2, sum_spectrum=first[band] * 2)
    film.add(0, 1, 2, zeros[1:3, 2:5], zeros[1:3, 2:5], 4, sum_spectrum=second[0, 1:3, 2:5] * 4)
    expected = first.sum(axis=0)
    expected[1:3, 2:5] += (second[0, 1:3, 2:5] * 4 - first[0, 1:3, 2:5] * 4) / 6  # (2·a + 4·b)/6 − a
    np.testing.assert_allclose(film.spectrum, expected)
    assert Film(3, 2).spectrum.shape == (2, 3, 0)


def test_without_the_spectrum_the_kernel_adds_none():
    """A render without bins gives a film without a spectrum; the image does not change when the spectrum is
    kept."""
    scene = s.scene(s.perspective_camera(4, 3), [s.medium(s.box_grid(), albedo=0.8)], [s.environment()], spp=4)
    plain = render(scene, backend="numpy").film
    kept = render(with_settings(scene, spectrum=True), backend="numpy").film
    assert plain.bins == 0 and plain.spectrum.shape == (3, 4, 0)
    assert kept.bins == 40 and kept.spectrum.any()
    np.testing.assert_array_equal(plain.sum_xyz, kept.sum_xyz)


# ----------------------------------------------------------------------------- what the bins hold


@pytest.mark.parametrize("bands", [1, 3])
def test_a_seen_emitter_gives_its_spectral_radiance_per_bin(bands):
    """The camera sees only the environment: each bin's image mean is the mean of the environment's spectral
    radiance (as lowered: W·m⁻²·sr⁻¹·nm⁻¹) over the bin, within 5 standard errors, for any number of bands (3
    bands over 360–830 nm split at 516.7 and 673.3 nm, inside bins, so each of those bins sums two bands' parts)."""
    scene = emitter_scene(bands=bands)
    film = render(scene, backend="numpy").film
    expected = bin_means(compile_scene(scene).lights.spd[0], film.spectrum_edges)
    mean, error = image_mean_and_error(film.spectrum)
    assert np.all(error > 0)
    assert np.all(np.abs(mean - expected) <= SIGMAS * error), np.max(np.abs(mean - expected) / error)
    assert spectral_film.radiance_units(scene) == "W.m^-2.sr^-1"


def test_the_bins_integrate_against_the_cie_cmfs_to_the_films_xyz():
    """A grey medium (albedo 0.7) in the smooth radiant environment, 'colour' wavelength sampling: the bins (10 nm,
    380–780 nm) integrated against colour-science's CIE 1931 2° tables, XYZ = Σ bin · ∫_bin cmf dλ / ∫ ȳ dλ, match
    the film's XYZ. Both come from the same paths, so what differs is the bins' discretisation (each path's
    wavelength weighed by its bin's mean CMF instead of its own, and nothing outside 380–780 nm) plus noise from it:
    the bound is 5 standard errors of the per-pixel difference plus the discretisation error of the smooth spectrum
    itself (the grey medium keeps every path's spectrum proportional to it), which is computed here: under 0.3 %."""
    medium = s.medium(s.box_grid(), 3.0, albedo=0.7, g=0.2)
    scene = with_settings(emitter_scene(), wavelength_sampling="colour")
    scene = dataclasses.replace(scene, media=(medium,))
    film = render(scene, backend="numpy").film
    edges = film.spectrum_edges

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    wavelengths, table = cmfs.wavelengths, cmfs.values  # 360–830 nm, 1 nm
    per_bin = np.array([[np.trapezoid(table[(wavelengths >= lo) & (wavelengths <= hi), c],
                                      wavelengths[(wavelengths >= lo) & (wavelengths <= hi)])
                         for c in range(3)] for lo, hi in zip(edges[:-1], edges[1:])])
    per_bin /= np.trapezoid(table[:, 1], wavelengths)
    from_bins = film.spectrum @ per_bin

    smooth = compile_scene(scene).lights.spd[0]
    on_cmf_grid = np.interp(wavelengths, GRID, smooth)
    exact = np.trapezoid(on_cmf_grid[:, None] * table, wavelengths, axis=0) / np.trapezoid(table[:, 1], wavelengths)
    discretisation = np.abs(bin_means(smooth, edges) @ per_bin - exact) / exact
    assert np.all(discretisation < 0.003), discretisation

    difference, error = image_mean_and_error(from_bins - film.xyz)
    mean_xyz = film.xyz.reshape(-1, 3).mean(axis=0)
    assert np.all(np.abs(difference) <= SIGMAS * error + discretisation * mean_xyz), (difference, error)
    assert np.all(np.abs(difference) < 0.01 * mean_xyz)


def test_units_are_absolute_only_where_every_source_is():
    radiant = emitter_scene()
    luminous = dataclasses.replace(radiant, lights=(s.environment(),))
    assert spectral_film.radiance_units(radiant) == "W.m^-2.sr^-1"
    assert spectral_film.radiance_units(luminous) == "relative"
    assert spectral_film.radiance_units(dataclasses.replace(radiant, lights=())) == "W.m^-2.sr^-1"


# ----------------------------------------------------------------------------- the file


def test_the_spectral_exr_reads_back_in_the_layout_of_fichet_et_al_2021(tmp_path):
    """Written by `image_io.spectral_exr`, read by OpenImageIO (channel names, header) and by colour-science's
    reader of the layout (`read_spectral_image_Fichet2021`): the same wavelengths and values, RGB beside them."""
    import OpenImageIO

    scene = with_settings(emitter_scene(), spp=4, spectrum_start=400.0, spectrum_end=700.0, spectrum_step=2.5)
    film = render(scene, backend="numpy").film
    path = image_io.write_spectral_exr(tmp_path / "spectrum.exr", film.spectrum, film.spectrum_edges,
                                       spectral_film.radiance_units(scene), film.rgb())
    image = OpenImageIO.ImageInput.open(str(path))
    spec = image.spec()
    image.close()
    assert spec.getattribute("spectralLayoutVersion") == "1.0"
    assert spec.getattribute("emissiveUnits") == "W.m^-2.sr^-1"
    names = list(spec.channelnames)
    assert names[:3] == ["R", "G", "B"] and "S0.401,25nm" in names and "S0.698,75nm" in names
    assert len(names) == 3 + 120

    components = colour.io.read_spectral_image_Fichet2021(str(path))
    wavelengths, values = components["S0"]
    np.testing.assert_allclose(wavelengths, (film.spectrum_edges[:-1] + film.spectrum_edges[1:]) / 2)
    np.testing.assert_allclose(values, film.spectrum, rtol=1e-6)  # float32 in the file
    channels = image_io.read_exr(path)
    np.testing.assert_allclose(np.stack([channels[c] for c in "RGB"], axis=2), film.rgb(), rtol=1e-6)


def test_a_spectral_exr_with_bins_that_do_not_match_is_refused(tmp_path):
    with pytest.raises(SpectralError, match="3 bins, but 3 edges make 2"):
        image_io.spectral_exr(tmp_path / "bad.exr", np.zeros((2, 2, 3)), [400.0, 500.0, 600.0], "relative")


def test_the_scene_file_keeps_the_spectrum_and_its_bins(tmp_path):
    """`render.spectrum` and its bins go through a scene file and back, and a bad one is refused on loading."""
    import json

    from addon.tracer.scene_io import load_scene, save_scene

    scene = with_settings(emitter_scene(), spectrum_start=400.0, spectrum_end=600.0, spectrum_step=5.0)
    path = save_scene(scene, tmp_path / "scene")
    loaded = load_scene(path).settings
    assert (loaded.spectrum, loaded.spectrum_start, loaded.spectrum_end, loaded.spectrum_step) == (True, 400, 600, 5)
    data = json.loads(path.read_text())
    data["render"]["spectrum_step"] = 0
    path.write_text(json.dumps(data))
    with pytest.raises(SpectralError, match="render.spectrum_step: must be above 0 nm"):
        load_scene(path)
