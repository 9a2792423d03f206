"""The .blend command line (`python -m addon.cli render`): files that are not blend files and frames
Blender does not have are bad input (exit 1, a message, nothing written), not tracebacks or clamped frames;
and what the add-on exports obeys the scene's rules before it is rendered."""

import subprocess
import sys
from pathlib import Path

import bpy
import pytest

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
    """The add-on's CSV albedo was never checked (issue 14): the exported scene now meets Scene.validate
    before it is rendered or saved."""
    from addon.export.scene import export_scene
    from addon.tracer.compile import compile_scene
    from addon.tracer.errors import SpectralError
    from tests.addon.builders import basic_scene

    _scene, cloud = basic_scene(tmp_path)
    table = tmp_path / "albedo.csv"
    table.write_text("250,0.5\n550,1.5\n830,0.5\n")
    albedo = cloud.material_slots[0].material.spectral.albedo
    albedo.source, albedo.filepath = "CSV", str(table)
    exported = export_scene(bpy.context.evaluated_depsgraph_get()).scene
    with pytest.raises(SpectralError, match=r"media\[0\]\.albedo: albedo must be within \[0, 1\], found 1.5 at 550 nm"):
        compile_scene(exported)
