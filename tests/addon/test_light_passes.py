"""The View Layer's light passes (Emission, Environment, Volume Direct, Volume Indirect) and Light Paths ▸ Clamping on
the Blender side: the toggles exported and registered, offered in the engine's passes panel, F12 filling the Render
Result and the EXR (the passes summing to Combined), the Emission and Volume Direct passes against Cycles' own, and
the clamping settings with Cycles' defaults."""

from types import SimpleNamespace

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from addon.export.passes import unmade_passes  # noqa: E402
from addon.export.scene import export_scene  # noqa: E402
from addon.tracer.render import render  # noqa: E402
from tests.addon.recording import draw  # noqa: E402
from tests.addon.test_data_passes import _f12_exr, offered_passes  # noqa: E402
from tests.support.cycles import BLOCK, NOISE_BOUND, blocks  # noqa: E402

PASSES = ("Emission", "Environment", "Volume Direct", "Volume Indirect")


def volume_scene(width=32, height=24):
    """Blender's factory scene, small: its cube a grey Principled Volume that emits, lit by the factory point light
    and the grey World; every light pass on."""
    bpy.ops.wm.read_factory_settings(use_empty=False)
    scene = bpy.context.scene
    scene.render.engine = "SPECTRAL_VOLUME"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    scene.spectral.samples, scene.spectral.denoise, scene.spectral.use_adaptive_sampling = 64, False, False
    bpy.data.objects["Light"].data.shadow_soft_size = 0.0  # the tracer's point lights are points
    material = bpy.data.objects["Cube"].active_material
    tree = material.node_tree
    volume = tree.nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
    volume.inputs["Density"].default_value = 1.0
    volume.inputs["Emission Color"].default_value = (0.2, 0.9, 0.3, 1.0)
    volume.inputs["Emission Strength"].default_value = 0.5
    output = tree.get_output_node("ALL")
    tree.links.new(volume.outputs[0], output.inputs["Volume"])
    tree.links.remove(output.inputs["Surface"].links[0])
    layer = scene.view_layers[0]
    layer.use_pass_emit = layer.use_pass_environment = True
    layer.cycles.use_pass_volume_direct = layer.cycles.use_pass_volume_indirect = True
    return scene, layer


def test_the_view_layer_toggles_are_exported_registered_and_offered(registered):
    scene, layer = volume_scene()
    assert export_scene(bpy.context.evaluated_depsgraph_get()).scene.settings.passes == PASSES
    assert set(PASSES) <= offered_passes(scene)
    assert unmade_passes(layer) == []
    layer.use_pass_environment = layer.cycles.use_pass_volume_indirect = False
    offered = offered_passes(scene)
    assert "Environment" not in offered and "Volume Indirect" not in offered
    assert {"Emission", "Volume Direct"} <= offered
    context = SimpleNamespace(scene=scene, engine=scene.render.engine, view_layer=layer, world=scene.world)
    drawn = {args[1] for kind, args, _ in draw(bpy.types.SPECTRAL_PT_view_layer_passes, context).calls
             if kind == "prop"}
    assert {"use_pass_emit", "use_pass_environment", "use_pass_volume_direct", "use_pass_volume_indirect"} <= drawn


def test_f12_writes_light_passes_that_sum_to_combined(registered, tmp_path):
    """The Render Result and the multilayer EXR get ViewLayer.Emission/Environment/Volume Direct/Volume Indirect.R/G/B; in a scene without
    surfaces they sum to Combined (Denoise off) within float32 rounding, and each holds light."""
    scene, _ = volume_scene()
    scene.spectral.backend = "numpy"  # tiny frames: no kernel to compile
    scene.spectral.samples = 8
    channels = _f12_exr(scene, tmp_path / "f12.exr")
    for letter in "RGB":
        total = sum(channels[f"ViewLayer.{name}.{letter}"].astype(np.float64) for name in PASSES)
        combined = channels[f"ViewLayer.Combined.{letter}"]
        np.testing.assert_allclose(total, combined, rtol=1e-5, atol=1e-6 * np.abs(combined).max())
        for name in PASSES:
            assert channels[f"ViewLayer.{name}.{letter}"].mean() > 0.0, name


def _cycles_passes(scene, folder, seed):
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device, cycles.samples, cycles.seed, cycles.use_denoising = "CPU", 64, seed, False
    cycles.use_adaptive_sampling = False
    cycles.max_bounces = cycles.volume_bounces = cycles.transparent_max_bounces = 64
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.volume_biased, cycles.light_sampling_threshold, cycles.use_volume_guiding = False, 0.0, False
    cycles.pixel_filter_type, cycles.filter_width = "BOX", 1.0
    try:
        channels = _f12_exr(scene, folder / f"cycles_{seed}.exr")
    finally:
        scene.render.engine = "SPECTRAL_VOLUME"
    return {name: np.stack([channels[f"ViewLayer.{name}.{c}"] for c in "RGB"], axis=-1).astype(np.float64)
            for name in ("Emission", "Volume Direct")}


def test_emission_and_volume_direct_agree_with_cycles(registered, tmp_path):
    """The cube's Emission and Volume Direct passes, the tracer's (two seeds) against Cycles' (two seeds), both
    unclamped: every 8×8 block's mean within 4 standard deviations of the two estimates' noise (each estimated from
    its two renders) and 5 % of the block (the spectral-versus-RGB difference of the green emission)."""
    scene, _ = volume_scene()
    scene.spectral.clamp_indirect = 0.0
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    ours = [render(export.scene, spp=64, seed=seed).passes.images for seed in (1, 2)]
    theirs = [_cycles_passes(scene, tmp_path, seed) for seed in (1, 2)]
    for name in ("Emission", "Volume Direct"):
        traced, cycled = (ours[0][name] + ours[1][name]) / 2, (theirs[0][name] + theirs[1][name]) / 2
        noise = (blocks((ours[0][name] - ours[1][name]) ** 2 / 4) + blocks((theirs[0][name] - theirs[1][name]) ** 2 / 4))
        sigma = np.sqrt(noise / BLOCK**2 + (0.05 * blocks(traced)) ** 2)
        lit = blocks(cycled) > 0.01 * blocks(cycled).max()
        assert lit.sum() >= 3, name
        z = np.abs(blocks(traced) - blocks(cycled))[lit] / np.maximum(sigma[lit], 1e-6)
        print(name, blocks(traced).mean(axis=(0, 1)), blocks(cycled).mean(axis=(0, 1)), z.max())
        assert z.max() < NOISE_BOUND, name


def test_clamping_settings_have_cycles_defaults_and_are_exported(registered):
    """Direct 0 (off) and Indirect 10, as Cycles' Light Paths ▸ Clamping; exported to the scene's settings; offered in
    the engine's Clamping panel. The tracer's scene file defaults to no clamping."""
    from addon.tracer.scene import RenderSettings

    scene, _ = volume_scene()
    assert (scene.spectral.clamp_direct, scene.spectral.clamp_indirect) == (0.0, 10.0)
    assert (scene.cycles.sample_clamp_direct, scene.cycles.sample_clamp_indirect) == (0.0, 10.0)
    scene.spectral.clamp_direct = 2.5
    settings = export_scene(bpy.context.evaluated_depsgraph_get()).scene.settings
    assert (settings.clamp_direct, settings.clamp_indirect) == (2.5, 10.0)
    assert (RenderSettings().clamp_direct, RenderSettings().clamp_indirect) == (0.0, 0.0)
    context = SimpleNamespace(scene=scene, engine=scene.render.engine)
    drawn = {args[1] for kind, args, _ in draw(bpy.types.SPECTRAL_PT_render_clamping, context).calls if kind == "prop"}
    assert drawn == {"clamp_direct", "clamp_indirect", "use_firefly_filter", "firefly_threshold"}


def test_the_firefly_filter_is_on_at_2_in_blender_and_exported(registered):
    """Light Paths ▸ Clamping ▸ Firefly Filter: on at 2 in a new scene (F12's clean image at a few samples), exported
    as the scene's firefly_threshold, 0 when off; the tracer's scene file defaults to off."""
    from addon.tracer.scene import RenderSettings

    scene, _ = volume_scene()
    assert scene.spectral.use_firefly_filter and scene.spectral.firefly_threshold == 2.0
    assert export_scene(bpy.context.evaluated_depsgraph_get()).scene.settings.firefly_threshold == 2.0
    scene.spectral.use_firefly_filter = False
    assert export_scene(bpy.context.evaluated_depsgraph_get()).scene.settings.firefly_threshold == 0.0
    assert RenderSettings().firefly_threshold == 0.0


def test_the_cycles_emulation_names_the_clamping_it_leaves_out(registered):
    """The emulation renders Cycles unclamped (Cycles' clamp would treat each render's three bands as R, G, B) and
    without the engine's firefly filter: with either set, its warning says so; without, nothing."""
    from addon.jobs.kinds import render_job

    scene, _ = volume_scene()
    scene.spectral.renderer = "CYCLES"
    job = render_job(scene, export_scene(bpy.context.evaluated_depsgraph_get()))
    assert any("does not clamp" in w and "Indirect 10" in w for w in job.warnings), job.warnings
    assert any("does not filter fireflies" in w for w in job.warnings), job.warnings
    scene.spectral.clamp_indirect = 0.0
    scene.spectral.use_firefly_filter = False
    job = render_job(scene, export_scene(bpy.context.evaluated_depsgraph_get()))
    assert not any("does not clamp" in w or "fireflies" in w for w in job.warnings)
