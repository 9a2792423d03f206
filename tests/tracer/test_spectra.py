"""Spectra: every source and operation, the CSV reader's checks, and the scene-format round trip."""

import json

import numpy as np
import pytest
import scipy.constants

from addon.tracer import colorimetry, spectra
from addon.tracer.errors import SpectralError
from addon.tracer.spectra import Spectrum
from addon.tracer.wavelengths import GRID

colour = colorimetry.colour_science()


def write(tmp_path, text, name="spectrum.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# --- constant, table, Gaussian ------------------------------------------------------------------------------

def test_constant_table_and_gaussian():
    assert np.all(spectra.constant(0.25).values == 0.25)
    ramp = spectra.table([400, 500], [0.0, 1.0])
    assert ramp(450) == pytest.approx(0.5) and ramp(399) == 0.0 and ramp(501) == 0.0
    bump = spectra.gaussian(550, 10, height=2)
    assert bump(550) == pytest.approx(2.0) and bump(560) == pytest.approx(2 * np.exp(-0.5))


def test_table_rejects_non_numbers():
    with pytest.raises(SpectralError, match="^leaf: the spectrum's values must be a list of numbers"):
        spectra.table([400, 500], ["a", "b"], name="leaf")


# --- CSV files -----------------------------------------------------------------------------------------------

def test_csv_with_header_comments_and_blank_lines(tmp_path):
    path = write(tmp_path, "# measured 2024\nwavelength_nm, value\n\n400, 0.1\n500, 0.5\n 600 ,0.9\n")
    spectrum = spectra.from_csv(path)
    assert spectrum(500) == pytest.approx(0.5) and spectrum(450) == pytest.approx(0.3)
    assert spectrum(399) == 0.0 and spectrum(601) == 0.0


@pytest.mark.parametrize("units, scale", [("um", 1e-3), ("µm", 1e-3), ("μm", 1e-3), ("A", 10.0), ("Å", 10.0)])
def test_csv_units_are_converted_to_nm(tmp_path, units, scale):
    nm = spectra.from_csv(write(tmp_path, "400,0.1\n500,0.5\n600,0.9\n", "nm.csv"))
    rows = "".join(f"{lam * scale!r},{value}\n" for lam, value in [(400, 0.1), (500, 0.5), (600, 0.9)])
    converted = spectra.from_csv(write(tmp_path, rows, "other.csv"), units=units)
    assert np.allclose(converted.values, nm.values)


BAD_CSV = {
    "a word": ("400,0.1\n500,high\n", r"line 2: 'high' is not a number"),
    "three columns": ("400,0.1\n500,0.2,0.3\n", r"line 2: expected 2 comma-separated columns.*got 3"),
    "one column": ("400\n", r"line 1: expected 2 comma-separated columns.*got 1"),
    "NaN": ("400,0.1\n500,nan\n", r"line 2: 'nan' is not a finite number"),
    "infinity": ("400,inf\n500,0.1\n", r"line 1: 'inf' is not a finite number"),
    "decreasing": ("400,0.1\n500,0.2\n450,0.3\n", r"line 3: wavelength 450 nm does not increase \(line 2 has 500"),
    "repeated": ("400,0.1\n400,0.2\n", r"line 2: wavelength 400 nm does not increase"),
    "empty": ("", r"has no data rows"),
    "header only": ("wavelength,value\n", r"has no data rows"),
    "second header": ("wavelength,value\nnm,1\n400,0.1\n", r"line 2: 'nm' is not a number"),
    "wrong units": ("0.4,0.1\n0.5,0.2\n", r"lies outside 250–830 nm \(are the units nm\?\)"),
}


@pytest.mark.parametrize("case", BAD_CSV)
def test_csv_bad_files_name_file_line_and_problem(tmp_path, case):
    text, message = BAD_CSV[case]
    path = write(tmp_path, text, "bad.csv")
    with pytest.raises(SpectralError, match=message) as error:
        spectra.from_csv(path)
    assert "bad.csv" in str(error.value)


def test_csv_missing_file_and_unknown_unit(tmp_path):
    with pytest.raises(SpectralError, match="spectrum file .*missing.csv does not exist"):
        spectra.from_csv(tmp_path / "missing.csv")
    with pytest.raises(SpectralError, match="unknown wavelength unit 'mm'; use one of nm, um"):
        spectra.from_csv(write(tmp_path, "400,1\n"), units="mm")


def test_csv_binary_file(tmp_path):
    path = tmp_path / "image.csv"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    with pytest.raises(SpectralError, match="image.csv' is not UTF-8 text"):
        spectra.from_csv(path)


# --- blackbody -----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("temperature", [3600, 4000, 5000, 5778, 6500, 10000])
def test_blackbody_peak_follows_wien(temperature):
    spectrum = spectra.blackbody(temperature)
    assert GRID[np.argmax(spectrum.values)] == pytest.approx(2.898e6 / temperature, abs=1.0)
    assert spectrum.values.max() == pytest.approx(1.0, abs=1e-5)


def test_blackbody_off_grid_peak_and_extreme_temperatures():
    assert spectra.blackbody(1000).values.max() < 0.01  # peak near 2.9 µm
    assert np.all(np.diff(spectra.blackbody(2000).values) > 0)
    assert np.all(spectra.blackbody(1).values == 0.0)  # no overflow: underflows to 0
    assert np.all(np.diff(spectra.blackbody(1e6).values) < 0)


def test_planck_broadcasts_over_wavelengths_and_temperatures():
    table = spectra.planck(GRID, np.array([[3000.0], [6000.0]]))
    assert table.shape == (2, GRID.size)
    assert np.array_equal(table[1], spectra.planck(GRID, 6000.0))
    with pytest.raises(SpectralError, match="got -5"):
        spectra.planck(500, [300.0, -5.0])


def test_planck_integrates_to_stefan_boltzmann():
    temperature = 5778.0
    lam = np.geomspace(50, 1e6, 200001)
    total = np.trapezoid(spectra.planck(lam, temperature), lam)
    assert total == pytest.approx(scipy.constants.sigma * temperature**4 / np.pi, rel=1e-6)


@pytest.mark.parametrize("temperature", [0, -300, float("nan")])
def test_blackbody_needs_a_positive_temperature(temperature):
    with pytest.raises(SpectralError, match="positive number of kelvin"):
        spectra.blackbody(temperature)


# --- illuminants ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", spectra.ILLUMINANT_NAMES)
def test_illuminant_is_the_dataset_on_the_grid_and_zero_outside_it(name):
    dataset = colour.SDS_ILLUMINANTS[name]
    spectrum = spectra.illuminant(name)
    on_grid = np.isin(GRID, dataset.wavelengths)
    assert np.array_equal(spectrum.values[on_grid], dataset.values[np.isin(dataset.wavelengths, GRID)])
    outside = (GRID < dataset.wavelengths[0]) | (GRID > dataset.wavelengths[-1])
    assert not spectrum.values[outside].any()
    between = np.interp(GRID[~on_grid & ~outside], dataset.wavelengths, dataset.values)
    assert np.allclose(spectrum.values[~on_grid & ~outside], between)


def test_illuminant_names():
    assert set(spectra.ILLUMINANT_NAMES) >= {"D65", "D50", "A", "E", "FL1", "FL12", "LED-B5", "LED-V2"}
    assert spectra.illuminant("led-rgb1") is spectra.illuminant("LED-RGB1")
    with pytest.raises(SpectralError, match="unknown illuminant 'D66'; valid names: D65, D50, A, E, FL1"):
        spectra.illuminant("D66")


# --- window, scale, sum --------------------------------------------------------------------------------------

def test_window_scale_and_sum():
    one = spectra.constant(1.0)
    band = spectra.window(one, 500, 600.5)
    assert band(500) == 1.0 and band(600) == 1.0 and band(499) == 0.0 and band(601) == 0.0
    assert band.values.sum() == 101
    assert np.array_equal((2.5 * band).values, band.values * 2.5)
    assert np.array_equal((band + one).values, band.values + 1.0)
    with pytest.raises(SpectralError, match="min ≤ max"):
        spectra.window(one, 600, 500)


# --- scene format --------------------------------------------------------------------------------------------

def test_from_spec_every_type(tmp_path):
    (tmp_path / "data").mkdir()
    write(tmp_path / "data", "400,1\n600,1\n", "leaf.csv")
    cases = [
        (0.5, spectra.constant(0.5)),
        ({"type": "constant", "value": 2}, spectra.constant(2)),
        ({"type": "table", "wavelengths": [400, 500], "values": [0, 1]}, spectra.table([400, 500], [0, 1])),
        ({"type": "gaussian", "peak": 550, "width": 20}, spectra.gaussian(550, 20)),
        ({"type": "gaussian", "peak": 550, "width": 20, "height": 3}, spectra.gaussian(550, 20, 3)),
        ({"type": "blackbody", "temperature": 3000}, spectra.blackbody(3000)),
        ({"type": "illuminant", "name": "FL2"}, spectra.illuminant("FL2")),
        ({"type": "csv", "path": "data/leaf.csv"}, spectra.table([400, 600], [1, 1])),
        ({"type": "csv", "path": str(tmp_path / "data" / "leaf.csv"), "units": "nm"},
         spectra.table([400, 600], [1, 1])),
        ({"type": "window", "of": 1, "min": 450, "max": 460}, spectra.window(spectra.constant(1), 450, 460)),
        ({"type": "scale", "of": {"type": "illuminant", "name": "A"}, "factor": 0.5}, 0.5 * spectra.illuminant("A")),
        ({"type": "sum", "of": [1, {"type": "gaussian", "peak": 500, "width": 5}]},
         spectra.constant(1) + spectra.gaussian(500, 5)),
    ]
    for spec, expected in cases:
        assert np.array_equal(spectra.from_spec(spec, base_dir=tmp_path).values, expected.values), spec


BAD_SPECS = {
    "not a spectrum": ("red", r"light\.colour: a spectrum is a number or an object"),
    "unknown type": ({"type": "rgb"}, r"unknown spectrum type 'rgb'; known types: constant, table"),
    "missing field": ({"type": "gaussian", "peak": 500}, r"type 'gaussian' needs the field 'width'"),
    "text for number": ({"type": "constant", "value": "1"},
                        r"field 'value' of a spectrum of type 'constant' must be a number"),
    "bool for number": ({"type": "blackbody", "temperature": True}, r"'temperature' .* must be a number"),
    "number for text": ({"type": "illuminant", "name": 65},
                        r"field 'name' of a spectrum of type 'illuminant' must be text"),
    "empty sum": ({"type": "sum", "of": []}, r"'of' of a 'sum' spectrum must be a non-empty list"),
    "nested error": ({"type": "sum", "of": [1, {"type": "scale", "of": {"type": "x"}, "factor": 2}]},
                     r"light\.colour\.of\[1\]\.of: unknown spectrum type 'x'"),
    "missing csv": ({"type": "csv", "path": "nowhere.csv"}, r"spectrum file .*nowhere.csv does not exist"),
    "misspelt field": ({"type": "gaussian", "peak": 550, "width": 50, "heigth": 0.5},
                       r"light\.colour: unknown field 'heigth' in a spectrum of type 'gaussian' "
                       r"\(allowed: type, peak, width, height\)"),
    "field of another type": ({"type": "constant", "value": 1, "of": 2}, r"unknown field 'of'"),
    "huge integer": (10**400, r"light\.colour: the number \(about 401 digits\) is too large"),
    "huge integer field": ({"type": "scale", "of": 1, "factor": -10**400}, r"'factor' .* is too large"),
    "huge integer in a table": ({"type": "table", "wavelengths": [400, 500], "values": [1, 10**400]},
                                r"values must be a list of numbers"),
    "deep nesting": (json.loads('{"type": "scale", "factor": 1, "of": ' * 600 + "1" + "}" * 600),
                     r"light\.colour(\.of){32}: spectra are nested more than 32 deep"),
}


@pytest.mark.parametrize("case", BAD_SPECS)
def test_from_spec_errors_name_the_spectrum_and_the_problem(tmp_path, case):
    spec, message = BAD_SPECS[case]
    with pytest.raises(SpectralError, match=message):
        spectra.from_spec(spec, "light.colour", base_dir=tmp_path)


def test_to_spec_round_trips_exactly_through_json():
    original = spectra.illuminant("D65") + spectra.blackbody(2700) * 3.7 + spectra.gaussian(432.1, 7.3)
    spec = json.loads(json.dumps(spectra.to_spec(original)))
    assert spec["type"] == "table"
    assert np.array_equal(spectra.from_spec(spec).values, original.values)


# --- RGB to spectrum -----------------------------------------------------------------------------------------

def d65_rec709(spectrum: Spectrum):
    """Linear Rec.709 colour of a reflectance lit by D65 (white reflector → 1, 1, 1)."""
    d65 = spectra.illuminant("D65").values
    white = colorimetry.spectrum_to_xyz(d65)
    return colorimetry.xyz_to_rgb(colorimetry.spectrum_to_xyz(spectrum.values * d65) / white[1])


@pytest.mark.parametrize("method", spectra.RGB_METHODS)
@pytest.mark.parametrize("rgb", [(0.8, 0.1, 0.1), (0.2, 0.5, 0.9), (0.5, 0.5, 0.5), (0.05, 0.6, 0.2)])
def test_from_rgb_reproduces_the_colour_under_d65(rgb, method):
    spectrum = spectra.from_rgb(rgb, method)
    assert spectrum.values.min() >= 0.0 and spectrum.values.max() <= 1.0
    assert np.abs(d65_rec709(spectrum) - rgb).max() < 3e-3


def test_from_rgb_red_has_its_energy_at_long_wavelengths():
    red = spectra.from_rgb((0.8, 0.1, 0.1)).values
    assert red[GRID > 600].sum() > red[GRID < 500].sum()


def test_from_rgb_is_deterministic():
    rgb = (0.3, 0.7, 0.2)
    first = spectra.from_rgb(rgb)
    spectra._from_rgb.cache_clear()
    assert np.array_equal(spectra.from_rgb(rgb).values, first.values)


def test_from_rgb_rejects_bad_input():
    with pytest.raises(SpectralError, match=r"components in \[0, 1\], got \[1.5, 0.0, 0.0\]"):
        spectra.from_rgb((1.5, 0, 0))
    with pytest.raises(SpectralError, match="three finite numbers"):
        spectra.from_rgb((1, 0))
    with pytest.raises(SpectralError, match="three finite numbers"):
        spectra.from_rgb("red")
    with pytest.raises(SpectralError, match="unknown RGB-to-spectrum method 'smits'; choose one of jakob2019"):
        spectra.from_rgb((1, 0, 0), "smits")
