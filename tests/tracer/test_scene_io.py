"""The scene file: round trips, the documented example, and one SpectralError per kind of bad input."""

import copy
import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

from addon.tracer import spectra
from addon.tracer.errors import SpectralError
from addon.tracer.scene import (BlackbodyEmission, Camera, Fluorescence, Glow, Grid, Light, Medium, RenderSettings,
                                Scene)
from addon.tracer.scene_io import load_scene, save_scene, validate_scene
from addon.tracer.spectra import Spectrum
from addon.tracer.wavelengths import GRID
from addon.tracer.validation import validate

DOC = Path(__file__).resolve().parents[2] / "docs" / "scene-format.md"


def full_scene() -> Scene:
    """Every field away from its default, every optional part present."""
    rng = np.random.default_rng(1)
    turn = np.array([[0, -1, 0, 1.5], [1, 0, 0, -2], [0, 0, 1, 0.25], [0, 0, 0, 1]], dtype=np.float64)
    smoke = Medium(
        name="smoke",
        density=Grid(rng.random((5, 4, 3), dtype=np.float32), turn * [[0.1], [0.2], [0.3], [1]], "dens"),
        density_scale=3.5,
        extinction=spectra.gaussian(450, 40, 2.0) + spectra.constant(0.1),
        albedo_densities=np.array([0.0, 0.5, 2.0]),
        albedo_table=np.stack(
            [spectra.constant(0.9).values, spectra.gaussian(600, 50, 0.8).values, np.full(GRID.size, 0.5)]
        ),
        anisotropy=spectra.table([300, 800], [0.7, -0.2]),
        phase="hg",
        fluorescence=Fluorescence(spectra.gaussian(365, 12), spectra.gaussian(520, 20, 3.0), 0.65),
        emission=BlackbodyEmission(
            Grid(rng.random((2, 3, 4), dtype=np.float32), np.diag([2.0, 2, 2, 1]), "heat"), 0.7, 1200.0, 250.0
        ),
    )
    glow = Glow(spectrum=spectra.gaussian(610, 30, 0.2), blackbody=2e-6, tint=spectra.gaussian(500, 200),
                temperature=Grid(rng.random((3, 2, 2), dtype=np.float32), np.diag([0.5, 0.5, 0.5, 1]), "flame"),
                temperature_scale=900.0, temperature_offset=400.0)
    haze = dataclasses.replace(
        smoke, name="haze", albedo_densities=np.array([0.0]), albedo_table=np.full((1, GRID.size), 0.99),
        phase="rayleigh", fluorescence=None, emission=None, glow=glow, anisotropy=spectra.constant(0.0),
    )
    lights = (
        Light("sun", spectra.gaussian(560, 100), 2.5, direction=np.array([0.6, 0, 0.8]), angle=0.0093, name="Sun"),
        Light("environment", spectra.constant(0.2), 0.4),
        Light("sky", spectra.gaussian(450, 60), 0.3, horizon_spectrum=spectra.constant(1.0), name="Sky"),
        Light("sky", spectra.constant(0.5), 0.1),
        Light("point", spectra.constant(1.0), 10.0, position=np.array([1.0, 2.0, 3.0])),
        Light("spot", spectra.gaussian(365, 8), 40.0, position=np.array([0, -3.0, 2]),
              spot_direction=np.array([0.0, 0.6, -0.8]), spot_size=np.radians(25), spot_blend=0.3, name="UV",
              unit="radiant"),
        Light("area", spectra.gaussian(600, 50), 25.0, position=np.array([0.5, -1.0, 3.0]),
              area_axes=np.array([[0.0, -2.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 3.0]]), area_shape="ellipse",
              size_x=0.75, size_y=1.25, name="Softbox", unit="radiant"),
        Light("area", spectra.constant(1.0), 3.0, position=np.array([0.0, 0.0, -2.0]), area_axes=-np.eye(3)),
    )
    camera = Camera(turn, 32, 24, "orthographic", np.radians(50), 4.5, "VERTICAL", 0.1, -0.05, 1.25)
    settings = RenderSettings(8, 3, 20, 2, "uv", 1, 300.0, 700.0, 4, "wyman3", "numpy")
    return Scene(camera, (smoke, haze), lights, settings=settings)


def assert_same(a, b, where="scene"):
    """Field-by-field equality; floats (angles pass through degrees) to within rounding."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for field in dataclasses.fields(a):
            assert_same(getattr(a, field.name), getattr(b, field.name), f"{where}.{field.name}")
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, np.ndarray) or isinstance(a, float):
        assert np.shape(a) == np.shape(b), where
        np.testing.assert_allclose(b, a, rtol=1e-13, atol=1e-15, err_msg=where)
        if isinstance(a, np.ndarray):
            assert np.asarray(b).dtype == a.dtype, where
    else:
        assert a == b and type(a) is type(b), f"{where}: {a!r} != {b!r}"


# ---------------------------------------------------------------------------------------------- good scenes


def test_round_trip_preserves_every_field(tmp_path):
    scene = full_scene()
    path = save_scene(scene, tmp_path / "out")
    assert path == tmp_path / "out" / "scene.json"
    assert_same(scene, load_scene(path))
    assert_same(scene, load_scene(tmp_path / "out"))  # the folder works too


def test_saved_file_is_readable_json(tmp_path):
    path = save_scene(full_scene(), tmp_path)
    text = path.read_text()
    data = json.loads(text)
    assert data["format"] == "spectral-volume-scene" and data["version"] == 1
    assert data["camera"]["fov"] == pytest.approx(50.0)
    assert data["media"][1]["albedo"] == 0.99 and data["media"][1]["extinction"]["type"] == "table"
    assert '"to_world": [[' in text  # matrices on one line, not one number per line
    grid_files = sorted(p.name for p in tmp_path.glob("*.npy"))
    assert grid_files == ["media0_density.npy", "media0_temperature.npy", "media1_density.npy",
                          "media1_glow_temperature.npy"]
    assert data["media"][1]["glow"]["temperature"]["grid"] == "flame"


@pytest.mark.parametrize("glow", [Glow(spectrum=spectra.constant(0.5)),
                                  Glow(blackbody=1e-6, temperature_offset=1800.0)], ids=["spectrum", "constant-temperature"])
def test_a_glow_round_trips_with_its_defaults(tmp_path, glow):
    """Fields left at their defaults round-trip, and a glow at constant temperature writes no grid."""
    scene = dataclasses.replace(full_scene(), media=(dataclasses.replace(full_scene().media[1], glow=glow),))
    path = save_scene(scene, tmp_path)
    assert_same(scene, load_scene(path))
    assert sorted(p.name for p in tmp_path.glob("*.npy")) == ["media0_density.npy"]


def test_tiny_scene_fixture_loads(tiny_scene):
    medium = tiny_scene.media[0]
    assert medium.density.values.shape == (4, 3, 2) and medium.density.values[3, 2, 1] == 1.0
    assert medium.albedo_table.shape == (1, GRID.size) and medium.albedo_densities.tolist() == [0.0]
    assert tiny_scene.camera.fov == pytest.approx(np.radians(39.6))
    assert tiny_scene.settings == RenderSettings(spp=1)


def doc_example() -> dict:
    blocks = re.findall(r"```json\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)
    assert len(blocks) == 1, "docs/scene-format.md should hold exactly one JSON example"
    return json.loads(blocks[0])


def test_documented_example_loads(openvdb, write_scene):
    scene = load_scene(write_scene(doc_example()))
    smoke = scene.media[0]
    assert smoke.albedo_table.shape == (2, GRID.size)
    assert smoke.albedo_table[1][GRID == 600] == pytest.approx(0.9)
    assert smoke.fluorescence.quantum_yield == 0.6
    assert smoke.emission.temperature.name == "temperature" and smoke.emission.temperature_scale == 1500.0
    lamp = scene.media[1].glow
    assert lamp.temperature is None and lamp.temperature_offset == 2700.0 and lamp.blackbody == 1e-6
    assert lamp.spectrum.values[GRID == 610] == pytest.approx(0.2) and np.all(lamp.tint.values == 1.0)
    sun, sky, spot, disk = scene.lights
    assert np.linalg.norm(sun.direction) == pytest.approx(1.0) and sun.angle == pytest.approx(np.radians(0.526))
    assert sky.horizon_spectrum is not None
    assert spot.spot_size == pytest.approx(np.radians(30)) and spot.spot_direction == pytest.approx([0, 0.8, -0.6])
    assert disk.area_shape == "ellipse" and disk.size_x == disk.size_y == 1.5 and disk.unit == "luminous"
    assert scene.settings.wavelength_sampling == "uv" and scene.settings.spp == 64


def test_vdb_grid_in_a_scene_uses_its_own_transform(openvdb, write_scene, scene_data):
    scene_data["media"][0]["density"] = {"file": "cloud.vdb"}
    scene = load_scene(write_scene(scene_data))
    assert scene.media[0].density.values.shape == (4, 3, 2)
    np.testing.assert_array_equal(scene.media[0].density.index_to_world, np.eye(4))


def test_validate_summarises(write_scene):
    lines = validate_scene(write_scene())
    text = "\n".join(lines)
    for words in ["camera: perspective, 8×6 pixels", "medium 'cloud'", "4×3×2 voxels", "light '(unnamed)': sun"]:
        assert words in text
    # world box of the tiny grid: cells of 0.5, each reaching half a cell beyond the outer centres.
    assert "world box (-1.25, -1, -0.25) to (0.75, 0.5, 0.75)" in text


# ---------------------------------------------------------------------------------------------- bad scenes


def set_path(data, path, value):
    """Set data[...] along a dotted/indexed path such as "media[0].albedo"; value DELETE removes the key."""
    keys = [int(k) if k.isdigit() else k for k in re.findall(r"[^.\[\]]+", path)]
    for key in keys[:-1]:
        data = data[key]
    if value is DELETE:
        del data[keys[-1]]
    else:
        data[keys[-1]] = value


class _Delete:
    """Marks a key to remove in `set_path`."""

    def __repr__(self):
        return "DELETE"

    def __deepcopy__(self, memo):
        return self


DELETE = _Delete()
AREA_LIGHT = {"kind": "area", "spectrum": 1, "position": [0, 0, 2], "area_axes": np.eye(3).tolist(), "size_x": 1,
              "size_y": 1}
RED_HOT = {"type": "table", "wavelengths": [500, 550, 600], "values": [0.5, 1.3, 0.5]}

BAD = [
    # (path, value, words the message must contain)
    ("format", "blender-scene", ["format: expected 'spectral-volume-scene'"]),
    ("version", 2, ["version", "found 2"]),
    ("camera", DELETE, ["missing required field 'camera'"]),
    ("extra", 1, ["unknown field 'extra'", "allowed: format, version, camera, media, lights, surfaces, render"]),
    ("camera.lens", 50, ["camera: unknown field 'lens'", "fov"]),
    ("camera.width", 0, ["camera.width: must be at least 1, found 0"]),
    ("camera.height", -3, ["camera.height: must be at least 1"]),
    ("camera.width", 6.5, ["camera.width: expected a whole number"]),
    ("camera.width", True, ["camera.width: expected a whole number"]),
    ("camera.width", 10**12, ["camera: a 1000000000000×6 film needs", "GiB of memory"]),
    ("camera.height", 10**11, ["camera: a 8×100000000000 film needs", "GiB"]),
    ("camera.height", 10**120, ["camera: a 8×1000000000", "… film needs more than 1e15 GiB of memory"]),
    ("camera.kind", "fisheye", ["camera.kind", "'fisheye'", "perspective, orthographic"]),
    ("camera.fov", 180, ["camera.fov: must be within (0, 180)"]),
    ("camera.sensor_fit", "auto", ["camera.sensor_fit", "AUTO, HORIZONTAL, VERTICAL"]),
    ("camera.pixel_aspect", 0, ["camera.pixel_aspect: must be positive, found 0"]),
    ("lights[0].unit", "watts", ["lights[0].unit", "'watts'", "luminous, radiant"]),
    ("lights[0].spectrum", {"type": "table", "wavelengths": [300, 350], "values": [1, 1]},
     ["lights[0].spectrum: the spectrum has no visible part", '"unit": "radiant"']),
    ("camera.pixel_aspect", "wide", ["camera.pixel_aspect", "'wide'"]),
    ("camera.to_world", [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [1, 2, 3, 1]], ["camera.to_world", "transposed"]),
    ("camera.to_world", [[1, 0, 0], [0, 1, 0], [0, 0, 1]], ["camera.to_world", "4 lists of 4"]),
    ("media", {}, ["media: expected a list"]),
    ("media[0].density", DELETE, ["media[0]: missing required field 'density'"]),
    ("media[0].albedo", DELETE, ["media[0]: missing required field 'albedo'"]),
    ("media[0].colour", 1, ["media[0]: unknown field 'colour'", "allowed: density, extinction, albedo"]),
    ("media[0].albedo", 1.3, ["media[0].albedo: albedo must be within [0, 1], found 1.3 at"]),
    ("media[0].albedo", -0.1, ["media[0].albedo: albedo must be within [0, 1], found -0.1"]),
    ("media[0].albedo", {"densities": [0, 1], "spectra": [0.5, RED_HOT]},
     ["media[0].albedo.spectra[1]: albedo must be within [0, 1], found 1.3 at 550 nm"]),
    ("media[0].albedo", {"densities": [1, 0], "spectra": [0.5, 0.5]}, ["media[0].albedo.densities", "increase"]),
    ("media[0].albedo", {"densities": [0, 1], "spectra": [0.5]}, ["media[0].albedo", "equal length", "2 and 1"]),
    ("media[0].albedo", {"densities": [0], "spectra": [0.5], "mode": 1}, ["media[0].albedo: unknown field 'mode'"]),
    ("media[0].albedo", {"densities": [-1], "spectra": [0.5]},
     ["media[0].albedo.densities[0]: must be within [0, inf]"]),
    ("media[0].anisotropy", 1.0, ["media[0].anisotropy: |g| must be at most 0.999999", "found 1 at"]),
    ("media[0].anisotropy", {"type": "table", "wavelengths": [400, 700], "values": [0, -1.2]},
     ["media[0].anisotropy: |g| must be at most 0.999999", "found -1.2 at 700 nm"]),
    ("media[0].anisotropy", 0.9999999999, ["media[0].anisotropy: |g| must be at most", "found 0.9999999999 at"]),
    ("media[0].extinction", -0.5, ["media[0].extinction: extinction must not be negative, found -0.5"]),
    ("media[0].extinction", {"type": "sparkle"}, ["media[0].extinction", "'sparkle'"]),
    ("media[0].extinction", {"type": "gaussian", "peak": "blue", "width": 10}, ["media[0].extinction"]),
    ("media[0].extinction", {"type": "gaussian", "peak": 500}, ["media[0].extinction", "width"]),
    ("media[0].extinction", "1.0", ["media[0].extinction", "a number or an object"]),
    ("media[0].density_scale", 0, ["media[0].density_scale: must be positive, found 0"]),
    ("media[0].density_scale", -2, ["media[0].density_scale: must be positive"]),
    ("media[0].phase", "mie", ["media[0].phase", "'mie'", "hg, rayleigh"]),
    ("media[0].fluorescence", {"excitation": 1, "emission": 1, "quantum_yield": 1.5},
     ["media[0].fluorescence.quantum_yield: must be within [0, 1], found 1.5"]),
    ("media[0].fluorescence", {"excitation": 1, "emission": 1, "quantum_yield": -0.1},
     ["media[0].fluorescence.quantum_yield: must be within [0, 1]"]),
    ("media[0].fluorescence", {"excitation": 1, "emission": 1},
     ["media[0].fluorescence: missing required field 'quantum_yield'"]),
    ("media[0].fluorescence", {"excitation": 1, "emission": 0, "quantum_yield": 1},
     ["media[0].fluorescence.emission", "zero everywhere"]),
    ("media[0].fluorescence", {"excitation": -1, "emission": 1, "quantum_yield": 1},
     ["media[0].fluorescence.excitation", "negative"]),
    ("media[0].emission",
     {"temperature": {"file": "density.npy", "index_to_world": np.eye(4).tolist()}, "temperature_offset": -100},
     ["media[0].emission: temperatures", "found -99.9", " K"]),
    ("media[0].emission", {"temperature": {"file": "nowhere.npy", "index_to_world": np.eye(4).tolist()}},
     ["media[0].emission.temperature", "nowhere.npy does not exist"]),
    ("media[0].glow", {"spectrum": -1}, ["media[0].glow.spectrum: a glow must not be negative, found -1"]),
    ("media[0].glow", {"blackbody": -1e-6}, ["media[0].glow.blackbody: must be within [0, inf], found -1e-06"]),
    ("media[0].glow", {"blackbody": 1, "tint": -0.5, "temperature_offset": 1000},
     ["media[0].glow.tint: a tint must not be negative, found -0.5"]),
    ("media[0].glow", {"blackbody": 1}, ["media[0].glow.temperature: a black-body glow needs a temperature"]),
    ("media[0].glow", {"blackbody": 1, "temperature_offset": -5}, ["media[0].glow: temperatures", "found -5 K"]),
    ("media[0].glow", {"spectrum": 1, "temperature": {"file": "density.npy", "index_to_world": np.eye(4).tolist()},
                       "temperature_scale": -100}, ["media[0].glow: temperatures", "found -100 K"]),
    ("media[0].glow", {"blackbody": 1, "temperature": {"file": "nowhere.npy", "index_to_world": np.eye(4).tolist()}},
     ["media[0].glow.temperature", "nowhere.npy does not exist"]),
    ("media[0].glow", {"colour": 1}, ["media[0].glow: unknown field 'colour'", "allowed: spectrum, blackbody, tint"]),
    ("media[0].glow", {"temperature_offset": "hot"}, ["media[0].glow.temperature_offset", "'hot'"]),
    ("media[0].density.file", "absent.npy", ["media[0].density", "absent.npy does not exist"]),
    ("media[0].density.file", 3, ["media[0].density.file: expected a path"]),
    ("media[0].density.index_to_world", DELETE, ["media[0].density", "needs an index_to_world"]),
    ("media[0].density.index_to_world", np.zeros((4, 4)).tolist(), ["media[0].density.index_to_world", "bottom row"]),
    ("media[0].density.grid", 7, ["media[0].density.grid: expected a grid name"]),
    ("media[0].density.scale", 1, ["media[0].density: unknown field 'scale'", "allowed: file, grid, index_to_world"]),
    ("lights", [], ["the scene has no lights: add a sun, environment, sky, envmap, point, spot or area light"]),
    ("lights", DELETE, ["the scene has no lights"]),
    ("lights[0].kind", "mesh", ["lights[0].kind", "'mesh'", "sun, environment, sky, point, spot, area"]),
    ("lights[0].kind", DELETE, ["lights[0]: a light is an object with a \"kind\""]),
    ("lights[0].position", [0, 0, 1],
     ["lights[0]: unknown field 'position' for sun lights", "allowed: kind, spectrum, direction"]),
    ("lights[0].direction", DELETE, ["lights[0]: missing required field 'direction' for sun lights"]),
    ("lights[0].direction", [0, 0, 0], ["lights[0].direction: a direction cannot have zero length"]),
    ("lights[0].direction", [0, 1], ["lights[0].direction: expected a list of 3 numbers"]),
    ("lights[0].direction", [0, "up", 1], ["lights[0].direction[1]: expected a finite number"]),
    ("lights[0].spectrum", DELETE, ["lights[0]: missing required field 'spectrum'"]),
    ("lights[0].spectrum", -1, ["lights[0].spectrum: a light spectrum must not be negative"]),
    ("lights[0].strength", -1, ["lights[0].strength: must be within [0, inf]"]),
    ("lights[0]", {"kind": "spot", "spectrum": 1, "position": [0, 0, 0], "spot_direction": [0, 0, 0]},
     ["lights[0].spot_direction: a direction cannot have zero length"]),
    ("lights[0]", {"kind": "spot", "spectrum": 1, "position": [0, 0, 0], "spot_direction": [0, 0, -1], "spot_blend": 2},
     ["lights[0].spot_blend: must be within [0, 1]"]),
    ("lights[0]", {"kind": "point", "spectrum": 1}, ["lights[0]: missing required field 'position' for point lights"]),
    ("lights[0]", {**AREA_LIGHT, "size_x": 0}, ["lights[0].size_x: must be positive, found 0"]),
    ("lights[0]", {**AREA_LIGHT, "size_y": -2}, ["lights[0].size_y: must be positive, found -2"]),
    ("lights[0]", {**AREA_LIGHT, "size_y": "wide"}, ["lights[0].size_y: expected a finite number, found 'wide'"]),
    ("lights[0]", {key: value for key, value in AREA_LIGHT.items() if key != "size_x"},
     ["lights[0]: missing required field 'size_x' for area lights"]),
    ("lights[0]", {**AREA_LIGHT, "area_shape": "disk"},
     ["lights[0].area_shape", "'disk'", "allowed: rectangle, ellipse"]),
    ("lights[0]", {**AREA_LIGHT, "area_axes": [[1, 0, 0], [0, 0, 0], [0, 0, 1]]},
     ["lights[0].area_axes: its column 1 (local Y) must have a non-zero length"]),
    ("lights[0]", {**AREA_LIGHT, "area_axes": [[1e300, 0, 0], [1e300, 0, 0], [0, 0, 1]]},  # a length of 1.4e300 is fine
     ["lights[0].area_axes: its column 1 (local Y) must have a non-zero length"]),
    ("lights[0]", {**AREA_LIGHT, "area_axes": [[1, 1, 0], [0, 1, 0], [0, 0, 1]]},
     ["lights[0].area_axes: its columns (local X, Y, Z) must be orthogonal", "local X and Y at cosine 0.707"]),
    ("lights[0]", {**AREA_LIGHT, "area_axes": [[1, 0], [0, 1]]}, ["lights[0].area_axes: expected a 3 × 3 matrix"]),
    ("lights[0]", {**AREA_LIGHT, "area_axes": [[1, 0, 0], [0, 1, "z"], [0, 0, 1]]},
     ["lights[0].area_axes[1][2]: expected a finite number"]),
    ("lights[0]", {**AREA_LIGHT, "spot_size": 30}, ["lights[0]: unknown field 'spot_size' for area lights"]),
    ("lights[0]", {"kind": "environment", "spectrum": 1, "direction": [0, 0, 1]},
     ["unknown field 'direction' for environment lights"]),
    ("render.spp", 0, ["render.spp: must be at least 1, found 0"]),
    ("render.samples", 4, ["render: unknown field 'samples'", "spp, seed"]),
    ("render.seed", -1, ["render.seed: must be at least 0"]),
    ("render.wavelength_sampling", "random",
     ["render.wavelength_sampling", "'random'", "uniform, d65_rejection, uv, light, visible, colour"]),
    ("render.cmf", "cie2006", ["render.cmf", "'cie2006'", "cie1931, wyman1, wyman3"]),
    ("render.backend", "metal", ["render.backend", "'metal'", "numba, numpy, cuda"]),
    ("render.lambda_min", 200, ["render.lambda_min: must be within [250, 830], found 200"]),
    ("render.lambda_max", 900, ["render.lambda_max: must be within [250, 830], found 900"]),
    ("render", {"lambda_min": 600, "lambda_max": 500}, ["render: the wavelength range 600–500 nm is empty"]),
    ("render", {"lambda_min": 500, "lambda_max": 500}, ["render: the wavelength range 500–500 nm is empty"]),
    ("render.bands", 0, ["render.bands: must be at least 1, found 0"]),
    ("render.wavelengths_per_path", 2, ["render.wavelengths_per_path: must be 1 or 4, found 2"]),
    ("render.seed", 2**64, ["render.seed: must be at most 18446744073709551615"]),
    ("media[0]", {"density": {"file": "density.npy", "index_to_world": np.eye(4).tolist()}, "density_scale": 1e6,
                  "extinction": 1e6, "albedo": 0.9},
     ["media[0]: the optical depth through the medium reaches 5.39e+12", "more than the 100000 the tracer accepts"]),
    ("media[0].extinction", 10**400, ["media[0].extinction: the number (about 401 digits) is too large"]),
    ("media[0].density_scale", 10**400, ["media[0].density_scale: expected a finite number, found 1000"]),
    ("media[0].extinction", {"type": "gaussian", "peak": 550, "width": 50, "heigth": 0.5},
     ["media[0].extinction: unknown field 'heigth' in a spectrum of type 'gaussian'"]),
]


@pytest.mark.parametrize(("path", "value", "words"), BAD, ids=[f"{p}={v!r}"[:60] for p, v, _ in BAD])
def test_bad_input_is_a_spectral_error_naming_the_problem(write_scene, scene_data, path, value, words):
    write_scene()  # the tiny scene's grid, and no other: missing files stay missing
    set_path(scene_data, path, copy.deepcopy(value))
    with pytest.raises(SpectralError) as error:
        load_scene(write_scene(scene_data, make_grids=False))
    for word in words:
        assert word in str(error.value)


def test_bad_grid_contents_are_named_with_the_json_path(write_scene, scene_data, tmp_path):
    folder = tmp_path / "scene"
    folder.mkdir()
    bad = np.ones((2, 2, 2), np.float32)
    bad[1, 0, 1] = -3
    np.save(folder / "density.npy", bad)
    expected = r"media\[0\]\.density: grid 'density' in .*density.npy has 1 negative values"
    with pytest.raises(SpectralError, match=expected):
        load_scene(write_scene(scene_data, folder))
    np.save(folder / "density.npy", np.ones((2, 2), np.float32))
    with pytest.raises(SpectralError, match="3-D"):
        load_scene(write_scene(scene_data, folder))


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("{", ["not valid JSON", "line 1"]),
        ('{"format": NaN}', ["NaN is not a number"]),
        ('{"format": 1, "format": 2}', ["'format' appears twice"]),
        ("[1, 2]", ["scene: expected an object"]),
        (b"\xff\xfe\x00", ["cannot be read"]),
        ("[" * 100_000 + "]" * 100_000, ["nests its lists and objects too deeply"]),
        ('{"format": ' + "7" * 5000 + "}", ["cannot be read as JSON", "5000 digits"]),
    ],
    ids=["truncated", "NaN", "duplicate key", "not an object", "not UTF-8", "nested 100000 deep", "5000 digits"],
)
def test_unreadable_scene_files(tmp_path, text, words):
    path = tmp_path / "scene.json"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    with pytest.raises(SpectralError) as error:
        load_scene(path)
    for word in words:
        assert word in str(error.value)
    with pytest.raises(SpectralError, match="does not exist"):
        load_scene(tmp_path / "nowhere.json")


def test_directions_are_normalised(write_scene, scene_data):
    scene_data["lights"][0]["direction"] = [0, 3, 4]
    assert load_scene(write_scene(scene_data)).lights[0].direction == pytest.approx([0, 0.6, 0.8])


def test_validate_raises_the_same_errors(write_scene, scene_data):
    scene_data["render"]["spp"] = 0
    with pytest.raises(SpectralError, match="render.spp"):
        validate_scene(write_scene(scene_data))


def leaf_paths(data, prefix=""):
    """Every path into a JSON value, e.g. "media[0].density.file"."""
    items = data.items() if isinstance(data, dict) else enumerate(data) if isinstance(data, list) else ()
    for key, value in items:
        path = f"{prefix}[{key}]" if isinstance(key, int) else f"{prefix}.{key}" if prefix else key
        yield path
        yield from leaf_paths(value, path)


@pytest.mark.parametrize("junk", [None, "x", True, [], {}, -1, 1e400, [[1]], {"type": None}])
def test_any_wrong_value_anywhere_is_a_spectral_error(write_scene, junk):
    """Replace each field of the tiny scene in turn: loading succeeds or raises SpectralError, nothing else."""
    base = json.loads(write_scene().read_text())
    for path in leaf_paths(base):
        data = copy.deepcopy(base)
        set_path(data, path, copy.deepcopy(junk))
        try:
            load_scene(write_scene(data))
        except SpectralError:
            pass


# ---------------------------------------------------------------------------------------------- validation.validate


INVALID_SCENES = {
    # what: (change to the full scene, words of the message)
    "albedo above 1": (lambda s: _medium(s, albedo_table=np.full((1, GRID.size), 1.5), albedo_densities=np.zeros(1)),
                       "media[0].albedo: albedo must be within [0, 1], found 1.5"),
    "g above 1": (lambda s: _medium(s, anisotropy=spectra.constant(1.2)), "media[0].anisotropy: |g| must be at most"),
    "phase": (lambda s: _medium(s, phase="mie"), "media[0].phase: unknown value 'mie'"),
    "no lights": (lambda s: dataclasses.replace(s, lights=(), media=(dataclasses.replace(s.media[0], emission=None),)),
                  "lights: the scene has no lights"),
    "emission and glow": (lambda s: _medium(s, glow=s.media[1].glow),
                          "media[0].glow: a medium has one temperature, so it takes either"),
    "negative glow": (lambda s: _medium(s, emission=None, glow=Glow(spectrum=spectra.constant(-1.0))),
                      "media[0].glow.spectrum: a glow must not be negative"),
    "dark lights": (lambda s: dataclasses.replace(s, lights=tuple(dataclasses.replace(light, strength=0.0)
                                                                  for light in s.lights)),
                    "lights: every light has strength 0"),
    "light kind": (lambda s: dataclasses.replace(s, lights=(dataclasses.replace(s.lights[0], kind="mesh"),)),
                   "lights[0].kind: unknown value 'mesh'"),
    "area size": (lambda s: _area(s, size_x=np.inf), "lights[0].size_x: expected a finite number, found inf"),
    "area shape": (lambda s: _area(s, area_shape="disk"), "lights[0].area_shape: unknown value 'disk'"),
    "area axes": (lambda s: _area(s, area_axes=np.ones((3, 3))),
                  "lights[0].area_axes: its columns (local X, Y, Z) must be orthogonal"),
    "no area axes": (lambda s: _area(s, area_axes=None), "lights[0].area_axes: expected a 3 × 3 matrix"),
    "zero light": (lambda s: dataclasses.replace(s, lights=(dataclasses.replace(s.lights[0],
                                                                                spectrum=spectra.constant(0.0)),)),
                   "lights[0].spectrum: the light's spectrum is zero everywhere"),
    "no excitation": (lambda s: _medium(s, fluorescence=dataclasses.replace(s.media[0].fluorescence,
                                                                              excitation=spectra.constant(0.0))),
                      "media[0].fluorescence.excitation: the excitation spectrum is zero everywhere"),
    "3 wavelengths": (lambda s: _settings(s, wavelengths_per_path=3), "render.wavelengths_per_path: must be 1 or 4"),
    "seed": (lambda s: _settings(s, seed=2**64), "render.seed: must be at most 18446744073709551615"),
    "backend": (lambda s: _settings(s, backend="metal"), "render.backend: unknown value 'metal'"),
    "optical depth": (lambda s: _medium(s, density_scale=1e12), "media[0]: the optical depth through the medium"),
    "fov": (lambda s: dataclasses.replace(s, camera=dataclasses.replace(s.camera, fov=np.pi)),
            "camera.fov: must be within (0, 180), found 180"),
}


def _medium(scene, **changes):
    return dataclasses.replace(scene, media=(dataclasses.replace(scene.media[0], **changes), *scene.media[1:]))


def _area(scene, **changes):
    """The scene lit by its first area light alone, changed."""
    light = next(light for light in scene.lights if light.kind == "area")
    return dataclasses.replace(scene, lights=(dataclasses.replace(light, **changes),))


def _settings(scene, **changes):
    return dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, **changes))


def test_a_valid_scene_validates_to_itself():
    scene = full_scene()
    assert validate(scene) is scene


@pytest.mark.parametrize("case", INVALID_SCENES)
def test_one_validation_for_load_save_and_compile(tmp_path, case):
    """A Scene built in code is checked by the rules of the file format: compile and save refuse it (and save
    writes nothing), so nothing can write a scene file that load_scene refuses."""
    from addon.tracer.lowering import compile_scene

    change, words = INVALID_SCENES[case]
    scene = change(full_scene())
    for action in (lambda: validate(scene), lambda: compile_scene(scene), lambda: save_scene(scene, tmp_path / "out")):
        with pytest.raises(SpectralError) as error:
            action()
        assert words in str(error.value)
    assert not (tmp_path / "out").exists()
