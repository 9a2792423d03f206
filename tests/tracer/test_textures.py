"""Surface textures (`scene.Texture`): the texel colours' spectra (`texel_spectra`) against their RGB under D65,
Blender's image reading (UV, extension, interpolation) against a reference written from Blender's definitions,
a textured plane under a sun against the closed form ρ(texel) E cos θ / π in both backends, the scene file's
round trip and its checks.

Statistical tests use fixed seeds and 4 standard errors of each block's mean (the film's own variance).
"""

import dataclasses

import numpy as np
import pytest

from addon.tracer import colorimetry, spectra, texel_spectra
from addon.tracer.builders import direction
from addon.tracer.errors import SpectralError
from addon.tracer.kernels.lookups import on_grid
from addon.tracer.kernels.surfaces import rgb_reflectance, texel_colour
from addon.tracer.lowering import compile_scene
from addon.tracer.render import render
from addon.tracer.scene import Texture
from addon.tracer.scene_io import load_scene, save_scene
from addon.tracer.validation import validate
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s

SIGMAS = 4.0
# A 4 × 4 image: a checker of saturated and pale colours, a grey ramp, black and white (rows top first).
IMAGE = np.array([
    [[0.9, 0.1, 0.1], [0.1, 0.8, 0.2], [0.1, 0.2, 0.9], [0.95, 0.9, 0.1]],
    [[0.0, 0.0, 0.0], [0.25, 0.25, 0.25], [0.5, 0.5, 0.5], [1.0, 1.0, 1.0]],
    [[0.3, 0.6, 0.45], [0.7, 0.35, 0.6], [0.05, 0.05, 0.3], [0.62, 0.51, 0.33]],
    [[0.2, 0.9, 0.9], [0.9, 0.2, 0.9], [0.4, 0.4, 0.1], [0.13, 0.77, 0.58]]], dtype=np.float32)


def _spectra_of(rgb):
    """The kernels' reflectance spectra (rows, GRID) of colours (rows, 3)."""
    rgb = np.asarray(rgb, dtype=np.float64)
    at = on_grid(np.broadcast_to(GRID, (rgb.shape[0], GRID.size)))
    return rgb_reflectance(texel_spectra.lattice_spectra(), rgb[:, 0:1], rgb[:, 1:2], rgb[:, 2:3], at)


def _rgb_under_d65(reflectance):
    """The linear Rec.709 colour of reflectance spectra (rows, GRID) lit by D65 of luminance 1."""
    d65 = spectra.illuminant("D65").values
    white = colorimetry.spectrum_to_xyz(d65)[1]
    return np.array([colorimetry.xyz_to_rgb(colorimetry.spectrum_to_xyz(r * d65) / white) for r in reflectance])


# ----------------------------------------------------------------------------- texel spectra

def test_texel_spectra_reproduce_their_colour_under_d65_within_0_001():
    """Random colours and greys: each texel's spectrum is a reflectance (in [0, 1]) whose colour under D65 is its
    RGB; greys are flat, as flat as the fit's own greys (`spectra.from_rgb` of a grey spreads by up to 0.25 %, at
    white)."""
    rng = np.random.default_rng(7)
    colours = np.concatenate([rng.uniform(0.0, 1.0, (200, 3)), np.repeat(rng.uniform(0.0, 1.0, (30, 1)), 3, 1)])
    reflectance = _spectra_of(colours)
    assert reflectance.min() >= 0.0 and reflectance.max() <= 1.0
    assert np.abs(_rgb_under_d65(reflectance) - colours).max() < 1e-3
    assert np.ptp(reflectance[200:], axis=1).max() < 3e-3


def test_a_texel_of_a_lattice_colour_is_that_constant_colour():
    """At a lattice node a texel's spectrum is the one a constant Base Color of that colour gets."""
    colours = np.array([[0.0, 0.0, 0.0], [0.25, 0.75, 0.5], [1.0, 0.125, 0.0], [0.625, 0.625, 0.625]])
    expected = np.array([spectra.scaled_from_rgb(c).values for c in colours])
    np.testing.assert_allclose(_spectra_of(colours), np.clip(expected, 0.0, 1.0), atol=1e-12)


# ----------------------------------------------------------------------------- reading the image

def _decoded(value):
    return np.where(value <= 0.04045, value / 12.92, ((value + 0.055) / 1.055) ** 2.4)


def _blender_texel(image, u, v, extension, interpolation, srgb):
    """Blender's Image Texture at (u, v), from its definition: texel (i, j) (j from the bottom) covers
    [i/W, (i+1)/W) × [j/H, (j+1)/H); Closest reads the texel a point is in, Linear weighs the 4 texel centres
    around it; Repeat wraps indices, Extend clamps them, Clip reads black outside the image; an 8-bit sRGB image's
    result is decoded from sRGB (Cycles: after interpolating)."""
    rows, columns = image.shape[:2]

    def read(i, j):
        if extension == "REPEAT":
            i, j = i % columns, j % rows
        elif extension == "EXTEND":
            i, j = min(max(i, 0), columns - 1), min(max(j, 0), rows - 1)
        elif not (0 <= i < columns and 0 <= j < rows):
            return np.zeros(3)
        return image[rows - 1 - j, i].astype(np.float64)

    if interpolation == "Closest":
        value = read(int(np.floor(u * columns)), int(np.floor(v * rows)))
    else:
        x, y = u * columns - 0.5, v * rows - 0.5
        i, j = int(np.floor(x)), int(np.floor(y))
        fx, fy = x - i, y - j
        value = ((1 - fx) * (1 - fy) * read(i, j) + fx * (1 - fy) * read(i + 1, j) + (1 - fx) * fy * read(i, j + 1)
                 + fx * fy * read(i + 1, j + 1))
    return _decoded(value) if srgb else value


@pytest.mark.parametrize("extension", ["REPEAT", "EXTEND", "CLIP"])
@pytest.mark.parametrize("interpolation", ["Linear", "Closest"])
@pytest.mark.parametrize("srgb", [False, True])
def test_texels_are_read_as_blender_reads_them(extension, interpolation, srgb):
    """Points of a plane whose UVs run from −0.5 to 1.5 (outside the image too), through the lowered scene."""
    image = IMAGE[:, :3]  # 4 rows, 3 columns: rows and columns not mixed up
    plane = s.parallelogram((0.0, 0.0, 0.0), (2.0, 0.0, 0.0), (0.0, 2.0, 0.0), 2, image=image,
                            extension=extension, interpolation=interpolation, srgb=srgb)
    uv = plane.texture.uv * 2.0 - 0.5
    plane = dataclasses.replace(plane, texture=dataclasses.replace(plane.texture, uv=uv))
    ks = compile_scene(s.scene(s.ortho_camera(), [], [s.sun((0, 0, 1))], [plane]))
    rng = np.random.default_rng(3)
    points = rng.uniform(0.0, 2.0, (300, 3))
    points[:, 2] = 0.0
    # the triangle each point lies in (b1, b2 ≥ 0, b1 + b2 ≤ 1)
    k = np.array([next(t for t in range(ks.surfaces.corner.shape[0]) if _inside(ks, t, p)) for p in points])
    got = np.stack(texel_colour(ks, np.zeros(len(points), np.int64), k, points[:, 0], points[:, 1], points[:, 2]), 1)
    expected = np.array([_blender_texel(image, p[0] - 0.5, p[1] - 0.5, extension, interpolation, srgb)
                         for p in points])
    np.testing.assert_allclose(got, expected, atol=1e-6)


def _inside(ks, t, p):
    e1, e2, c = ks.surfaces.edge1[t], ks.surfaces.edge2[t], ks.surfaces.corner[t]
    b = np.linalg.lstsq(np.stack([e1, e2], 1), p - c, rcond=None)[0]
    return b.min() >= -1e-12 and b.sum() <= 1 + 1e-12


# ----------------------------------------------------------------------------- closed form

@pytest.mark.parametrize("backend, srgb", [("numpy", False), ("numpy", True), ("numba", False), ("numba", True)])
def test_textured_plane_under_a_sun_reflects_each_texels_albedo(backend, srgb):
    """A plane filling an orthographic camera's 16 × 16 pixels with a 4 × 4 image (Closest: each texel covers 4 × 4
    pixels; linear, or sRGB-encoded) under a sun at 60°: each block's XYZ is that of ρ_texel(λ) E cos θ / π."""
    elevation, size = 60.0, 4.0
    plane = s.parallelogram((-size / 2, -size / 2, 0.0), (size, 0, 0), (0, size, 0), 2, image=IMAGE,
                            interpolation="Closest", srgb=srgb)
    scene = s.scene(s.ortho_camera(16, 16, scale=size), [], [s.sun(direction(elevation, 30.0), 1.0)], [plane],
                    spp=32 if backend == "numba" else 8, seed=4, backend=backend)
    film = render(scene).film
    expected = _spectra_of((_decoded(IMAGE) if srgb else IMAGE).reshape(-1, 3)) * np.sin(np.radians(elevation)) / np.pi
    for texel in range(16):
        row, column = divmod(texel, 4)
        block = (slice(4 * row, 4 * row + 4), slice(4 * column, 4 * column + 4))
        xyz = colorimetry.spectrum_to_xyz(expected[texel])
        for channel in range(3):
            mean = film.xyz[block][..., channel].mean()
            error = np.sqrt(film.variance[block][..., channel].sum()) / 16
            assert abs(mean - xyz[channel]) <= SIGMAS * error + 1e-9, (texel, channel, mean, xyz[channel], error)


# ----------------------------------------------------------------------------- the scene file

def test_textures_and_camera_visibility_round_trip_through_the_scene_file(tmp_path):
    plane = s.parallelogram((0, 0, 0), (1, 0, 0), (0, 1, 0), 2, image=IMAGE, extension="CLIP",
                            interpolation="Closest", srgb=True, camera=False)
    loaded = load_scene(save_scene(s.scene(s.ortho_camera(), [], [s.sun((0, 0, 1))], [plane]), tmp_path))
    surface = loaded.surfaces[0]
    assert surface.camera is False
    np.testing.assert_array_equal(surface.texture.image, plane.texture.image)
    np.testing.assert_array_equal(surface.texture.uv, plane.texture.uv)
    assert (surface.texture.extension, surface.texture.interpolation, surface.texture.srgb) == ("CLIP", "Closest", True)


@pytest.mark.parametrize("change, message", [
    (dict(image=np.zeros((4, 4))), r"texture\.image: expected an array of H ≥ 1 rows"),
    (dict(image=np.full((2, 2, 3), np.nan)), r"texture\.image: a reflectance texel must be a finite colour"),
    (dict(image=np.full((2, 2, 3), 1.5)), r"texture\.image: a reflectance texel must be a finite colour"),
    (dict(uv=np.zeros((3, 3, 2))), r"texture\.uv: expected a \(u, v\) for each corner of the surface's 8 triangles"),
    (dict(uv=np.full((8, 3, 2), np.inf)), r"texture\.uv: must be finite"),
    (dict(extension="MIRROR"), r"texture\.extension: unknown value"),
    (dict(interpolation="Cubic"), r"texture\.interpolation: unknown value"),
    (dict(srgb="yes"), r"texture\.srgb: expected true or false"),
])
def test_bad_textures_are_refused_naming_the_field(change, message):
    plane = s.parallelogram((0, 0, 0), (1, 0, 0), (0, 1, 0), 2, image=IMAGE)
    plane = dataclasses.replace(plane, texture=dataclasses.replace(plane.texture, **change))
    with pytest.raises(SpectralError, match=r"surfaces\[0\]\." + message):
        validate(s.scene(s.ortho_camera(), [], [s.sun((0, 0, 1))], [plane]))


def test_bad_textures_in_the_scene_file_are_refused_naming_the_field(tmp_path):
    plane = s.parallelogram((0, 0, 0), (1, 0, 0), (0, 1, 0), 2, image=IMAGE)
    folder = save_scene(s.scene(s.ortho_camera(), [], [s.sun((0, 0, 1))], [plane]), tmp_path)
    np.save(tmp_path / "surfaces0_uv.npy", np.zeros((8, 3)))
    with pytest.raises(SpectralError, match=r"surfaces\[0\]\.texture\.uv: expected a \(u, v\)"):
        load_scene(folder)
