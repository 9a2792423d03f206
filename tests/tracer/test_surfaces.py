"""Opaque Lambertian surfaces and emissive surfaces (mesh lights) against closed forms, and the triangles'
hierarchy against brute force.

Every statistical test uses a fixed seed and compares an image mean with its expected value within 4 standard
errors (from the film's own per-pixel variance; `test_transport.assert_within`): a correct renderer fails such a
test with probability about 6e-5, a biased one as soon as its bias exceeds the bound.
"""

import dataclasses

import numpy as np
import pytest

from addon.tracer import bvh, colorimetry, spectra
from addon.tracer.builders import direction
from addon.tracer.errors import SpectralError
from addon.tracer.lowering import compile_scene
from addon.tracer.render import render
from addon.tracer.scene import Light, Surface
from addon.tracer.wavelengths import GRID
from tests.support import scenes as s
from tests.tracer.test_transport import assert_within
from addon.tracer.validation import validate

ALBEDO = s.smooth_ramp(0.2, 0.8, 400.0, 700.0)  # a chromatic reflectance


def ground(albedo=ALBEDO, size=40.0, subdivisions=4, z=0.0, **fields):
    """A square in the plane z = `z`, `size` on a side, centred on the z axis."""
    return s.parallelogram((-size / 2, -size / 2, z), (size, 0, 0), (0, size, 0), subdivisions, reflectance=albedo,
                           **fields)


def expected_xyz(radiance):
    return colorimetry.spectrum_to_xyz(np.asarray(radiance, dtype=np.float64) * np.ones(GRID.size))


def assert_xyz(film, radiance):
    expected = expected_xyz(radiance)
    for channel in range(3):
        assert_within(film, expected[channel], channel)


# ----------------------------------------------------------------------------- the hierarchy

def _random_triangles(count, seed):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-1.0, 1.0, (count, 1, 3))
    return centres + rng.normal(scale=0.08, size=(count, 3, 3))


def _brute_force(corners, origins, directions):
    """The nearest hit of each ray over every triangle, by the scalar Möller–Trumbore written out here."""
    best_t, best = np.full(len(origins), np.inf), np.full(len(origins), -1)
    for k, (a, b, c) in enumerate(corners):
        e1, e2 = b - a, c - a
        p = np.cross(directions, e2)
        det = p @ e1
        with np.errstate(divide="ignore", invalid="ignore"):
            tvec = origins - a
            u = np.sum(tvec * p, axis=1) / det
            q = np.cross(tvec, e1)
            v = np.sum(directions * q, axis=1) / det
            t = q @ e2 / det
        hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0) & (t < best_t)
        best_t[hit], best[hit] = t[hit], k
    return best_t, best


@pytest.mark.parametrize("count", [1, 7, 300])
def test_hierarchy_finds_the_nearest_triangle_as_brute_force_does(count):
    """Random triangles and rays: the kernel's walk of the hierarchy (`_closest_hit`) finds the same nearest
    triangle at the same distance as testing every triangle, and its any-hit walk finds one exactly where there
    is one."""
    from addon.tracer.kernels import numba_backend

    corners = _random_triangles(count, seed=count)
    vertices = corners.reshape(-1, 3)
    surface = Surface("random", vertices, np.arange(vertices.shape[0]).reshape(-1, 3), spectra.constant(0.5))
    ks = compile_scene(s.scene(s.ortho_camera(), [], [s.sun((0, 0, 1))], [surface]))
    # The lowering reorders the triangles: map them back by their corners.
    lowered = np.stack([ks.surfaces.corner, ks.surfaces.corner + ks.surfaces.edge1,
                        ks.surfaces.corner + ks.surfaces.edge2], axis=1)
    rng = np.random.default_rng(7)
    origins = rng.uniform(-1.5, 1.5, (400, 3))
    directions = rng.normal(size=(400, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    directions[:20] = [0.0, 0.0, 1.0]  # rays along an axis: slabs they run along
    expected_t, expected = _brute_force(lowered, origins, directions)
    hit = numba_backend._new_hit()
    for ray in range(len(origins)):
        t, k = numba_backend._closest_hit(ks, *origins[ray], *directions[ray], np.inf, False, False, hit)
        assert k == expected[ray]
        if k >= 0:
            assert t == pytest.approx(expected_t[ray], rel=1e-12)
        _, any_k = numba_backend._closest_hit(ks, *origins[ray], *directions[ray], np.inf, True, False, hit)
        assert (any_k >= 0) == (expected[ray] >= 0)


def test_hierarchy_of_a_million_triangles_builds_in_seconds():
    """A subdivided plane of a million triangles: every triangle in exactly one leaf, every box holding its
    children's and its triangles' boxes."""
    import time

    plane = s.parallelogram((0, 0, 0), (1, 0, 0), (0, 1, 0), 708)  # 2 · 708² ≈ 1.0 M triangles
    vertices = plane.vertices[plane.triangles]
    start = time.perf_counter()
    order, bounds, first, count = bvh.build(vertices.min(axis=1), vertices.max(axis=1))
    seconds = time.perf_counter() - start
    assert seconds < 30  # ~1.5 s on one core of the 2-core CI machine; minutes would be a regression
    leaves = np.flatnonzero(count > 0)
    covered = np.zeros(order.size, dtype=int)
    np.add.at(covered, np.concatenate([np.arange(f, f + c) for f, c in zip(first[leaves], count[leaves])]), 1)
    assert (covered == 1).all()
    low, high = vertices.min(axis=1)[order], vertices.max(axis=1)[order]
    leaf_of = np.repeat(leaves, count[leaves])
    triangle_of = np.concatenate([np.arange(f, f + c) for f, c in zip(first[leaves], count[leaves])])
    assert (low[triangle_of] >= bounds[leaf_of, :3]).all() and (high[triangle_of] <= bounds[leaf_of, 3:]).all()
    inner = np.flatnonzero(count == 0)
    for child in (first[inner], first[inner] + 1):
        assert (bounds[child, :3] >= bounds[inner, :3]).all() and (bounds[child, 3:] <= bounds[inner, 3:]).all()


# ----------------------------------------------------------------------------- closed forms

def test_plane_under_a_sun_reflects_albedo_times_irradiance_cosine_over_pi():
    """A chromatic Lambertian plane under a sun at 60° elevation, no medium: L = ρ(λ) E cos θ / π."""
    elevation = 60.0
    scene = s.scene(s.ortho_camera(8, 8, scale=4.0), [], [s.sun(direction(elevation, 30.0), 1.0)], [ground()],
                    spp=64, seed=1)
    assert_xyz(render(scene).film, ALBEDO.values * np.sin(np.radians(elevation)) / np.pi)


def test_plane_under_a_point_light_falls_off_as_cosine_over_distance_squared():
    """A point light of intensity I at (x0, 0, h) over a grey plane, seen near the origin by a narrow orthographic
    camera: L = ρ I cos θ / (π r²), cos θ = h / r."""
    x0, h, intensity, albedo = 1.5, 2.0, 3.0, 0.7
    light = Light(kind="point", spectrum=spectra.constant(1.0), strength=intensity, position=np.array([x0, 0.0, h]))
    scene = s.scene(s.ortho_camera(8, 8, scale=0.01, distance=1.0), [], [light], [ground(albedo)], spp=32, seed=2)
    r2 = x0**2 + h**2
    assert_xyz(render(scene).film, albedo * intensity * (h / np.sqrt(r2)) / (np.pi * r2))


def test_plane_in_a_uniform_environment_reflects_albedo_times_its_radiance():
    """A plane under an environment of radiance L: the sky above it gives irradiance πL, so L_out = ρ(λ) L
    (the environment below it is hidden: the surface is opaque)."""
    scene = s.scene(s.ortho_camera(8, 8, scale=4.0), [], [s.environment(1.0)], [ground()], spp=64, seed=3)
    assert_xyz(render(scene).film, ALBEDO.values)


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_surface_the_camera_does_not_see_still_casts_its_shadow(backend):
    """Indirect Only (`Surface.camera` off): a black square 1 above a grey ground over x < 0, under a sun at 45° from
    +x, seen from straight above (x from −2 to 2). Its shadow covers x < −1 (0: no other light); the camera sees
    through it to the lit ground at −1 < x < 0 (ρ E cos θ / π, where a square it saw would show black)."""
    albedo = 0.5
    hidden = s.parallelogram((-4.0, -4.0, 1.0), (4.0, 0, 0), (0, 8.0, 0), 1, reflectance=0.0, camera=False)
    scene = s.scene(s.ortho_camera(8, 8, scale=4.0), [], [s.sun(direction(45.0, 90.0), 1.0)], [ground(albedo), hidden],
                    spp=16 if backend == "numba" else 4, seed=5, backend=backend, passes=("Depth",))
    result = render(scene)
    np.testing.assert_allclose(result.film.xyz[:, :2, 1], 0.0, atol=1e-12)
    lit = result.film.xyz[:, 2:, 1]
    error = np.sqrt(result.film.variance[:, 2:, 1].sum()) / lit.size
    assert error > 0 and abs(lit.mean() - expected_xyz(albedo * np.sin(np.radians(45.0)) / np.pi)[1]) <= 4.0 * error
    np.testing.assert_allclose(result.passes.images["Depth"][..., 0], 6.0, rtol=1e-9)  # the passes see the ground


def test_shadow_of_an_occluding_triangle_is_black():
    """A black triangle between a grey plane and an overhead sun: the plane is dark where its shadow falls (no
    other light reaches it: the triangle reflects nothing back) and ρ E / π elsewhere."""
    blocker = Surface("blocker", np.array([[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [-1.0, 1.0, 1.0]]),
                      np.array([[0, 1, 2]]), spectra.constant(0.0))
    scene = s.scene(s.ortho_camera(16, 16, scale=4.0, distance=0.5), [], [s.sun((0, 0, 1), 1.0)],
                    [ground(0.6), blocker], spp=16, seed=4)
    film = render(scene).film
    y = film.xyz[..., 1]
    # Pixel (row, column) is centred at x = −2 + 0.25 (column + ½), y = 2 − 0.25 (row + ½); the shadow covers
    # x, y ≥ −1 with x + y ≤ 0: rows 4–11, columns 4–11, below the diagonal.
    rows, columns = np.indices(y.shape)
    shadow = (rows >= 4) & (rows <= 11) & (columns >= 4) & (rows - columns > 0)
    assert (y[shadow] == 0.0).all()
    assert (y[~shadow & ((rows < 3) | (rows > 12) | (columns < 3) | (columns > 12))] > 0.0).all()
    expected = expected_xyz(0.6 / np.pi)[1]
    outside = y[:, 13:]  # x > 1.25: beyond the triangle's shadow
    error = np.sqrt(film.variance[:, 13:, 1].sum()) / outside.size
    assert abs(outside.mean() - expected) <= 4.0 * error


def test_plane_inside_an_absorbing_medium_is_dimmed_on_the_way_in_and_out():
    """A plane cutting a purely absorbing box (σ, albedo 0) at depth d below its top, an overhead sun, the camera
    above the box looking down: the sun's light and the reflected light each cross d of the medium, so
    L = ρ(λ) E / π · exp(−2 σ(λ) d). The tracking of the camera ray ends at the plane, and the shadow ray and
    the reflected path start from it, inside the medium's box."""
    sigma, depth = s.smooth_ramp(1.2, 0.4), 0.35
    box = s.medium(s.box_grid(cells=(4, 4, 4), size=(6.0, 6.0, 1.0)), extinction=sigma, albedo=0.0)
    plane = ground(z=0.5 - depth)
    scene = s.scene(s.ortho_camera(8, 8, scale=1.0, distance=2.0), [box], [s.sun((0, 0, 1), 1.0)], [plane], spp=64,
                    seed=8)
    assert_xyz(render(scene).film, ALBEDO.values / np.pi * np.exp(-2.0 * sigma.values * depth))


def _emissive_box(emission, albedo):
    """The six walls of the cube [−1, 1]³, each emitting `emission` and reflecting `albedo`."""
    walls = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            corner, u, v = np.zeros(3), np.zeros(3), np.zeros(3)
            corner[axis] = side
            corner[(axis + 1) % 3], corner[(axis + 2) % 3] = -1.0, -1.0
            u[(axis + 1) % 3], v[(axis + 2) % 3] = 2.0, 2.0
            walls.append(s.parallelogram(corner, u, v, 2, reflectance=albedo, emission=emission, name=f"wall{axis}"))
    return walls


def test_white_emissive_box_furnace():
    """Inside a closed box whose walls emit Le and reflect ρ (both sides), every direction sees the same radiance
    L = Le + ρ L, so L = Le / (1 − ρ): emission hit directly, mesh-light sampling and BRDF sampling combined by
    MIS, through many bounces."""
    emission, albedo = 0.3, 0.6
    camera = s.perspective_camera(8, 8, fov_degrees=60.0, distance=0.0)
    scene = s.scene(camera, [], [], _emissive_box(emission, albedo), spp=64, seed=5, max_depth=200, rr_depth=200)
    assert_xyz(render(scene).film, emission / (1.0 - albedo))


@pytest.mark.parametrize("chromatic", [False, True], ids=["grey", "chromatic"])
def test_emissive_box_furnace_filled_with_a_white_medium(chromatic):
    """The same box filled (in part) with a medium of albedo 1: in a uniform radiance field a non-absorbing
    medium changes nothing, so the camera inside it still sees Le / (1 − ρ). Phase sampling and mesh-light
    sampling are weighed by MIS at every scattering vertex: on a grey medium with the controls' transmittance
    (residual tracking), on a chromatic one with ratio tracking's null-event probabilities."""
    emission, albedo = 0.3, 0.6
    extinction = s.smooth_ramp(3.0, 0.8) if chromatic else 2.0
    medium = s.medium(s.box_grid(cells=(6, 6, 6), size=(1.6, 1.6, 1.6)), extinction=extinction, albedo=1.0, g=0.4)
    camera = s.perspective_camera(8, 8, fov_degrees=60.0, distance=0.0)
    scene = s.scene(camera, [medium], [], _emissive_box(emission, albedo), spp=64, seed=9, max_depth=400,
                    rr_depth=400)
    assert_xyz(render(scene).film, emission / (1.0 - albedo))


def _square_irradiance(radiance, half, height):
    """Irradiance on the axis of a square emitter of radiance L, side 2a, at distance h: four corner rectangles
    a × a, each L/2 · 2 A/√(1+A²) · atan(A/√(1+A²)) with A = a/h."""
    a = half / height
    root = np.sqrt(1.0 + a * a)
    return 4.0 * radiance * a / root * np.arctan(a / root)


@pytest.mark.parametrize("half", [0.5, 3.0])
def test_plane_under_an_emissive_square_sees_its_view_factor(half):
    """A black square emitter of radiance L facing a grey plane at height h, the camera between them looking
    down at the axis: L_out = ρ E / π with E the square's on-axis irradiance. A small square (light sampling
    does the work) and a large one (BRDF sampling finds it too: MIS)."""
    height, radiance, albedo = 1.0, 2.0, 0.5
    emitter = s.parallelogram((-half, -half, height), (2 * half, 0, 0), (0, 2 * half, 0), 3, reflectance=0.0,
                              emission=radiance, name="lamp")
    camera = s.ortho_camera(8, 8, scale=0.01, distance=0.5 * height)
    scene = s.scene(camera, [], [], [ground(albedo), emitter], spp=64, seed=6)
    assert_xyz(render(scene).film, albedo * _square_irradiance(radiance, half, height) / np.pi)


def test_plane_under_a_square_area_light_sees_its_view_factor():
    """A square area light of power P (radiance L = P / (π A) below it) facing a grey plane: the same on-axis
    irradiance as an emissive square of radiance L, through the area light's own sampler."""
    half, height, power, albedo = 0.8, 1.0, 5.0, 0.5
    light = Light(kind="area", spectrum=spectra.constant(1.0), strength=power, unit="radiant",
                  position=np.array([0.0, 0.0, height]), area_axes=np.eye(3), size_x=2 * half, size_y=2 * half)
    radiance = power / (np.pi * 4 * half * half) / (GRID[-1] - GRID[0])  # its spectrum integrates to the power
    camera = s.ortho_camera(8, 8, scale=0.01, distance=0.5 * height)
    scene = s.scene(camera, [], [light], [ground(albedo)], spp=64, seed=10)
    assert_xyz(render(scene).film, albedo * _square_irradiance(radiance, half, height) / np.pi)


def test_an_emissive_surface_seen_directly_shows_its_radiance_on_both_sides():
    """Camera rays hitting an emitter see its radiance, from above and from below."""
    emission = s.smooth_ramp(0.5, 2.0)
    below = np.diag([1.0, -1.0, -1.0, 1.0])  # turned over: looking up the z axis from z = −1
    below[2, 3] = -1.0
    for camera in (s.ortho_camera(4, 4, scale=1.0, distance=1.0),
                   dataclasses.replace(s.ortho_camera(4, 4, scale=1.0), to_world=below)):
        scene = s.scene(camera, [], [], [ground(0.0, emission=emission)], spp=16, seed=7)
        assert_xyz(render(scene).film, emission.values)


def test_the_light_wavelength_mode_follows_an_emissive_surface():
    """The `light` wavelength mode's composite includes each emissive surface's emission, with its selection
    probability."""
    from addon.tracer.wavelength_modes import light_mode_sources

    emission = s.smooth_ramp(0.1, 2.0)
    ks = compile_scene(s.scene(s.ortho_camera(), [], [s.sun((0, 0, 1))], [ground(0.5, emission=emission)],
                               wavelength_sampling="light"))
    sources = light_mode_sources(ks)
    assert len(sources) == 2
    np.testing.assert_array_equal(sources[1][0].values, emission.values)
    assert sources[1][1] == ks.lights.pmf[1] > 0


# ----------------------------------------------------------------------------- the scene's checks

@pytest.mark.parametrize("change, message", [
    (dict(vertices=np.array([[0.0, 0, 0], [1, 0, 0], [np.nan, 1, 0]])), r"surfaces\[0\]\.vertices: must be finite"),
    (dict(triangles=np.array([[0, 1, 3]])), r"surfaces\[0\]\.triangles: vertex index 3"),
    (dict(triangles=np.array([[0.0, 1, 2]])), r"surfaces\[0\]\.triangles: expected whole numbers"),
    (dict(triangles=np.zeros((0, 3), dtype=int)), r"surfaces\[0\]\.triangles: expected a non-empty list"),
    (dict(reflectance=spectra.constant(1.2)), r"surfaces\[0\]\.reflectance: a reflectance must be within"),
    (dict(emission=spectra.constant(-1.0)), r"surfaces\[0\]\.emission: an emission must not be negative"),
])
def test_invalid_surfaces_are_refused_naming_the_field(change, message):
    fields = dict(name="tri", vertices=np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), triangles=np.array([[0, 1, 2]]),
                  reflectance=spectra.constant(0.5))
    surface = Surface(**{**fields, **change})
    with pytest.raises(SpectralError, match=message):
        validate(s.scene(s.ortho_camera(), [], [s.sun((0, 0, 1))], [surface]))


def test_an_emissive_surface_alone_lights_a_scene():
    lamp = ground(0.5, emission=1.0)
    validate(s.scene(s.ortho_camera(), [], [], [lamp]))
    with pytest.raises(SpectralError, match="no lights"):
        validate(s.scene(s.ortho_camera(), [], [], [ground(0.5)]))


def test_zero_area_triangles_are_dropped():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 2, 2]])
    surface = Surface("with a sliver", vertices, np.array([[0, 1, 2], [0, 1, 1], [3, 3, 3]]), spectra.constant(0.5),
                      emission=spectra.constant(1.0))
    ks = compile_scene(s.scene(s.ortho_camera(), [], [], [surface]))
    assert ks.surfaces.corner.shape == (1, 3)
    assert ks.surfaces.area[0] == pytest.approx(0.5)


# ----------------------------------------------------------------------------- the scene file

def _scene_with(surfaces_json):
    return {"format": "spectral-volume-scene", "version": 1,
            "camera": {"to_world": np.eye(4).tolist(), "width": 4, "height": 4},
            "surfaces": surfaces_json}


def _write(tmp_path, data):
    import json

    (tmp_path / "scene.json").write_text(json.dumps(data))
    return tmp_path


def test_surfaces_round_trip_through_the_scene_file(tmp_path):
    from addon.tracer.scene_io import load_scene, save_scene

    emission = s.smooth_ramp(0.0, 2.0)
    original = s.scene(s.ortho_camera(), [], [], [ground(), ground(0.3, z=2.0, emission=emission)])
    loaded = load_scene(save_scene(original, tmp_path))
    for before, after in zip(original.surfaces, loaded.surfaces):
        assert after.name == before.name
        np.testing.assert_array_equal(after.vertices, before.vertices)
        np.testing.assert_array_equal(after.triangles, before.triangles)
        np.testing.assert_allclose(after.reflectance.values, before.reflectance.values)
    assert loaded.surfaces[0].emission is None
    np.testing.assert_allclose(loaded.surfaces[1].emission.values, emission.values)


def test_surfaces_read_inline_lists_and_obj_files(tmp_path):
    from addon.tracer.scene_io import load_scene

    (tmp_path / "quad.obj").write_text("# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n"
                                       "f 1/1/1 2/2/1 3/3/1 -1\n")
    data = _scene_with([
        {"name": "inline", "vertices": [[0, 0, 1], [1, 0, 1], [0, 1, 1]], "triangles": [[0, 1, 2]], "reflectance": 0.5,
         "emission": 1.0},
        {"mesh": "quad.obj", "reflectance": 0.25},
    ])
    scene = load_scene(_write(tmp_path, data))
    np.testing.assert_array_equal(scene.surfaces[0].triangles, [[0, 1, 2]])
    assert scene.surfaces[0].emission.values[0] == 1.0
    np.testing.assert_array_equal(scene.surfaces[1].triangles, [[0, 1, 2], [0, 2, 3]])
    np.testing.assert_array_equal(scene.surfaces[1].vertices[2], [1, 1, 0])
    assert scene.surfaces[1].name == "surfaces[1]"


@pytest.mark.parametrize("surface, message", [
    ({"vertices": [[0, 0, 0]], "reflectance": 0.5}, r"surfaces\[0\]: missing required field 'triangles'"),
    ({"vertices": [[0, 0]], "triangles": [[0, 0, 0]], "reflectance": 0.5}, r"surfaces\[0\]\.vertices: expected rows"),
    ({"vertices": [[0, 0, "a"]], "triangles": [[0, 0, 0]], "reflectance": 0.5}, r"surfaces\[0\]\.vertices: expected"),
    ({"vertices": [[0, 0, 0]], "triangles": [[0, 0, 1]], "reflectance": 0.5},
     r"surfaces\[0\]\.triangles: vertex index 1"),
    ({"mesh": "missing.obj", "reflectance": 0.5}, r"surfaces\[0\]\.mesh: the file .* does not exist"),
    ({"mesh": "x.obj", "vertices": [], "reflectance": 0.5}, r"surfaces\[0\]: give either"),
    ({"vertices": [[0, 0, 0]], "triangles": [[0, 0, 0]], "reflectance": 0.5, "colour": 1}, r"unknown field 'colour'"),
])
def test_bad_surfaces_in_the_scene_file_are_refused_naming_the_field(tmp_path, surface, message):
    from addon.tracer.scene_io import load_scene

    data = _scene_with([surface])
    data["lights"] = [{"kind": "sun", "spectrum": 1.0, "direction": [0, 0, 1]}]
    with pytest.raises(SpectralError, match=message):
        load_scene(_write(tmp_path, data))


def test_validate_scene_describes_the_surfaces(tmp_path):
    from addon.tracer.scene_io import save_scene, validate_scene

    scene = s.scene(s.ortho_camera(), [], [], [ground(name="floor"), ground(0.3, z=2.0, emission=1.0, name="lamp")])
    lines = validate_scene(save_scene(scene, tmp_path))
    assert "surface 'floor': 32 triangles" in lines
    assert "surface 'lamp': 32 triangles, emissive" in lines
