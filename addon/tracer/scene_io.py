"""The scene file (docs/scene-format.md): reading, checking and writing `scene.json` and its grids.

Owns the translation between the JSON format and `scene.Scene`: every field is validated here, units
are converted (degrees in JSON, radians in memory) and every problem is a SpectralError that starts
with the JSON path of the offending field, e.g. `media[0].albedo.spectra[1]: ...`.
"""

import json
from dataclasses import fields
from pathlib import Path

import numpy as np

from . import spectra
from .errors import SpectralError
from .film import check_film_memory, film_bytes
from .grids import affine_matrix, load_grid, save_grid_npy
from .scene import BlackbodyEmission, Camera, Fluorescence, Grid, Light, Medium, RenderSettings, Scene
from .spectra import Spectrum
from .wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN

FORMAT = "spectral-volume-scene"
VERSION = 1
SCENE_FILE = "scene.json"

CAMERA_KINDS = ("perspective", "orthographic")
SENSOR_FITS = ("AUTO", "HORIZONTAL", "VERTICAL")
PHASES = ("hg", "rayleigh")
LIGHT_KINDS = ("sun", "environment", "sky", "point", "spot")
WAVELENGTH_SAMPLINGS = ("uniform", "d65_rejection", "uv", "light", "visible", "colour")
WAVELENGTHS_PER_PATH = (1, 4)
CMFS = ("cie1931", "wyman1", "wyman3")
BACKENDS = ("numba", "numpy")
# The film keeps XYZ sums and squared sums per pixel: 2 × 4 float64.

_TOP = {"required": ("format", "version", "camera"), "optional": ("media", "lights", "render")}
_CAMERA = {
    "required": ("to_world", "width", "height"),
    "optional": ("kind", "fov", "ortho_scale", "sensor_fit", "shift_x", "shift_y"),
}
_MEDIUM = {
    "required": ("density", "extinction", "albedo"),
    "optional": ("name", "density_scale", "anisotropy", "phase", "fluorescence", "emission"),
}
_GRID = {"required": ("file",), "optional": ("grid", "index_to_world")}
_ALBEDO_TABLE = {"required": ("densities", "spectra"), "optional": ()}
_FLUORESCENCE = {"required": ("excitation", "emission", "quantum_yield"), "optional": ()}
_EMISSION = {"required": ("temperature",), "optional": ("intensity", "temperature_scale", "temperature_offset")}
_LIGHT_COMMON = ("kind", "spectrum")
_LIGHT_OPTIONAL = ("strength", "name")
_LIGHT_FIELDS = {
    "sun": {"required": ("direction",), "optional": ("angle",)},
    "environment": {"required": (), "optional": ()},
    "sky": {"required": (), "optional": ("horizon_spectrum",)},
    "point": {"required": ("position",), "optional": ()},
    "spot": {"required": ("position", "spot_direction"), "optional": ("spot_size", "spot_blend")},
}
_RENDER = {"required": (), "optional": tuple(f.name for f in fields(RenderSettings))}


# ---------------------------------------------------------------------------------------------- loading


def load_scene(path) -> Scene:
    """Read and check a scene file (or a folder holding `scene.json`); grids resolve against its folder."""
    path = _scene_path(path)
    data = _fields(_read_json(path), "scene", _TOP)
    if data["format"] != FORMAT:
        raise SpectralError(f"format: expected {FORMAT!r}, found {data['format']!r} (is {path} a scene file?)")
    if _int(data["version"], "version", minimum=1) != VERSION:
        raise SpectralError(f"version: this tracer reads version {VERSION} of the format, found {data['version']}")
    folder = path.parent
    camera = _camera(data["camera"], "camera")
    media = tuple(_medium(spec, f"media[{i}]", folder) for i, spec in enumerate(_list(data.get("media", []), "media")))
    lights = tuple(_light(spec, f"lights[{i}]", folder) for i, spec in enumerate(_list(data.get("lights", []), "lights")))
    if not lights and not any(medium.emission is not None for medium in media):
        raise SpectralError("lights: the scene has no lights: add a sun, environment, sky, point or spot light")
    return Scene(camera=camera, media=media, lights=lights, settings=_render(data.get("render", {}), "render"))


def _scene_path(path) -> Path:
    path = Path(path)
    return path / SCENE_FILE if path.is_dir() else path


def _read_json(path: Path):
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SpectralError(f"scene file {path} does not exist") from None
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
    width = _int(data["width"], f"{where}.width", minimum=1)
    height = _int(data["height"], f"{where}.height", minimum=1)
    _check_film_memory(width, height, where)
    kind = _choice(data.get("kind", "perspective"), f"{where}.kind", CAMERA_KINDS)
    fov = _float(data.get("fov", np.degrees(Camera.fov)), f"{where}.fov", 0.0, 180.0, closed=False)
    return Camera(
        to_world=affine_matrix(data["to_world"], f"{where}.to_world"),
        width=width,
        height=height,
        kind=kind,
        fov=float(np.radians(fov)),
        ortho_scale=_positive(data.get("ortho_scale", Camera.ortho_scale), f"{where}.ortho_scale"),
        sensor_fit=_choice(data.get("sensor_fit", "AUTO"), f"{where}.sensor_fit", SENSOR_FITS),
        shift_x=_float(data.get("shift_x", 0.0), f"{where}.shift_x"),
        shift_y=_float(data.get("shift_y", 0.0), f"{where}.shift_y"),
    )


def _check_film_memory(width: int, height: int, where: str) -> None:
    try:
        check_film_memory(width, height)
    except SpectralError as problem:
        raise SpectralError(f"{where}: {problem}") from None


def _medium(value, where: str, folder: Path) -> Medium:
    data = _fields(value, where, _MEDIUM)
    name = data.get("name", where)
    if not isinstance(name, str):
        raise SpectralError(f"{where}.name: expected a string, found {name!r}")
    extinction = _spectrum(data["extinction"], f"{where}.extinction", folder)
    _check_range(extinction, f"{where}.extinction", "extinction must not be negative", 0.0, np.inf)
    densities, table = _albedo(data["albedo"], f"{where}.albedo", folder)
    anisotropy = _spectrum(data.get("anisotropy", 0.0), f"{where}.anisotropy", folder)
    _check_range(anisotropy, f"{where}.anisotropy", "|g| must be below 1", -1.0, 1.0, closed=False)
    fluorescence = data.get("fluorescence")
    emission = data.get("emission")
    return Medium(
        name=name,
        density=_grid(data["density"], f"{where}.density", folder),
        density_scale=_positive(data.get("density_scale", 1.0), f"{where}.density_scale"),
        extinction=extinction,
        albedo_densities=densities,
        albedo_table=table,
        anisotropy=anisotropy,
        phase=_choice(data.get("phase", "hg"), f"{where}.phase", PHASES),
        fluorescence=None if fluorescence is None else _fluorescence(fluorescence, f"{where}.fluorescence", folder),
        emission=None if emission is None else _emission(emission, f"{where}.emission", folder),
    )


def _grid(value, where: str, folder: Path, nonnegative: bool = True) -> Grid:
    data = _fields(value, where, _GRID)
    file = data["file"]
    if not isinstance(file, str) or not file:
        raise SpectralError(f"{where}.file: expected a path relative to the scene file, found {file!r}")
    grid_name = data.get("grid")
    if grid_name is not None and not isinstance(grid_name, str):
        raise SpectralError(f"{where}.grid: expected a grid name, found {grid_name!r}")
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
        densities = np.array([_float(d, f"{where}.densities[{i}]", 0.0) for i, d in enumerate(levels)])
        if np.any(np.diff(densities) <= 0):
            raise SpectralError(f"{where}.densities: density levels must increase strictly, found {levels}")
        rows = [_albedo_spectrum(s, f"{where}.spectra[{i}]", folder) for i, s in enumerate(spectra_)]
        return densities, np.stack([row.values for row in rows])
    return np.zeros(1), _albedo_spectrum(value, where, folder).values[np.newaxis, :].copy()


def _albedo_spectrum(value, where: str, folder: Path) -> Spectrum:
    albedo = _spectrum(value, where, folder)
    _check_range(albedo, where, "albedo must be within [0, 1]", 0.0, 1.0)
    return albedo


def _fluorescence(value, where: str, folder: Path) -> Fluorescence:
    data = _fields(value, where, _FLUORESCENCE)
    excitation = _spectrum(data["excitation"], f"{where}.excitation", folder)
    _check_range(excitation, f"{where}.excitation", "excitation must not be negative", 0.0, np.inf)
    emission = _spectrum(data["emission"], f"{where}.emission", folder)
    _check_range(emission, f"{where}.emission", "emission must not be negative", 0.0, np.inf)
    if emission.integral() <= 0:
        raise SpectralError(f"{where}.emission: the emission spectrum is zero everywhere, so it cannot be a pdf")
    return Fluorescence(
        excitation=excitation,
        emission=emission,
        quantum_yield=_float(data["quantum_yield"], f"{where}.quantum_yield", 0.0, 1.0),
    )


def _emission(value, where: str, folder: Path) -> BlackbodyEmission:
    data = _fields(value, where, _EMISSION)
    temperature = _grid(data["temperature"], f"{where}.temperature", folder, nonnegative=False)
    scale = _float(data.get("temperature_scale", 1.0), f"{where}.temperature_scale")
    offset = _float(data.get("temperature_offset", 0.0), f"{where}.temperature_offset")
    coldest = min(float(temperature.values.min()) * scale, float(temperature.values.max()) * scale) + offset
    if coldest < 0:
        raise SpectralError(
            f"{where}: temperatures (grid value × temperature_scale + temperature_offset) must be "
            f"non-negative kelvin, found {coldest:g} K"
        )
    return BlackbodyEmission(
        temperature=temperature,
        intensity=_float(data.get("intensity", 1.0), f"{where}.intensity", 0.0),
        temperature_scale=scale,
        temperature_offset=offset,
    )


def _light(value, where: str, folder: Path) -> Light:
    if not isinstance(value, dict) or "kind" not in value:
        kinds = ", ".join(LIGHT_KINDS)
        raise SpectralError(f"{where}: a light is an object with a \"kind\" ({kinds}), found {value!r}")
    kind = _choice(value["kind"], f"{where}.kind", LIGHT_KINDS)
    extra = _LIGHT_FIELDS[kind]
    schema = {"required": _LIGHT_COMMON + extra["required"], "optional": _LIGHT_OPTIONAL + extra["optional"]}
    data = _fields(value, where, schema, what=f" for {kind} lights")
    spectrum = _light_spectrum(data["spectrum"], f"{where}.spectrum", folder)
    fields = {}
    if kind == "sun":
        fields["direction"] = _direction(data["direction"], f"{where}.direction")
        fields["angle"] = float(np.radians(_float(data.get("angle", 0.0), f"{where}.angle", 0.0, 180.0)))
    if kind == "sky" and "horizon_spectrum" in data:
        fields["horizon_spectrum"] = _light_spectrum(
            data["horizon_spectrum"], f"{where}.horizon_spectrum", folder)
    if kind in ("point", "spot"):
        fields["position"] = _vector(data["position"], f"{where}.position")
    if kind == "spot":
        fields["spot_direction"] = _direction(data["spot_direction"], f"{where}.spot_direction")
        size = data.get("spot_size", np.degrees(Light.spot_size))
        fields["spot_size"] = float(np.radians(_float(size, f"{where}.spot_size", 0.0, 180.0, closed=False)))
        fields["spot_blend"] = _float(data.get("spot_blend", Light.spot_blend), f"{where}.spot_blend", 0.0, 1.0)
    name = data.get("name", "")
    if not isinstance(name, str):
        raise SpectralError(f"{where}.name: expected a string, found {name!r}")
    strength = _float(data.get("strength", 1.0), f"{where}.strength", 0.0)
    return Light(kind=kind, spectrum=spectrum, strength=strength, name=name, **fields)


def _light_spectrum(value, where: str, folder: Path) -> Spectrum:
    spectrum = _spectrum(value, where, folder)
    _check_range(spectrum, where, "a light spectrum must not be negative", 0.0, np.inf)
    return spectrum


def _render(value, where: str) -> RenderSettings:
    data = _fields(value, where, _RENDER)
    defaults = RenderSettings()

    def get(key):
        return data.get(key, getattr(defaults, key))

    lambda_min = _float(get("lambda_min"), f"{where}.lambda_min", LAMBDA_MIN, LAMBDA_MAX)
    lambda_max = _float(get("lambda_max"), f"{where}.lambda_max", LAMBDA_MIN, LAMBDA_MAX)
    if lambda_min >= lambda_max:
        raise SpectralError(
            f"{where}: the wavelength range {lambda_min:g}–{lambda_max:g} nm is empty "
            "(lambda_min must be below lambda_max)"
        )
    per_path = _int(get("wavelengths_per_path"), f"{where}.wavelengths_per_path", minimum=1)
    if per_path not in WAVELENGTHS_PER_PATH:
        raise SpectralError(f"{where}.wavelengths_per_path: must be 1 or 4, found {per_path}")
    return RenderSettings(
        spp=_int(get("spp"), f"{where}.spp", minimum=1),
        seed=_int(get("seed"), f"{where}.seed", minimum=0),
        max_depth=_int(get("max_depth"), f"{where}.max_depth", minimum=1),
        rr_depth=_int(get("rr_depth"), f"{where}.rr_depth", minimum=0),
        wavelength_sampling=_choice(get("wavelength_sampling"), f"{where}.wavelength_sampling", WAVELENGTH_SAMPLINGS),
        wavelengths_per_path=per_path,
        lambda_min=lambda_min,
        lambda_max=lambda_max,
        bands=_int(get("bands"), f"{where}.bands", minimum=1),
        cmf=_choice(get("cmf"), f"{where}.cmf", CMFS),
        backend=_choice(get("backend"), f"{where}.backend", BACKENDS),
    )


# ---------------------------------------------------------------------------------------------- values


def _fields(value, where: str, schema: dict, what: str = "") -> dict:
    """`value` as a dict with every required key and no unknown one; `what` qualifies the messages."""
    if not isinstance(value, dict):
        raise SpectralError(f"{where}: expected an object, found {value!r}")
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
        raise SpectralError(f"{where}: expected a list, found {value!r}")
    return value


def _float(value, where: str, low: float = -np.inf, high: float = np.inf, closed: bool = True) -> float:
    """A finite number in [low, high] (or (low, high) when not `closed`)."""
    try:
        number = float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else np.nan
    except OverflowError:
        number = np.nan
    if not np.isfinite(number):
        raise SpectralError(f"{where}: expected a finite number, found {value!r}")
    inside = low <= number <= high if closed else low < number < high
    if not inside:
        brackets = "[]" if closed else "()"
        raise SpectralError(f"{where}: must be within {brackets[0]}{low:g}, {high:g}{brackets[1]}, found {number:g}")
    return number


def _positive(value, where: str) -> float:
    number = _float(value, where)
    if number <= 0:
        raise SpectralError(f"{where}: must be positive, found {number:g}")
    return number


def _int(value, where: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise SpectralError(f"{where}: expected a whole number, found {value!r}")
    if value < minimum:
        raise SpectralError(f"{where}: must be at least {minimum}, found {value}")
    return value


def _choice(value, where: str, allowed: tuple) -> str:
    if value not in allowed:
        raise SpectralError(f"{where}: unknown value {value!r} (allowed: {', '.join(allowed)})")
    return value


def _vector(value, where: str) -> np.ndarray:
    if not isinstance(value, list) or len(value) != 3:
        raise SpectralError(f"{where}: expected a list of 3 numbers, found {value!r}")
    return np.array([_float(c, f"{where}[{i}]") for i, c in enumerate(value)])


def _direction(value, where: str) -> np.ndarray:
    vector = _vector(value, where)
    length = np.linalg.norm(vector)
    if length == 0:
        raise SpectralError(f"{where}: a direction cannot have zero length")
    return vector / length


def _spectrum(value, where: str, folder: Path) -> Spectrum:
    """`spectra.from_spec` with the JSON path in every error, and NumPy's complaints about wrongly typed
    fields turned into a SpectralError that shows the description."""
    try:
        return spectra.from_spec(value, name=where, base_dir=folder)
    except SpectralError as problem:
        message = str(problem)
        raise SpectralError(message if where in message else f"{where}: {message}") from None
    except (TypeError, ValueError) as problem:
        raise SpectralError(f"{where}: invalid spectrum description {value!r} ({problem})") from None


def _check_range(spectrum: Spectrum, where: str, rule: str, low: float, high: float, closed: bool = True) -> None:
    """Error naming the worst value outside [low, high] (or the open interval) and its wavelength."""
    values = spectrum.values
    outside = (values < low) | (values > high) if closed else (values <= low) | (values >= high)
    if outside.any():
        excess = np.where(outside, np.maximum(low - values, values - high), -np.inf)
        worst = int(np.argmax(excess))
        raise SpectralError(f"{where}: {rule}, found {values[worst]:g} at {GRID[worst]:g} nm")


# ---------------------------------------------------------------------------------------------- saving


def save_scene(scene: Scene, folder) -> Path:
    """Write `scene` as `folder/scene.json` plus one `.npy` per grid; returns the JSON file's path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    data = {
        "format": FORMAT,
        "version": VERSION,
        "camera": _camera_json(scene.camera),
        "media": [_medium_json(medium, i, folder) for i, medium in enumerate(scene.media)],
        "lights": [_light_json(light) for light in scene.lights],
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


def _light_json(light: Light) -> dict:
    data = {"kind": light.kind, "name": light.name, "spectrum": _spectrum_json(light.spectrum)}
    data["strength"] = float(light.strength)
    if light.kind == "sun":
        data["direction"] = _floats(light.direction)
        data["angle"] = float(np.degrees(light.angle))
    if light.kind == "sky" and light.horizon_spectrum is not None:
        data["horizon_spectrum"] = _spectrum_json(light.horizon_spectrum)
    if light.kind in ("point", "spot"):
        data["position"] = _floats(light.position)
    if light.kind == "spot":
        data["spot_direction"] = _floats(light.spot_direction)
        data["spot_size"] = float(np.degrees(light.spot_size))
        data["spot_blend"] = float(light.spot_blend)
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
    return text


def _world_bounds(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """World-space box around all voxels (cells extend half a voxel beyond the outer centres)."""
    nx, ny, nz = grid.values.shape
    corners = np.array([[x, y, z, 1.0] for x in (-0.5, nx - 0.5) for y in (-0.5, ny - 0.5) for z in (-0.5, nz - 0.5)])
    world = corners @ np.asarray(grid.index_to_world).T
    return world[:, :3].min(axis=0), world[:, :3].max(axis=0)


def _describe_light(light: Light) -> str:
    text = f"light {light.name or '(unnamed)'!r}: {light.kind}, strength {light.strength:g}"
    if light.kind == "sun":
        text += f", towards ({', '.join(f'{c:.3g}' for c in light.direction)}), {np.degrees(light.angle):.3g}° wide"
    if light.kind in ("point", "spot"):
        text += f", at ({', '.join(f'{c:.4g}' for c in light.position)})"
    return text
