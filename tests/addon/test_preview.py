"""Material previews: Blender renders its preview scene with the engine (`ID.asset_generate_preview()`
does so headless), lit by the key light of `addon.preview` since the tracer has no area lights."""

import numpy as np
import pytest

from addon import dispatch
from addon.preview import preview_scene
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
    scene = bpy.context.scene
    scene.render.engine = "SPECTRAL_VOLUME"
    material = bpy.data.materials.new("Ink")
    material.spectral.enabled = True
    material.spectral.density_scale = 20.0  # the preview sphere is 0.4 across: optical depth about 8
    material.spectral.albedo.value = 0.2  # a dark, mostly absorbing sphere in front of the preview World
    rendered = []
    real_run = dispatch.run

    def run(tracer_scene, *args, **options):
        rendered.append(tracer_scene)
        return real_run(tracer_scene, *args, **options)

    monkeypatch.setattr(dispatch, "run", run)
    material.asset_generate_preview()  # renders at once in Blender-as-a-module
    [preview] = rendered
    assert preview.settings.spp == 32  # the preview scene's Viewport Samples (its defaults: not the user's)
    assert [medium.name for medium in preview.media] == ["preview_sphere"]
    assert [light.kind for light in preview.lights] == ["environment", "sun"]
    size = preview.camera.width
    pixels = np.array(material.preview.image_pixels_float[:]).reshape(size, size, 4)
    centre, corner = pixels[size // 2, size // 2, :3].mean(), pixels[2, 2, :3].mean()
    assert centre < 0.5 * corner, (centre, corner)
    captured = capfd.readouterr()
    assert "area lights are not supported" not in captured.out + captured.err  # previews report nothing
