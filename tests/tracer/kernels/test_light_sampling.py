"""Every light sampler of next-event estimation against the pdf it returns (Pearson χ², as the phase samplers
in test_phase.py): the choice of a light by its pmf, a finite sun's cone, the sphere of an environment or a
sky, an envmap's texels and the directions inside them, a rectangle light in the solid angle it subtends and
over its area, an ellipse over its area, and the pdf a ray that meets an area light's face is weighed with
(`area_light_hit`, `area_direction_pdf`) against the sampler's draws; and the delta lights (point, spot), which
have no pdf, aim at their light with Blender's falloff.

The samplers are the shared functions of `kernels/light_sampling.py`, called here on arrays of samples as the
NumPy backend calls them (the Numba kernel compiles the same code). Every χ² test uses a fixed seed and passes
when p > P_MIN; the expected counts come from the pdf the sampler returns (or, for an area light, the solid
angle or area it says it sampled in), integrated over each bin in closed form, so a sampler whose draws and
pdf disagree fails whichever is wrong.
"""

import numpy as np
import pytest

from addon.tracer import spectra
from addon.tracer.kernels.envmap import row_solid_angle, texel_of
from addon.tracer.kernels.light_sampling import (
    SOLID_ANGLE_SAMPLED, area_direction_pdf, area_light_hit, choose_light, infinite_pdf, sample_light)
from addon.tracer.lowering import compile_scene
from addon.tracer.phase import orthonormal_basis
from addon.tracer.scene import Light
from tests.support import scenes as s
from tests.support.statistics import chi_square_pvalue

P_MIN = 1e-3
N = 100_000


def compiled(*lights):
    return compile_scene(s.scene(s.ortho_camera(), [s.medium(s.box_grid())], list(lights)))


def uniforms(seed, n=N):
    return np.random.default_rng(seed).random((2, n))


def rotation(seed):
    """A fixed random rotation (columns: a light's local X, Y, Z in world space)."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.sign(np.linalg.det(q))


def histogram2d(x, y, x_edges, y_edges):
    counts = np.histogram2d(x, y, [x_edges, y_edges])[0]
    assert counts.sum() == x.size, "a sample fell outside the bins"
    return counts


# ----------------------------------------------------------------------------- the choice of a light

def test_lights_are_chosen_by_their_pmf():
    """Four lights of different powers: how often each is chosen matches `ks.lights.pmf` (χ²), and a uniform
    at the very top of [0, 1) still chooses a light."""
    ks = compiled(s.sun([0, 0, 1], 3.0), s.environment(0.5), s.sun([1, 0, 1], 1.0, angle=0.1),
                  Light(kind="point", spectrum=spectra.constant(1.0), strength=2.0, position=np.array([0, 0, 3.0])))
    pmf = ks.lights.pmf
    assert pmf.sum() == pytest.approx(1.0) and np.all(pmf > 0.02)
    chosen = choose_light(pmf, np.random.default_rng(1).random(N))
    counts = np.bincount(chosen, minlength=pmf.size)
    assert counts.size == pmf.size
    assert chi_square_pvalue(counts, pmf) > P_MIN
    assert choose_light(pmf, np.nextafter(1.0, 0.0)) == pmf.size - 1


# ----------------------------------------------------------------------------- suns, environments, skies

@pytest.mark.parametrize("angle_degrees", [0.53, 5.0, 40.0])
def test_a_finite_sun_is_sampled_uniformly_in_its_cone(angle_degrees):
    """Directions uniform in cos θ about the sun's direction and in azimuth, every one inside the cone, with
    the pdf 1 / (2π (1 − cos θ_max)) that `infinite_pdf` also gives (MIS needs both alike)."""
    towards = np.array([0.3, -0.5, 0.8])
    towards /= np.linalg.norm(towards)
    ks = compiled(s.sun(towards, angle=np.radians(angle_degrees)))
    u1, u2 = uniforms(2)
    wx, wy, wz, pdf, distance, falloff = sample_light(ks, 0, 0.0, 0.0, 0.0, u1, u2)
    cos_max = np.cos(0.5 * np.radians(angle_degrees))
    assert pdf == pytest.approx(1.0 / (2 * np.pi * (1 - cos_max)), rel=1e-12)
    assert distance == np.inf and falloff == 1.0
    np.testing.assert_allclose(infinite_pdf(ks, 0, wx, wy, wz), pdf, rtol=1e-12)
    t, b = orthonormal_basis(towards)
    cos_theta = wx * towards[0] + wy * towards[1] + wz * towards[2]
    azimuth = np.arctan2(wx * b[0] + wy * b[1] + wz * b[2], wx * t[0] + wy * t[1] + wz * t[2])
    cos_edges, azimuth_edges = np.linspace(cos_max, 1.0, 21), np.linspace(-np.pi, np.pi, 13)
    # Rounding may put a direction a hair outside [cos_max, 1]: clip within the outer bins.
    counts = histogram2d(np.clip(cos_theta, cos_max, 1.0), azimuth, cos_edges, azimuth_edges)
    probabilities = pdf * np.outer(np.diff(cos_edges), np.diff(azimuth_edges))
    assert probabilities.sum() == pytest.approx(1.0, rel=1e-9)
    assert chi_square_pvalue(counts, probabilities) > P_MIN


def test_a_delta_sun_gives_its_direction():
    ks = compiled(s.sun([0.0, 0.6, 0.8]))
    wx, wy, wz, pdf, distance, falloff = sample_light(ks, 0, 0.0, 0.0, 0.0, 0.3, 0.7)
    assert (wx, wy, wz) == pytest.approx((0.0, 0.6, 0.8)) and pdf == 1.0 and distance == np.inf and falloff == 1.0


@pytest.mark.parametrize("light", [s.environment(1.0), Light(kind="sky", spectrum=spectra.constant(1.0),
                                                             horizon_spectrum=spectra.constant(0.3))],
                         ids=["environment", "sky"])
def test_environments_and_skies_are_sampled_uniformly_on_the_sphere(light):
    """Directions uniform in z and in azimuth, with the pdf 1/4π that `infinite_pdf` also gives."""
    ks = compiled(light)
    u1, u2 = uniforms(3)
    wx, wy, wz, pdf, distance, _ = sample_light(ks, 0, 0.0, 0.0, 0.0, u1, u2)
    assert pdf == 1.0 / (4 * np.pi) and distance == np.inf
    np.testing.assert_allclose(np.sqrt(wx * wx + wy * wy + wz * wz), 1.0, rtol=1e-12)
    assert np.all(infinite_pdf(ks, 0, wx, wy, wz) == pdf)
    z_edges, azimuth_edges = np.linspace(-1.0, 1.0, 21), np.linspace(-np.pi, np.pi, 13)
    counts = histogram2d(np.clip(wz, -1.0, 1.0), np.arctan2(wy, wx), z_edges, azimuth_edges)
    probabilities = pdf * np.outer(np.diff(z_edges), np.diff(azimuth_edges))
    assert probabilities.sum() == pytest.approx(1.0, rel=1e-12)
    assert chi_square_pvalue(counts, probabilities) > P_MIN


# ----------------------------------------------------------------------------- envmaps

def test_an_envmap_is_sampled_as_its_pdf_says_inside_every_texel():
    """Each texel split in four (two halves of its z range, which hold equal solid angles, times two halves of
    its columns' azimuths): every quarter is drawn with the pdf that `infinite_pdf` gives the texel times the
    quarter's solid angle (test_envmap.py checks the texels as wholes), on a map turned about z."""
    rng = np.random.default_rng(4)
    image = (rng.uniform(0.0, 2.0, (4, 6, 3)) * (rng.random((4, 6, 3)) > 0.2)).astype(np.float32)
    image[1, 2:4] = 0.0
    c, s_ = np.cos(np.radians(25.0)), np.sin(np.radians(25.0))
    to_world = np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])
    ks = compiled(s.envmap(image, to_world=to_world))
    rows, columns = image.shape[:2]
    u1, u2 = uniforms(5)
    wx, wy, wz, pdf, _, _ = sample_light(ks, 0, 0.0, 0.0, 0.0, u1, u2)
    np.testing.assert_allclose(infinite_pdf(ks, 0, wx, wy, wz), pdf, rtol=1e-12)
    row, column = texel_of(ks, 0, wx, wy, wz)
    x, y, z = to_world.T @ np.array([wx, wy, wz])  # the map's frame
    top, bottom = np.cos(np.pi * row / rows), np.cos(np.pi * (row + 1) / rows)
    lower_half = z < 0.5 * (top + bottom)
    u = (0.5 - np.arctan2(y, x) / (2 * np.pi)) * columns
    right_half = u - column >= 0.5
    quarter = ((row * columns + column) * 2 + lower_half) * 2 + right_half
    counts = np.bincount(quarter, minlength=rows * columns * 4)
    # The pdf of each texel, read at its centre, × a quarter of its solid angle.
    polar = np.pi * (np.arange(rows) + 0.5) / rows
    azimuth = np.pi * (1.0 - 2.0 * (np.arange(columns) + 0.5) / columns)
    p, a = np.meshgrid(polar, azimuth, indexing="ij")
    centres = to_world @ np.array([np.sin(p) * np.cos(a), np.sin(p) * np.sin(a), np.cos(p)]).reshape(3, -1)
    texel_pdf = infinite_pdf(ks, 0, *centres).reshape(rows, columns)
    texel_probability = texel_pdf * row_solid_angle(rows, columns, np.arange(rows))[:, None]
    assert texel_probability.sum() == pytest.approx(1.0, rel=1e-12)
    probabilities = np.repeat(texel_probability.ravel() / 4, 4)
    assert counts[probabilities == 0].sum() == 0
    assert chi_square_pvalue(counts[probabilities > 0], probabilities[probabilities > 0]) > P_MIN


# ----------------------------------------------------------------------------- area lights

AXES = rotation(7)
CENTRE = np.array([0.3, -0.2, 1.5])


def area_light(shape, size_x, size_y):
    return Light(kind="area", spectrum=spectra.constant(1.0), strength=2.0, unit="radiant", position=CENTRE,
                 area_axes=AXES, area_shape=shape, size_x=size_x, size_y=size_y)


def area_sample(light, offset, seed):
    """Points drawn on `light` from CENTRE + AXES @ offset: their coordinates (a, b) along the light's half
    sizes (in [−1, 1]), the point seen from, and the sampler's solid-angle pdf. Its falloff is 1 / area in
    front of the light (the radiance is then the spectrum over the area)."""
    ks = compiled(light)
    point = CENTRE + AXES @ np.asarray(offset, dtype=np.float64)
    u1, u2 = uniforms(seed)
    wx, wy, wz, pdf, distance, falloff = sample_light(ks, 0, *(np.full(N, c) for c in point), u1, u2)
    area = light.size_x * light.size_y * (np.pi / 4 if light.area_shape == "ellipse" else 1.0)
    np.testing.assert_allclose(falloff, 1.0 / area, rtol=1e-12)
    q = point[:, None] + distance * np.array([wx, wy, wz])
    local = AXES.T @ (q - CENTRE[:, None])
    np.testing.assert_allclose(local[2], 0.0, atol=1e-9)  # in the light's plane
    return local[0] / (0.5 * light.size_x), local[1] / (0.5 * light.size_y), point, pdf


def triangle_solid_angle(a, b, c):
    """The solid angle of the triangle of vertex vectors a, b, c (..., 3) from the origin (Van Oosterom and
    Strackee 1983)."""
    la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
    numerator = np.abs(np.einsum("...i,...i", a, np.cross(b, c)))
    denominator = (la * lb * lc + np.einsum("...i,...i", a, b) * lc + np.einsum("...i,...i", a, c) * lb
                   + np.einsum("...i,...i", b, c) * la)
    return 2.0 * np.arctan2(numerator, denominator)


def cell_solid_angles(light, point, edges):
    """The solid angle of each cell [edges[i], edges[i+1]] × [edges[j], edges[j+1]] (in half sizes) of a
    rectangle light, seen from `point`: two triangles each, exactly."""
    x0, y0 = np.meshgrid(edges[:-1], edges[:-1], indexing="ij")
    x1, y1 = np.meshgrid(edges[1:], edges[1:], indexing="ij")

    def corner(x, y):
        return (CENTRE + 0.5 * light.size_x * x[..., None] * AXES[:, 0] + 0.5 * light.size_y * y[..., None] * AXES[:, 1]
                - point)

    c00, c10, c11, c01 = corner(x0, y0), corner(x1, y0), corner(x1, y1), corner(x0, y1)
    return triangle_solid_angle(c00, c10, c11) + triangle_solid_angle(c00, c11, c01)


@pytest.mark.parametrize("size_x, size_y, offset", [
    (1.2, 0.5, [0.4, -0.3, -0.9]),  # off axis
    (0.8, 0.8, [0.0, 0.0, -0.6]),  # a square from its axis
    (1.2, 0.5, [0.5, 0.2, -0.05]),  # close: most of a hemisphere
])
def test_a_rectangle_is_sampled_uniformly_in_the_solid_angle_it_subtends(size_x, size_y, offset):
    """Points on a rectangle in front of it, binned in 10 × 10 cells: each cell is drawn with probability
    (its solid angle) / Ω, and the sampler's pdf is 1 / Ω."""
    light = area_light("rectangle", size_x, size_y)
    a, b, point, pdf = area_sample(light, offset, seed=8)
    edges = np.linspace(-1.0, 1.0, 11)
    solid_angles = cell_solid_angles(light, point, edges)
    total = solid_angles.sum()
    assert SOLID_ANGLE_SAMPLED[0] < total < SOLID_ANGLE_SAMPLED[1]
    np.testing.assert_allclose(1.0 / pdf, total, rtol=1e-9)
    counts = histogram2d(np.clip(a, -1.0, 1.0), np.clip(b, -1.0, 1.0), edges, edges)
    assert chi_square_pvalue(counts, solid_angles / total) > P_MIN


@pytest.mark.parametrize("shape, size_x, size_y, offset", [
    ("rectangle", 0.1, 0.05, [1.0, 2.0, -5.0]),  # a solid angle of 1.5e-4, below SOLID_ANGLE_SAMPLED: by area
    ("ellipse", 1.5, 0.4, [0.4, -0.3, -0.9]),
    ("ellipse", 0.7, 0.7, [0.0, 0.0, -0.2]),  # a disk, close
])
def test_area_samples_are_uniform_over_the_area(shape, size_x, size_y, offset):
    """Points drawn over the area (pdf 1/A): equal counts in cells of equal area (a rectangle's 10 × 10 cells;
    an ellipse's 8 rings of equal area × 12 sectors), with the solid-angle pdf d² / (A cos θ_q) of a point drawn
    so."""
    light = area_light(shape, size_x, size_y)
    a, b, point, pdf = area_sample(light, offset, seed=9)
    if shape == "rectangle":
        edges = np.linspace(-1.0, 1.0, 11)
        counts = histogram2d(np.clip(a, -1.0, 1.0), np.clip(b, -1.0, 1.0), edges, edges)
    else:
        counts = histogram2d(np.clip(a * a + b * b, 0.0, 1.0), np.arctan2(b, a), np.linspace(0.0, 1.0, 9),
                             np.linspace(-np.pi, np.pi, 13))
    assert chi_square_pvalue(counts, np.full(counts.shape, 1.0 / counts.size)) > P_MIN
    q = CENTRE[:, None] + AXES[:, :2] @ np.array([0.5 * size_x * a, 0.5 * size_y * b])
    v = q - point[:, None]
    d2 = (v * v).sum(axis=0)
    cos_light = np.maximum(v.T @ AXES[:, 2], 0.0) / np.sqrt(d2)  # it emits along its local −Z, towards −v
    area = size_x * size_y * (np.pi / 4 if shape == "ellipse" else 1.0)
    np.testing.assert_allclose(1.0 / pdf, area * cos_light / d2, rtol=1e-9)


def fine_points(shape, nodes):
    """Midpoints of a fine grid over a light in half sizes (a, b), each with its share of the area (summing to
    1): a square grid for a rectangle, polar for an ellipse."""
    mid = (np.arange(nodes) + 0.5) / nodes
    if shape == "rectangle":
        a, b = np.meshgrid(2 * mid - 1, 2 * mid - 1, indexing="ij")
        return a.ravel(), b.ravel(), np.full(a.size, 1.0 / a.size)
    rho, phi = np.meshgrid(np.sqrt(mid), 2 * np.pi * mid, indexing="ij")  # rings of equal area
    return (rho * np.cos(phi)).ravel(), (rho * np.sin(phi)).ravel(), np.full(rho.size, 1.0 / rho.size)


def cells(shape, a, b):
    """The cell of each point (a, b): 10 × 10 for a rectangle, 8 rings of equal area × 12 sectors for an
    ellipse."""
    if shape == "rectangle":
        return (np.clip(((a + 1) * 5).astype(int), 0, 9) * 10 + np.clip(((b + 1) * 5).astype(int), 0, 9)), 100
    ring = np.clip((np.clip(a * a + b * b, 0.0, 1.0) * 8).astype(int), 0, 7)
    sector = np.clip(((np.arctan2(b, a) + np.pi) / (2 * np.pi) * 12).astype(int), 0, 11)
    return ring * 12 + sector, 96


@pytest.mark.parametrize("shape, size_x, size_y, offset", [
    ("rectangle", 1.2, 0.5, [0.4, -0.3, -0.9]),  # near: by solid angle
    ("rectangle", 1.2, 0.5, [0.5, 0.2, -0.05]),  # very near: most of a hemisphere
    ("rectangle", 0.1, 0.05, [1.0, 2.0, -5.0]),  # far: a solid angle below SOLID_ANGLE_SAMPLED, by area
    ("ellipse", 1.5, 0.4, [0.4, -0.3, -0.9]),  # near
    ("ellipse", 0.1, 0.05, [1.0, 2.0, -5.0]),  # far
])
def test_a_ray_meeting_an_area_light_has_the_samplers_pdf(shape, size_x, size_y, offset):
    """The pdf a ray that meets the light's face is weighed with (`area_light_hit` for where, then
    `area_direction_pdf`) against the sampler: for each sampled direction the ray from the point meets the
    light at the sampled distance with the pdf the sampler returned; and integrated over cells of the light
    (the solid angle of fine points times their pdf) it predicts the sampler's counts per cell (χ²) and sums
    to 1."""
    light = area_light(shape, size_x, size_y)
    ks = compiled(light)
    a, b, point, pdf = area_sample(light, offset, seed=10)
    u1, u2 = uniforms(10)
    wx, wy, wz, _, distance, _ = sample_light(ks, 0, *(np.full(N, c) for c in point), u1, u2)
    t = area_light_hit(ks, 0, *(np.full(N, c) for c in point), wx, wy, wz, np.inf)
    np.testing.assert_allclose(t, distance, rtol=1e-9)
    cos_light = -(np.array([wx, wy, wz]).T @ ks.lights.dir[0])
    np.testing.assert_allclose(area_direction_pdf(ks, 0, *(np.full(N, c) for c in point), t, cos_light), pdf,
                               rtol=1e-9)
    fa, fb, share = fine_points(shape, 400)
    q = CENTRE[:, None] + AXES[:, :2] @ np.array([0.5 * size_x * fa, 0.5 * size_y * fb])
    v = q - point[:, None]
    d = np.linalg.norm(v, axis=0)
    w = v / d
    count = fa.size
    t = area_light_hit(ks, 0, *(np.full(count, c) for c in point), *w, np.inf)
    cos_light = -(w.T @ ks.lights.dir[0])
    area = size_x * size_y * (np.pi / 4 if shape == "ellipse" else 1.0)
    solid_angle = share * area * cos_light / d**2
    probability = area_direction_pdf(ks, 0, *(np.full(count, c) for c in point), t, cos_light) * solid_angle
    assert probability.sum() == pytest.approx(1.0, abs=2e-3)
    fine_cell, cell_count = cells(shape, fa, fb)
    expected = np.bincount(fine_cell, weights=probability, minlength=cell_count)
    sampled_cell, _ = cells(shape, a, b)
    counts = np.bincount(sampled_cell, minlength=cell_count)
    assert chi_square_pvalue(counts, expected / expected.sum()) > P_MIN


@pytest.mark.parametrize("shape", ["rectangle", "ellipse"])
def test_rays_pass_an_area_light_behind_it_beside_it_and_beyond_reach(shape):
    """A ray meets only the emitting face (its local −Z side), inside the shape, before t_max."""
    light = area_light(shape, 1.0, 0.6)
    ks = compiled(light)
    front, behind = CENTRE - 2.0 * AXES[:, 2], CENTRE + 2.0 * AXES[:, 2]
    towards = AXES[:, 2]
    assert area_light_hit(ks, 0, *front, *towards, np.inf) == pytest.approx(2.0)
    assert area_light_hit(ks, 0, *front, *towards, 1.9) == np.inf  # beyond reach
    assert area_light_hit(ks, 0, *behind, *-towards, np.inf) == np.inf  # its back
    assert area_light_hit(ks, 0, *front, *-towards, np.inf) == np.inf  # away from it
    corner = CENTRE + 0.45 * AXES[:, 0] + 0.27 * AXES[:, 1]  # inside the rectangle, outside the ellipse
    hit = area_light_hit(ks, 0, *(corner - 2.0 * AXES[:, 2]), *towards, np.inf)
    assert (hit == pytest.approx(2.0)) if shape == "rectangle" else hit == np.inf
    beside = CENTRE + 0.55 * AXES[:, 0]
    assert area_light_hit(ks, 0, *(beside - 2.0 * AXES[:, 2]), *towards, np.inf) == np.inf


# ----------------------------------------------------------------------------- delta lights

def test_a_point_light_is_aimed_at_with_inverse_square_falloff():
    ks = compiled(Light(kind="point", spectrum=spectra.constant(1.0), position=np.array([1.0, 2.0, 3.0])))
    wx, wy, wz, pdf, distance, falloff = sample_light(ks, 0, 0.0, 0.0, 1.0, 0.2, 0.9)
    assert distance == pytest.approx(3.0) and pdf == 1.0 and falloff == pytest.approx(1 / 9.0)
    assert (wx, wy, wz) == pytest.approx((1 / 3, 2 / 3, 2 / 3))


def test_a_spot_light_falls_off_as_blenders_smooth_edge():
    """Cycles' spot attenuation: 1/d² × smoothstep((cos α − cos(size/2)) / ((1 − cos(size/2)) · blend)), with α
    the angle from the spot's axis; 0 outside the cone."""
    size, blend = np.radians(60.0), 0.3
    ks = compiled(Light(kind="spot", spectrum=spectra.constant(1.0), position=np.zeros(3),
                        spot_direction=np.array([0.0, 0.0, -1.0]), spot_size=size, spot_blend=blend))
    alpha = np.radians(np.linspace(0.0, 40.0, 81))
    points = 2.0 * np.array([np.sin(alpha), np.zeros_like(alpha), -np.cos(alpha)])
    _, _, _, pdf, distance, falloff = sample_light(ks, 0, *points, 0.5, 0.5)
    cos_half = np.cos(0.5 * size)
    t = np.clip((np.cos(alpha) - cos_half) / ((1.0 - cos_half) * blend), 0.0, 1.0)
    np.testing.assert_allclose(distance, 2.0, rtol=1e-12)
    np.testing.assert_allclose(falloff, 0.25 * t * t * (3.0 - 2.0 * t), rtol=1e-9, atol=1e-15)
    assert falloff[alpha > 0.5 * size].max() == 0.0 and falloff[0] == pytest.approx(0.25) and np.all(pdf == 1.0)
