"""Light-spectrum and material presets as Blender presets: built-in ones apply, users save, apply, share
and remove their own, and a light preset never touches the light's wavelength window."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from addon import presets
from addon.props import curves
from tests.addon.recording import draw

bpy = pytest.importorskip("bpy")

LIGHT_MENU, MATERIAL_MENU = "SPECTRAL_PT_light_presets", "SPECTRAL_PT_material_presets"


@pytest.fixture
def user_presets(registered):
    """The user's preset folders for this add-on, empty before and removed after the test."""
    folder = Path(bpy.utils.user_resource("SCRIPTS", path="presets")) / "spectral_volume"
    shutil.rmtree(folder, ignore_errors=True)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def _built_in(subdir, name):
    path = presets.BUILT_IN / subdir / f"{name}.py"
    assert path.is_file(), path
    return path


def _apply(path, menu, **context):
    with bpy.context.temp_override(**context):
        assert bpy.ops.script.execute_preset(filepath=str(path), menu_idname=menu) == {"FINISHED"}


def _uv_lamp():
    spectrum = bpy.data.lights.new("UV Lamp", "SPOT").spectral.spectrum
    spectrum.source, spectrum.band = "BAND", "UV365"
    spectrum.use_window, spectrum.window_min, spectrum.window_max = True, 275.0, 450.0
    return spectrum


def test_blender_finds_the_built_in_presets(registered):
    for subdir, count in ((presets.LIGHT_SUBDIR, 11), (presets.MATERIAL_SUBDIR, 6)):
        assert str(presets.BUILT_IN / subdir) in bpy.utils.preset_paths(subdir)
        assert len(list((presets.BUILT_IN / subdir).glob("*.py"))) == count


def test_a_light_preset_keeps_the_wavelength_window(registered):
    spectrum = _uv_lamp()
    _apply(_built_in(presets.LIGHT_SUBDIR, "Tungsten_(A)"), LIGHT_MENU, spectral_spectrum=spectrum)
    assert (spectrum.source, spectrum.illuminant) == ("ILLUMINANT", "A")
    assert spectrum.use_window and (spectrum.window_min, spectrum.window_max) == (275.0, 450.0)


def test_every_built_in_light_preset_applies(registered):
    spectrum = bpy.data.lights.new("Lamp", "POINT").spectral.spectrum
    for path in sorted((presets.BUILT_IN / presets.LIGHT_SUBDIR).glob("*.py")):
        spectrum.source = "CURVE"
        _apply(path, LIGHT_MENU, spectral_spectrum=spectrum)
        assert spectrum.source != "CURVE", path.name
    _apply(_built_in(presets.LIGHT_SUBDIR, "Candle_(1900_K)"), LIGHT_MENU, spectral_spectrum=spectrum)
    assert spectrum.source == "BLACKBODY" and spectrum.temperature == pytest.approx(1900.0)


def test_a_built_in_material_preset_sets_everything_it_stores(registered):
    material = bpy.data.materials.new("Dye")
    settings = material.spectral
    settings.use_blackbody = True
    settings.albedo.source = "COLOR"
    settings.albedo_levels.add().density = 3.0
    _apply(_built_in(presets.MATERIAL_SUBDIR, "Fluorescein_Dye"), MATERIAL_MENU, material=material)
    assert settings.enabled and settings.use_fluorescence and not settings.use_blackbody
    assert settings.albedo.source == "CONSTANT" and settings.albedo.value == pytest.approx(0.95)
    assert len(settings.albedo_levels) == 0
    assert settings.emission.peak == pytest.approx(515.0) and settings.quantum_yield == pytest.approx(0.93)
    _apply(_built_in(presets.MATERIAL_SUBDIR, "Rayleigh_Haze"), MATERIAL_MENU, material=material)
    assert settings.phase == "rayleigh" and settings.extinction.source == "CURVE"
    assert curves.points(curves.find_mapping(settings.extinction.curve))[0] == pytest.approx((360.0, 1.0))


def test_every_built_in_material_preset_applies(registered):
    material = bpy.data.materials.new("Volume")
    for path in sorted((presets.BUILT_IN / presets.MATERIAL_SUBDIR).glob("*.py")):
        material.spectral.enabled = False
        _apply(path, MATERIAL_MENU, material=material)
        assert material.spectral.enabled, path.name


def test_a_saved_light_preset_is_a_file_that_restores_the_spectrum(user_presets):
    spectrum = _uv_lamp()
    spectrum.source = "CURVE"
    spectrum.set_curve_points(((300.0, 0.0), (365.0, 1.0), (420.0, 0.25)))
    with bpy.context.temp_override(spectral_spectrum=spectrum):
        assert bpy.ops.spectral.light_preset_add(name="My UV Lamp") == {"FINISHED"}
    path = user_presets / "light_spectrum" / "My_UV_Lamp.py"
    assert path.is_file() and "window" not in path.read_text()
    assert str(path) == bpy.utils.preset_find("My_UV_Lamp", presets.LIGHT_SUBDIR)

    other = bpy.data.lights.new("Other", "SUN").spectral.spectrum  # another light, another blend: shared
    other.use_window, other.window_min = True, 400.0
    _apply(path, LIGHT_MENU, spectral_spectrum=other)
    assert other.source == "CURVE"
    np.testing.assert_allclose(curves.points(curves.find_mapping(other.curve)),
                               [(300.0, 0.0), (365.0, 1.0), (420.0, 0.25)], atol=1e-5)
    assert other.use_window and (other.window_min, other.window_max) == (400.0, 780.0)


def test_a_saved_material_preset_restores_spectra_and_albedo_levels(user_presets):
    material = bpy.data.materials.new("Mist")
    settings = material.spectral
    settings.enabled, settings.density_scale, settings.phase = True, 7.5, "rayleigh"
    settings.albedo.source, settings.albedo.color = "COLOR", (0.2, 0.4, 0.6)
    level = settings.albedo_levels.add()
    level.density, level.spectrum.source = 2.5, "CURVE"
    level.spectrum.set_curve_points(((400.0, 0.1), (700.0, 0.9)))
    with bpy.context.temp_override(material=material):
        assert bpy.ops.spectral.material_preset_add(name="Mist") == {"FINISHED"}
    assert (user_presets / "material" / "Mist.py").is_file()

    copy = bpy.data.materials.new("Fresh")
    _apply(user_presets / "material" / "Mist.py", MATERIAL_MENU, material=copy)
    restored = copy.spectral
    assert restored.enabled and restored.density_scale == pytest.approx(7.5) and restored.phase == "rayleigh"
    assert restored.albedo.source == "COLOR" and tuple(restored.albedo.color) == pytest.approx((0.2, 0.4, 0.6))
    (level,) = restored.albedo_levels
    assert level.density == pytest.approx(2.5) and level.spectrum.source == "CURVE"
    np.testing.assert_allclose(curves.points(curves.find_mapping(level.spectrum.curve)), [(400.0, 0.1), (700.0, 0.9)],
                               atol=1e-5)


def test_users_remove_their_presets_but_not_the_built_in_ones(user_presets):
    spectrum = bpy.data.lights.new("Lamp", "POINT").spectral.spectrum
    with bpy.context.temp_override(spectral_spectrum=spectrum):
        bpy.ops.spectral.light_preset_add(name="Mine")
        assert (user_presets / "light_spectrum" / "Mine.py").is_file()
        assert bpy.ops.spectral.light_preset_add(name="Mine", remove_name=True) == {"FINISHED"}
        assert not (user_presets / "light_spectrum" / "Mine.py").exists()
        with pytest.raises(RuntimeError, match="'Tungsten \\(A\\)' is a built-in preset: it cannot be removed"):
            bpy.ops.spectral.light_preset_add(name="Tungsten_(A)", remove_name=True)
    assert _built_in(presets.LIGHT_SUBDIR, "Tungsten_(A)").is_file()


def test_a_preset_needs_settings_to_save(user_presets):
    with pytest.raises(RuntimeError, match="No light spectrum here to save as a preset"):
        bpy.ops.spectral.light_preset_add(name="Nothing")
    with pytest.raises(RuntimeError, match="No material here to save as a preset"):
        bpy.ops.spectral.material_preset_add(name="Nothing")
    assert not user_presets.exists() or not any(user_presets.rglob("*.py"))


def test_preset_popovers_list_built_in_and_user_presets(user_presets):
    spectrum = bpy.data.lights.new("Lamp", "POINT").spectral.spectrum
    with bpy.context.temp_override(spectral_spectrum=spectrum):
        bpy.ops.spectral.light_preset_add(name="Mine")
    layout = draw(bpy.types.SPECTRAL_PT_light_presets, bpy.context)
    names = [kwargs["text"] for kind, _args, kwargs in layout.calls if kind == "operator" and kwargs.get("text")]
    assert "Tungsten (A)" in names and "Mine" in names
    assert ("operator", ("spectral.light_preset_add",), {"text": "", "icon": "ADD"}) in layout.calls
    layout = draw(bpy.types.SPECTRAL_PT_material_presets, bpy.context)
    assert any(kwargs.get("text") == "Rayleigh Haze" for kind, _args, kwargs in layout.calls if kind == "operator")


def test_a_broken_preset_file_says_what_is_wrong(registered, tmp_path):
    spectrum = bpy.data.lights.new("Lamp", "POINT").spectral.spectrum
    path = tmp_path / "Broken.py"
    path.write_text("import bpy\nspectrum = bpy.context.spectral_spectrum\nspectrum.source = 'CURVE'\n"
                    "spectrum.set_curve_points(((400.0, 1.0),))\n")
    with bpy.context.temp_override(spectral_spectrum=spectrum), pytest.raises(
            RuntimeError, match="a spectrum curve needs at least two \\(nm, value\\) points, got 1"):
        bpy.ops.script.execute_preset(filepath=str(path), menu_idname=LIGHT_MENU)
