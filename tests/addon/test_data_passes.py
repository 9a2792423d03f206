"""The View Layer's data passes (Z, Mist, Normal, Cryptomatte): registered exactly as the engine writes them,
rendered by F12 into the Render Result and the EXR (read back with OpenImageIO), passes the engine does not make
named in the render report's warning, and Depth, Mist and Normal against Cycles' own passes."""

import json

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from addon.export.passes import unmade_passes  # noqa: E402
from addon.export.scene import export_scene  # noqa: E402
from addon.tracer import image_io, passes  # noqa: E402
from addon.tracer.render import render  # noqa: E402
from tests.addon.builders import add_camera, add_sun, tiny_render  # noqa: E402
from tests.support.cycles import look_at  # noqa: E402


def surfaces_scene(width=24, height=16):
    """A camera 6 above a floor (object "Floor", material "Grey") with a box ("Box", material "Red") on it, a sun."""
    scene = bpy.context.scene
    tiny_render(scene, width, height, samples=8)
    scene.spectral.backend = "numpy"  # tiny frames: no kernel to compile
    camera = add_camera(location=(0.3, -2.0, 6.0))
    look_at(camera, (0.0, 0.0, 0.0))
    add_sun()
    bpy.ops.mesh.primitive_plane_add(size=30.0)
    floor = bpy.context.object
    floor.name = "Floor"
    floor.data.materials.append(bpy.data.materials.new("Grey"))
    bpy.ops.mesh.primitive_cube_add(size=1.5, location=(0.5, 0.3, 0.75), rotation=(0.0, 0.0, 0.4))
    box = bpy.context.object
    box.name = "Box"
    box.data.materials.append(bpy.data.materials.new("Red"))
    layer = scene.view_layers[0]
    layer.use_pass_z = layer.use_pass_mist = layer.use_pass_normal = True
    layer.use_pass_cryptomatte_object = layer.use_pass_cryptomatte_material = True
    layer.pass_cryptomatte_depth = 4
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    scene.world.mist_settings.start, scene.world.mist_settings.depth = 2.0, 10.0
    scene.world.mist_settings.falloff = "LINEAR"
    return scene, layer


def offered_passes(scene):
    tree = bpy.data.node_groups.new("Compositing", "CompositorNodeTree")
    scene.compositing_node_group = tree
    layers = tree.nodes.new("CompositorNodeRLayers")
    layers.scene = scene
    scene.view_layers[0].update_render_passes()
    return {socket.name for socket in layers.outputs if socket.enabled}


def test_the_render_layer_offers_exactly_the_passes_the_view_layer_asks_for(registered):
    scene, layer = surfaces_scene()
    scene.render.engine = "SPECTRAL_VOLUME"
    offered = offered_passes(scene)
    assert {"Image", "XYZ", "XYZ Variance", "Depth", "Mist", "Normal", "CryptoObject00", "CryptoObject01",
            "CryptoMaterial00", "CryptoMaterial01"} <= offered
    assert "CryptoObject02" not in offered
    layer.use_pass_mist = layer.use_pass_cryptomatte_material = False
    offered = offered_passes(scene)
    assert "Mist" not in offered and "CryptoMaterial00" not in offered and "Depth" in offered


def test_export_reads_the_view_layer_and_world_and_warns_of_unmade_passes(registered):
    scene, layer = surfaces_scene()
    layer.use_pass_diffuse_direct = layer.use_pass_ambient_occlusion = True
    layer.aovs.add().name = "mask"
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    settings = export.scene.settings
    assert settings.passes == ("Depth", "Mist", "Normal", "CryptoObject", "CryptoMaterial")
    assert (settings.mist_start, settings.mist_depth, settings.mist_falloff) == (2.0, 10.0, "linear")
    assert settings.cryptomatte_depth == 4
    assert {(surface.object, surface.material) for surface in export.scene.surfaces} == {("Floor", "Grey"),
                                                                                        ("Box", "Red")}
    assert unmade_passes(layer) == ["Diffuse Direct", "Ambient Occlusion", "AOV 'mask'"]
    warning = next(w for w in export.warnings if "not rendered by this engine" in w)
    assert "Diffuse Direct" in warning and "Ambient Occlusion" in warning and "AOV 'mask'" in warning


def _f12_exr(scene, path) -> dict:
    """F12 of `scene` by its render engine, written as a 32-bit multilayer EXR at `path`: its channels."""
    settings = scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format, settings.color_depth = "OPEN_EXR_MULTILAYER", "32"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return image_io.read_exr(scene.render.filepath)


def test_f12_fills_the_render_result_and_the_exr_has_the_passes_and_manifest(registered, tmp_path):
    scene, _ = surfaces_scene()
    scene.render.engine = "SPECTRAL_VOLUME"
    channels = _f12_exr(scene, tmp_path / "f12.exr")
    for name in ("ViewLayer.Depth.Z", "ViewLayer.Mist.Z", "ViewLayer.Normal.X", "ViewLayer.Normal.Z",
                 "ViewLayer.CryptoObject00.R", "ViewLayer.CryptoObject01.A", "ViewLayer.CryptoMaterial00.G"):
        assert name in channels, sorted(channels)
    depth = channels["ViewLayer.Depth.Z"]
    assert ((depth > 3.0) & (depth < 8.0)).all()  # every ray meets the floor or the box, 6 m away or nearer
    ids = set(np.unique(channels["ViewLayer.CryptoObject00.R"]))
    assert ids <= {passes.hash_float("Floor"), passes.hash_float("Box")} and len(ids) == 2
    np.testing.assert_allclose(channels["ViewLayer.CryptoObject00.G"] + channels["ViewLayer.CryptoObject00.A"]
                               + channels["ViewLayer.CryptoObject01.G"] + channels["ViewLayer.CryptoObject01.A"], 1.0,
                               rtol=1e-6)
    oiio = image_io._open_image_io()
    spec = oiio.ImageInput.open(scene.render.filepath).spec()
    manifests = {attribute.name: attribute.value for attribute in spec.extra_attribs
                 if attribute.name.startswith("cryptomatte/") and attribute.name.endswith("/manifest")}
    names = {name for value in manifests.values() for name in json.loads(value)}
    assert {"Floor", "Box", "Grey", "Red"} <= names


def test_depth_mist_and_normal_agree_with_cycles(registered, tmp_path):
    """The same scene through Cycles (its own Z, Mist and Normal passes, box filter) and through the export and
    tracer: region means of the 4×4-pixel blocks all on the floor agree within 0.05 m (Depth), 0.01 (Mist) and 0.02
    (Normal); blocks with an edge of the box differ by where each engine's samples fell."""
    scene, _ = surfaces_scene(32, 24)
    scene.render.engine = "CYCLES"
    scene.cycles.device, scene.cycles.samples, scene.cycles.use_denoising = "CPU", 16, False
    scene.cycles.pixel_filter_type, scene.cycles.filter_width = "BOX", 1.0
    cycles = _f12_exr(scene, tmp_path / "cycles.exr")
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    ours = render(export.scene, spp=16, backend="numpy").passes.images

    def blocks(image):
        return image.reshape(6, 4, 8, 4, -1).mean(axis=(1, 3))

    crypto = ours["CryptoObject00"]
    whole = blocks((crypto[..., 1:2] == 1.0) & (crypto[..., 0:1] == crypto[0, 0, 0]))[..., 0]
    inner = whole == 1.0  # blocks all floor (the top-left pixel's object): no edge of the box in them
    assert 10 < inner.sum() < inner.size
    for name, tolerance in (("Depth", 0.05), ("Mist", 0.01)):
        theirs = blocks(cycles[f"ViewLayer.{name}.Z"][..., None])[inner]
        np.testing.assert_allclose(blocks(ours[name])[inner], theirs, atol=tolerance, err_msg=name)
    theirs = np.stack([cycles[f"ViewLayer.Normal.{c}"] for c in "XYZ"], axis=-1)
    np.testing.assert_allclose(blocks(ours["Normal"])[inner], blocks(theirs)[inner], atol=0.02)


def test_the_passes_panel_offers_only_the_passes_the_engine_makes(registered):
    from types import SimpleNamespace

    from addon.export.passes import LIGHT_TOGGLES, TOGGLES
    from tests.addon.recording import draw

    scene, layer = surfaces_scene()
    scene.render.engine = "SPECTRAL_VOLUME"
    context = SimpleNamespace(scene=scene, engine=scene.render.engine, view_layer=layer, world=scene.world)
    layout = draw(bpy.types.SPECTRAL_PT_view_layer_passes, context)
    drawn = {args[1] for kind, args, _ in layout.calls if kind == "prop"}
    light = {toggle for _, toggle in LIGHT_TOGGLES.values()}
    assert drawn == {"use_pass_combined", "pass_cryptomatte_depth", *TOGGLES.values(), *light,
                     "spectral_exr", "spectral_exr_start", "spectral_exr_end", "spectral_exr_step"}
    mist = {args[1] for kind, args, _ in draw(bpy.types.SPECTRAL_PT_world_mist, context).calls if kind == "prop"}
    assert mist == {"start", "depth", "falloff"}
    # Blender's generic pass panels (which offer Emission, AO, AOVs, …) do not show under this engine
    for name in ("VIEWLAYER_PT_layer_passes", "VIEWLAYER_PT_eevee_layer_passes_light", "VIEWLAYER_PT_layer_passes_aov"):
        assert "SPECTRAL_VOLUME" not in getattr(bpy.types, name).COMPAT_ENGINES


@pytest.mark.parametrize("renderer", ["farm", "emulation"])
def test_a_farm_makes_every_pass_and_the_emulation_names_the_light_passes_it_leaves_out(registered, renderer):
    from addon.jobs.kinds import render_job

    scene, _ = surfaces_scene()
    scene.view_layers[0].use_pass_emit = True
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    data = ("Depth", "Mist", "Normal", "CryptoObject", "CryptoMaterial")  # made from the first hits
    if renderer == "farm":
        job = render_job(scene, export, scheduler="tcp://127.0.0.1:1")
        assert job.scene.settings.passes == (*data, "Emission")  # the farm's tasks sum the light passes too
        assert not any("light passes" in w for w in job.warnings)
        return
    scene.spectral.renderer = "CYCLES"
    job = render_job(scene, export)
    assert job._tracer_scene.settings.passes == data
    warning = next(w for w in job.warnings if "does not render light passes" in w)
    assert warning.endswith("yet: Emission left out of the render")


def test_the_emulation_makes_the_data_passes_as_the_tracer(registered):
    """The Cycles emulation's data passes are the tracer's: the same first hits, so the same images."""
    from addon.cycles_emulation.job import EmulationJob
    from addon.tracer.render import band_scenes, first_hit_passes

    surfaces_scene()
    export = export_scene(bpy.context.evaluated_depsgraph_get())
    job = EmulationJob.for_export(bpy.context.scene, export, spp=2)
    assert job.run() is job.result and not job.result.cancelled
    tracer = first_hit_passes(export.scene, band_scenes(export.scene)[0], 2, export.scene.settings.seed,
                              export.scene.settings.backend)
    assert set(job.result.passes.images) == set(tracer.images) and len(tracer.images) >= 5
    for name, image in tracer.images.items():
        np.testing.assert_array_equal(job.result.passes.images[name], image)
    assert job.result.passes.mattes == tracer.mattes


def test_render_to_image_and_the_cli_write_the_data_passes_as_f12(registered, tmp_path):
    """With a Render Region placed in the full frame (Crop off): F12's EXR, Render to Image's and the .blend
    command line's hold the same data passes, placed alike, with the same Cryptomatte manifests."""
    from tests.addon.test_render import _run_cli

    scene, _ = surfaces_scene()
    render = scene.render
    render.engine = "SPECTRAL_VOLUME"
    render.image_settings.media_type = "MULTI_LAYER_IMAGE"
    render.filepath = str(tmp_path / "f12.exr")
    render.use_border, render.use_crop_to_border = True, False
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = 0.25, 0.75, 0.1, 0.6
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    assert bpy.ops.spectral.render_image(image_name="Spectral", exr_path=str(tmp_path / "image.exr")) == {"FINISHED"}
    blend = tmp_path / "passes.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    done = _run_cli("render", blend, "--out", tmp_path / "cli.exr", "--quiet")
    assert done.returncode == 0, done.stderr
    f12 = image_io.read_exr(tmp_path / "f12.exr")
    names = [name for name in f12 if name.split(".")[1] in ("Depth", "Mist", "Normal", "CryptoObject00",
                                                             "CryptoMaterial01")]
    assert len(names) == 2 + 3 + 4 + 4
    inside = f12["ViewLayer.Depth.Z"] < 1e9
    assert inside.any() and not inside.all()  # the region, and the frame around it
    for written in ("image.exr", "cli.exr"):
        channels = image_io.read_exr(tmp_path / written)
        for name in names:
            np.testing.assert_allclose(channels[name], f12[name], rtol=1e-6, err_msg=f"{written} {name}")


def test_blenders_cryptomatte_node_finds_the_layers_of_an_exr_the_tracer_wrote(registered, tmp_path):
    """The Cryptomatte node (source Image) lists the EXR's Cryptomatte layers from its metadata: the names
    and manifests are where Blender looks for them."""
    from addon.tracer import builders

    from tests.support import scenes as s

    floor = builders.parallelogram((-20.0, -20.0, 0.0), (40.0, 0.0, 0.0), (0.0, 40.0, 0.0), name="Floor")
    scene = s.scene(s.ortho_camera(4, 3), lights=[s.environment()], surfaces=[floor], spp=2,
                    passes=("CryptoObject", "CryptoMaterial"))
    result = render(scene, backend="numpy")
    film = result.film
    path = image_io.write_exr(tmp_path / "tracer.exr", film.xyz, film.rgb(), data=result.passes)
    image = bpy.data.images.load(str(path))
    tree = bpy.data.node_groups.new("Compositing", "CompositorNodeTree")
    node = tree.nodes.new("CompositorNodeCryptomatteV2")
    node.source, node.image = "IMAGE", image
    node.layer_name = "ViewLayer.CryptoMaterial"  # an unknown layer would raise: the enum lists the file's
    with pytest.raises(TypeError, match="'ViewLayer.CryptoObject', 'ViewLayer.CryptoMaterial'"):
        node.layer_name = "ViewLayer.CryptoAsset"
