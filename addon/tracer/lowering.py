"""Lowers a `Scene` to the arrays the kernels consume (`KernelScene`, grouped by concept), for one wavelength band.

Everything the integrator needs is precomputed here once per band: spectra tabulated on the grid,
light spectra scaled to their strength and the lights' selection probabilities (`lights`), majorant
and minorant grids, the hero-wavelength distribution (`wavelength_modes`) and the XYZ weights. Both backends read
the same `KernelScene`, so they cannot disagree about the scene.
"""

import numpy as np

from . import bvh, colorimetry, envmaps, sampling, texel_spectra
from .checks import unit
from .errors import SpectralError
from .glow import normalisation_table
from .kernels.layout import (
    AREA_SHAPES,
    CAMERA_KINDS,
    LIGHT_KINDS,
    LIGHT_MESH,
    PHASES,
    TEXTURE_EXTENSIONS,
    TEXTURE_INTERPOLATIONS,
    KernelCamera,
    KernelDensity,
    KernelEnvmaps,
    KernelFluorescence,
    KernelGlow,
    KernelLights,
    KernelMajorant,
    KernelMedia,
    KernelScene,
    KernelSurfaces,
    KernelTemperature,
    KernelTermination,
    KernelWavelengths,
)
from .kernels.media import attenuation
from .lights import kernel_spectrum, selection_powers, surface_power, texel_weights
from .majorant import block_size_for, glow_floor, majorant_grid, minorant_grid
from .probe_grid import no_probe, with_probe
from .scene import Grid, Light, Medium, Scene, Surface
from .spectral_film import bin_edges
from .wavelength_modes import default_band, with_band
from .wavelengths import GRID, LAMBDA_MAX, LAMBDA_MIN
from .validation import validate


def _world_to_padded(grid: Grid) -> np.ndarray:
    try:
        inverse = np.linalg.inv(np.asarray(grid.index_to_world, dtype=np.float64))
    except np.linalg.LinAlgError:
        raise SpectralError(f"grid {grid.name!r}: its index-to-world transform is singular") from None
    shift = np.eye(4)
    shift[:3, 3] = 1.0
    return shift @ inverse


def _flatten(arrays):
    """The grids back to back in one float32 array (a single C-contiguous float32 grid is not copied:
    at 512³ a copy is 0.5 GiB), with each grid's offset and shape."""
    offsets = np.cumsum([0] + [a.size for a in arrays[:-1]]).astype(np.int64) if arrays else np.zeros(0, np.int64)
    flat = [np.ascontiguousarray(a, dtype=np.float32).ravel() for a in arrays]
    data = (flat[0] if len(flat) == 1 else np.concatenate(flat)) if flat else np.zeros(1, np.float32)
    shapes = np.array([a.shape for a in arrays], dtype=np.int64).reshape(-1, 3)
    return data, offsets, shapes


def _media_arrays(media: tuple[Medium, ...], cmf: str) -> dict:
    """The kernel scene's groups that describe the media, by name: `density`, `majorant`, `temperature`,
    `glow`, `media` and `fluorescence`."""
    count = len(media)
    levels = max([m.albedo_densities.size for m in media], default=1)
    optics = KernelMedia(
        density_scale=np.array([m.density_scale for m in media], dtype=np.float64),
        extinction=np.array([m.extinction.values for m in media]).reshape(count, GRID.size),
        anisotropy=np.array([m.anisotropy.values for m in media]).reshape(count, GRID.size),
        phase_kind=np.array([PHASES.index(m.phase) for m in media], dtype=np.int64),
        albedo_densities=np.zeros((count, levels)),
        albedo_count=np.array([m.albedo_densities.size for m in media], dtype=np.int64),
        albedo_table=np.zeros((count, levels, GRID.size)),
    )
    fluorescence = KernelFluorescence(
        excitation=np.zeros((count, GRID.size)),
        excitation_mean=np.zeros(count),
        strength=np.zeros(count),
        emission_pdf=np.zeros((count, GRID.size)),
        excitation_cdf=np.zeros((count, GRID.size)),
        excitation_pdf=np.zeros((count, GRID.size - 1)),
    )
    for index, medium in enumerate(media):
        n = medium.albedo_densities.size
        optics.albedo_densities[index, :n] = medium.albedo_densities
        optics.albedo_table[index, :n] = medium.albedo_table
        if medium.fluorescence is not None:
            dye = medium.fluorescence
            fluorescence.excitation[index] = dye.excitation.values
            total = dye.excitation.integral()
            emission_total = dye.emission.integral()
            fluorescence.strength[index] = dye.quantum_yield * total
            fluorescence.excitation_mean[index] = np.trapezoid(dye.excitation.values ** 2, GRID) / total
            fluorescence.emission_pdf[index] = dye.emission.values / emission_total
            excitation = sampling.from_spectrum(dye.excitation, LAMBDA_MIN, LAMBDA_MAX)
            fluorescence.excitation_cdf[index] = excitation.cdf
            fluorescence.excitation_pdf[index] = excitation.bin_pdf
    peak = attenuation(1.0, optics.extinction, fluorescence.excitation)  # σ_t per unit density, as tracking sees it

    densities = [np.asarray(m.density.values, dtype=np.float32) for m in media]
    density = KernelDensity(*_flatten(densities),
                            world_to_padded=np.array([_world_to_padded(m.density) for m in media]).reshape(count, 4, 4))
    blocks = [block_size_for(d.shape) for d in densities]
    majorants = [majorant_grid(d, b) for d, b in zip(densities, blocks)]
    coeff = optics.density_scale * (peak.max(axis=1) if count else np.zeros(0))
    for index, medium in enumerate(media):
        if medium.glow is not None:
            coeff[index] = max(coeff[index], glow_floor(densities[index], medium.density.world_diagonal()))
    majorant = KernelMajorant(*_flatten(majorants),
                              block=np.array(blocks, dtype=np.int64),
                              coeff=coeff,
                              minorant=_flatten([minorant_grid(d, b) for d, b in zip(densities, blocks)])[0])
    return {"density": density, "majorant": majorant, "temperature": _temperature_grids(media),
            "glow": _glow_arrays(media, cmf), "media": optics, "fluorescence": fluorescence}


# A black-body glow without a temperature grid reads this one-cell grid of 0: its temperature_offset everywhere.
_NO_TEMPERATURE_GRID = Grid(np.zeros((1, 1, 1), dtype=np.float32), np.eye(4), name="constant temperature")


def _temperature(medium: Medium) -> tuple[Grid, float, float, float] | None:
    """A medium's temperature (grid, scale, offset) and thermal intensity, or None where it emits no black body."""
    if medium.emission is not None:
        emission = medium.emission
        return emission.temperature, emission.temperature_scale, emission.temperature_offset, emission.intensity
    glow = medium.glow
    if glow is not None and glow.blackbody > 0:
        grid = glow.temperature if glow.temperature is not None else _NO_TEMPERATURE_GRID
        return grid, glow.temperature_scale, glow.temperature_offset, 0.0
    return None


def _temperature_grids(media: tuple[Medium, ...]) -> KernelTemperature:
    """The temperature grids of the media emitting a black body, one after another (offset -1 for the others)."""
    count = len(media)
    offset = np.full(count, -1, dtype=np.int64)
    world_to_padded = np.tile(np.eye(4), (count, 1, 1))
    temperature_map = np.zeros((count, 3))
    shape = np.zeros((count, 3), dtype=np.int64)
    temperatures = []
    for index, medium in enumerate(media):
        temperature = _temperature(medium)
        if temperature is None:
            continue
        grid, scale, shift, intensity = temperature
        offset[index] = sum(t.size for t in temperatures)
        temperatures.append(np.asarray(grid.values, dtype=np.float32))
        world_to_padded[index] = _world_to_padded(grid)
        temperature_map[index] = (scale, shift, intensity)
        shape[index] = grid.values.shape
    return KernelTemperature(data=_flatten(temperatures)[0], offset=offset, shape=shape,
                             world_to_padded=world_to_padded, map=temperature_map)


def _glow_arrays(media: tuple[Medium, ...], cmf: str) -> KernelGlow:
    """The media's glows on the grid and the black body's normalisation table for the render's CMFs."""
    count = len(media)
    glow = KernelGlow(np.zeros(count, dtype=np.bool_), np.zeros((count, GRID.size)), np.zeros((count, GRID.size)),
                      *normalisation_table(cmf))
    for index, medium in enumerate(media):
        if medium.glow is not None:
            glow.glowing[index] = True
            if medium.glow.spectrum is not None:
                glow.spectrum[index] = medium.glow.spectrum.values
            glow.blackbody[index] = medium.glow.blackbody * medium.glow.tint.values
    return glow


def _light_arrays(lights: tuple[Light, ...], media: tuple[Medium, ...], cmf: str) -> KernelLights:
    count = len(lights)
    out = {
        "kind": np.array([LIGHT_KINDS.index(light.kind) for light in lights], dtype=np.int64),
        "spd": np.array([kernel_spectrum(light, cmf=cmf) for light in lights]).reshape(count, GRID.size),
        "spd_horizon": np.zeros((count, GRID.size)),
        "dir": np.zeros((count, 3)),
        "pos": np.zeros((count, 3)),
        "cos": np.ones(count),
        "smooth": np.zeros(count),
        "area_span": np.zeros((count, 2, 3)),
        "area_shape": np.zeros(count, dtype=np.int64),
        "camera_visible": np.array([bool(light.camera_visible) for light in lights], dtype=np.bool_),
    }
    for index, light in enumerate(lights):
        if light.kind == "sun":
            out["dir"][index] = unit(light.direction)
            out["cos"][index] = np.cos(0.5 * light.angle)
        elif light.kind == "sky":
            horizon = light.horizon_spectrum or light.spectrum
            out["spd_horizon"][index] = kernel_spectrum(light, horizon, cmf)
        elif light.kind in ("point", "spot", "area"):
            out["pos"][index] = light.position
            if light.kind == "spot":
                out["dir"][index] = unit(light.spot_direction)
                cos_half = np.cos(0.5 * light.spot_size)
                out["cos"][index] = cos_half
                out["smooth"][index] = (1.0 - cos_half) * light.spot_blend
            if light.kind == "area":
                axes = unit(light.area_axes, axis=0)
                out["dir"][index] = -axes[:, 2]
                out["area_span"][index] = 0.5 * np.array([light.size_x * axes[:, 0], light.size_y * axes[:, 1]])
                out["area_shape"][index] = AREA_SHAPES.index(light.area_shape)
    power = selection_powers(lights, out["spd"], media, cmf)
    out["pmf"] = _selection_pmf(power)
    out["power"] = power
    return KernelLights(**out, **no_probe())


def _selection_pmf(power: np.ndarray) -> np.ndarray:
    """The probabilities of choosing each light, in proportion to `power`: scaled into [0, 1] first, so the sum
    cannot overflow; lights that all weigh nothing (far beyond the media) are chosen alike."""
    if power.size == 0:
        return power
    scaled = power / power.max() if power.max() > 0 else np.ones(power.size)
    return scaled / scaled.sum()


def _triangles(surfaces: tuple[Surface, ...]):
    """Every surface's triangles of non-zero area, back to back: (corner, edge1, edge2, cross, owner, uv), cross
    being edge1 × edge2 (twice the area along the normal), owner each triangle's surface and uv its corners' (u, v)
    (T, 6) (zeros without a texture)."""
    parts = []
    for index, surface in enumerate(surfaces):
        vertices = np.asarray(surface.vertices, dtype=np.float64)
        triangles = np.asarray(surface.triangles, dtype=np.int64)
        corner = vertices[triangles[:, 0]]
        edge1, edge2 = vertices[triangles[:, 1]] - corner, vertices[triangles[:, 2]] - corner
        cross = np.cross(edge1, edge2)
        keep = np.linalg.norm(cross, axis=1) > 0.0
        uv = (np.zeros((len(triangles), 6)) if surface.texture is None
              else np.asarray(surface.texture.uv, dtype=np.float64).reshape(-1, 6))
        parts.append((corner[keep], edge1[keep], edge2[keep], cross[keep], np.full(keep.sum(), index, np.int64),
                      uv[keep]))
    if not parts:
        return (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.int64),
                np.zeros((0, 6)))
    return tuple(np.concatenate(columns) for columns in zip(*parts))


def _textures(surfaces: tuple[Surface, ...]) -> dict:
    """The surfaces' textures for `KernelSurfaces`: every texel back to back (float32) with each surface's offset
    (-1: none), shape and modes, and the RGB lattice's spectra where any surface has a texture."""
    offset, shape, mode = np.full(len(surfaces), -1, np.int64), np.zeros((len(surfaces), 2), np.int64), \
        np.zeros((len(surfaces), 3), np.int64)
    texels, total = [np.zeros((0, 3), np.float32)], 0
    for index, surface in enumerate(surfaces):
        texture = surface.texture
        if texture is None:
            continue
        image = np.asarray(texture.image, dtype=np.float32)
        offset[index], shape[index], total = total, image.shape[:2], total + image.shape[0] * image.shape[1]
        mode[index] = (TEXTURE_EXTENSIONS.index(texture.extension), TEXTURE_INTERPOLATIONS.index(texture.interpolation),
                       int(texture.srgb))
        texels.append(image.reshape(-1, 3))
    spectra = texel_spectra.lattice_spectra() if total else np.zeros((0, GRID.size))
    spectra.flags.writeable = False  # as the lattice's (cached): the kernel's argument types, textures or none
    return dict(texture_offset=offset, texture_shape=shape, texture_mode=mode,
                texels=np.ascontiguousarray(np.concatenate(texels)), rgb_spectra=spectra)


def _surface_arrays(surfaces: tuple[Surface, ...], first_light: int) -> tuple[KernelSurfaces, list[int]]:
    """The surfaces' triangles in the order of their hierarchy (`bvh.build`) with its nodes, their spectra,
    and the emissive surfaces' triangle distributions, each emissive surface (of some area and emission)
    being kernel light `first_light`, `first_light` + 1, ... in turn; and the list of those surfaces."""
    corner, edge1, edge2, cross, owner, uv = _triangles(surfaces)
    count = len(surfaces)
    bounds, first, node_count = np.zeros((0, 6)), np.zeros(0, np.int64), np.zeros(0, np.int64)
    if owner.size:
        points = np.stack([corner, corner + edge1, corner + edge2])
        order, bounds, first, node_count = bvh.build(points.min(axis=0), points.max(axis=0))
        corner, edge1, edge2, cross, owner, uv = (corner[order], edge1[order], edge2[order], cross[order],
                                                  owner[order], uv[order])
    double_area = np.linalg.norm(cross, axis=1)
    area = 0.5 * np.bincount(owner, weights=double_area, minlength=count)
    light = np.full(count, -1, dtype=np.int64)
    emitter_offset, emitter_count = np.zeros(count, np.int64), np.zeros(count, np.int64)
    cdfs, bins, emissive = [np.zeros(0)], [np.zeros(0, np.int64)], []
    for index, surface in enumerate(surfaces):
        if surface.emission is None or not surface.emission.values.any() or not area[index] > 0:
            continue
        triangles = np.flatnonzero(owner == index)
        cdf = np.concatenate([[0.0], np.cumsum(double_area[triangles])])
        cdf = cdf / cdf[-1]
        cdf[-1] = 1.0
        emitter_offset[index], emitter_count[index] = sum(map(len, cdfs)), triangles.size
        cdfs.append(cdf)
        bins.append(np.append(triangles, -1))  # laid out as the cdf: one more entry than bins
        light[index] = first_light + len(emissive)
        emissive.append(index)
    of_light = np.full(first_light + len(emissive), -1, dtype=np.int64)
    of_light[first_light:] = emissive
    reflectance = np.array([surface.reflectance.values for surface in surfaces]).reshape(count, GRID.size)
    kernel_surfaces = KernelSurfaces(
        corner=corner, edge1=edge1, edge2=edge2,
        normal=cross / np.maximum(double_area, np.finfo(np.float64).tiny)[:, None], surface=owner,
        node_bounds=bounds, node_first=first.astype(np.int64), node_count=node_count.astype(np.int64),
        reflectance=reflectance, light=light, holdout=np.array([bool(s.holdout) for s in surfaces], dtype=bool),
        camera=np.array([bool(s.camera) for s in surfaces], dtype=bool), uv=uv, **_textures(surfaces),
        of_light=of_light, area=area,
        emitter_cdf=np.concatenate(cdfs), emitter_triangle=np.concatenate(bins), emitter_offset=emitter_offset,
        emitter_count=emitter_count)
    return kernel_surfaces, emissive


def _with_surface_lights(lights: KernelLights, surfaces: tuple[Surface, ...], emissive: list[int],
                         kernel_surfaces: KernelSurfaces, media: tuple[Medium, ...], cmf: str) -> KernelLights:
    """The kernel lights followed by one LIGHT_MESH light per emissive surface (its spectrum the radiance
    leaving it), the selection probabilities renormalised over them all."""
    if not emissive:
        return lights
    spd = np.array([surfaces[index].emission.values for index in emissive])
    centres = []
    for index in emissive:
        mine = kernel_surfaces.surface == index
        weights = np.linalg.norm(np.cross(kernel_surfaces.edge1[mine], kernel_surfaces.edge2[mine]), axis=1)
        centroids = kernel_surfaces.corner[mine] + (kernel_surfaces.edge1[mine] + kernel_surfaces.edge2[mine]) / 3.0
        centres.append(weights @ centroids / weights.sum())
    power = np.concatenate([lights.power, [surface_power(values, kernel_surfaces.area[index], centre, media, cmf)
                                           for values, index, centre in zip(spd, emissive, centres)]])
    extra = len(emissive)
    return KernelLights(
        kind=np.concatenate([lights.kind, np.full(extra, LIGHT_MESH, np.int64)]),
        spd=np.concatenate([lights.spd, spd]),
        spd_horizon=np.concatenate([lights.spd_horizon, np.zeros((extra, GRID.size))]),
        dir=np.concatenate([lights.dir, np.zeros((extra, 3))]),
        pos=np.concatenate([lights.pos, np.array(centres)]),
        area_span=np.concatenate([lights.area_span, np.zeros((extra, 2, 3))]),
        area_shape=np.concatenate([lights.area_shape, np.zeros(extra, np.int64)]),
        camera_visible=np.concatenate([lights.camera_visible, np.zeros(extra, np.bool_)]),
        cos=np.concatenate([lights.cos, np.ones(extra)]),
        smooth=np.concatenate([lights.smooth, np.zeros(extra)]),
        pmf=_selection_pmf(power),
        power=power,
        **no_probe())


def _envmap_arrays(lights: tuple[Light, ...], cmf: str) -> KernelEnvmaps:
    """The envmap lights' maps, bases, rotations and cdfs back to back (`KernelEnvmaps`; other lights have none)."""
    count = len(lights)
    shape = np.zeros((count, 2), dtype=np.int64)
    offsets = np.zeros((3, count), dtype=np.int64)  # texels, row cdf nodes, column cdf nodes before each light
    basis, to_map = np.zeros((3 * count, GRID.size)), np.tile(np.eye(3), (count, 1, 1))
    # The same types in every scene (the kernels' argument types), empty without an envmap.
    rgb, row_cdfs, column_cdfs = [np.zeros((0, 3), np.float32)], [np.zeros(0)], [np.zeros(0)]
    for index, light in enumerate(lights):
        offsets[:, index] = (sum(map(len, rgb)), sum(map(len, row_cdfs)), sum(map(len, column_cdfs)))
        if light.kind != "envmap":
            continue
        shape[index] = light.image.shape[:2]
        rgb.append(np.asarray(light.image, dtype=np.float32).reshape(-1, 3))
        basis[3 * index:3 * index + 3] = envmaps.kernel_basis(light)
        if light.to_world is not None:
            to_map[index] = np.asarray(light.to_world, dtype=np.float64).T
        row_cdf, column_cdf = envmaps.cdfs(texel_weights(light, cmf))
        row_cdfs.append(row_cdf)
        column_cdfs.append(column_cdf)
    return KernelEnvmaps(rgb=np.concatenate(rgb), basis=basis, to_map=to_map, shape=shape, texel_offset=offsets[0],
                         row_cdf=np.concatenate(row_cdfs), row_cdf_offset=offsets[1],
                         column_cdf=np.concatenate(column_cdfs), column_cdf_offset=offsets[2])


def camera_extent(camera) -> np.ndarray:
    """Film extent (x, y) and shift (x, y) in camera space: at z = -1 (perspective) or absolute (ortho).
    The frame's aspect is width · pixel_aspect : height, and AUTO fits its larger side (as Blender)."""
    aspect = camera.width * camera.pixel_aspect / camera.height
    fit = camera.sensor_fit
    if fit == "AUTO":
        fit = "HORIZONTAL" if aspect >= 1.0 else "VERTICAL"
    span = 2.0 * np.tan(0.5 * camera.fov) if camera.kind == "perspective" else camera.ortho_scale
    extent_x, extent_y = (span, span / aspect) if fit == "HORIZONTAL" else (span * aspect, span)
    return np.array([extent_x, extent_y, camera.shift_x * span, camera.shift_y * span])


def white_y(settings) -> float:
    """Y of a unit equal-energy radiance over the camera's wavelengths (`default_band`): the scale of a path's
    transparency (`kernels/transparency.py`), the integral of the XYZ weights' ȳ, linear between grid nodes."""
    lo, hi = default_band(settings)
    inside = GRID[(GRID > lo) & (GRID < hi)]
    nodes = np.concatenate([[lo], inside, [hi]])
    return float(np.trapezoid(np.interp(nodes, GRID, colorimetry.xyz_weights(settings.cmf)[1]), nodes))


def compile_scene(scene: Scene) -> KernelScene:
    """The kernel data for the whole wavelength range of a valid scene (`validation.validate`, called here);
    `wavelength_modes.with_band` restricts it to one band."""
    settings = validate(scene).settings
    camera = scene.camera
    lights = _light_arrays(scene.lights, scene.media, settings.cmf)
    surfaces, emissive = _surface_arrays(scene.surfaces, len(scene.lights))
    kernel_scene = KernelScene(
        camera=KernelCamera(
            to_world=np.asarray(camera.to_world, dtype=np.float64),
            kind=CAMERA_KINDS.index(camera.kind),
            width=int(camera.width),
            height=int(camera.height),
            extent=camera_extent(camera),
            transparent=bool(settings.transparent),
            white_y=white_y(settings),
        ),
        **_media_arrays(scene.media, settings.cmf),
        lights=_with_surface_lights(lights, scene.surfaces, emissive, surfaces, scene.media, settings.cmf),
        envmaps=_envmap_arrays(scene.lights, settings.cmf),
        surfaces=surfaces,
        wavelengths=KernelWavelengths(
            cdf=np.zeros(GRID.size),
            pdf=np.zeros(GRID.size - 1),
            per_path=int(settings.wavelengths_per_path),
            xyz_weights=colorimetry.xyz_weights(settings.cmf),
            spectrum_edges=bin_edges(settings),
        ),
        # int64 whatever the value (check_settings bounds it), so that no value changes the kernel's argument types
        termination=KernelTermination(max_depth=np.int64(settings.max_depth), rr_depth=np.int64(settings.rr_depth),
                                      clamp_direct=float(settings.clamp_direct),
                                      clamp_indirect=float(settings.clamp_indirect),
                                      xyz_to_rgb=np.array(colorimetry.xyz_to_rgb_matrix("rec709"))),
    )
    return with_band(with_probe(kernel_scene), settings.wavelength_sampling, *default_band(settings))
