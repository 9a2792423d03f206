"""The figures that prove each demo's phenomenon, computed from the rendered film (XYZ per pixel).

Pixels are selected by geometry, never by colour: each region is the set of pixels whose camera ray
(through the pixel centre, the tracer's camera model) meets a given part of the scene or lies within
a given angle of the sun. Colours of regions are the mean XYZ of their pixels, so noise averages out.

Colour vocabulary: chromaticity (x, y); CIE LCh hue angle h (degrees, CIELAB against a stated white:
≈ 30° red, 90° yellow, 160° green, 270°–300° blue to violet); dominant wavelength against a white
(colorimetry.dominant_wavelength; a negative value is minus the complementary wavelength of a purple).
"""

import warnings

import numpy as np

from addon.tracer import colorimetry
from addon.tracer.lights import strength_scale
from addon.tracer.lowering import camera_extent
from addon.tracer.scene import Camera, Grid, Light
from addon.tracer.wavelengths import LAMBDA_STEP

D65_WHITE_XY = (0.3127, 0.3290)
NEUTRAL = 0.004  # colours this close to the white in xy have no hue or dominant wavelength (NaN)
EQUAL_ENERGY_XY = (1.0 / 3.0, 1.0 / 3.0)

# ----------------------------------------------------------------------------- pixels and regions


def pixel_rays(camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """World origins and unit directions, (height, width, 3) each, of the rays through pixel centres."""
    ex, ey, sx, sy = camera_extent(camera)
    cx = (-0.5 + (np.arange(camera.width) + 0.5) / camera.width) * ex + sx
    cy = (0.5 - (np.arange(camera.height) + 0.5) / camera.height) * ey + sy
    cx, cy = np.meshgrid(cx, cy)
    matrix = np.asarray(camera.to_world, dtype=np.float64)
    if camera.kind == "perspective":
        local = np.stack([cx, cy, -np.ones_like(cx)], axis=-1)
        origins = np.broadcast_to(matrix[:3, 3], local.shape)
    else:
        local = np.broadcast_to([0.0, 0.0, -1.0], cx.shape + (3,))
        origins = np.stack([cx, cy, np.zeros_like(cx)], axis=-1) @ matrix[:3, :3].T + matrix[:3, 3]
    directions = local @ matrix[:3, :3].T
    return np.array(origins), directions / np.linalg.norm(directions, axis=-1, keepdims=True)


def angle_from(camera: Camera, direction) -> np.ndarray:
    """Angle in degrees between each pixel's ray and `direction`."""
    _, rays = pixel_rays(camera)
    direction = np.asarray(direction, dtype=np.float64) / np.linalg.norm(direction)
    return np.degrees(np.arccos(np.clip(rays @ direction, -1.0, 1.0)))


def elevation(camera: Camera) -> np.ndarray:
    """Elevation in degrees of each pixel's ray above the horizontal plane."""
    _, rays = pixel_rays(camera)
    return np.degrees(np.arcsin(np.clip(rays[..., 2], -1.0, 1.0)))


def plane_hits(camera: Camera, axis: int, value: float) -> np.ndarray:
    """World points (height, width, 3) where the pixel rays meet the plane `coordinate[axis] = value`
    (NaN where they point away from it)."""
    origins, rays = pixel_rays(camera)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (value - origins[..., axis]) / rays[..., axis]
    t = np.where(t > 0, t, np.nan)
    return origins + t[..., None] * rays


def face_mask(camera: Camera, centre, edge: float, inset: float = 0.2) -> np.ndarray:
    """Pixels that see the inner part of a cube's front face (the face towards −y), `inset` of the
    edge left out on each side so the cube's soft edges and neighbours never count."""
    centre = np.asarray(centre, dtype=np.float64)
    hits = plane_hits(camera, 1, centre[1] - edge / 2)
    half = edge * (0.5 - inset)
    with np.errstate(invalid="ignore"):
        return (np.abs(hits[..., 0] - centre[0]) < half) & (np.abs(hits[..., 2] - centre[2]) < half)


def column_density(camera: Camera, grid: Grid, steps: int = 256) -> np.ndarray:
    """∫ density ds along each pixel's ray through the grid's box (trilinear, as the tracer reads it)."""
    return ray_column_density(*pixel_rays(camera), grid, steps)


def ray_column_density(origins: np.ndarray, rays: np.ndarray, grid: Grid, steps: int = 256) -> np.ndarray:
    """∫ density ds along rays (origins and unit directions, (..., 3) each) through the grid's box, from each
    origin on (trilinear, as the tracer reads it; NaN origins give NaN)."""
    from scipy.ndimage import map_coordinates

    shape = np.array(grid.values.shape)
    corners = np.array([grid.index_to_world @ np.append(np.where(c, shape, -1.0), 1.0) for c in np.ndindex(2, 2, 2)])
    lo, hi = corners[:, :3].min(axis=0), corners[:, :3].max(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # NaN origins: all-NaN slices
        t0 = np.nanmax(np.minimum((lo - origins) / rays, (hi - origins) / rays), axis=-1)
        t1 = np.nanmin(np.maximum((lo - origins) / rays, (hi - origins) / rays), axis=-1)
    t0, t1 = np.maximum(t0, 0.0), np.maximum(t1, np.maximum(t0, 0.0))
    world_to_index = np.linalg.inv(grid.index_to_world)
    total = np.zeros(rays.shape[:-1])
    padded = np.pad(grid.values, 1)
    for k in range(steps):
        t = t0 + (k + 0.5) / steps * (t1 - t0)
        points = np.nan_to_num(origins + t[..., None] * rays, nan=-1e30)
        index = points @ world_to_index[:3, :3].T + world_to_index[:3, 3] + 1.0
        total += map_coordinates(padded, index.reshape(-1, 3).T, order=1, mode="constant").reshape(t.shape)
    return np.where(np.isnan(origins).any(axis=-1), np.nan, total * (t1 - t0) / steps)


def medium(scene, name: str):
    """The scene's medium called `name` (exported media are named after their Blender objects)."""
    for candidate in scene.media:
        if candidate.name == name:
            return candidate
    raise ValueError(f"the scene has no medium {name!r}; it has {[m.name for m in scene.media]}")


def sun(scene) -> Light:
    """The scene's first sun (the demos' main light; fills and worlds come after it or are not suns)."""
    return next(light for light in scene.lights if light.kind == "sun")


def region_xyz(xyz: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Mean XYZ of the pixels in `mask`."""
    if not mask.any():
        raise ValueError("empty pixel region")
    return xyz[mask].mean(axis=0)


# ----------------------------------------------------------------------------- colour


def light_xyz(light: Light) -> np.ndarray:
    """XYZ of a light's spectrum in the tracer's radiometric units (its strength sets Y)."""
    return colorimetry.spectrum_to_xyz(light.spectrum.values * strength_scale(light))


def hue_angle(xyz, white_xyz) -> float:
    """CIE LCh(ab) hue angle in degrees of `xyz` against the white `white_xyz`."""
    colour = colorimetry.colour_science()
    white = np.asarray(white_xyz, dtype=np.float64)
    lab = colour.XYZ_to_Lab(np.asarray(xyz, dtype=np.float64) / white[1], colour.XYZ_to_xy(white))
    return float(colour.Lab_to_LCHab(lab)[2])


def describe(xyz, white_xyz) -> dict:
    """Chromaticity, LCh hue and dominant wavelength of `xyz`, against `white_xyz`."""
    xy = colorimetry.xyz_to_xy(xyz)
    white_xy = colorimetry.xyz_to_xy(white_xyz)
    if np.hypot(*(xy - white_xy)) < NEUTRAL:  # as good as the white itself: no hue, no dominant wavelength
        hue = dominant = float("nan")
    else:
        hue, dominant = hue_angle(xyz, white_xyz), colorimetry.dominant_wavelength(xy, white_xy)
    return {"x": float(xy[0]), "y": float(xy[1]), "Y": float(np.asarray(xyz)[1]), "hue": hue, "dominant_nm": dominant}


def format_colour(label: str, figures: dict) -> str:
    if np.isfinite(figures["hue"]):
        hue = f"hue {figures['hue']:5.1f}°  dominant {figures['dominant_nm']:5.0f} nm"
    else:
        hue = "neutral (the white)"
    return f"{label:<16} x={figures['x']:.3f} y={figures['y']:.3f}  {hue}  Y={figures['Y']:.3g}"


# ----------------------------------------------------------------------------- Rayleigh skies

SKY_AWAY = (60.0, 15.0)  # "sky away from the sun": at least this far from it and this high (degrees)
NEAR_SUN_DEGREES = (2.5, 10.0)  # "around the sun": this ring (the disc itself has a radius of 1°)


def rayleigh(scene, xyz: np.ndarray) -> dict:
    """Colours of the sky far from the sun, of the ring around it, of the sun's disc as seen through
    the air, and of the light itself (its spectrum), all against the light's own colour as white."""
    white = light_xyz(sun(scene))
    figures = {name: describe(region_xyz(xyz, mask), white) for name, mask in sky_regions(scene).items()}
    figures["light"] = describe(white, white)
    return figures


def sky_regions(scene) -> dict:
    """Pixel masks of the sky far from the sun, the ring around it and the sun's disc."""
    light = sun(scene)
    angle = angle_from(scene.camera, light.direction)
    height = elevation(scene.camera)
    return {
        "sky away": (angle >= SKY_AWAY[0]) & (height >= SKY_AWAY[1]),
        "around sun": (height > 0.0) & (angle >= NEAR_SUN_DEGREES[0]) & (angle <= NEAR_SUN_DEGREES[1]),
        # the inner part of the disc, or the one pixel nearest its centre in a coarse image
        "sun disc": (angle <= 0.35 * np.degrees(light.angle)) | (angle == angle.min()),
    }


# ----------------------------------------------------------------------------- metamerism


def cube_faces(scene, xyz: np.ndarray, centres, edge: float) -> list[np.ndarray]:
    """Mean XYZ of the front face of each cube."""
    return [region_xyz(xyz, face_mask(scene.camera, centre, edge)) for centre in centres]


def metamerism(scene, xyz: np.ndarray, centres, edge: float, white_response: float) -> dict:
    """CIEDE2000 between the two cubes' front faces. The white for CIELAB is what a white cube
    (albedo 1) shows there: `white_response` (G(1) of the calibration) times the light's XYZ."""
    left, right = cube_faces(scene, xyz, centres, edge)
    white = white_response * light_xyz(sun(scene))
    return {"left": describe(left, white), "right": describe(right, white),
            "delta_e": float(colorimetry.delta_e_2000(left, right, white))}


# ----------------------------------------------------------------------------- fluorescence


FROG_COLUMN = 0.3  # a pixel shows the frog if its ray crosses at least this much of its body (units)


def frog(scene, xyz: np.ndarray) -> dict:
    """Colour of the frog (pixels whose rays cross the medium "frog"), of the white "pad" around it
    and of the lamp's own spectrum, against the D65 white (the display's white: what "green" and
    "violet" mean on screen). The lamp has no white of its own to compare with, being nearly all UV."""
    white = np.array(colorimetry.colour_science().xy_to_XYZ(D65_WHITE_XY))
    on_frog = column_density(scene.camera, medium(scene, "frog").density) >= FROG_COLUMN
    on_pad = (column_density(scene.camera, medium(scene, "pad").density) >= 0.02) & ~on_frog
    return {"frog": describe(region_xyz(xyz, on_frog), white),
            "pad": describe(region_xyz(xyz, on_pad), white),
            "lamp": describe(light_xyz(sun(scene)), white)}


INK_COLUMN = 0.2  # a pixel shows a glass if its ray crosses at least this much of its ink (units)


def ink(scene, xyz: np.ndarray) -> dict:
    """Colour of the dense ink, of the diluted ink, of the pad and of the lamp, against the D65 white."""
    white = np.array(colorimetry.colour_science().xy_to_XYZ(D65_WHITE_XY))
    glasses = {name: column_density(scene.camera, medium(scene, name).density) >= INK_COLUMN
               for name in ("ink", "diluted ink")}
    on_pad = (column_density(scene.camera, medium(scene, "pad").density) >= 0.02) & ~glasses["ink"] & ~glasses["diluted ink"]
    return {**{name: describe(region_xyz(xyz, mask), white) for name, mask in glasses.items()},
            "pad": describe(region_xyz(xyz, on_pad), white), "lamp": describe(light_xyz(sun(scene)), white)}


def absorbed_power(medium, light: Light, supersample: int = 4) -> float:
    """Power (W, per unit² of the scene's length) that the fluorophore absorbs from a sun shining
    straight down (+z): ∫ E(λ) ∫∫ (1 − exp(−τ(x, y, λ))) dx dy dλ, with τ the fluorophore's optical
    depth along z. Exact up to quadrature when, as for the frog, nothing else in the medium
    interacts at the excitation wavelengths: the integral of the trilinear density along z is the
    bilinear interpolation of the columns' sums, sampled here `supersample`² times per cell."""
    from scipy.ndimage import map_coordinates

    assert np.allclose(light.direction, (0.0, 0.0, 1.0)), "absorbed_power expects a sun straight above"
    grid = medium.density
    step = np.abs(np.diag(grid.index_to_world)[:3])
    columns = np.pad(grid.values.sum(axis=2) * step[2], 1)  # zero beyond the grid, as the tracer reads it
    n = supersample
    ix = (np.arange(columns.shape[0] * n) + 0.5) / n - 0.5
    iy = (np.arange(columns.shape[1] * n) + 0.5) / n - 0.5
    points = np.stack(np.meshgrid(ix, iy, indexing="ij")).reshape(2, -1)
    column = map_coordinates(columns, points, order=1, mode="nearest")
    area = step[0] * step[1] / n**2
    irradiance = light.spectrum.values * strength_scale(light)
    excitation = medium.density_scale * medium.fluorescence.excitation.values
    active = np.flatnonzero(irradiance * excitation > 0)
    absorbed = np.array([area * np.sum(-np.expm1(-excitation[i] * column)) for i in active])
    return float(np.sum(irradiance[active] * absorbed) * LAMBDA_STEP)


def emitted_power(scenes_and_films, emission) -> tuple[float, np.ndarray]:
    """Power (W) a fluorescent object sends out, from orthographic views spread evenly over the
    sphere: each view's intensity I(ω) = Σ pixels L·A (W/sr), L the radiance from the pixel's Y and
    the emission spectrum's shape; power = 4π · mean I. Also returns the views' intensities."""
    pdf = emission.values / emission.integral()
    y_per_watt = float(colorimetry.spectrum_to_xyz(pdf)[1])
    intensities = []
    for scene, xyz in scenes_and_films:
        camera = scene.camera
        pixel_area = (camera.ortho_scale / camera.width) * (camera.ortho_scale / camera.width)
        intensities.append(xyz[..., 1].sum() / y_per_watt * pixel_area)
    intensities = np.array(intensities)
    return float(4.0 * np.pi * intensities.mean()), intensities


# ----------------------------------------------------------------------------- fire

BRIGHT = 0.1  # "bright pixels": Y at least this fraction of the image's 99.5th percentile of Y


def correlated_colour_temperature(xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CCT (K) and Duv of XYZ values (n, 3) by Ohno 2013 (CIE 1960 uv, valid from 1000 K). The usual
    xy formulas are fits for daylight-like sources: McCamy 1992 gives 2422 K for a 1000 K black body
    and Hernandez 1999 −109 K, so they cannot measure a fire."""
    colour = colorimetry.colour_science()
    uv = colour.xy_to_UCS_uv(colorimetry.xyz_to_xy(xyz))
    cct_duv = colour.temperature.uv_to_CCT(uv, method="Ohno 2013")
    return cct_duv[..., 0], cct_duv[..., 1]


def flame_mask(xyz: np.ndarray) -> np.ndarray:
    """The image's bright pixels (the flame)."""
    luminance = xyz[..., 1]
    return luminance >= BRIGHT * np.percentile(luminance, 99.5)


def fire(scene, xyz: np.ndarray) -> dict:
    """Colour temperatures of the image's bright pixels (the flame)."""
    bright = flame_mask(xyz)
    cct, duv = correlated_colour_temperature(xyz[bright])
    return {"pixels": int(bright.sum()), "cct_min": float(cct.min()), "cct_max": float(cct.max()),
            "cct_p5": float(np.percentile(cct, 5)), "cct_median": float(np.median(cct)),
            "cct_p95": float(np.percentile(cct, 95)), "duv_max": float(np.abs(duv).max())}


def cloud_shadow(scene, xyz: np.ndarray, lit_depth: float = 0.01, shadow_depth: float = 3.0) -> dict:
    """The cloud's shadow on the ground: the mean colour of the ground where the sun's light crosses an
    optical depth above `shadow_depth` of cloud (shadow) and below `lit_depth` (lit), each seen by the camera
    through less than `lit_depth` of cloud; their luminance ratio is the shadow's contrast."""
    cloud, light = medium(scene, "cloud"), sun(scene)
    (ground,) = scene.surfaces
    half = np.abs(ground.vertices[:, :2]).max()
    points = plane_hits(scene.camera, 2, 0.0)
    with np.errstate(invalid="ignore"):
        on_ground = (np.abs(points[..., 0]) < half) & (np.abs(points[..., 1]) < half)
    towards_sun = np.broadcast_to(light.direction / np.linalg.norm(light.direction), points.shape)
    to_sun = cloud.density_scale * ray_column_density(np.where(on_ground[..., None], points, np.nan), towards_sun,
                                                     cloud.density)
    seen = cloud.density_scale * column_density(scene.camera, cloud.density)
    with np.errstate(invalid="ignore"):
        clear = on_ground & (seen < lit_depth)
        shadow, lit = clear & (to_sun > shadow_depth), clear & (to_sun < lit_depth)
    white = light_xyz(light)
    shadow_xyz, lit_xyz = region_xyz(xyz, shadow), region_xyz(xyz, lit)
    return {"shadow": describe(shadow_xyz, white), "lit ground": describe(lit_xyz, white),
            "contrast": float(lit_xyz[1] / shadow_xyz[1]), "shadow_pixels": int(shadow.sum()),
            "lit_pixels": int(lit.sum()), "lit_closed_form_Y": lit_ground_luminance(scene, ground)}


def alpha_coverage(scene, alpha: np.ndarray, seen_depth: float = 0.05) -> dict:
    """Film ▸ Transparent's alpha against its closed form: where the camera sees the sky through the cloud
    (optical depth above `seen_depth`), the mean alpha and the mean 1 − e^(−τ) of the (grey) cloud along each
    pixel's ray; where it sees the sky alone, the mean alpha (0); on the ground, the mean alpha (1, less the
    pixels on its far edge, which see some sky)."""
    cloud = medium(scene, "cloud")
    (ground,) = scene.surfaces
    half = np.abs(ground.vertices[:, :2]).max()
    points = plane_hits(scene.camera, 2, 0.0)
    with np.errstate(invalid="ignore"):
        on_ground = (np.abs(points[..., 0]) < half) & (np.abs(points[..., 1]) < half)
    seen = cloud.density_scale * column_density(scene.camera, cloud.density)
    through_cloud, clear_sky = ~on_ground & (seen > seen_depth), ~on_ground & (seen == 0.0)
    return {"cloud_alpha": float(alpha[through_cloud].mean()),
            "cloud_closed_form": float((1.0 - np.exp(-seen[through_cloud])).mean()),
            "cloud_pixels": int(through_cloud.sum()), "sky_alpha": float(alpha[clear_sky].mean()),
            "sky_pixels": int(clear_sky.sum()), "ground_alpha": float(alpha[on_ground].mean())}


def lit_ground_luminance(scene, ground) -> float:
    """Closed form of a Lambertian ground's luminance under the scene's sun and its uniform sky, unshadowed
    (the cloud's small share of the sky left out): ρ (E cos θ + π L) / π, with ρ the reflectance weighted by the
    lights' spectrum (sun and sky share one) and E, L their luminous irradiance and radiance."""
    light = sun(scene)
    (sky,) = [candidate for candidate in scene.lights if candidate.kind == "environment"]
    spectrum = light.spectrum.values * strength_scale(light)
    reflected = colorimetry.spectrum_to_xyz(spectrum * ground.reflectance.values)[1] / colorimetry.spectrum_to_xyz(spectrum)[1]
    cos_theta = light.direction[2] / np.linalg.norm(light.direction)
    return float(reflected * (light.strength * cos_theta + np.pi * sky.strength) / np.pi)
