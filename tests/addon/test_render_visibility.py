"""Render to Image, Export Scene, Estimate Bands and the CLI export what F12 renders: objects and
collections by their render visibility, modifiers by their render settings, not the viewport's."""

import contextlib

import pytest

import addon.cli.command
import addon.engine.render_engine
import addon.jobs.kinds
import addon.jobs.tracer_job
import addon.operators.emulation
from addon.props.render import ENGINE_ID
from addon.export.rendered import export_rendered
from addon.tracer.errors import SpectralError
from addon.tracer.scene_io import load_scene
from tests.addon.builders import add_camera, add_sun, add_volume, spectral_material, write_vdb

bpy = pytest.importorskip("bpy")


def _visibility_scene(tmp_path):
    """Volumes shown everywhere, disabled in renders (itself or by its collection), hidden or disabled in
    the viewport; a voxelised cube whose Array modifier shows only in the viewport."""
    scene = bpy.context.scene
    scene.render.engine = ENGINE_ID
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    add_camera()
    add_sun()
    vdb = write_vdb(tmp_path / "cloud.vdb")
    add_volume(vdb, "Shown")
    add_volume(vdb, "Disabled In Renders").hide_render = True
    add_volume(vdb, "Hidden In Viewport").hide_set(True)
    add_volume(vdb, "Disabled In Viewports").hide_viewport = True
    off = bpy.data.collections.new("Not Rendered")
    scene.collection.children.link(off)
    off.hide_render = True
    in_off = add_volume(vdb, "In A Collection Not Rendered")
    scene.collection.objects.unlink(in_off)
    off.objects.link(in_off)
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.5))
    cube = bpy.context.active_object
    cube.name = "Cube"
    cube.data.materials.append(spectral_material("Cube Volume"))
    cube.spectral.voxel_size = 0.25
    array = cube.modifiers.new("Array", "ARRAY")
    array.count, array.show_render = 3, False


def _media(export_scene):
    """Each medium's name and grid shape."""
    return {medium.name: medium.density.values.shape for medium in export_scene.media}


F12 = {"Shown": (4, 3, 2), "Hidden In Viewport": (4, 3, 2), "Disabled In Viewports": (4, 3, 2), "Cube": (6, 6, 6)}


def test_f12_renders_by_render_visibility(registered, tmp_path, monkeypatch):
    """The reference: what F12's engine exports (its render is stopped before tracing)."""
    _visibility_scene(tmp_path)
    exported, export_scene = [], addon.engine.render_engine.export_scene

    def record_and_stop(depsgraph):
        exported.append(export_scene(depsgraph).scene)
        raise SpectralError("recorded, not rendered")

    monkeypatch.setattr(addon.engine.render_engine, "export_scene", record_and_stop)
    with contextlib.suppress(RuntimeError):
        bpy.ops.render.render()
    assert [_media(scene) for scene in exported] == [F12]


def _render_to_image(monkeypatch, tmp_path):
    exported = []

    class Recorded(addon.jobs.tracer_job.TracerJob):
        def run(self, progress=None, notice=None, cancel=None):
            exported.append(self.scene)
            self.error = "recorded, not rendered"

    monkeypatch.setattr(addon.jobs.kinds, "TracerJob", Recorded)
    with contextlib.suppress(RuntimeError):
        bpy.ops.spectral.render_image()
    return exported[0]


def _export_scene(monkeypatch, tmp_path):
    out = tmp_path / "exported" / "scene.json"
    assert bpy.ops.spectral.export_scene(filepath=str(out)) == {"FINISHED"}
    return load_scene(out)


def _estimate_bands(monkeypatch, tmp_path):
    exported = []

    def record(scene, max_renders):
        exported.append(scene)
        raise SpectralError("recorded, not planned")

    monkeypatch.setattr(addon.operators.emulation, "plan_bands", record)
    with contextlib.suppress(RuntimeError):
        bpy.ops.spectral.estimate_emulation_bands()
    return exported[0]


def _cli(monkeypatch, tmp_path):
    return addon.cli.command.export_context_scene().scene


@pytest.mark.parametrize("path", [_render_to_image, _export_scene, _estimate_bands, _cli],
                         ids=["render_to_image", "export_scene", "estimate_bands", "cli"])
def test_every_export_outside_f12_matches_f12(registered, tmp_path, monkeypatch, path):
    _visibility_scene(tmp_path)
    assert _media(path(monkeypatch, tmp_path)) == F12


def test_another_engine_is_put_back(registered, tmp_path):
    _visibility_scene(tmp_path)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    assert _media(export_rendered(scene, bpy.context.view_layer).scene) == F12
    assert scene.render.engine == "CYCLES"


def test_a_view_layer_not_used_for_rendering_is_refused(registered, tmp_path):
    _visibility_scene(tmp_path)
    bpy.context.view_layer.use = False
    with pytest.raises(SpectralError, match="renders nothing of view layer 'ViewLayer': its Use for Rendering"):
        export_rendered(bpy.context.scene, bpy.context.view_layer)


def test_no_camera_is_blenders_message(registered, tmp_path):
    _visibility_scene(tmp_path)
    bpy.context.scene.camera = None
    with pytest.raises(SpectralError, match="Blender cannot render the scene: Cannot render, no camera"):
        export_rendered(bpy.context.scene, bpy.context.view_layer)


def test_an_export_error_reaches_the_caller(registered, tmp_path):
    _visibility_scene(tmp_path)
    bpy.data.objects["Shown"].data.filepath = str(tmp_path / "gone.vdb")
    with pytest.raises(SpectralError, match="Volume 'Shown': VDB file"):
        export_rendered(bpy.context.scene, bpy.context.view_layer)
