"""The scene file (docs/scene-format.md): reading, checking and writing `scene.json` and its grids.

Owns the translation between the JSON format and `scene.Scene`: every field is validated here, units
are converted (degrees in JSON, radians in memory) and every problem is a SpectralError that starts
with the JSON path of the offending field, e.g. `media[0].albedo.spectra[1]: ...`.
"""

import json
from dataclasses import fields
from pathlib import Path

import numpy as np

from . import checks, spectra
from .checks import affine_matrix, shown
from .errors import SpectralError
from .files import IMAGE_LIMIT, SCENE_LIMIT, regular_file
from .film import check_film_memory, film_bytes
from .grids import load_grid, save_grid_npy
from .kernels.layout import LIGHT_KINDS
from .scene import (RADIANT_UNITS, BlackbodyEmission, Camera, Fluorescence, Glow, Grid, Light, Medium,
                    RenderSettings, Scene, Surface, Texture)
from .spectra import Spectrum
from .wavelengths import GRID
from .validation import validate

FORMAT = "spectral-volume-scene"
VERSION = 1
SCENE_FILE = "scene.json"

_TOP = {"required": ("format", "version", "camera"), "optional": ("media", "lights", "surfaces", "render")}
_CAMERA = {
    "required": ("to_world", "width", "height"),
    "optional": ("kind", "fov", "ortho_scale", "sensor_fit", "shift_x", "shift_y", "pixel_aspect"),
}
_MEDIUM = {
    "required": ("density", "extinction", "albedo"),
    "optional": ("name", "density_scale", "anisotropy", "phase", "fluorescence", "emission", "glow"),
}
_GRID = {"required": ("file",), "optional": ("grid", "index_to_world")}
_ALBEDO_TABLE = {"required": ("densities", "spectra"), "optional": ()}
_FLUORESCENCE = {"required": ("excitation", "emission", "quantum_yield"), "optional": ()}
_EMISSION = {"required": ("temperature",), "optional": ("intensity", "temperature_scale", "temperature_offset")}
_GLOW = {"required": (),
         "optional": ("spectrum", "blackbody", "tint", "temperature", "temperature_scale", "temperature_offset")}
_LIGHT_COMMON = ("kind",)
_LIGHT_OPTIONAL = ("strength", "unit", "name")
_LIGHT_FIELDS = {
    "sun": {"required": ("spectrum", "direction"), "optional": ("angle",)},
    "environment": {"required": ("spectrum",), "optional": ()},
    "sky": {"required": ("spectrum",), "optional": ("horizon_spectrum",)},
    "point": {"required": ("spectrum", "position"), "optional": ()},
    "spot": {"required": ("spectrum", "position", "spot_direction"), "optional": ("spot_size", "spot_blend")},
    "area": {"required": ("spectrum", "position", "area_axes", "size_x", "size_y"), "optional": ("area_shape", "camera_visible")},
    "envmap": {"required": ("image", "basis"), "optional": ("to_world",)},
}
_ENVMAP_UNIT = "radiant"  # an envmap's only unit (its strength multiplies its map), so the file may omit it
_SURFACE = {"required": ("reflectance",), "optional": ("name", "object", "material", "vertices", "triangles", "mesh",
                                                  "emission", "holdout", "camera", "texture")}
_TEXTURE = {"required": ("image", "uv"), "optional": ("extension", "interpolation", "srgb")}
_RENDER = {"required": (), "optional": tuple(f.name for f in fields(RenderSettings))}


# ---------------------------------------------------------------------------------------------- loading


def load_scene(path) -> Scene:
    """Read and check a scene file (or a folder holding `scene.json`); grids resolve against its folder.

    The reader checks the file's structure and types; `validation.validate` then checks the values."""
    path = _scene_path(path)
    data = _fields(_read_json(path), "scene", _TOP)
    if data["format"] != FORMAT:
        raise SpectralError(f"format: expected {FORMAT!r}, found {shown(data['format'])} (is {path} a scene file?)")
    if data["version"] != VERSION:
        raise SpectralError(f"version: this tracer reads version {VERSION} of the format, "
                            f"found {shown(data['version'])}")
    folder = path.parent
    camera = _camera(data["camera"], "camera")
    media = tuple(_medium(spec, f"media[{i}]", folder) for i, spec in enumerate(_list(data.get("media", []), "media")))
    lights = tuple(_light(spec, f"lights[{i}]", folder) for i, spec in enumerate(_list(data.get("lights", []), "lights")))
    surfaces = tuple(_surface(spec, f"surfaces[{i}]", folder)
                     for i, spec in enumerate(_list(data.get("surfaces", []), "surfaces")))
    scene = Scene(camera=camera, media=media, lights=lights, surfaces=surfaces,
                  settings=_render(data.get("render", {}), "render"))
    return validate(scene)


def _scene_path(path) -> Path:
    path = Path(path)
    return path / SCENE_FILE if path.is_dir() else path


def _read_json(path: Path):
    try:
        text = regular_file(path, "scene file", SCENE_LIMIT).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as problem:
        raise SpectralError(f"scene file {path} cannot be read: {problem}") from None
    try:
        return json.loads(text, object_pairs_hook=_unique_keys, parse_constant=_no_constant)
    except json.JSONDecodeError as problem:
        raise SpectralError(
            f"scene file {path} is not valid JSON: {problem.msg} at line {problem.lineno}, column {problem.colno}"
        ) from None
    except SpectralError as problem:
        raise SpectralError(f"scene file {path}: {problem}") from None
    except RecursionError:
        raise SpectralError(f"scene file {path} nests its lists and objects too deeply to be a scene") from None
    except ValueError as problem:  # e.g. an integer of more than 4300 digits
        raise SpectralError(f"scene file {path} cannot be read as JSON: {problem}") from None


def _unique_keys(pairs):
    keys = [key for key, _ in pairs]
    for key in keys:
        if keys.count(key) > 1:
            raise SpectralError(f"the key {key!r} appears twice in one object")
    return dict(pairs)


def _no_constant(name):
    raise SpectralError(f"{name} is not a number the scene format accepts")


def _camera(value, where: str) -> Camera:
    data = _fields(value, where, _CAMERA)
    width = checks.whole_within(data["width"], f"{where}.width", 1)
    height = checks.whole_within(data["height"], f"{where}.height", 1)
    _check_film_memory(width, height, where)
    return Camera(
        to_world=affine_matrix(data["to_world"], f"{where}.to_world"),
        width=width,
        height=height,
        kind=data.get("kind", Camera.kind),
        fov=float(np.radians(checks.number(data.get("fov", np.degrees(Camera.fov)), f"{where}.fov"))),
        ortho_scale=checks.number(data.get("ortho_scale", Camera.ortho_scale), f"{where}.ortho_scale"),
        sensor_fit=data.get("sensor_fit", Camera.sensor_fit),
        shift_x=checks.number(data.get("shift_x", 0.0), f"{where}.shift_x"),
        shift_y=checks.number(data.get("shift_y", 0.0), f"{where}.shift_y"),
        pixel_aspect=checks.number(data.get("pixel_aspect", Camera.pixel_aspect), f"{where}.pixel_aspect"),
    )


def _check_film_memory(width: int, height: int, where: str) -> None:
    try:
        check_film_memory(width, height)
    except SpectralError as problem:
        raise SpectralError(f"{where}: {problem}") from None


def _medium(value, where: str, folder: Path) -> Medium:
    data = _fields(value, where, _MEDIUM)
    fluorescence = data.get("fluorescence")
    emission = data.get("emission")
    glow = data.get("glow")
    densities, table = _albedo(data["albedo"], f"{where}.albedo", folder)
    return Medium(
        name=data.get("name", where),
        density=_grid(data["density"], f"{where}.density", folder),
        density_scale=checks.number(data.get("density_scale", 1.0), f"{where}.density_scale"),
        extinction=_spectrum(data["extinction"], f"{where}.extinction", folder),
        albedo_densities=densities,
        albedo_table=table,
        anisotropy=_spectrum(data.get("anisotropy", 0.0), f"{where}.anisotropy", folder),
        phase=data.get("phase", Medium.phase),
        fluorescence=None if fluorescence is None else _fluorescence(fluorescence, f"{where}.fluorescence", folder),
        emission=None if emission is None else _emission(emission, f"{where}.emission", folder),
        glow=None if glow is None else _glow(glow, f"{where}.glow", folder),
    )


def _grid(value, where: str, folder: Path, nonnegative: bool = True) -> Grid:
    data = _fields(value, where, _GRID)
    file = data["file"]
    if not isinstance(file, str) or not file:
        raise SpectralError(f"{where}.file: expected a path relative to the scene file, found {shown(file)}")
    grid_name = data.get("grid")
    if grid_name is not None and not isinstance(grid_name, str):
        raise SpectralError(f"{where}.grid: expected a grid name, found {shown(grid_name)}")
    matrix = data.get("index_to_world")
    if matrix is not None:
        matrix = affine_matrix(matrix, f"{where}.index_to_world")
    try:
        return load_grid(folder / file, grid_name, matrix, nonnegative=nonnegative)
    except SpectralError as problem:
        raise SpectralError(f"{where}: {problem}") from None


def _albedo(value, where: str, folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """(densities, table): one spectrum is a single level at density 0 (the same at every density)."""
    if isinstance(value, dict) and "type" not in value:
        data = _fields(value, where, _ALBEDO_TABLE)
        levels = _list(data["densities"], f"{where}.densities")
        spectra_ = _list(data["spectra"], f"{where}.spectra")
        if not levels or len(levels) != len(spectra_):
            raise SpectralError(
                f"{where}: densities and spectra must be two non-empty lists of equal length, "
                f"found {len(levels)} and {len(spectra_)}"
            )
        densities = np.array([checks.number(d, f"{where}.densities[{i}]") for i, d in enumerate(levels)])
        rows = [_spectrum(s, f"{where}.spectra[{i}]", folder) for i, s in enumerate(spectra_)]
        return densities, np.stack([row.values for row in rows])
    return np.zeros(1), _spectrum(value, where, folder).values[np.newaxis, :].copy()


def _fluorescence(value, where: str, folder: Path) -> Fluorescence:
    data = _fields(value, where, _FLUORESCENCE)
    return Fluorescence(
        excitation=_spectrum(data["excitation"], f"{where}.excitation", folder),
        emission=_spectrum(data["emission"], f"{where}.emission", folder),
        quantum_yield=checks.number(data["quantum_yield"], f"{where}.quantum_yield"),
    )


def _emission(value, where: str, folder: Path) -> BlackbodyEmission:
    data = _fields(value, where, _EMISSION)
    return BlackbodyEmission(
        temperature=_grid(data["temperature"], f"{where}.temperature", folder, nonnegative=False),
        intensity=checks.number(data.get("intensity", 1.0), f"{where}.intensity"),
        temperature_scale=checks.number(data.get("temperature_scale", 1.0), f"{where}.temperature_scale"),
        temperature_offset=checks.number(data.get("temperature_offset", 0.0), f"{where}.temperature_offset"),
    )


def _glow(value, where: str, folder: Path) -> Glow:
    """A glow from the fields given (the others take `Glow`'s defaults)."""
    data = _fields(value, where, _GLOW)
    given = {key: _spectrum(data[key], f"{where}.{key}", folder) for key in ("spectrum", "tint") if key in data}
    given.update({key: checks.number(data[key], f"{where}.{key}")
                  for key in ("blackbody", "temperature_scale", "temperature_offset") if key in data})
    if "temperature" in data:
        given["temperature"] = _grid(data["temperature"], f"{where}.temperature", folder, nonnegative=False)
    return Glow(**given)


def _light(value, where: str, folder: Path) -> Light:
    if not isinstance(value, dict) or "kind" not in value:
        kinds = ", ".join(LIGHT_KINDS)
        raise SpectralError(f"{where}: a light is an object with a \"kind\" ({kinds}), found {shown(value)}")
    kind = checks.one_of(value["kind"], f"{where}.kind", LIGHT_KINDS)
    extra = _LIGHT_FIELDS[kind]
    schema = {"required": _LIGHT_COMMON + extra["required"], "optional": _LIGHT_OPTIONAL + extra["optional"]}
    data = _fields(value, where, schema, what=f" for {kind} lights")
    fields = {}
    if kind == "sun":
        fields["direction"] = checks.unit_vector(data["direction"], f"{where}.direction")
        fields["angle"] = float(np.radians(checks.number(data.get("angle", 0.0), f"{where}.angle")))
    if kind == "sky" and "horizon_spectrum" in data:
        fields["horizon_spectrum"] = _spectrum(data["horizon_spectrum"], f"{where}.horizon_spectrum", folder)
    if kind in ("point", "spot", "area"):
        fields["position"] = checks.vector(data["position"], f"{where}.position")
    if kind == "spot":
        fields["spot_direction"] = checks.unit_vector(data["spot_direction"], f"{where}.spot_direction")
        size = data.get("spot_size", np.degrees(Light.spot_size))
        fields["spot_size"] = float(np.radians(checks.number(size, f"{where}.spot_size")))
        fields["spot_blend"] = checks.number(data.get("spot_blend", Light.spot_blend), f"{where}.spot_blend")
    if kind == "area":
        fields["area_axes"] = checks.matrix3(data["area_axes"], f"{where}.area_axes")
        fields["area_shape"] = data.get("area_shape", Light.area_shape)
        for key in ("size_x", "size_y"):
            fields[key] = checks.number(data[key], f"{where}.{key}")
        fields["camera_visible"] = data.get("camera_visible", Light.camera_visible)
    if kind == "envmap":
        fields["image"] = _image(data["image"], f"{where}.image", folder)
        basis = _list(data["basis"], f"{where}.basis")
        if len(basis) != 3:
            raise SpectralError(f"{where}.basis: expected 3 spectra (R, G, B), found {len(basis)}")
        fields["basis"] = tuple(_spectrum(item, f"{where}.basis[{i}]", folder) for i, item in enumerate(basis))
        if "to_world" in data:
            fields["to_world"] = checks.matrix3(data["to_world"], f"{where}.to_world")
    else:
        fields["spectrum"] = _spectrum(data["spectrum"], f"{where}.spectrum", folder)
    unit = data.get("unit", _ENVMAP_UNIT if kind == "envmap" else Light.unit)
    return Light(kind=kind, strength=checks.number(data.get("strength", 1.0), f"{where}.strength"),
                 name=data.get("name", ""), unit=unit, **fields)


def _surface(value, where: str, folder: Path) -> Surface:
    """A surface: its triangles as `vertices` and `triangles` (inline lists or `.npy` files), or as a `mesh`
    (an OBJ file); `validation.validate` checks the values."""
    data = _fields(value, where, _SURFACE)
    if "mesh" in data:
        if "vertices" in data or "triangles" in data:
            raise SpectralError(f"{where}: give either \"mesh\" or \"vertices\" and \"triangles\", not both")
        vertices, triangles = _obj(data["mesh"], f"{where}.mesh", folder)
    else:
        for key in ("vertices", "triangles"):
            if key not in data:
                raise SpectralError(f"{where}: missing required field {key!r} (or give a \"mesh\" file)")
        vertices = _mesh_array(data["vertices"], f"{where}.vertices", folder)
        triangles = _mesh_array(data["triangles"], f"{where}.triangles", folder)
    emission = data.get("emission")
    name = data.get("name", where)
    if not isinstance(name, str):
        raise SpectralError(f"{where}.name: expected a string, found {shown(name)}")
    return Surface(name=name, vertices=vertices, triangles=triangles,
                   reflectance=_spectrum(data["reflectance"], f"{where}.reflectance", folder),
                   emission=None if emission is None else _spectrum(emission, f"{where}.emission", folder),
                   holdout=data.get("holdout", False), camera=data.get("camera", True),
                   texture=_texture(data["texture"], f"{where}.texture", folder) if "texture" in data else None,
                   object=data.get("object", ""), material=data.get("material", ""))


def _texture(value, where: str, folder: Path) -> Texture:
    """A surface's texture: its image and its triangles' corners' UVs as `.npy` files named relative to the
    scene's folder; `validation.validate` checks the values."""
    data = _fields(value, where, _TEXTURE)
    return Texture(image=_image(data["image"], f"{where}.image", folder), uv=_image(data["uv"], f"{where}.uv", folder),
                   extension=data.get("extension", Texture.extension),
                   interpolation=data.get("interpolation", Texture.interpolation),
                   srgb=data.get("srgb", Texture.srgb))


def _mesh_array(value, where: str, folder: Path) -> np.ndarray:
    """A list of rows of 3 numbers, inline or as a `.npy` file named relative to the scene's folder."""
    if isinstance(value, str):
        array = _image(value, where, folder)
    else:
        rows = _list(value, where)
        if any(isinstance(item, bool) for row in rows if isinstance(row, list) for item in row):
            raise SpectralError(f"{where}: expected rows of 3 numbers, found a boolean")
        try:
            array = np.array(rows)
        except (TypeError, ValueError):
            array = None
        if array is None or array.dtype == object or not (np.issubdtype(array.dtype, np.number) or array.size == 0):
            raise SpectralError(f"{where}: expected rows of 3 numbers, found {shown(value)}")
        array = array.reshape(-1, 3) if array.size == 0 else array
    if array.ndim != 2 or array.shape[1] != 3:
        raise SpectralError(f"{where}: expected rows of 3 numbers, found an array of shape {array.shape}")
    return array


def _obj(value, where: str, folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of a Wavefront OBJ file named relative to the scene's folder: its `v` lines and its
    `f` lines (polygons cut into fans of triangles; indices from 1, negative ones counting back from the last
    vertex so far; texture and normal indices ignored). Other lines are ignored."""
    if not isinstance(value, str) or not value:
        raise SpectralError(f"{where}: expected the name of an OBJ file, found {shown(value)}")
    path = folder / value
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except FileNotFoundError:
        raise SpectralError(f"{where}: the file {path} does not exist") from None
    except OSError as problem:
        raise SpectralError(f"{where}: the file {path} cannot be read: {problem}") from None
    vertices, triangles = [], []
    for number, line in enumerate(lines, 1):
        words = line.split()
        try:
            if words[:1] == ["v"]:
                vertices.append([float(word) for word in words[1:4]])
                if len(vertices[-1]) != 3:
                    raise ValueError("a vertex needs 3 coordinates")
            elif words[:1] == ["f"]:
                corners = [int(word.split("/")[0]) for word in words[1:]]
                if len(corners) < 3:
                    raise ValueError("a face needs 3 corners or more")
                corners = [c - 1 if c > 0 else len(vertices) + c for c in corners]
                triangles += [[corners[0], corners[i], corners[i + 1]] for i in range(1, len(corners) - 1)]
        except ValueError as problem:
            raise SpectralError(f"{where}: {path} line {number}: {problem}") from None
    return np.array(vertices, dtype=np.float64).reshape(-1, 3), np.array(triangles, dtype=np.int64).reshape(-1, 3)


def _image(value, where: str, folder: Path) -> np.ndarray:
    """A `.npy` file named relative to the scene's folder: an envmap's image of shape (H, W, 3), a surface's
    vertices or triangles (`validation.validate` checks their values)."""
    if not isinstance(value, str):
        raise SpectralError(f"{where}: expected the name of a .npy file, found {shown(value)}")
    try:
        path = regular_file(folder / value, "image file", IMAGE_LIMIT)
        return np.load(path, allow_pickle=False)
    except SpectralError as problem:
        raise SpectralError(f"{where}: {problem}") from None
    except (OSError, ValueError) as problem:
        raise SpectralError(f"{where}: the file {path} is not a .npy array: {problem}") from None


def _render(value, where: str) -> RenderSettings:
    data = _fields(value, where, _RENDER)
    defaults = RenderSettings()
    values = {key: data.get(key, getattr(defaults, key)) for key in _RENDER["optional"]}
    for key in ("lambda_min", "lambda_max"):
        values[key] = checks.number(values[key], f"{where}.{key}")
    if isinstance(values["passes"], list):
        values["passes"] = tuple(values["passes"])
    return RenderSettings(**values)


# ---------------------------------------------------------------------------------------------- values


def _fields(value, where: str, schema: dict, what: str = "") -> dict:
    """`value` as a dict with every required key and no unknown one; `what` qualifies the messages."""
    if not isinstance(value, dict):
        raise SpectralError(f"{where}: expected an object, found {shown(value)}")
    allowed = schema["required"] + schema["optional"]
    for key in value:
        if key not in allowed:
            raise SpectralError(f"{where}: unknown field {key!r}{what} (allowed: {', '.join(allowed)})")
    for key in schema["required"]:
        if key not in value:
            raise SpectralError(f"{where}: missing required field {key!r}{what}")
    return value


def _list(value, where: str) -> list:
    if not isinstance(value, list):
        raise SpectralError(f"{where}: expected a list, found {shown(value)}")
    return value


def _spectrum(value, where: str, folder: Path) -> Spectrum:
    """`spectra.from_spec` with the JSON path in every error, and NumPy's complaints about wrongly typed
    fields turned into a SpectralError that shows the description."""
    try:
        return spectra.from_spec(value, name=where, base_dir=folder)
    except SpectralError as problem:
        message = str(problem)
        raise SpectralError(message if where in message else f"{where}: {message}") from None
    except (TypeError, ValueError) as problem:
        raise SpectralError(f"{where}: invalid spectrum description {shown(value)} ({problem})") from None


# ---------------------------------------------------------------------------------------------- saving


def save_scene(scene: Scene, folder) -> Path:
    """Write `scene` (valid: `validation.validate`) as `folder/scene.json` plus one `.npy` per grid; returns
    the JSON file's path."""
    validate(scene)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    data = {
        "format": FORMAT,
        "version": VERSION,
        "camera": _camera_json(scene.camera),
        "media": [_medium_json(medium, i, folder) for i, medium in enumerate(scene.media)],
        "lights": [_light_json(light, i, folder) for i, light in enumerate(scene.lights)],
        "surfaces": [_surface_json(surface, i, folder) for i, surface in enumerate(scene.surfaces)],
        "render": {key: getattr(scene.settings, key) for key in _RENDER["optional"]},
    }
    path = folder / SCENE_FILE
    path.write_text(_dumps(data) + "\n", encoding="utf-8")
    return path


def _camera_json(camera: Camera) -> dict:
    return {
        "to_world": _floats(camera.to_world),
        "width": int(camera.width),
        "height": int(camera.height),
        "kind": camera.kind,
        "fov": float(np.degrees(camera.fov)),
        "ortho_scale": float(camera.ortho_scale),
        "sensor_fit": camera.sensor_fit,
        "shift_x": float(camera.shift_x),
        "shift_y": float(camera.shift_y),
        "pixel_aspect": float(camera.pixel_aspect),
    }


def _medium_json(medium: Medium, index: int, folder: Path) -> dict:
    data = {
        "name": medium.name,
        "density": _grid_json(medium.density, f"media{index}_density.npy", folder),
        "density_scale": float(medium.density_scale),
        "extinction": _spectrum_json(medium.extinction),
        "albedo": _albedo_json(medium.albedo_densities, medium.albedo_table),
        "anisotropy": _spectrum_json(medium.anisotropy),
        "phase": medium.phase,
    }
    if medium.fluorescence is not None:
        data["fluorescence"] = {
            "excitation": _spectrum_json(medium.fluorescence.excitation),
            "emission": _spectrum_json(medium.fluorescence.emission),
            "quantum_yield": float(medium.fluorescence.quantum_yield),
        }
    if medium.emission is not None:
        data["emission"] = {
            "temperature": _grid_json(medium.emission.temperature, f"media{index}_temperature.npy", folder),
            "intensity": float(medium.emission.intensity),
            "temperature_scale": float(medium.emission.temperature_scale),
            "temperature_offset": float(medium.emission.temperature_offset),
        }
    if medium.glow is not None:
        data["glow"] = _glow_json(medium.glow, index, folder)
    return data


def _glow_json(glow: Glow, index: int, folder: Path) -> dict:
    data = {} if glow.spectrum is None else {"spectrum": _spectrum_json(glow.spectrum)}
    data.update(blackbody=float(glow.blackbody), tint=_spectrum_json(glow.tint))
    if glow.temperature is not None:
        data["temperature"] = _grid_json(glow.temperature, f"media{index}_glow_temperature.npy", folder)
    data.update(temperature_scale=float(glow.temperature_scale), temperature_offset=float(glow.temperature_offset))
    return data


def _grid_json(grid: Grid, file: str, folder: Path) -> dict:
    save_grid_npy(folder / file, grid)
    return {"file": file, "grid": grid.name, "index_to_world": _floats(grid.index_to_world)}


def _albedo_json(densities: np.ndarray, table: np.ndarray):
    if len(densities) == 1 and densities[0] == 0:
        return _spectrum_json(Spectrum(table[0]))
    return {"densities": _floats(densities), "spectra": [_spectrum_json(Spectrum(row)) for row in table]}


def _spectrum_json(spectrum: Spectrum):
    """A number for a constant spectrum, else a table on the 1 nm grid (exact: it is the grid)."""
    values = spectrum.values
    if np.all(values == values[0]):
        return float(values[0])
    return {"type": "table", "wavelengths": GRID.tolist(), "values": values.tolist()}


def _light_json(light: Light, index: int, folder: Path) -> dict:
    data = {"kind": light.kind, "name": light.name}
    if light.spectrum is not None:
        data["spectrum"] = _spectrum_json(light.spectrum)
    data["strength"] = float(light.strength)
    data["unit"] = light.unit
    if light.kind == "sun":
        data["direction"] = _floats(light.direction)
        data["angle"] = float(np.degrees(light.angle))
    if light.kind == "sky" and light.horizon_spectrum is not None:
        data["horizon_spectrum"] = _spectrum_json(light.horizon_spectrum)
    if light.kind in ("point", "spot", "area"):
        data["position"] = _floats(light.position)
    if light.kind == "spot":
        data["spot_direction"] = _floats(light.spot_direction)
        data["spot_size"] = float(np.degrees(light.spot_size))
        data["spot_blend"] = float(light.spot_blend)
    if light.kind == "area":
        data["area_axes"] = _floats(light.area_axes)
        data["area_shape"] = light.area_shape
        data["size_x"], data["size_y"] = float(light.size_x), float(light.size_y)
        data["camera_visible"] = bool(light.camera_visible)
    if light.kind == "envmap":
        data["image"] = f"lights{index}_image.npy"
        np.save(folder / data["image"], np.ascontiguousarray(light.image, dtype=np.float32), allow_pickle=False)
        data["basis"] = [_spectrum_json(Spectrum(values)) for values in light.basis_values()]
        if light.to_world is not None:
            data["to_world"] = _floats(light.to_world)
    return data


def _surface_json(surface: Surface, index: int, folder: Path) -> dict:
    data = {"name": surface.name, "vertices": f"surfaces{index}_vertices.npy",
            "triangles": f"surfaces{index}_triangles.npy", "reflectance": _spectrum_json(surface.reflectance)}
    np.save(folder / data["vertices"], np.asarray(surface.vertices, dtype=np.float64), allow_pickle=False)
    np.save(folder / data["triangles"], np.asarray(surface.triangles, dtype=np.int64), allow_pickle=False)
    if surface.emission is not None:
        data["emission"] = _spectrum_json(surface.emission)
    if surface.holdout:
        data["holdout"] = True
    if not surface.camera:
        data["camera"] = False
    if surface.texture is not None:
        texture = surface.texture
        data["texture"] = {"image": f"surfaces{index}_texture.npy", "uv": f"surfaces{index}_uv.npy",
                           "extension": texture.extension, "interpolation": texture.interpolation}
        if texture.srgb:
            data["texture"]["srgb"] = True
        np.save(folder / data["texture"]["image"], np.asarray(texture.image, dtype=np.float32), allow_pickle=False)
        np.save(folder / data["texture"]["uv"], np.asarray(texture.uv, dtype=np.float64), allow_pickle=False)
    data.update({key: getattr(surface, key) for key in ("object", "material") if getattr(surface, key)})
    return data


def _floats(array) -> list:
    return np.asarray(array, dtype=np.float64).tolist()


def _dumps(value, indent: str = "") -> str:
    """JSON with one key per line but lists of numbers (and matrices' rows) kept on one line."""
    inner = indent + "  "
    if isinstance(value, dict) and value:
        items = (f"{inner}{json.dumps(key)}: {_dumps(item, inner)}" for key, item in value.items())
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(value, list) and value and any(isinstance(item, (dict, list)) for item in value):
        if all(isinstance(item, list) and len(item) <= 4 for item in value):
            return json.dumps(value, allow_nan=False)
        return "[\n" + ",\n".join(inner + _dumps(item, inner) for item in value) + "\n" + indent + "]"
    return json.dumps(value, allow_nan=False)


# ---------------------------------------------------------------------------------------------- summary


def validate_scene(path) -> list[str]:
    """Load the scene (raising SpectralError on the first problem) and describe it in a few lines."""
    path = _scene_path(path)
    scene = load_scene(path)
    camera = scene.camera
    if camera.kind == "perspective":
        lens = f"fov {np.degrees(camera.fov):.4g}°"
    else:
        lens = f"ortho scale {camera.ortho_scale:g}"
    film = film_bytes(camera.width, camera.height)
    lines = [
        f"scene {path}: {FORMAT} version {VERSION}",
        f"camera: {camera.kind}, {camera.width}×{camera.height} pixels, {lens}, film {film / 2**20:.3g} MiB",
    ]
    lines += [_describe_medium(medium) for medium in scene.media]
    lines += [_describe_light(light) for light in scene.lights]
    lines += [f"surface {surface.name!r}: {len(surface.triangles)} triangles"
              + (", emissive" if surface.emission is not None else "") + (", holdout" if surface.holdout else "")
              + ("" if surface.camera else ", unseen by the camera")
              + (f", a {surface.texture.image.shape[1]} × {surface.texture.image.shape[0]} texture"
                 if surface.texture is not None else "")
              for surface in scene.surfaces]
    s = scene.settings
    lines.append(
        f"render: {s.spp} spp, seed {s.seed}, max depth {s.max_depth}, {s.lambda_min:g}–{s.lambda_max:g} nm "
        f"in {s.bands} band(s), {s.wavelength_sampling!r} sampling, {s.wavelengths_per_path} wavelength(s) per path, "
        f"{s.cmf} colour matching, {s.backend} backend"
    )
    return lines


def _describe_medium(medium: Medium) -> str:
    grid = medium.density
    low, high = _world_bounds(grid)
    text = (
        f"medium {medium.name!r}: density grid {grid.name!r} {'×'.join(map(str, grid.values.shape))} voxels, "
        f"max {grid.values.max():g} × scale {medium.density_scale:g}, world box "
        f"({', '.join(f'{c:.4g}' for c in low)}) to ({', '.join(f'{c:.4g}' for c in high)}), "
        f"{medium.phase} phase, albedo at {len(medium.albedo_densities)} density level(s)"
    )
    if medium.fluorescence is not None:
        text += f", fluorescent (quantum yield {medium.fluorescence.quantum_yield:g})"
    if medium.emission is not None:
        text += f", blackbody emission from grid {medium.emission.temperature.name!r}"
    if medium.glow is not None:
        text += ", glowing"
    return text


def _world_bounds(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """World-space box around all voxels (cells extend half a voxel beyond the outer centres)."""
    nx, ny, nz = grid.values.shape
    corners = np.array([[x, y, z, 1.0] for x in (-0.5, nx - 0.5) for y in (-0.5, ny - 0.5) for z in (-0.5, nz - 0.5)])
    world = corners @ np.asarray(grid.index_to_world).T
    return world[:, :3].min(axis=0), world[:, :3].max(axis=0)


def _describe_light(light: Light) -> str:
    unit = RADIANT_UNITS[light.kind] if light.unit == "radiant" else "(luminance Y)"
    text = f"light {light.name or '(unnamed)'!r}: {light.kind}, strength {light.strength:g} {unit}"
    if light.kind == "sun":
        text += f", towards ({', '.join(f'{c:.3g}' for c in light.direction)}), {np.degrees(light.angle):.3g}° wide"
    if light.kind in ("point", "spot", "area"):
        text += f", at ({', '.join(f'{c:.4g}' for c in light.position)})"
    if light.kind == "area":
        text += f", {light.area_shape} {light.size_x:.4g} × {light.size_y:.4g}"
    if light.kind == "envmap":
        text += f", a {light.image.shape[1]} × {light.image.shape[0]} map"
    return text
