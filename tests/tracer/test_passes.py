"""The data passes (`passes`): Depth, Mist and Normal against closed forms, the background's values,
Cryptomatte's hash, ranking, coverage and manifest, the scene file's and CLI's passes, and the EXR holding them
under Blender's names (read back with OpenImageIO)."""

import json

import numpy as np
import pytest

from addon.tracer import cli, image_io, passes, scene_io
from addon.tracer.errors import SpectralError
from addon.tracer.lowering import compile_scene
from tests.support import scenes as s
from addon.tracer.validation import validate

ALL = passes.DATA_PASSES


def _scene(camera, surfaces, **settings):
    settings = {"spp": 16, "passes": ALL, **settings}
    return s.scene(camera, lights=[s.environment()], surfaces=surfaces, **settings)


def _passes(scene, backend="numba"):
    return passes.render_passes(scene, compile_scene(scene), scene.settings.spp, scene.settings.seed, backend)


def _floor(size=40.0, name="floor", **fields):
    surface = s.parallelogram((-size / 2, -size / 2, 0.0), (size, 0.0, 0.0), (0.0, size, 0.0), 2, name=name)
    return surface if not fields else type(surface)(**{**surface.__dict__, **fields})


def test_depth_is_the_plane_distance_along_the_view_axis_and_1e10_on_the_background():
    """A camera 6 above a floor, looking down: Depth 6 in every pixel (the z-depth of a plane facing the camera
    does not depend on the pixel), 1e10 where the floor ends."""
    images = _passes(_scene(s.perspective_camera(10, 8, 60.0), [_floor(size=4.0)])).images
    depth = images["Depth"][..., 0]
    assert depth.shape == (8, 10)
    on_floor = depth < 1e9
    assert on_floor[3:5, 4:6].all() and not on_floor[0, 0]  # the centre sees the floor, the corner the sky
    np.testing.assert_allclose(depth[on_floor], 6.0, rtol=1e-12)
    assert (depth[~on_floor] == passes.NO_HIT_DEPTH).all()


@pytest.mark.parametrize("falloff, expected", [("quadratic", 0.25), ("linear", 0.5),
                                               ("inverse_quadratic", np.sqrt(0.5))])
def test_mist_falloffs(falloff, expected):
    """An orthographic camera 6 above a floor: distance 6 everywhere, (6 − start) / depth = 0.5 with start 2 and
    depth 8, and Mist = 0.5², 0.5 or √0.5 by the falloff."""
    scene = _scene(s.ortho_camera(6, 4, scale=3.0), [_floor()], mist_start=2.0, mist_depth=8.0, mist_falloff=falloff)
    np.testing.assert_allclose(_passes(scene).images["Mist"], expected, rtol=1e-12)


def test_mist_is_0_before_its_start_and_1_beyond_its_end_and_on_the_background():
    near = _scene(s.ortho_camera(4, 4, scale=3.0), [_floor()], mist_start=7.0)
    far = _scene(s.ortho_camera(4, 4, scale=3.0), [_floor()], mist_start=0.0, mist_depth=5.0)
    empty = _scene(s.ortho_camera(4, 4, scale=3.0), [_floor(size=0.1, name="speck")])
    assert (_passes(near).images["Mist"] == 0.0).all() and (_passes(far).images["Mist"] == 1.0).all()
    images = _passes(empty).images
    corner = (0, 0)
    assert images["Mist"][corner] == 1.0 and (images["Normal"][corner] == 0.0).all()
    assert (images["CryptoObject00"][corner] == 0.0).all()


def test_normal_of_a_tilted_plane_and_its_average_on_an_edge():
    """A floor tilted 30° about x, seen from above: Normal (0, −sin 30°, cos 30°) where a pixel is all floor, a
    fraction of it (the background counts 0) where the floor's edge crosses the pixel."""
    angle = np.radians(30.0)
    v = np.array([0.0, np.cos(angle), np.sin(angle)]) * 2.0
    tilted = s.parallelogram(-np.array([20.0, 0.0, 0.0]) - v / 2, (40.0, 0.0, 0.0), v, 1, name="tilted")
    images = _passes(_scene(s.ortho_camera(8, 8, scale=4.0), [tilted])).images
    normal = images["Normal"]
    full = np.isclose(images["CryptoObject00"][..., 1], 1.0)
    assert full.any() and (~full).any()
    np.testing.assert_allclose(normal[full], np.broadcast_to([0.0, -np.sin(angle), np.cos(angle)], (full.sum(), 3)),
                               atol=1e-12)
    coverage = images["CryptoObject00"][..., 1]
    np.testing.assert_allclose(normal[~full], coverage[~full, None] * [0.0, -np.sin(angle), np.cos(angle)], atol=1e-12)


def test_murmurhash3_reference_values():
    """MurmurHash3_x86_32 with seed 0, as Cryptomatte uses: the hash's published test values."""
    assert passes.murmurhash3_32("") == 0
    assert passes.murmurhash3_32("hello") == 0x248BFA47
    assert passes.murmurhash3_32("The quick brown fox jumps over the lazy dog") == 0x2E4FF723


def test_hash_float_keeps_ordinary_exponents_and_fixes_the_others():
    for name in ("hello", "Cube", "Suzanne.001", "ω"):
        value = passes.hash_float(name)
        assert np.isfinite(value) and value != 0.0 and abs(value) >= np.finfo(np.float32).tiny
        bits = int(np.array([value], np.float32).view(np.uint32)[0])
        assert bits ^ passes.murmurhash3_32(name) in (0, 1 << 23)
    # "hello" = 0x248bfa47: its exponent 0x49 is ordinary, so its float is its bits unchanged
    assert np.array([passes.hash_float("hello")], np.float32).view(np.uint32)[0] == 0x248BFA47


def test_cryptomatte_coverage_edge_split_and_manifest():
    """Two objects abutting at x = 0 seen from above by a 5-pixel-wide orthographic camera: the middle column
    straddles the line, so its coverage splits between them; every pixel's coverage sums to 1; the manifest
    names both objects and both materials, with their hashes."""
    left = s.parallelogram((-20.0, -20.0, 0.0), (20.0, 0.0, 0.0), (0.0, 40.0, 0.0), 1, name="Left")
    right = s.parallelogram((0.0, -20.0, 0.0), (20.0, 0.0, 0.0), (0.0, 40.0, 0.0), 1, name="Right ▸ Red")
    right = type(right)(**{**right.__dict__, "object": "Right", "material": "Red"})
    result = _passes(_scene(s.ortho_camera(5, 3, scale=5.0), [left, right], spp=32, cryptomatte_depth=4))
    crypto = np.concatenate([result.images["CryptoObject00"], result.images["CryptoObject01"]], axis=2)
    ids, coverage = crypto[..., 0::2], crypto[..., 1::2]
    np.testing.assert_allclose(coverage.sum(axis=2), 1.0, rtol=1e-12)
    assert (np.diff(coverage, axis=2) <= 0).all()  # ranked by coverage
    middle = coverage[:, 2]
    assert ((middle[:, 0] > 0.2) & (middle[:, 1] > 0.2)).all()  # both objects in the middle column
    assert set(ids[:, 2, :2].ravel()) == {passes.hash_float("Left"), passes.hash_float("Right")}
    assert (ids[:, 0, 0] == passes.hash_float("Left")).all() and (ids[:, 4, 0] == passes.hash_float("Right")).all()
    assert result.mattes == {"CryptoObject": ["Left", "Right"], "CryptoMaterial": ["Left", "Red"]}
    metadata = result.metadata("ViewLayer")
    key = f"cryptomatte/{passes.murmurhash3_32('ViewLayer.CryptoObject'):08x}"[:19]
    assert metadata[f"{key}/name"] == "ViewLayer.CryptoObject"
    assert metadata[f"{key}/hash"] == "MurmurHash3_32" and metadata[f"{key}/conversion"] == "uint32_to_float32"
    assert json.loads(metadata[f"{key}/manifest"]) == {name: f"{passes.murmurhash3_32(name):08x}"
                                                       for name in ("Left", "Right")}


def test_numpy_backend_gives_the_same_passes():
    scene = _scene(s.perspective_camera(6, 5, 50.0), [_floor(size=5.0)], spp=4)
    fast, slow = _passes(scene), _passes(scene, "numpy")
    assert fast.images.keys() == slow.images.keys()
    for name in fast.images:
        np.testing.assert_allclose(fast.images[name], slow.images[name], rtol=1e-12, atol=1e-12)


def test_settings_checks_name_the_field():
    scene = _scene(s.ortho_camera(4, 4), [_floor()])
    for change, field in ((dict(passes=("Depth", "AO")), "render.passes[1]"), (dict(mist_depth=0.0), "render.mist_depth"),
                          (dict(mist_falloff="cubic"), "render.mist_falloff"),
                          (dict(cryptomatte_depth=17), "render.cryptomatte_depth")):
        with pytest.raises(SpectralError, match=field.replace("[", r"\[").replace("]", r"\]")):
            validate(_scene(s.ortho_camera(4, 4), [_floor()], **change))
    assert validate(scene) is scene


def test_scene_file_keeps_the_passes_and_old_scenes_ask_for_none(tmp_path, scene_data, write_scene):
    old = scene_io.load_scene(write_scene(scene_data))
    assert old.settings.passes == ()
    scene_data["render"]["passes"] = ["Depth", "CryptoMaterial"]
    scene_data["render"]["mist_falloff"] = "linear"
    loaded = scene_io.load_scene(write_scene(scene_data))
    assert loaded.settings.passes == ("Depth", "CryptoMaterial") and loaded.settings.mist_falloff == "linear"
    again = scene_io.load_scene(scene_io.save_scene(loaded, tmp_path / "again"))
    assert again.settings.passes == ("Depth", "CryptoMaterial")


def test_cli_writes_the_passes_with_blenders_names_and_cryptomatte_metadata(tmp_path):
    """`--passes` on the command line: the EXR holds ViewLayer.Depth.Z, ViewLayer.Mist.Z, ViewLayer.Normal.X/Y/Z
    and ViewLayer.CryptoObject00.R/G/B/A … beside Combined, with Cryptomatte's header entries."""
    folder = scene_io.save_scene(_scene(s.ortho_camera(4, 3, scale=3.0), [_floor(name="Floor")], spp=2, passes=()),
                                 tmp_path / "scene")
    out = tmp_path / "out.exr"
    code = cli.main(["render", str(folder), "--out", str(out), "--backend", "numpy", "--quiet", "--passes",
                     "Depth,Mist,Normal,CryptoObject"])
    assert code == 0
    channels = image_io.read_exr(out)
    expected = (["ViewLayer.Depth.Z", "ViewLayer.Mist.Z"] + [f"ViewLayer.Normal.{c}" for c in "XYZ"]
                + [f"ViewLayer.CryptoObject0{i}.{c}" for i in range(3) for c in "RGBA"])
    assert set(expected) <= set(channels)
    np.testing.assert_allclose(channels["ViewLayer.Depth.Z"], 6.0, rtol=1e-6)
    assert (channels["ViewLayer.CryptoObject00.R"] == passes.hash_float("Floor")).all()
    oiio = image_io._open_image_io()
    spec = oiio.ImageInput.open(str(out)).spec()
    key = f"cryptomatte/{passes.murmurhash3_32('ViewLayer.CryptoObject'):08x}"[:19]
    assert spec.getattribute(f"{key}/name") == "ViewLayer.CryptoObject"
    assert json.loads(spec.getattribute(f"{key}/manifest")) == {"Floor": f"{passes.murmurhash3_32('Floor'):08x}"}


def test_cli_names_an_unknown_pass(tmp_path):
    folder = scene_io.save_scene(_scene(s.ortho_camera(4, 3), [_floor()], passes=()), tmp_path / "scene")
    with pytest.raises(SpectralError, match="--passes: render.passes\\[0\\]: unknown pass 'Shadow'"):
        cli.with_passes(scene_io.load_scene(folder), "Shadow")


def test_chunks_of_rows_and_samples_give_the_same_passes(monkeypatch):
    """With a tiny memory budget the passes are made a row and a few samples at a time: the same images (Depth
    from sample 0 of the first chunk, sums and counts over all chunks)."""
    left = s.parallelogram((-20.0, -20.0, 0.0), (20.0, 0.0, 0.0), (0.0, 40.0, 0.0), 1, name="Left")
    right = s.parallelogram((0.0, -20.0, 0.0), (20.0, 0.0, 0.0), (0.0, 40.0, 0.0), 1, name="Right")
    scene = _scene(s.perspective_camera(7, 5, 60.0), [left, right, _floor(size=3.0, name="Mid")], spp=12)
    whole = _passes(scene)
    monkeypatch.setattr(passes, "FIRST_HIT_BYTES", 7 * 8 * 5 * 5)  # one row of 5 samples per chunk
    chunked = _passes(scene)
    assert whole.images.keys() == chunked.images.keys()
    for name in whole.images:
        np.testing.assert_allclose(chunked.images[name], whole.images[name], rtol=1e-12, atol=1e-12, err_msg=name)


def test_first_hit_kernel_is_ready_before_the_passes_are_made():
    scene = _scene(s.ortho_camera(4, 4), [_floor()])
    assert passes.first_hit_ready(compile_scene(scene)) is True
