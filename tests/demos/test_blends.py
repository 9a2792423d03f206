"""The committed demo .blend files: each scene exports (through the add-on) to the tracer scene that
`demo_blends.scenes` builds in code, and `build_blends` rebuilds what is committed: exactly, except the
designed metamers' albedos, which rest on a seeded Monte Carlo calibration and so reproduce on another
CPU only within that calibration's noise (`demo_blends.metamers`).

No rendering here except the metamer design's calibration inside the rebuild (a few seconds)."""

import numpy as np
import pytest
from scipy.ndimage import maximum_filter1d

from addon.cli import command as cli
from addon.tracer.spectra import Spectrum
from demo_blends import build_blends, run_demos, scenes
from tests.support.scene_compare import assert_same_scene

# Blender object names (the exported media's names) that differ from the code-built media's.
RENAMED = {"Report air": "air", "Rayleigh air": "air", "Simple left cube": "left cube",
           "Simple right cube": "right cube", "Designed left cube": "left cube", "Designed right cube": "right cube"}
REFERENCES = {
    "rayleigh_report": scenes.rayleigh_report,
    "rayleigh_true": scenes.rayleigh_true,
    "fluorescent_frog": scenes.fluorescent_frog,
    "highlighter_ink": scenes.highlighter_ink,
    "fire": scenes.fire,
    "cloud_shadow": scenes.cloud_shadow,
    "metamers_simple_d65": scenes.metamerism_simple("D65"),
    "metamers_simple_lower_half": scenes.metamerism_simple("D65 lower half"),
}
# A rebuilt designed albedo may differ from the committed one by this many standard deviations of the
# difference of two calibrations (√2 × the design's own standard error at each wavelength): a correct
# rebuild on another CPU exceeds it with probability below 1e-6 per wavelength for normal errors.
DESIGN_SIGMAS = 5.0


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
