"""Comparing two tracer scenes field by field, with the tolerances that Blender's curves need: a scene
exported from a .blend against the scene it was built from (the demos, the importer's round trip)."""

import numpy as np
import pytest

from addon.tracer.spectra import Spectrum
from addon.tracer.wavelengths import GRID

# Spectra drawn as curves differ from the code's by Blender's curve table (256 steps over 250–830 nm):
# at most 0.05 next to a kink (the report's anisotropy starts rising at 380 nm with infinite slope).
CURVE_MAX_ERROR, CURVE_MEAN_ERROR = 0.06, 0.005


def assert_same_spectrum(a, b, lambda_min: float, curve: bool, what: str, tolerance=1e-6):
    """Equal over the rendered range [lambda_min, 830] nm, up to the curve table when `curve`, else
    within `tolerance` (a number, or one per wavelength of GRID)."""
    rendered = GRID >= lambda_min + (5.0 if curve else 0.0)
    error = np.abs(a.values - b.values)[rendered]
    if curve:
        assert error.max() < CURVE_MAX_ERROR and error.mean() < CURVE_MEAN_ERROR, what
    else:
        excess = error - np.broadcast_to(tolerance, GRID.shape)[rendered]
        assert excess.max() <= 0.0, f"{what}: {error[excess.argmax()]:.3g} off at " \
                                    f"{GRID[rendered][excess.argmax()]:.0f} nm, beyond the tolerance"


def assert_same_grid(a, b, what: str):
    """The same non-zero voxels at the same world positions (VDB files keep only the active box)."""
    def voxels(grid):
        index = np.argwhere(grid.values > 0)
        world = index @ grid.index_to_world[:3, :3].T + grid.index_to_world[:3, 3]
        order = np.lexsort(np.round(world, 4).T[::-1])
        return world[order], grid.values[tuple(index.T)][order]

    (world_a, values_a), (world_b, values_b) = voxels(a), voxels(b)
    assert world_a.shape == world_b.shape, what
    np.testing.assert_allclose(world_a, world_b, atol=1e-5, err_msg=what)
    np.testing.assert_allclose(values_a, values_b, rtol=1e-6, err_msg=what)


def light_shape(light, lambda_min: float, field: str = "spectrum") -> np.ndarray:
    values = np.where(GRID >= lambda_min, getattr(light, field).values, 0.0)
    return values / values.max()


def assert_same_scene(exported, reference, curve: bool, renamed=None, albedo_tolerances=None,
                      light_curves: bool = False):
    """`exported` equals `reference`: camera, settings, lights (spectra as shapes, up to the curve table
    when `light_curves`) and media, whose names in `exported` map to `reference`'s through `renamed`
    (default: the same names); the albedo of a medium named in `albedo_tolerances` within that tolerance
    (per wavelength); surfaces (triangles, reflectance and emission, matched by name)."""
    renamed, albedo_tolerances = renamed or {}, albedo_tolerances or {}
    cam_a, cam_b = exported.camera, reference.camera
    assert (cam_a.width, cam_a.height, cam_a.kind) == (cam_b.width, cam_b.height, cam_b.kind)
    np.testing.assert_allclose(cam_a.to_world, cam_b.to_world, atol=1e-5)
    assert cam_a.fov == pytest.approx(cam_b.fov, abs=1e-6)
    assert (cam_a.ortho_scale, cam_a.shift_x, cam_a.shift_y) == pytest.approx(
        (cam_b.ortho_scale, cam_b.shift_x, cam_b.shift_y), abs=1e-6)
    assert exported.settings == reference.settings
    low = exported.settings.lambda_min
    lights_a, lights_b = (sorted(scene.lights, key=lambda light: light.kind) for scene in (exported, reference))
    assert [light.kind for light in lights_a] == [light.kind for light in lights_b]
    for a, b in zip(lights_a, lights_b):
        assert a.strength == pytest.approx(b.strength, rel=1e-6) and a.angle == pytest.approx(b.angle, abs=1e-6)
        for field in ("direction", "position", "spot_direction"):
            if getattr(b, field) is not None:
                np.testing.assert_allclose(getattr(a, field), getattr(b, field), atol=1e-5, err_msg=f"{a.name} {field}")
        assert (a.spot_size, a.spot_blend) == pytest.approx((b.spot_size, b.spot_blend), abs=1e-6)
        assert a.unit == b.unit, a.name
        if b.kind == "area":
            assert a.area_shape == b.area_shape and (a.size_x, a.size_y) == pytest.approx((b.size_x, b.size_y))
            assert a.camera_visible == b.camera_visible, f"{a.name} camera visibility"
            np.testing.assert_allclose(a.area_axes, b.area_axes, atol=1e-6, err_msg=f"{a.name} axes")
        assert (a.horizon_spectrum is None) == (b.horizon_spectrum is None)
        shapes = [(light_shape(a, low), light_shape(b, low))]
        if b.horizon_spectrum is not None:
            shapes.append(tuple(light_shape(light, low, "horizon_spectrum") for light in (a, b)))
        for shape_a, shape_b in shapes:
            if light_curves:
                assert_same_spectrum(Spectrum(shape_a), Spectrum(shape_b), low, True, f"{a.name} spectrum")
            else:
                np.testing.assert_allclose(shape_a, shape_b, atol=1e-6, err_msg=a.name)
    media_b = {medium.name: medium for medium in reference.media}
    assert sorted(renamed.get(m.name, m.name) for m in exported.media) == sorted(media_b)
    for a in exported.media:
        b = media_b[renamed.get(a.name, a.name)]
        assert a.density_scale == pytest.approx(b.density_scale) and a.phase == b.phase, a.name
        assert_same_grid(a.density, b.density, a.name)
        for field in ("extinction", "anisotropy"):
            assert_same_spectrum(getattr(a, field), getattr(b, field), low, curve, f"{a.name} {field}")
        np.testing.assert_array_equal(a.albedo_densities, b.albedo_densities)
        for level, (row_a, row_b) in enumerate(zip(a.albedo_table, b.albedo_table)):
            assert_same_spectrum(Spectrum(row_a), Spectrum(row_b), low, curve, f"{a.name} albedo {level}",
                                 albedo_tolerances.get(a.name, 1e-6))
        assert (a.fluorescence is None) == (b.fluorescence is None) and (a.emission is None) == (b.emission is None)
        if b.fluorescence is not None:
            fa, fb = a.fluorescence, b.fluorescence
            assert fa.quantum_yield == pytest.approx(fb.quantum_yield)
            assert_same_spectrum(fa.excitation, fb.excitation, GRID[0], curve, f"{a.name} excitation")
            assert_same_spectrum(fa.emission, fb.emission, GRID[0], curve, f"{a.name} emission")
        if b.emission is not None:
            ea, eb = a.emission, b.emission
            assert (ea.intensity, ea.temperature_scale, ea.temperature_offset) == pytest.approx(
                (eb.intensity, eb.temperature_scale, eb.temperature_offset))
            assert_same_grid(ea.temperature, eb.temperature, f"{a.name} temperature")
    surfaces_b = {surface.name: surface for surface in reference.surfaces}
    assert sorted(surface.name for surface in exported.surfaces) == sorted(surfaces_b)
    for a in exported.surfaces:
        b = surfaces_b[a.name]
        np.testing.assert_allclose(a.vertices[a.triangles], b.vertices[b.triangles], atol=1e-5, err_msg=a.name)
        np.testing.assert_allclose(a.reflectance.values, b.reflectance.values, atol=1e-6, err_msg=a.name)
        assert (a.emission is None) == (b.emission is None), a.name
        if b.emission is not None:
            np.testing.assert_allclose(a.emission.values, b.emission.values, rtol=1e-6, err_msg=a.name)
