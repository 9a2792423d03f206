"""Material previews: Blender renders its preview scene with the engine (`ID.asset_generate_preview()`
does so headless), lit by its own lights, or by the key light of `addon.engine.thumbnails` where it has none."""

import numpy as np
import pytest

from addon.jobs import tracer_job
from addon.engine.thumbnails import preview_scene
from addon.tracer.scene import Camera, look_at
from tests.support import scenes

bpy = pytest.importorskip("bpy")


def test_a_material_preview_gets_a_key_light_and_a_light_preview_keeps_its_light():
    camera = Camera(to_world=look_at((0.0, -5.0, 0.0), (0.0, 0.0, 0.0)), width=16, height=16)
    material = preview_scene(scenes.scene(camera, lights=[scenes.environment()], spp=64), samples=5)
    assert material.settings.spp == 5 and [light.kind for light in material.lights] == ["environment", "sun"]
    key = material.lights[1].direction
    assert key[0] < 0 and key[2] > 0 and key[1] < 0  # towards the camera's left, up, and back towards it
    lit = preview_scene(scenes.scene(camera, lights=[scenes.environment(), scenes.sun((0, 0, 1))]), samples=5)
    assert [light.kind for light in lit.lights] == ["environment", "sun"] and lit.lights[1].direction[2] == 1


@pytest.mark.slow
def test_a_material_preview_renders_the_spectral_material(registered, monkeypatch, capfd):
    """Blender's preview scene (its area lights and World) lights the sphere: a dark material (albedo 0.2)
    shows darker than a bright one (0.95), over the same background (the preview's floor)."""
    scene = bpy.context.scene
    scene.render.engine = "SPECTRAL_VOLUME"
    rendered = []
    real_run = tracer_job.render_tracer

    def run(tracer_scene, *args, **options):
        rendered.append(tracer_scene)
        return real_run(tracer_scene, *args, **options)

    monkeypatch.setattr(tracer_job, "render_tracer", run)
    centres, corners = [], []
    for albedo in (0.2, 0.95):
        material = bpy.data.materials.new(f"Ink {albedo}")
        material.spectral.enabled = True
        material.spectral.density_scale = 20.0  # the preview sphere is 0.4 across: optical depth about 8
        material.spectral.albedo.value = albedo
        material.asset_generate_preview()  # renders at once in Blender-as-a-module
        preview = rendered[-1]
        size = preview.camera.width
        pixels = np.array(material.preview.image_pixels_float[:]).reshape(size, size, 4)
        centres.append(pixels[size // 2, size // 2, :3].mean())
        corners.append(pixels[2, 2, :3].mean())
    assert len(rendered) == 2
    assert preview.settings.spp == 32  # the preview scene's Viewport Samples (its defaults: not the user's)
    assert [medium.name for medium in preview.media] == ["preview_sphere"]
    assert [light.kind for light in preview.lights] == ["area", "area", "environment"]  # Blender's preview lights
    assert centres[0] < 0.7 * centres[1], centres
    assert [surface.name for surface in preview.surfaces] == ["Floor"]  # Blender's preview backdrop
    # The same backdrop behind both, which the brighter sphere lights a little more.
    assert corners[0] - 0.005 <= corners[1] <= corners[0] + 0.06, corners
    captured = capfd.readouterr()
    assert "not rendered" not in captured.out + captured.err  # previews report nothing
