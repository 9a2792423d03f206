"""Panels, menus and UI lists draw against real data; spectrum operators work."""

import os
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

from addon import registration
from addon.props import curves
from addon.props.spectrum_values import to_spectrum
from addon.props.render import ENGINE_ID
from addon.tracer.errors import SpectralError

from tests.addon.recording import RecordingLayout, draw

bpy = pytest.importorskip("bpy")


def _classes(base):
    return [cls for module in registration.MODULES for cls in module.CLASSES if issubclass(cls, base)]


def _scene_with_everything():
    """A scene with a volume object, a mesh, every light type and a sky world, materials fully set."""
    scene = bpy.context.scene
    material = bpy.data.materials.new("Smoke")
    settings = material.spectral
    settings.enabled = settings.use_fluorescence = settings.use_blackbody = True
    settings.albedo_levels.add().spectrum.source = "CURVE"
    volume = bpy.data.objects.new("Volume", bpy.data.volumes.new("Volume"))
    volume.data.materials.append(material)
    scene.collection.objects.link(volume)
    lights = []
    for kind in ("SUN", "POINT", "SPOT", "AREA"):
        light = bpy.data.objects.new(kind.title(), bpy.data.lights.new(kind.title(), kind))
        light.data.spectral.enabled = True
        scene.collection.objects.link(light)
        lights.append(light)
    scene.world = bpy.data.worlds.new("World")
    scene.world.spectral.enabled = True
    scene.world.spectral.kind = "sky"
    scene.render.engine = ENGINE_ID
    return scene, volume, material, lights


def _context(scene, obj, material=None):
    light = obj.data if obj is not None and obj.type == "LIGHT" else None
    return SimpleNamespace(scene=scene, engine=scene.render.engine, object=obj, active_object=obj,
                           material=material, light=light, world=scene.world, view_layer=scene.view_layers[0])


def test_every_panel_draws_for_every_object(registered):
    scene, volume, material, lights = _scene_with_everything()
    panels = _classes(bpy.types.Panel)
    assert len(panels) >= 10
    for obj in (volume, *lights, None):
        context = _context(scene, obj, material if obj is volume else None)
        for panel in panels:
            if hasattr(panel, "poll") and not panel.poll(context):
                continue
            draw(panel, context)
            for method in ("draw_header", "draw_header_preset"):
                if hasattr(panel, method):
                    draw(panel, context, method)


def test_properties_panels_show_with_the_spectral_engine_only(registered):
    scene, volume, material, _lights = _scene_with_everything()
    context = _context(scene, volume, material)
    assert bpy.types.SPECTRAL_PT_material.poll(context) and bpy.types.SPECTRAL_PT_render.poll(context)
    scene.render.engine = "CYCLES"
    context = _context(scene, volume, material)
    assert not bpy.types.SPECTRAL_PT_material.poll(context) and not bpy.types.SPECTRAL_PT_render.poll(context)


@pytest.mark.parametrize("role", ["albedo", "extinction", "anisotropy", "excitation", "emission", "reflectance"])
def test_material_panels_draw_every_spectrum_source(registered, role):
    scene, volume, material, _lights = _scene_with_everything()
    material.spectral.use_surface = True  # the Spectral Surface panel draws its reflectance
    spectrum = getattr(material.spectral, role)
    context = _context(scene, volume, material)
    for item in spectrum.bl_rna.properties["source"].enum_items:
        spectrum.source = item.identifier
        for panel in _classes(bpy.types.Panel):
            if getattr(panel, "bl_context", "") == "material":
                draw(panel, context)
    assert curves.find_mapping(spectrum.curve) is not None  # the Curve source made its curve


def test_a_curve_draws_its_widget_and_a_bad_csv_its_error(registered):
    scene, volume, material, _lights = _scene_with_everything()
    settings = material.spectral
    settings.albedo.source = "CURVE"
    layout = draw(bpy.types.SPECTRAL_PT_material, _context(scene, volume, material))
    assert any(name == "template_curve_mapping" for name, _a, _k in layout.calls)
    settings.extinction.source = "CSV"
    layout = draw(bpy.types.SPECTRAL_PT_material, _context(scene, volume, material))
    assert any("no CSV file chosen" in text for text in layout.texts())


def test_light_spectrum_shows_presets_and_swatch(registered):
    scene, _volume, _material, lights = _scene_with_everything()
    sun = lights[0]
    layout = draw(bpy.types.SPECTRAL_PT_light, _context(scene, sun))
    assert ("popover", (), {"panel": "SPECTRAL_PT_light_presets", "text": "", "icon": "PRESET"}) in layout.calls
    assert any(name == "prop" and args[1] == "preview" for name, args, _k in layout.calls)
    area = lights[3]
    layout = draw(bpy.types.SPECTRAL_PT_light, _context(scene, area))
    for name in ("shape", "size", "spread"):
        assert layout.index("prop", area.data, name) is not None
    assert any(name == "prop" and args[1] == "preview" for name, args, _k in layout.calls)


def test_light_size_is_drawn_sun_angle_and_greyed_radius(registered):
    scene, _volume, _material, lights = _scene_with_everything()
    sun, point, spot = (obj.data for obj in lights[:3])
    layout = draw(bpy.types.SPECTRAL_PT_light, _context(scene, lights[0]))
    assert layout.setting_before(layout.index("prop", sun, "angle"), "active") in (None, True)
    for obj, light in ((lights[1], point), (lights[2], spot)):
        layout = draw(bpy.types.SPECTRAL_PT_light, _context(scene, obj))
        assert layout.setting_before(layout.index("prop", light, "shadow_soft_size"), "active") is False
        assert any("only the Cycles emulation uses the Radius" in text for text in layout.texts())


def test_light_shows_blenders_colour_until_spectral_light_is_on(registered):
    scene, _volume, _material, lights = _scene_with_everything()
    point = lights[1].data
    point.spectral.enabled = False
    layout = draw(bpy.types.SPECTRAL_PT_light, _context(scene, lights[1]))
    assert layout.index("prop", point, "color") is not None and layout.index("prop", point, "temperature") is not None
    assert not any(name == "prop" and args[1] == "preview" for name, args, _k in layout.calls)  # no spectrum
    point.spectral.enabled = True
    layout = draw(bpy.types.SPECTRAL_PT_light, _context(scene, lights[1]))
    assert any(name == "prop" and args[1] == "preview" for name, args, _k in layout.calls)


def test_ui_list_draws(registered):
    """A row of the albedo levels' list shows the level's colour swatch and its density, in one row."""
    scene, volume, material, lights = _scene_with_everything()
    level = material.spectral.albedo_levels[0]
    layout = RecordingLayout()
    bpy.types.SPECTRAL_UL_albedo_levels.draw_item(None, None, layout, material.spectral, level, 0,
                                                   material.spectral, "albedo_index")
    swatch, density = layout.index("prop", level.spectrum, "preview"), layout.index("prop", level, "density")
    assert layout.calls[0][0] == "row" and 0 < swatch < density


def test_spectrum_files_may_be_blend_relative(registered, tmp_path):
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "scene.blend"))
    csv = tmp_path / "lamp.csv"
    csv.write_text("400,1\n700,2\n")
    spectrum = bpy.data.lights.new("Lamp", "POINT").spectral.spectrum
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # Blender warns about "//" paths on properties that do not allow them
        assert bpy.ops.spectral.import_spectrum_csv(filepath=str(csv), **_target(spectrum)) == {"FINISHED"}
        assert spectrum.filepath == "//lamp.csv"
    assert to_spectrum(spectrum).values.max() == pytest.approx(2.0)


def _target(settings):
    owner = settings.id_data
    return {"id_type": owner.id_type, "id_name": owner.name, "data_path": settings.path_from_id()}


def test_import_csv_accepts_a_good_file(registered, tmp_path):
    good = tmp_path / "lamp.csv"
    good.write_text("wavelength,value\n400,0.1\n500,1.0\n700,0.4\n")
    spectrum = bpy.data.lights.new("Lamp", "POINT").spectral.spectrum
    assert bpy.ops.spectral.import_spectrum_csv(filepath=str(good), **_target(spectrum)) == {"FINISHED"}
    assert spectrum.source == "CSV" and spectrum.filepath == str(good)


def test_import_csv_rejects_a_bad_file_and_changes_nothing(registered, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("400,0.1\n390,0.2\n")
    spectrum = bpy.data.lights.new("Lamp", "POINT").spectral.spectrum
    with pytest.raises(RuntimeError, match=r"Not imported: .*bad.csv, line 2: wavelength 390 nm does not increase"):
        bpy.ops.spectral.import_spectrum_csv(filepath=str(bad), **_target(spectrum))
    assert spectrum.source == "ILLUMINANT" and spectrum.filepath == ""


def test_edit_as_curve_keeps_the_shape(registered):
    from addon.props.spectrum_values import to_spectrum

    albedo = bpy.data.materials.new("Red").spectral.albedo
    albedo.source = "COLOR"
    albedo.color = (0.8, 0.1, 0.1)
    before = to_spectrum(albedo).values
    assert bpy.ops.spectral.spectrum_to_curve(**_target(albedo)) == {"FINISHED"}
    assert albedo.source == "CURVE"
    after = to_spectrum(albedo).values
    assert abs(after - before).max() < 0.05
    assert tuple(albedo.preview) == pytest.approx((0.8, 0.1, 0.1), abs=0.03)


def test_removing_an_albedo_level_removes_its_curve(registered):
    material = bpy.data.materials.new("Layered")
    with bpy.context.temp_override(material=material):
        bpy.ops.spectral.albedo_level_add()
        material.spectral.albedo_levels[0].spectrum.source = "CURVE"
        assert len(material.spectral.curve_group.nodes) == 1
        bpy.ops.spectral.albedo_level_remove()
    assert len(material.spectral.albedo_levels) == 0 and len(material.spectral.curve_group.nodes) == 0


def test_missing_curve_is_reported_not_raised(registered):
    albedo = bpy.data.materials.new("Lost").spectral.albedo
    albedo.source = "CURVE"
    curves.discard(albedo.curve)
    from addon.props.spectrum_values import to_spectrum
    with pytest.raises(SpectralError, match="the curve is missing"):
        to_spectrum(albedo)


def test_copied_material_can_make_its_curves_its_own(registered):
    material = bpy.data.materials.new("Original")
    material.spectral.albedo.source = "CURVE"
    copy = material.copy()
    assert copy.spectral.curve_group == material.spectral.curve_group and curves.is_shared(copy)
    scene, volume, _material, _lights = _scene_with_everything()
    layout = draw(bpy.types.SPECTRAL_PT_material, _context(scene, volume, copy))
    assert "Curves shared with a copy" in layout.texts()
    assert bpy.ops.spectral.curves_single_user(**_target(copy.spectral.albedo)) == {"FINISHED"}
    assert copy.spectral.curve_group != material.spectral.curve_group and not curves.is_shared(material)
    curves.set_points(curves.find_mapping(copy.spectral.albedo.curve), (400, 700), (0.1, 0.2))
    assert curves.points(curves.find_mapping(material.spectral.albedo.curve))[0][1] == pytest.approx(0.9)


def _counting(monkeypatch, module, name):
    """Replace `module.name` by a wrapper that counts its calls; the list of calls."""
    calls, original = [], getattr(module, name)

    def wrapper(*args, **kwargs):
        calls.append(args)
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, wrapper)
    return calls


def _draw_light(scene, light_object):
    return draw(bpy.types.SPECTRAL_PT_light, _context(scene, light_object))


def test_redraws_reuse_spectra_by_content(registered, tmp_path, monkeypatch):
    from addon.tracer import spectra

    scene, _volume, _material, lights = _scene_with_everything()
    spectrum = lights[0].data.spectral.spectrum
    csv = tmp_path / "lamp.csv"
    csv.write_text("".join(f"{nm},{1 + nm / 1000}\n" for nm in range(300, 800)))
    spectrum.source, spectrum.filepath = "CSV", str(csv)
    reads = _counting(monkeypatch, spectra, "from_csv")
    for _redraw in range(3):
        _draw_light(scene, lights[0])
    assert len(reads) == 1
    os.utime(csv, ns=(csv.stat().st_atime_ns, csv.stat().st_mtime_ns + 10**9))  # the file changed
    _draw_light(scene, lights[0])
    assert len(reads) == 2
    samples = _counting(monkeypatch, curves, "sample")
    spectrum.source = "CURVE"
    for _redraw in range(3):
        _draw_light(scene, lights[0])
    assert len(samples) == 1
    curves.find_mapping(spectrum.curve).curves[0].points[0].location = (3.0, 0.2)
    _draw_light(scene, lights[0])
    assert len(samples) == 2


def test_redraws_never_recover_spectra_from_colours(registered, monkeypatch):
    from addon.tracer import spectra

    def refuse(*_args, **_kwargs):
        raise AssertionError("RGB → spectrum recovery while drawing")

    scene, volume, material, lights = _scene_with_everything()
    lights[0].data.spectral.spectrum.source = material.spectral.albedo.source = "COLOR"
    lights[0].data.spectral.spectrum.color = material.spectral.albedo.color = (0.8, 0.2, 0.1)
    monkeypatch.setattr(spectra, "from_rgb", refuse)
    _draw_light(scene, lights[0])
    for panel in _classes(bpy.types.Panel):
        context = _context(scene, volume, material)
        if not hasattr(panel, "poll") or panel.poll(context):
            draw(panel, context)
    np.testing.assert_allclose(material.spectral.albedo.preview, (0.8, 0.2, 0.1), atol=1e-6)
    np.testing.assert_allclose(lights[0].data.spectral.spectrum.preview, (1.0, 0.25, 0.125), atol=1e-6)
    monkeypatch.undo()  # once computed (by a render), the swatch is the spectrum's own colour
    to_spectrum(material.spectral.albedo)
    np.testing.assert_allclose(material.spectral.albedo.preview, (0.8, 0.2, 0.1), atol=0.02)


def test_panels_follow_blender_layout_and_show_under_this_engine_only(registered):
    from bl_ui.utils import PresetPanel

    from addon.ui.panel import SpectralPanel

    scene, volume, material, lights = _scene_with_everything()
    panels = [panel for panel in _classes(bpy.types.Panel) if not issubclass(panel, PresetPanel)]  # popovers
    assert all(issubclass(panel, SpectralPanel) and panel.COMPAT_ENGINES == {ENGINE_ID} for panel in panels)
    for obj in (volume, lights[0]):
        context = _context(scene, obj, material if obj is volume else None)
        for panel in panels:
            if panel.poll(context):
                layout = draw(panel, context)
                assert layout.calls[:2] == [("set", ("use_property_split", True), {}),
                                            ("set", ("use_property_decorate", True), {})]
    scene.render.engine = "CYCLES"
    context = _context(scene, volume, material)
    assert not any(panel.poll(context) for panel in panels)  # the sidebar tab too


def test_labels_are_ready_for_translation():
    """Blender translates a label by its text: one built by an f-string has no translatable msgid (build it
    from `iface_("...").format(...)` and pass translate=False)."""
    import ast
    from pathlib import Path

    import addon.ui

    found = []
    for path in Path(addon.ui.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.keyword) and node.arg == "text" and isinstance(node.value, ast.JoinedStr):
                found.append(f"{path.name}:{node.value.lineno}")
    assert found == []


def test_device_draws_with_why_the_gpu_cannot_render_here(registered, monkeypatch):
    """Device sits under Renderer for the tracer (not for the Cycles emulation, which Cycles renders); with GPU
    Compute where no CUDA device is usable, the reason is drawn under it; Backend is greyed out for the GPU."""
    from addon.ui import render as render_ui

    scene, volume, material, _lights = _scene_with_everything()
    context = _context(scene, volume, material)
    layout = draw(bpy.types.SPECTRAL_PT_render, context)
    assert ("prop", (scene.spectral, "device"), {}) in layout.calls
    monkeypatch.setattr(render_ui, "gpu_problem", lambda: "No usable CUDA device: the NVIDIA driver is missing.")
    scene.spectral.device = "GPU"
    layout = draw(bpy.types.SPECTRAL_PT_render, context)
    assert any("No usable CUDA device" in text for text in layout.texts())
    performance = draw(bpy.types.SPECTRAL_PT_render_performance, context)
    assert performance.setting_before(performance.index("prop", scene.spectral, "backend"), "active") is False
    monkeypatch.setattr(render_ui, "gpu_problem", lambda: None)
    assert not any("CUDA" in text for text in draw(bpy.types.SPECTRAL_PT_render, context).texts())
    scene.spectral.renderer = "CYCLES"
    calls = draw(bpy.types.SPECTRAL_PT_render, context).calls
    assert ("prop", (scene.spectral, "device"), {}) not in calls
