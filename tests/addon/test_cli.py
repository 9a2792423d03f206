"""The .blend command line (`python -m addon.cli render`): files that are not blend files and frames
Blender does not have are bad input (exit 1, a message, nothing written), not tracebacks or clamped frames;
frame lists, `#` output paths, resolution and percentage as Blender's `-b -f/-a`; and what the add-on
exports obeys the scene's rules before it is rendered."""

import subprocess
import sys
from pathlib import Path

import bpy
import pytest

from addon.cli.frame_options import check_frame_paths, frame_path, parse_frames
from addon.tracer.errors import SpectralError

ROOT = Path(__file__).resolve().parents[2]


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "addon.cli", "render", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)


@pytest.fixture
def blend(clean, tmp_path):
    path = tmp_path / "empty.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def _not_a_blend(path):
    path.write_bytes(b"this is not a blend file")


def _truncated(path):
    path.write_bytes(path.read_bytes()[:5000])


@pytest.mark.parametrize(("damage", "words"), [(_not_a_blend, "File format is not supported"),
                                               (_truncated, "cannot be opened")])
def test_a_file_that_is_not_a_whole_blend_is_bad_input(blend, tmp_path, damage, words):
    damage(blend)
    out = tmp_path / "out.exr"
    done = run_cli(blend, "--out", out, "--quiet")
    assert done.returncode == 1, done.stderr
    assert f"error: blend file {blend} cannot be opened" in done.stderr and words in done.stderr
    assert "Traceback" not in done.stderr and not out.exists()


@pytest.mark.parametrize("frame", [2_000_000, -1_048_575, 99_999_999_999])
def test_frames_outside_blenders_range_are_refused(blend, tmp_path, frame):
    """Blender clamps frame_set(2000000) to 1048574 (a wrong image, silently) and raises ValueError beyond
    2³¹; both are refused before the file is opened."""
    out = tmp_path / "out.exr"
    done = run_cli(blend, "--out", out, "--frame", frame, "--quiet")
    assert done.returncode == 1, done.stderr
    assert f"--frame: Blender's frames run from -1048574 to 1048574, found {frame}" in done.stderr
    assert "Traceback" not in done.stderr and not out.exists()


def test_an_unwritable_output_is_refused_before_rendering(blend, tmp_path):
    (tmp_path / "file").write_text("x")
    done = run_cli(blend, "--out", tmp_path / "file" / "out.exr", "--quiet")
    assert done.returncode == 1 and "is a file, not a folder" in done.stderr and "Traceback" not in done.stderr


def test_an_albedo_csv_above_one_is_refused_by_the_scene_rules(registered, tmp_path):
    """The add-on's CSV albedo was never checked (issue 14): the exported scene meets validation.validate when it is
    exported, and the problem names the Blender volume (issue 28), not `media[0]`."""
    from addon.export.scene import export_scene
    from tests.addon.builders import basic_scene

    _scene, cloud = basic_scene(tmp_path)
    table = tmp_path / "albedo.csv"
    table.write_text("250,0.5\n550,1.5\n830,0.5\n")
    albedo = cloud.material_slots[0].material.spectral.albedo
    albedo.source, albedo.filepath = "CSV", str(table)
    with pytest.raises(SpectralError,
                       match=r"^volume 'Cloud' albedo: albedo must be within \[0, 1\], found 1.5 at 550 nm"):
        export_scene(bpy.context.evaluated_depsgraph_get())


def test_frame_lists_read_as_blenders():
    limits = (-1048574, 1048574)
    assert parse_frames("1-3, 7,2,5-6", limits) == [1, 2, 3, 7, 5, 6]  # in the order given, each once
    assert parse_frames("-2--1", limits) == [-2, -1]
    assert len(parse_frames("1-250", limits)) == 250


def test_hashes_become_the_zero_padded_frame_number():
    assert frame_path(Path("out/frame_####.exr"), 7) == Path("out/frame_0007.exr")
    assert frame_path(Path("out/#/frame_##.exr"), 123) == Path("out/#/frame_123.exr")  # the last run only
    assert frame_path(Path("out/still.exr"), 7) == Path("out/still.exr")
    check_frame_paths({"--out": Path("still.exr")}, [7])  # one frame needs no '#'
    with pytest.raises(SpectralError, match=r"--png: 2 frames need a '#' in the file name .*e\.g\. a_####\.png"):
        check_frame_paths({"--out": Path("f_#.exr"), "--png": Path("a.png")}, [1, 2])


@pytest.mark.parametrize(("options", "words"), [
    (["--frames", "5-3"], "--frames: the range 5-3 runs backwards; write 3-5"),
    (["--frames", "1,x"], "--frames: 'x' is neither a frame nor a range FIRST-LAST (e.g. 1-250 or 1,3,5-7)"),
    (["--frames", "1-99999999999"], "--frames: Blender's frames run from -1048574 to 1048574, found 99999999999"),
    (["--frames", "1-3"], "--out: 3 frames need a '#' in the file name where the frame number goes"),
    (["--resolution", "1920"], "--resolution: write it as WIDTHxHEIGHT in pixels (e.g. 1920x1080), found '1920'"),
    (["--resolution", "2x1080"], "--resolution: each side must be from 4 to 65536 pixels, as in Blender, found 2x1080"),
    (["--percentage", "0"], "--percentage: must be from 1 to 32767, as in Blender, found 0"),
])
def test_bad_frames_and_sizes_are_refused_before_rendering(blend, tmp_path, options, words):
    done = run_cli(blend, "--out", tmp_path / "out.exr", *options, "--quiet")
    assert done.returncode == 1, done.stderr
    assert f"error: {words}" in done.stderr and "Traceback" not in done.stderr
    assert sorted(path.name for path in tmp_path.iterdir()) == ["empty.blend"]


def test_frame_and_frames_together_are_a_usage_error(blend, tmp_path):
    done = run_cli(blend, "--out", tmp_path / "out_#.exr", "--frame", 1, "--frames", "1-2")
    assert done.returncode == 2 and "not allowed with argument" in done.stderr


@pytest.mark.slow
def test_frames_render_at_the_size_asked_for_each_to_its_own_files(registered, tmp_path):
    from addon.tracer import image_io
    from tests.addon.builders import basic_scene

    scene, _cloud = basic_scene(tmp_path)
    scene.frame_current = 1
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    done = run_cli(blend, "--frames", "2,4-5", "--resolution", "40x20", "--percentage", 25, "--spp", 1,
                   "--out", tmp_path / "out" / "frame_###.exr", "--png", tmp_path / "out" / "preview_#.png", "--quiet")
    assert done.returncode == 0, done.stderr
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == [
        "frame_002.exr", "frame_004.exr", "frame_005.exr", "preview_2.png", "preview_4.png", "preview_5.png"]
    assert done.stdout.count("wrote ") == 3 and "(10×5, frame 4," in done.stdout
    assert image_io.read_exr(tmp_path / "out" / "frame_005.exr")["ViewLayer.XYZ.Y"].shape == (5, 10)


@pytest.mark.slow
def test_a_later_frame_that_fails_is_named_and_the_earlier_frames_kept(registered, tmp_path):
    from tests.addon.builders import basic_scene

    scene, _cloud = basic_scene(tmp_path)
    scene.spectral.lambda_max = 830.0
    for frame, shortest in ((1, 360.0), (2, 830.0)):  # at frame 2 the wavelength range is empty
        scene.spectral.lambda_min = shortest
        scene.spectral.keyframe_insert("lambda_min", frame=frame)
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    done = run_cli(blend, "--frames", "1-3", "--spp", 1, "--out", tmp_path / "out" / "f_#.exr", "--quiet")
    assert done.returncode == 1, done.stderr
    assert "error: frame 2: render settings: the wavelength range 830–830 nm is empty" in done.stderr
    assert "wrote" in done.stdout and sorted(path.name for path in (tmp_path / "out").iterdir()) == ["f_1.exr"]


def test_an_exr_and_a_png_naming_one_file_are_refused_before_opening(tmp_path, monkeypatch, capsys):
    """Issue 30: `--png` a link to `--out` would replace the EXR just written."""
    from addon.cli import command as cli

    out = tmp_path / "out_0001.exr"
    out.write_bytes(b"previous render")
    (tmp_path / "out_0001.png").symlink_to(out)
    monkeypatch.setattr(cli, "open_scene", lambda *args: pytest.fail("the file was opened: too late"))
    assert cli.main([str(tmp_path / "x.blend"), "--out", str(tmp_path / "out_####.exr"), "--png",
                     str(tmp_path / "out_####.png"), "--frame", "1", "--quiet"]) == 1
    assert "--out and --png name the same file" in capsys.readouterr().err
    assert out.read_bytes() == b"previous render"
