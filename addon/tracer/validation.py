"""Scene validation: every rule a scene must meet, whoever built it (the scene file reader, the exporter, code).

`validate(scene)` raises a SpectralError naming the first invalid field by its scene-file path (`media[0].albedo:
...`) and in the file's units; `check_settings` checks render settings alone (the command lines' overrides).
Above the data model (`scene`), the grid and light policies it asks (`checks`, `lights`), so that the model
itself imports none of them.
"""

import numpy as np

from . import backends, checks, colorimetry
from .colorimetry import CMF_NAMES as CMFS
from .errors import SpectralError
from .kernels.layout import (AREA_SHAPES, CAMERA_KINDS, LIGHT_KINDS, PHASES, TEXTURE_EXTENSIONS, TEXTURE_INTERPOLATIONS,
                             WAVELENGTHS_PER_PATH)
from .lights import peak_emission
from .phase import HG_G_LIMIT
from .scene import (DEPTH_MAX, LIGHT_UNITS, RADIANT_UNITS, SEED_MAX, SENSOR_FITS, SPP_MAX,
                    WAVELENGTH_SAMPLINGS, BlackbodyEmission, Camera, Fluorescence, Glow, Grid, Light, Medium,
                    RenderSettings, Scene, Surface, Texture)
from .spectra import Spectrum
from .wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN

# Delta and ratio tracking take about one step per unit of optical depth (through the majorant) along a
# ray, so a medium far thicker than this renders for hours and cannot be interrupted mid-ray. It is also
# far beyond anything visible: light through optical depth 30 is dimmed by e⁻³⁰ ≈ 1e-13.
MAX_OPTICAL_DEPTH = 1e5
# The most a light may emit per nm (its spectrum × strength in the unit of RADIANT_UNITS per nm, at its peak; an
# envmap's brightest texel): a pixel's samples of brighter light, and their squares (the variance), overflow
# the float32 of the image files (3.4e38). The Sun at noon gives about 1.9 W·m⁻²·nm⁻¹.
MAX_LIGHT_PEAK = 1e15
# An area light's axes (the columns of `Light.area_axes`) may be this far from orthogonal (the cosine of
# their angle): Blender's float32 matrices are orthogonal to about 1e-7.
AREA_AXES_ORTHOGONAL_TO = 1e-5
# An envmap's `to_world` may be this far from orthonormal (its columns' lengths from 1, their cosines from 0).
ENVMAP_ORTHONORMAL_TO = 1e-5


def validate(scene: Scene) -> Scene:
    """`scene`, or a SpectralError naming its first invalid field by its scene-file path and in the file's units
    (`media[0].albedo: ...`, `camera.fov` in degrees)."""
    check_settings(scene.settings, "render")  # first: the lights' check uses its colour matching functions
    _check_camera(scene.camera, "camera")
    for index, medium in enumerate(scene.media):
        _check_medium(medium, f"media[{index}]")
    if scene.settings.backend == "cuda":
        backends.check_cuda_media(len(scene.media), "media")
    for index, light in enumerate(scene.lights):
        _check_light(light, f"lights[{index}]", scene.settings.cmf)
    for index, surface in enumerate(scene.surfaces):
        _check_surface(surface, f"surfaces[{index}]")
    emitters = any(medium.emits() for medium in scene.media) or any(s.emission is not None for s in scene.surfaces)
    if not scene.lights and not emitters:
        raise SpectralError("lights: the scene has no lights: add a sun, environment, sky, envmap, point, spot "
                            "or area light (or an emitting medium or surface)")
    if scene.lights and not any(light.strength > 0 for light in scene.lights):
        raise SpectralError("lights: every light has strength 0, so nothing is lit")
    return scene


def _check_camera(camera: Camera, where: str) -> None:
    checks.whole_within(camera.width, f"{where}.width", 1)
    checks.whole_within(camera.height, f"{where}.height", 1)
    checks.one_of(camera.kind, f"{where}.kind", CAMERA_KINDS)
    checks.within(np.degrees(checks.number(camera.fov, f"{where}.fov")), f"{where}.fov", 0.0, 180.0, closed=False)
    checks.positive(checks.number(camera.ortho_scale, f"{where}.ortho_scale"), f"{where}.ortho_scale")
    checks.one_of(camera.sensor_fit, f"{where}.sensor_fit", SENSOR_FITS)
    checks.number(camera.shift_x, f"{where}.shift_x")
    checks.number(camera.shift_y, f"{where}.shift_y")
    checks.positive(checks.number(camera.pixel_aspect, f"{where}.pixel_aspect"), f"{where}.pixel_aspect")
    checks.affine_matrix(camera.to_world, f"{where}.to_world")


def _check_grid(grid: Grid, where: str, nonnegative: bool = True) -> None:
    checks.grid_values(np.asarray(grid.values), f"{where}: grid {grid.name!r}", nonnegative)
    checks.affine_matrix(grid.index_to_world, f"{where}.index_to_world")


def _check_medium(medium: Medium, where: str) -> None:
    if not isinstance(medium.name, str):
        raise SpectralError(f"{where}.name: expected a string, found {checks.shown(medium.name)}")
    _check_grid(medium.density, f"{where}.density")
    checks.positive(checks.number(medium.density_scale, f"{where}.density_scale"), f"{where}.density_scale")
    checks.spectrum_within(medium.extinction.values, f"{where}.extinction", "extinction must not be negative",
                           0.0, np.inf)
    _check_albedo(medium.albedo_densities, medium.albedo_table, f"{where}.albedo")
    checks.spectrum_within(medium.anisotropy.values, f"{where}.anisotropy",
                           f"|g| must be at most {HG_G_LIMIT!r} (sharper lobes are not resolved by float64 directions)",
                           -HG_G_LIMIT, HG_G_LIMIT)
    checks.one_of(medium.phase, f"{where}.phase", PHASES)
    _check_optical_depth(medium, where)
    if medium.fluorescence is not None:
        _check_fluorescence(medium.fluorescence, f"{where}.fluorescence")
    if medium.emission is not None:
        _check_emission(medium.emission, f"{where}.emission")
    if medium.glow is not None:
        if medium.emission is not None:
            raise SpectralError(f"{where}.glow: a medium has one temperature, so it takes either \"emission\" "
                                "(thermal) or \"glow\", not both")
        _check_glow(medium.glow, f"{where}.glow")


def _check_surface(surface: Surface, where: str) -> None:
    for key in ("name", "object", "material"):
        if not isinstance(getattr(surface, key), str):
            raise SpectralError(f"{where}.{key}: expected a string, found {checks.shown(getattr(surface, key))}")
    _check_boolean(surface.holdout, f"{where}.holdout")
    vertices = _float_array(lambda: surface.vertices, f"{where}.vertices")
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise SpectralError(f"{where}.vertices: expected a list of [x, y, z] points, found an array of shape "
                            f"{vertices.shape}")
    finite = np.isfinite(vertices)
    if not finite.all():
        at = tuple(int(i) for i in np.argwhere(~finite)[0])
        raise SpectralError(f"{where}.vertices: must be finite, found {vertices[at]:g} at index {list(at)}")
    triangles = np.asarray(surface.triangles)
    if triangles.ndim != 2 or triangles.shape[1] != 3 or triangles.shape[0] == 0:
        raise SpectralError(f"{where}.triangles: expected a non-empty list of [i, j, k] vertex indices, found an "
                            f"array of shape {triangles.shape}")
    if not np.issubdtype(triangles.dtype, np.integer):
        raise SpectralError(f"{where}.triangles: expected whole numbers (vertex indices), found {triangles.dtype}")
    outside = (triangles < 0) | (triangles >= vertices.shape[0])
    if outside.any():
        at = tuple(int(i) for i in np.argwhere(outside)[0])
        raise SpectralError(f"{where}.triangles: vertex index {int(triangles[at])} at {list(at)} is outside the "
                            f"{vertices.shape[0]} vertices (indices count from 0)")
    checks.spectrum_within(surface.reflectance.values, f"{where}.reflectance", "a reflectance must be within [0, 1]",
                           0.0, 1.0)
    _check_boolean(surface.camera, f"{where}.camera")
    if surface.texture is not None:
        _check_texture(surface.texture, triangles.shape[0], f"{where}.texture")
    if surface.emission is not None:
        checks.spectrum_within(surface.emission.values, f"{where}.emission", "an emission must not be negative",
                               0.0, np.inf)


def _rgb_image(get, where: str, least_columns: int) -> np.ndarray:
    """An (H, W, 3) RGB image (an envmap's, a texture's) as a float array: H ≥ 1 rows, W ≥ `least_columns`."""
    image = _float_array(get, where)
    if image.ndim != 3 or image.shape[0] < 1 or image.shape[1] < least_columns or image.shape[2] != 3:
        raise SpectralError(f"{where}: expected an array of H ≥ 1 rows, W ≥ {least_columns} columns and 3 channels "
                            f"(R, G, B), found shape {image.shape}")
    return image


def _check_texture(texture: Texture, triangles: int, where: str) -> None:
    """A surface's texture: an (H, W, 3) image of texels within [0, 1], a (u, v) per corner of each of the
    surface's `triangles`, all finite, and Blender's names for its extension and interpolation."""
    if not isinstance(texture, Texture):
        raise SpectralError(f"{where}: expected a texture (image, uv, extension, interpolation), found "
                            f"{checks.shown(texture)}")
    image = _rgb_image(lambda: texture.image, f"{where}.image", least_columns=1)
    bad = ~np.isfinite(image) | (image < 0.0) | (image > 1.0)
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        raise SpectralError(f"{where}.image: a reflectance texel must be a finite colour within [0, 1], found "
                            f"{image[at]:g} at texel [row, column, channel] {list(at)}")
    uv = _float_array(lambda: texture.uv, f"{where}.uv")
    if uv.shape != (triangles, 3, 2):
        raise SpectralError(f"{where}.uv: expected a (u, v) for each corner of the surface's {triangles} triangles, "
                            f"shape ({triangles}, 3, 2), found shape {uv.shape}")
    if not np.isfinite(uv).all():
        at = tuple(int(i) for i in np.argwhere(~np.isfinite(uv))[0])
        raise SpectralError(f"{where}.uv: must be finite, found {uv[at]:g} at [triangle, corner, u/v] {list(at)}")
    checks.one_of(texture.extension, f"{where}.extension", TEXTURE_EXTENSIONS)
    checks.one_of(texture.interpolation, f"{where}.interpolation", TEXTURE_INTERPOLATIONS)
    _check_boolean(texture.srgb, f"{where}.srgb")


def optical_depth(medium: Medium) -> float:
    """An upper bound of the optical depth along any straight path through the medium: its largest
    extinction coefficient (with fluorescent absorption) times the diagonal of its grid's world box."""
    extinction = medium.extinction.values
    if medium.fluorescence is not None:
        extinction = extinction + medium.fluorescence.excitation.values
    diagonal = medium.density.world_diagonal()
    return float(medium.density_scale * extinction.max() * medium.density.values.max()) * diagonal


def _check_optical_depth(medium: Medium, where: str) -> None:
    depth = optical_depth(medium)
    if not depth <= MAX_OPTICAL_DEPTH:
        raise SpectralError(
            f"{where}: the optical depth through the medium reaches {depth:.3g} (density_scale × extinction × "
            f"density × size), more than the {MAX_OPTICAL_DEPTH:g} the tracer accepts: tracking would take about "
            f"that many steps per ray, and nothing shows through beyond ~30; lower density_scale or extinction")


def _check_albedo(densities, table, where: str) -> None:
    """The table's rows are written as `where` when it is one level at density 0 (the scene file's single
    spectrum), else as `where.spectra[i]` with their levels `where.densities[i]`."""
    densities, table = np.asarray(densities, dtype=np.float64), np.asarray(table, dtype=np.float64)
    if densities.ndim != 1 or densities.size == 0 or table.shape != (densities.size, GRID.size):
        raise SpectralError(f"{where}: expected L density levels and an L × {GRID.size} table, found shapes "
                            f"{densities.shape} and {table.shape}")
    single = densities.size == 1 and densities[0] == 0
    for index, density in enumerate(densities):
        checks.within(checks.number(density, f"{where}.densities[{index}]"), f"{where}.densities[{index}]", 0.0)
    if np.any(np.diff(densities) <= 0):
        raise SpectralError(f"{where}.densities: density levels must increase strictly, found {densities.tolist()}")
    for index, row in enumerate(table):
        row_where = where if single else f"{where}.spectra[{index}]"
        if not np.all(np.isfinite(row)):
            raise SpectralError(f"{row_where}: the albedo contains NaN or infinite values")
        checks.spectrum_within(row, row_where, "albedo must be within [0, 1]", 0.0, 1.0)


def _check_fluorescence(fluorescence: Fluorescence, where: str) -> None:
    for part in ("excitation", "emission"):
        values = getattr(fluorescence, part).values
        checks.spectrum_within(values, f"{where}.{part}", f"{part} must not be negative", 0.0, np.inf)
        if not values.any():
            raise SpectralError(f"{where}.{part}: the {part} spectrum is zero everywhere"
                                + (", so it cannot be a pdf" if part == "emission" else ""))
    checks.within(checks.number(fluorescence.quantum_yield, f"{where}.quantum_yield"), f"{where}.quantum_yield",
                  0.0, 1.0)


def _check_emission(emission: BlackbodyEmission, where: str) -> None:
    checks.within(checks.number(emission.intensity, f"{where}.intensity"), f"{where}.intensity", 0.0)
    _check_temperature(emission.temperature, emission.temperature_scale, emission.temperature_offset, where)


def _check_glow(glow: Glow, where: str) -> None:
    if glow.spectrum is not None:
        checks.spectrum_within(glow.spectrum.values, f"{where}.spectrum", "a glow must not be negative", 0.0, np.inf)
    blackbody = checks.within(checks.number(glow.blackbody, f"{where}.blackbody"), f"{where}.blackbody", 0.0)
    checks.spectrum_within(glow.tint.values, f"{where}.tint", "a tint must not be negative", 0.0, np.inf)
    _check_temperature(glow.temperature, glow.temperature_scale, glow.temperature_offset, where)
    if blackbody > 0 and glow.temperature is None and glow.temperature_offset == 0:
        raise SpectralError(f"{where}.temperature: a black-body glow needs a temperature: a grid, or a constant "
                            "temperature_offset in kelvin")


def _check_temperature(grid: Grid | None, scale, offset, where: str) -> None:
    """Temperature = grid value × scale + offset (a missing grid reads 0) must be non-negative kelvin."""
    if grid is not None:
        _check_grid(grid, f"{where}.temperature", nonnegative=False)
    scale = checks.number(scale, f"{where}.temperature_scale")
    offset = checks.number(offset, f"{where}.temperature_offset")
    coldest = offset
    if grid is not None:
        coldest += min(float(grid.values.min()) * scale, float(grid.values.max()) * scale)
    if coldest < 0:
        raise SpectralError(f"{where}: temperatures (grid value × temperature_scale + temperature_offset) must be "
                            f"non-negative kelvin, found {coldest:g} K")


def _check_light(light: Light, where: str, cmf: str) -> None:
    kind = checks.one_of(light.kind, f"{where}.kind", LIGHT_KINDS)
    unit = checks.one_of(light.unit, f"{where}.unit", LIGHT_UNITS)
    if kind == "envmap":
        _check_envmap(light, where)
    elif light.spectrum is None:
        raise SpectralError(f"{where}.spectrum: a {kind} light needs a spectrum")
    else:
        _check_light_spectrum(light.spectrum, f"{where}.spectrum", unit, cmf)
    checks.within(checks.number(light.strength, f"{where}.strength"), f"{where}.strength", 0.0)
    if not isinstance(light.name, str):
        raise SpectralError(f"{where}.name: expected a string, found {checks.shown(light.name)}")
    if kind == "sun":
        checks.direction(light.direction, f"{where}.direction")
        checks.within(np.degrees(checks.number(light.angle, f"{where}.angle")), f"{where}.angle", 0.0, 180.0)
    if kind == "sky" and light.horizon_spectrum is not None:
        _check_light_spectrum(light.horizon_spectrum, f"{where}.horizon_spectrum", unit, cmf)
    if kind in ("point", "spot", "area"):
        checks.vector(light.position, f"{where}.position")
    if kind == "spot":
        checks.direction(light.spot_direction, f"{where}.spot_direction")
        checks.within(np.degrees(checks.number(light.spot_size, f"{where}.spot_size")), f"{where}.spot_size",
                      0.0, 180.0, closed=False)
        checks.within(checks.number(light.spot_blend, f"{where}.spot_blend"), f"{where}.spot_blend", 0.0, 1.0)
    if kind == "area":
        _check_area_axes(light.area_axes, f"{where}.area_axes")
        checks.one_of(light.area_shape, f"{where}.area_shape", AREA_SHAPES)
        for key in ("size_x", "size_y"):
            checks.positive(checks.number(getattr(light, key), f"{where}.{key}"), f"{where}.{key}")
        if not isinstance(light.camera_visible, (bool, np.bool_)):
            raise SpectralError(f"{where}.camera_visible: expected true or false, found {checks.shown(light.camera_visible)}")
    _check_light_peak(light, where, cmf)


def _check_light_peak(light: Light, where: str, cmf: str) -> None:
    peak = peak_emission(light, cmf)
    if not peak <= MAX_LIGHT_PEAK:
        raise SpectralError(f"{where}.strength: the light's spectrum × strength peaks at {peak:.3g} "
                            f"{RADIANT_UNITS[light.kind]} per nm, more than the {MAX_LIGHT_PEAK:g} the tracer "
                            "accepts (its samples' squares, the variance, would overflow the float32 of the image "
                            "files): lower the strength")


def _check_envmap(light: Light, where: str) -> None:
    """An envmap's image, basis and rotation (its spectrum is its image and basis; its strength a factor)."""
    if light.spectrum is not None:
        raise SpectralError(f"{where}.spectrum: an envmap's colour is its image and basis: give it no spectrum")
    if light.unit != "radiant":
        raise SpectralError(f"{where}.unit: an envmap's strength multiplies its map (radiance = strength × Σ rgb · "
                            f"basis): its unit must be \"radiant\", found {checks.shown(light.unit)}")
    image = _rgb_image(lambda: light.image, f"{where}.image", least_columns=2)
    with np.errstate(over="ignore"):  # the kernels read it as float32: a value beyond float32 is inf, refused
        _check_finite_nonnegative(image.astype(np.float32), f"{where}.image", "texel [row, column, channel]")
    basis = _float_array(light.basis_values, f"{where}.basis")
    if basis.shape != (3, GRID.size):
        raise SpectralError(f"{where}.basis: expected 3 spectra (R, G, B) on the {GRID.size}-node grid, found shape "
                            f"{basis.shape}")
    _check_finite_nonnegative(basis, f"{where}.basis", "[channel, wavelength index]")
    if not (image.sum(axis=(0, 1)) @ basis).any():
        raise SpectralError(f"{where}.image: the map is black (every texel's radiance Σ rgb · basis is zero)")
    if light.to_world is not None:
        to_world = checks.matrix3(light.to_world, f"{where}.to_world")
        error = np.abs(to_world.T @ to_world - np.eye(3)).max()
        if error > ENVMAP_ORTHONORMAL_TO:
            raise SpectralError(f"{where}.to_world: must be orthonormal (a rotation), found its columns' lengths and "
                                f"cosines off by up to {error:.3g}")


def _float_array(values, where: str) -> np.ndarray:
    """The float64 array that `values()` gives, or an error naming `where`."""
    try:
        return np.asarray(values(), dtype=np.float64)
    except (TypeError, ValueError):
        raise SpectralError(f"{where}: expected an array of numbers") from None


def _check_finite_nonnegative(values: np.ndarray, where: str, index: str) -> None:
    bad = ~np.isfinite(values) | (values < 0)
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        raise SpectralError(f"{where}: must be finite and non-negative, found {values[at]:g} at {index} "
                            f"{list(at)}")


def _check_area_axes(axes, where: str) -> None:
    """Three mutually orthogonal columns (to AREA_AXES_ORTHOGONAL_TO) of finite, non-zero length."""
    columns = checks.matrix3(axes, where).T
    for index, column in enumerate(columns):
        if not np.abs(column).max() > 0:
            raise SpectralError(f"{where}: its column {index} (local {'XYZ'[index]}) must have a non-zero length")
    unit = checks.unit(columns)
    for first, second in ((0, 1), (0, 2), (1, 2)):
        cosine = float(unit[first] @ unit[second])
        if abs(cosine) > AREA_AXES_ORTHOGONAL_TO:
            raise SpectralError(f"{where}: its columns (local X, Y, Z) must be orthogonal, found local "
                                f"{'XYZ'[first]} and {'XYZ'[second]} at cosine {cosine:.3g}")


def _check_light_spectrum(spectrum: Spectrum, where: str, unit: str, cmf: str) -> None:
    checks.spectrum_within(spectrum.values, where, "a light spectrum must not be negative", 0.0, np.inf)
    if not spectrum.values.any():
        raise SpectralError(f"{where}: the light's spectrum is zero everywhere")
    if unit == "luminous" and not colorimetry.spectrum_to_xyz(spectrum.values, cmf)[1] > 0:
        raise SpectralError(f"{where}: the spectrum has no visible part (luminance Y = 0), so a luminous "
                            "strength cannot scale it: give the light \"unit\": \"radiant\" (watts)")


def check_settings(settings: RenderSettings, where: str = "render") -> None:
    """The render settings' part of `validation.validate` (also for settings overridden after loading)."""
    checks.whole_within(settings.spp, f"{where}.spp", 1, SPP_MAX)
    checks.whole_within(settings.seed, f"{where}.seed", 0, SEED_MAX)
    checks.whole_within(settings.max_depth, f"{where}.max_depth", 1, DEPTH_MAX)
    checks.whole_within(settings.rr_depth, f"{where}.rr_depth", 0, DEPTH_MAX)
    checks.one_of(settings.wavelength_sampling, f"{where}.wavelength_sampling", WAVELENGTH_SAMPLINGS)
    per_path = checks.whole(settings.wavelengths_per_path, f"{where}.wavelengths_per_path")
    if per_path not in WAVELENGTHS_PER_PATH:
        raise SpectralError(f"{where}.wavelengths_per_path: must be "
                            f"{' or '.join(map(str, WAVELENGTHS_PER_PATH))}, found {per_path}")
    lambda_min, lambda_max = (
        checks.within(checks.number(getattr(settings, key), f"{where}.{key}"), f"{where}.{key}", LAMBDA_MIN, LAMBDA_MAX)
        for key in ("lambda_min", "lambda_max"))
    if lambda_min >= lambda_max:
        raise SpectralError(f"{where}: the wavelength range {lambda_min:g}–{lambda_max:g} nm is empty "
                            "(lambda_min must be below lambda_max)")
    if checks.whole_within(settings.bands, f"{where}.bands", 1) > 1:
        from .sampling import band_ranges  # the rule of bands, where they are made
        from .wavelength_modes import default_band

        try:
            band_ranges(*default_band(settings), settings.bands)
        except SpectralError as problem:
            raise SpectralError(f"{where}.bands: {problem}") from None
    checks.one_of(settings.cmf, f"{where}.cmf", CMFS)
    checks.one_of(settings.backend, f"{where}.backend", backends.NAMES)
    checks.within(checks.number(settings.noise_threshold, f"{where}.noise_threshold"), f"{where}.noise_threshold",
                  0.0, 1.0)
    checks.whole_within(settings.min_samples, f"{where}.min_samples", 0)
    _check_boolean(settings.transparent, f"{where}.transparent")
    for key in ("clamp_direct", "clamp_indirect", "firefly_threshold"):
        checks.within(checks.number(getattr(settings, key), f"{where}.{key}"), f"{where}.{key}", 0.0)
    from .passes import check_passes  # the passes' rules, where they are made

    check_passes(settings, where)
    from .spectral_film import check_bins  # the spectral image's rules, where its bins are made

    check_bins(settings, where)


def _check_boolean(value, where: str) -> None:
    if not isinstance(value, (bool, np.bool_)):
        raise SpectralError(f"{where}: expected true or false, found {checks.shown(value)}")
