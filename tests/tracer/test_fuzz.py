"""A seeded fuzzer of scene files (issue 14): random mutations of valid scenes (types, magnitudes, nesting,
keys) either load or are refused with a clear SpectralError, one that starts with the scene-file path of
what it refuses (docs/scene-format.md, "General rules"); a scene that loads is a valid scene, which the
tracer writes and reads back unchanged, and renders a small image without NaN. A fixed number of cases
from a fixed seed (the same ones on every machine), each under a watchdog."""

import copy
import dataclasses
import json
import math
import re
import signal

import numpy as np
import pytest

from addon.tracer.errors import SpectralError
from addon.tracer.render import render
from addon.tracer.scene_io import load_scene, save_scene
from tests.tracer.conftest import TINY_INDEX_TO_WORLD, tiny_scene_dict
from tests.tracer.test_scene_io import leaf_paths, set_path
from addon.tracer.validation import validate

SEED = 14
CASES = 30  # mutated scenes per run: the same ones on every machine (a time budget reached fewer on a busy one)
CASE_SECONDS = 30  # one case (load and a 16×16, 1 spp render at most) taking longer is a hang

JUNK = [None, True, False, "", "x", "heigth", [], {}, [[1]], {"type": None}, {"type": "gaussian"}, 0, -1, 1, 0.5,
        -0.5, 1.5, 1e-300, 1e300, -1e300, 2**63, 2**64, -(2**64), 10**400, 1e308, [0, 0, 0], [1, 2],
        {"type": "scale", "of": 1, "factor": 1e300}, {"type": "table", "wavelengths": [500], "values": [1]},
        {"type": "csv", "path": "scene.json"}, {"type": "illuminant", "name": "D65"}, "density.npy"]


def rich_scene_dict() -> dict:
    """Every part of the format: fluorescence, blackbody emission, an albedo table, every light kind and
    every spectrum type that needs no extra file."""
    data = tiny_scene_dict()
    grid = {"file": "density.npy", "index_to_world": TINY_INDEX_TO_WORLD}
    data["media"][0].update(
        anisotropy={"type": "table", "wavelengths": [400, 700], "values": [0.8, -0.3]},
        extinction={"type": "sum", "of": [0.5, {"type": "gaussian", "peak": 450, "width": 40, "height": 2}]},
        albedo={"densities": [0, 0.5], "spectra": [0.9, {"type": "window", "of": 0.8, "min": 400, "max": 700}]},
        fluorescence={"excitation": {"type": "gaussian", "peak": 365, "width": 15}, "emission":
                      {"type": "blackbody", "temperature": 5000}, "quantum_yield": 0.5},
        emission={"temperature": {"file": "temperature.npy", "index_to_world": TINY_INDEX_TO_WORLD},
                  "temperature_scale": 1500.0, "temperature_offset": 300.0, "intensity": 0.5},
    )
    data["media"].append({"name": "haze", "density": grid, "extinction": 0.3, "albedo": 0.99, "phase": "rayleigh"})
    data["lights"] = [
        {"kind": "sun", "spectrum": {"type": "illuminant", "name": "D65"}, "direction": [0.3, 0, 1], "angle": 0.5},
        {"kind": "sky", "spectrum": {"type": "scale", "of": 1, "factor": 0.5}, "horizon_spectrum": 1.0},
        {"kind": "spot", "spectrum": 1.0, "position": [0, -3, 2], "spot_direction": [0, 0.6, -0.8], "strength": 20},
        {"kind": "point", "spectrum": {"type": "constant", "value": 1}, "position": [1, 1, 2], "strength": 5},
        {"kind": "environment", "spectrum": 0.2},
    ]
    data["render"] = {"spp": 2, "seed": 3, "wavelength_sampling": "uv", "bands": 2, "wavelengths_per_path": 4}
    return data


def _paths(data) -> list[str]:
    return list(leaf_paths(data))


def _keys(path: str) -> list:
    return [int(key) if key.isdigit() else key for key in re.findall(r"[^.\[\]]+", path)]


def _get(data, path: str):
    for key in _keys(path):
        data = data[key]
    return data


def mutate(rng: np.random.Generator, data) -> str:
    """Change `data` in place by one random mutation; returns what was done (for the failure message)."""
    paths = _paths(data)
    path = paths[rng.integers(len(paths))]
    value = _get(data, path)
    kind = rng.integers(7)
    if kind == 0:
        new = copy.deepcopy(JUNK[rng.integers(len(JUNK))])
    elif kind == 1 and isinstance(value, (int, float)) and not isinstance(value, bool):
        new = value * float(10.0 ** rng.integers(-40, 41)) * rng.choice([1, -1])
        new = int(new) if isinstance(value, int) and abs(new) < 1e30 else new
    elif kind == 2:
        keys = _keys(path)
        parent = data
        for key in keys[:-1]:
            parent = parent[key]
        parent.pop(keys[-1])
        return f"deleted {path}"
    elif kind == 3 and isinstance(value, dict):
        value[str(rng.choice(["heigth", "colour", "scale", "type", "of", "file"]))] = 1
        return f"added a key to {path}"
    elif kind == 4:
        new = value
        for _ in range(int(rng.integers(1, 60))):
            new = {"type": "scale", "of": new, "factor": 1} if rng.random() < 0.5 else [new]
    elif kind == 5:
        other = paths[rng.integers(len(paths))]
        set_path(data, path, copy.deepcopy(_get(data, other)))
        return f"copied {other} into {path}"
    else:
        new = [value, value] if rng.random() < 0.5 else value
    set_path(data, path, new)
    return f"set {path} = {json.dumps(new)[:120]}"


class Hang(Exception):
    pass


def _alarm(_signum, _frame):
    raise Hang


# Where a refusal starts: the scene-file path of the offending field (`media[0].albedo.spectra[1]`), or
# "scene" for the file as a whole (a missing top-level field).
FIELD_PATH = re.compile(r"(scene|format|version|camera|media|lights|render)(\[\d+\]|\.\w+)*: \S")


def refused(problem: SpectralError) -> str:
    assert FIELD_PATH.match(str(problem)), f"a refusal that does not start with the field it refuses: {problem}"
    return "refused"


def same_json(a, b) -> bool:
    """Equal JSON, numbers to 1e-12 (a direction is normalised again on reading, which may move its last bit)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_json(a[key], b[key]) for key in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same_json(x, y) for x, y in zip(a, b))
    if isinstance(a, float) or isinstance(b, float):
        return type(a) is type(b) and math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300)
    return type(a) is type(b) and a == b


def run_case(write_scene, data, folder) -> str:
    """'refused' or 'rendered'; fails on anything else (a traceback, a refusal that names no field, a scene
    that loads but is not valid or does not survive writing and reading back, a NaN, a hang)."""
    try:
        scene = load_scene(write_scene(data, make_grids=False))
    except SpectralError as problem:
        return refused(problem)
    assert validate(scene) is scene
    written = save_scene(scene, folder / "written")
    rewritten = save_scene(load_scene(written), folder / "rewritten")
    assert same_json(json.loads(rewritten.read_text()), json.loads(written.read_text())), \
        "changed by writing and reading back"
    settings = dataclasses.replace(scene.settings, max_depth=min(scene.settings.max_depth, 64),
                                   bands=min(scene.settings.bands, 4))
    camera = dataclasses.replace(scene.camera, width=min(scene.camera.width, 16), height=min(scene.camera.height, 16))
    try:
        film = render(dataclasses.replace(scene, camera=camera, settings=settings), spp=1, backend="numpy").film
    except SpectralError as problem:
        return refused(problem)
    assert np.all(np.isfinite(film.xyz)), "NaN or infinite pixels"
    return "rendered"


@pytest.mark.slow
def test_mutated_scenes_load_or_are_refused_and_render_without_nan(write_scene, tmp_path):
    write_scene(rich_scene_dict())  # the grid files, once; mutations may point elsewhere (then they are missing)
    rng = np.random.default_rng(SEED)
    bases = [tiny_scene_dict(), rich_scene_dict()]
    outcomes = {"refused": 0, "rendered": 0}
    previous = signal.signal(signal.SIGALRM, _alarm)
    try:
        for _case in range(CASES):
            data = copy.deepcopy(bases[rng.integers(len(bases))])
            changes = [mutate(rng, data) for _ in range(int(rng.integers(1, 4)))]
            signal.alarm(CASE_SECONDS)
            try:
                outcomes[run_case(write_scene, data, tmp_path / "case")] += 1
            except Hang:
                pytest.fail(f"no answer within {CASE_SECONDS} s after {changes}")
            except Exception as problem:  # noqa: BLE001 - the point of the test
                pytest.fail(f"{type(problem).__name__}: {problem} after {changes}")
            finally:
                signal.alarm(0)
    finally:
        signal.signal(signal.SIGALRM, previous)
    assert outcomes["refused"] >= 5 and outcomes["rendered"] >= 5, outcomes  # both kinds of case were reached


@pytest.mark.parametrize("message", ["media[0].albedo.spectra[1]: albedo must be within [0, 1], found 1.3 at 550 nm",
                                     "scene: missing required field 'format'", "render.spp: expected an integer"])
def test_a_clear_refusal_names_its_field(message):
    assert refused(SpectralError(message)) == "refused"


@pytest.mark.parametrize("message", ["spectrum 'media[0].anisotropy': values must be a list of numbers",
                                     "Gaussian spectrum width must be positive, got -1.0", "", "media: "])
def test_a_refusal_that_names_no_field_fails(message):
    with pytest.raises(AssertionError):
        refused(SpectralError(message))
