"""The committed demo .blend files: each scene exports (through the add-on) to the tracer scene that
`demo_blends.scenes` builds in code, and `build_blends` rebuilds what is committed: exactly, except the
designed metamers' albedos, which rest on a seeded Monte Carlo calibration and so reproduce on another
CPU only within that calibration's noise (`demo_blends.metamers`).

No rendering here except the metamer design's calibration inside the rebuild (a few seconds)."""

import numpy as np
import pytest
from scipy.ndimage import maximum_filter1d

from addon import cli
from addon.tracer.spectra import Spectrum
from addon.tracer.wavelengths import GRID
from demo_blends import build_blends, run_demos, scenes

# Blender object names (the exported media's names) that differ from the code-built media's.
RENAMED = {"Report air": "air", "Rayleigh air": "air", "Simple left cube": "left cube",
           "Simple right cube": "right cube", "Designed left cube": "left cube", "Designed right cube": "right cube"}
REFERENCES = {
    "rayleigh_report": scenes.rayleigh_report,
    "rayleigh_true": scenes.rayleigh_true,
    "fluorescent_frog": scenes.fluorescent_frog,
    "fire": scenes.fire,
    "metamers_simple_d65": scenes.metamerism_simple("D65"),
    "metamers_simple_lower_half": scenes.metamerism_simple("D65 lower half"),
}
# A rebuilt designed albedo may differ from the committed one by this many standard deviations of the
# difference of two calibrations (√2 × the design's own standard error at each wavelength): a correct
# rebuild on another CPU exceeds it with probability below 1e-6 per wavelength for normal errors.
DESIGN_SIGMAS = 5.0
# Spectra drawn as curves differ from the code's by Blender's curve table (256 steps over 250–830 nm):
# at most 0.05 next to a kink (the report's anisotropy starts rising at 380 nm with infinite slope).
CURVE_MAX_ERROR, CURVE_MEAN_ERROR = 0.06, 0.005


def export_all(folder) -> dict:
    with run_demos.addon_registered():
        exported = {}
        for name, where in build_blends.DEMO_SCENES.items():
            cli.open_scene(folder / where.blend, where.scene)
            exported[name] = cli.export_context_scene().scene
        return exported


@pytest.fixture(scope="module")
def committed():
    return export_all(build_blends.HERE)


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


def light_shape(light, lambda_min: float) -> np.ndarray:
    values = np.where(GRID >= lambda_min, light.spectrum.values, 0.0)
    return values / values.max()


def assert_same_scene(exported, reference, curve: bool, renamed=None, albedo_tolerances=None):
    """`exported` equals `reference`: camera, settings, lights (spectra as shapes) and media, whose
    names in `exported` map to `reference`'s through `renamed` (default: the same names); the albedo
    of a medium named in `albedo_tolerances` within that tolerance (per wavelength)."""
    renamed, albedo_tolerances = renamed or {}, albedo_tolerances or {}
    cam_a, cam_b = exported.camera, reference.camera
    assert (cam_a.width, cam_a.height, cam_a.kind) == (cam_b.width, cam_b.height, cam_b.kind)
    np.testing.assert_allclose(cam_a.to_world, cam_b.to_world, atol=1e-5)
    assert cam_a.fov == pytest.approx(cam_b.fov, abs=1e-6)
    assert exported.settings == reference.settings
    low = exported.settings.lambda_min
    lights_a, lights_b = (sorted(scene.lights, key=lambda light: light.kind) for scene in (exported, reference))
    assert [light.kind for light in lights_a] == [light.kind for light in lights_b]
    for a, b in zip(lights_a, lights_b):
        assert a.strength == pytest.approx(b.strength, rel=1e-6) and a.angle == pytest.approx(b.angle, abs=1e-6)
        if b.direction is not None:
            np.testing.assert_allclose(a.direction, b.direction, atol=1e-5)
        np.testing.assert_allclose(light_shape(a, low), light_shape(b, low), atol=1e-6, err_msg=a.name)
    media_b = {medium.name: medium for medium in reference.media}
    assert sorted(renamed.get(m.name, m.name) for m in exported.media) == sorted(media_b)
    for a in exported.media:
        b = media_b[renamed.get(a.name, a.name)]
        assert a.density_scale == pytest.approx(b.density_scale) and a.phase == b.phase, a.name
        assert_same_grid(a.density, b.density, a.name)
        for field in ("extinction", "anisotropy"):
            assert_same_spectrum(getattr(a, field), getattr(b, field), low, curve, f"{a.name} {field}")
        np.testing.assert_array_equal(a.albedo_densities, b.albedo_densities)
        assert_same_spectrum(Spectrum(a.albedo_table[0]), Spectrum(b.albedo_table[0]), low, curve,
                             f"{a.name} albedo", albedo_tolerances.get(a.name, 1e-6))
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


@pytest.mark.parametrize("name", sorted(REFERENCES))
def test_blend_scene_exports_the_code_built_scene(committed, name):
    where = build_blends.DEMO_SCENES[name]
    reference = REFERENCES[name](build_blends.WIDTH, build_blends.HEIGHT, where.spp)
    assert_same_scene(committed[name], reference, curve=True, renamed=RENAMED)


@pytest.mark.parametrize("name,light", [("metamers_d65", "D65"), ("metamers_a", "A")])
def test_designed_cubes_stand_where_the_simple_ones_do(committed, name, light):
    """The designed pair's scenes are the two-cube scene with the designed albedos (which the rebuild
    test checks against a fresh design)."""
    exported = committed[name]
    albedos = [Spectrum(m.albedo_table[0]) for m in sorted(exported.media, key=lambda m: m.name)]
    reference = scenes.two_cubes(*albedos, scenes.LIGHTS[light], build_blends.WIDTH, build_blends.HEIGHT,
                                 build_blends.DEMO_SCENES[name].spp)
    assert_same_scene(exported, reference, curve=False, renamed=RENAMED)


def test_build_script_reproduces_the_committed_files(committed, tmp_path):
    """Rebuilt from factory settings (the metamers designed afresh), every scene exports the same, the
    designed albedos within DESIGN_SIGMAS of the design's noise."""
    build_blends.build(tmp_path, log=lambda *args: None)
    rebuilt = export_all(tmp_path)
    errors = build_blends.designed_pair().albedo_errors  # the pair the rebuild designed (cached)
    # The .blend holds each albedo as a curve, read back through Blender's curve table (a step of 2.3 nm):
    # a value there mixes the design's values up to 3 nm away, so it takes the largest error among them.
    tolerances = {f"Designed {side} cube": DESIGN_SIGMAS * np.sqrt(2.0) * maximum_filter1d(error, 7) + 1e-6
                  for side, error in zip(("left", "right"), errors)}
    for name in build_blends.DEMO_SCENES:
        assert_same_scene(rebuilt[name], committed[name], curve=False, albedo_tolerances=tolerances)
