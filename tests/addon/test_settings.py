"""Settings: registration leaves no trace, values survive save and reload, curves and swatches work."""

import numpy as np
import pytest

import addon
from addon.props import curves
from addon.props.spectrum_values import to_spectrum
from addon.tracer import spectra
from addon.tracer.errors import SpectralError
from addon.tracer.wavelengths import GRID

bpy = pytest.importorskip("bpy")

OWNERS = ("Scene", "Material", "Light", "World", "Object")


def _our_types():
    return {name for name in dir(bpy.types) if name.startswith(("SPECTRAL_", "Spectral"))}


def _all_panels(base=None):
    for cls in (base or bpy.types.Panel).__subclasses__():
        yield cls
        yield from _all_panels(cls)


def test_register_unregister_leaves_no_trace(clean):
    before = _our_types()
    addon.register()
    assert all(hasattr(getattr(bpy.types, owner), "spectral") for owner in OWNERS)
    assert _our_types() - before
    assert "SPECTRAL_VOLUME" in bpy.types.DATA_PT_volume_file.COMPAT_ENGINES  # Blender's generic panels show
    addon.unregister()
    assert not any(hasattr(getattr(bpy.types, owner), "spectral") for owner in OWNERS)
    assert _our_types() == before
    assert not any("SPECTRAL_VOLUME" in getattr(panel, "COMPAT_ENGINES", ()) for panel in _all_panels()
                   if not panel.__name__.startswith("SPECTRAL_"))  # Blender's panels; ours name it themselves
    addon.register()  # and again, as when the user toggles the add-on
    addon.unregister()


def test_settings_survive_save_and_reload(registered, tmp_path):
    material = bpy.data.materials.new("Smoke")
    settings = material.spectral
    settings.enabled = True
    settings.density_scale = 7.5
    settings.albedo.source = "COLOR"
    settings.albedo.color = (0.2, 0.4, 0.8)
    level = settings.albedo_levels.add()
    level.density = 2.0
    level.spectrum.source = "CURVE"
    curves.set_points(curves.find_mapping(level.spectrum.curve), (400, 550, 700), (0.1, 0.9, 0.3))
    settings.use_fluorescence = True
    settings.excitation.band = "V405"
    settings.quantum_yield = 0.4
    material.use_fake_user = True
    light = bpy.data.lights.new("Lamp", "POINT")
    light.spectral.spectrum.source = "BLACKBODY"
    light.spectral.spectrum.temperature = 3200.0
    light.use_fake_user = True
    scene = bpy.context.scene
    scene.spectral.samples = 9
    scene.spectral.wavelength_sampling = "uv"
    scene.spectral.scheduler_address = "tcp://farm:8786"
    path = tmp_path / "settings.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=str(path))
    settings = bpy.data.materials["Smoke"].spectral
    assert settings.enabled and settings.density_scale == 7.5
    assert tuple(settings.albedo.color) == pytest.approx((0.2, 0.4, 0.8))
    level = settings.albedo_levels[0]
    assert level.density == 2.0
    reloaded = curves.points(curves.find_mapping(level.spectrum.curve))
    np.testing.assert_allclose(reloaded, [(400, 0.1), (550, 0.9), (700, 0.3)], atol=1e-5)
    assert settings.excitation.band == "V405" and settings.quantum_yield == pytest.approx(0.4)
    assert bpy.data.lights["Lamp"].spectral.spectrum.temperature == 3200.0
    s = bpy.context.scene.spectral
    assert (s.samples, s.wavelength_sampling, s.scheduler_address) == (9, "uv", "tcp://farm:8786")


def test_settings_are_animatable(registered):
    material = bpy.data.materials.new("Smoke")
    cube = bpy.data.objects.new("Cube", bpy.data.meshes.new("Cube"))
    cube.data.materials.append(material)
    bpy.context.scene.collection.objects.link(cube)
    material.spectral.density_scale = 1.0
    material.keyframe_insert("spectral.density_scale", frame=1)
    material.spectral.density_scale = 5.0
    material.keyframe_insert("spectral.density_scale", frame=10)
    bpy.context.scene.frame_set(10)
    assert material.spectral.density_scale == pytest.approx(5.0)
    bpy.context.scene.frame_set(1)
    assert material.spectral.density_scale == pytest.approx(1.0)


def test_curve_is_sampled_in_nanometres(registered):
    material = bpy.data.materials.new("Dye")
    albedo = material.spectral.albedo
    albedo.source = "CURVE"
    mapping = curves.find_mapping(albedo.curve)
    curves.set_points(mapping, (400.0, 500.0, 600.0), (0.2, 0.8, 0.2))
    values = to_spectrum(albedo).values
    assert values[GRID == 500.0][0] == pytest.approx(0.8, abs=1e-3)
    assert values[GRID == 400.0][0] == pytest.approx(0.2, abs=1e-3)
    assert values.max() <= 1.0 and values.min() >= 0.0
    assert material.spectral.curve_group.name.startswith(".")  # hidden from node group lists


def test_swatch_previews_the_spectrum(registered):
    material = bpy.data.materials.new("Red")
    albedo = material.spectral.albedo
    albedo.source = "COLOR"
    albedo.color = (0.7, 0.1, 0.05)
    assert tuple(albedo.preview) == pytest.approx((0.7, 0.1, 0.05), abs=0.02)
    light = bpy.data.lights.new("Candle", "POINT").spectral.spectrum
    light.source = "BLACKBODY"
    light.temperature = 1900.0
    red, green, blue = light.preview
    assert red == pytest.approx(1.0) and red > green > blue


def test_light_spectrum_sources_and_window(registered):
    spectrum = bpy.data.lights.new("Sun", "SUN").spectral.spectrum
    spectrum.source = "ILLUMINANT"
    spectrum.illuminant = "A"
    np.testing.assert_allclose(to_spectrum(spectrum).values, spectra.illuminant("A").values)
    spectrum.use_window = True
    spectrum.window_min, spectrum.window_max = 250.0, 400.0
    windowed = to_spectrum(spectrum).values
    assert windowed[GRID > 400.0].max() == 0.0 and windowed[GRID < 380.0].max() > 0.0


def test_missing_csv_is_named(registered, tmp_path):
    spectrum = bpy.data.lights.new("Lamp", "SPOT").spectral.spectrum
    spectrum.source = "CSV"
    spectrum.filepath = str(tmp_path / "missing.csv")
    with pytest.raises(SpectralError, match=r"Light 'Lamp' spectrum: spectrum file .*missing.csv does not exist"):
        to_spectrum(spectrum)
    assert tuple(spectrum.preview) == (0.0, 0.0, 0.0)


def _visible_properties(rna):
    return [prop for prop in rna.properties if prop.identifier != "rna_type" and not prop.is_hidden
            and not prop.identifier.startswith("bl_")]


def _addon_rnas():
    """The RNA of the add-on's settings and operators."""
    from addon import registration

    groups = [cls.bl_rna for module in registration.MODULES for cls in module.CLASSES
              if issubclass(cls, bpy.types.PropertyGroup)]
    return groups + [getattr(bpy.ops.spectral, name).get_rna_type() for name in dir(bpy.ops.spectral)]


def test_every_setting_and_choice_has_a_description(registered):
    """Tooltips: every visible property of the add-on's settings and operators, and every enum item."""
    missing = []
    for rna in _addon_rnas():
        for prop in _visible_properties(rna):
            if not prop.description:
                missing.append(f"{rna.identifier}.{prop.identifier}")
            if prop.type == "ENUM":
                missing += [f"{rna.identifier}.{prop.identifier}: {item.identifier}"
                            for item in prop.enum_items if not item.description]
    assert missing == []


def test_ui_strings_spell_color_as_blender_does(registered):
    texts = []
    for rna in _addon_rnas():
        for prop in _visible_properties(rna):
            texts += [prop.name, prop.description]
            if prop.type == "ENUM":
                texts += [text for item in prop.enum_items for text in (item.name, item.description)]
    british = [text for text in texts if "colour" in text.lower().replace("colour-science", "")
               or "centre" in text.lower()]
    assert british == []


def test_only_the_generic_panels_that_apply_are_shown(registered):
    from addon.engine import render_engine as engine

    shown = {panel.__name__ for panel in _all_panels() if "SPECTRAL_VOLUME" in getattr(panel, "COMPAT_ENGINES", ())}
    for applies in ("DATA_PT_lens", "DATA_PT_spot", "DATA_PT_volume_grids", "RENDER_PT_format", "PARTICLE_PT_render",
                    "RENDER_PT_color_management", "PHYSICS_PT_smoke", "PHYSICS_PT_fire", "PHYSICS_PT_cache"):
        assert applies in shown
    for does_not in ("PHYSICS_PT_cloth", "RENDER_PT_freestyle", "VIEWLAYER_PT_freestyle",
                     "TEXTURE_PT_image", "PHYSICS_PT_liquid", "DATA_PT_lightprobe"):
        assert does_not not in shown
    assert not any(name.startswith(engine.NOT_RENDERED) for name in shown)
    print(f"{len(shown)} generic panels shown")


def test_f12_samples_adaptively_and_denoises_by_default_as_cycles_does(registered):
    """A new scene: Noise Threshold on at 0.01 with automatic Min Samples, Denoise on for renders and off
    for the viewport, as in Cycles; the export carries the threshold, and turning it off gives 0."""
    from addon.export.scene import render_settings

    scene = bpy.context.scene
    settings = scene.spectral
    assert settings.use_adaptive_sampling and settings.adaptive_threshold == pytest.approx(0.01)
    assert settings.adaptive_min_samples == 0
    assert settings.denoise and not settings.viewport_denoise
    exported = render_settings(scene)
    assert exported.noise_threshold == pytest.approx(0.01) and exported.min_samples == 0
    settings.use_adaptive_sampling = False
    assert render_settings(scene).noise_threshold == 0.0
