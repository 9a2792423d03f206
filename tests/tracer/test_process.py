"""The command line as a process (issue 30, item 5): a render that has written its files exits 0 whatever
becomes of stdout and stderr (closed, full, a broken pipe); its messages are true (what was written is
said when a later step fails); a full disk is said to be full."""

import errno
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from addon.tracer import cli, image_io
from addon.tracer.errors import SpectralError

ROOT = Path(__file__).resolve().parents[2]


def _render_command(scene: Path, out: Path) -> str:
    return f"{sys.executable} -m addon.tracer render {scene} --out {out} --npy {out.with_suffix('.npy')} --spp 1"


@pytest.mark.parametrize("streams", ["2>&-", ">&- 2>&-", ">/dev/full", ">/dev/full 2>/dev/full", "broken pipe"])
def test_a_render_that_wrote_its_files_exits_0_whatever_its_streams(write_scene, tmp_path, streams):
    """On main a closed stderr crashed the render (the progress bar) and a full stdout ended as exit 70 saying
    "Nothing was written" after the image was written."""
    out = tmp_path / "image.exr"
    command = _render_command(write_scene(), out)
    if streams == "broken pipe":
        process = subprocess.Popen(["bash", "-c", f"exec {command}"], cwd=ROOT, stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE)
        process.stdout.close()  # nobody reads: the summary line meets a broken pipe
        stderr = process.stderr.read().decode()
        code = process.wait(timeout=600)
    else:
        done = subprocess.run(["bash", "-c", f"exec {command} {streams}"], cwd=ROOT, capture_output=True,
                              text=True, timeout=600)
        code, stderr = done.returncode, done.stderr
    assert code == 0, stderr
    assert "internal error" not in stderr and "Traceback" not in stderr and "Exception ignored" not in stderr
    assert image_io.read_exr(out)["ViewLayer.XYZ.Y"].shape == (6, 8)
    assert np.isfinite(np.load(out.with_suffix(".npy"))).all()


def test_a_failure_after_files_were_written_says_which_were_kept(capsys, tmp_path):
    def fails_after_writing():
        written.append(tmp_path / "frame_1.exr")
        raise RuntimeError("frame 2 broke")

    written = []
    assert cli.run_reporting(fails_after_writing, written) == cli.EXIT_CRASH
    err = capsys.readouterr().err
    assert "Nothing was written" not in err and f"Written before that, and kept: {tmp_path / 'frame_1.exr'}" in err
    assert cli.run_reporting(lambda: 1 / 0, []) == cli.EXIT_CRASH
    assert "Nothing was written." in capsys.readouterr().err


def test_say_and_the_progress_bar_survive_a_broken_stream():
    class Broken:
        def write(self, text):
            raise BrokenPipeError(errno.EPIPE, "Broken pipe")

        def fileno(self):
            raise OSError("no file")

    assert not cli.say("lost", Broken())
    bar = cli.ProgressBar(stream=Broken())
    bar.notice("Compiling the kernel")
    bar(None, 1.0)
    assert bar.stream is None


def test_a_full_disk_is_said_to_be_full(tmp_path):
    def full(name):
        raise OSError(errno.ENOSPC, "No space left on device")

    target = tmp_path / "stats.json"
    target.write_text("previous")
    with pytest.raises(SpectralError, match=f"cannot write {target}: the disk is full"):
        image_io.write_all([image_io.Output(target, full)])
    assert target.read_text() == "previous" and [p.name for p in tmp_path.iterdir()] == ["stats.json"]


def test_an_exr_write_that_fails_says_why(tmp_path, monkeypatch):
    """On main: "OpenImageIO ... gave no reason". The link stands for a full disk's file."""
    link = tmp_path / "full.exr"
    link.symlink_to("/dev/full")
    pixels = np.random.default_rng(0).random((64, 64, 3), dtype=np.float32)  # beyond what compression hides
    with pytest.raises(SpectralError, match="Failed OpenEXR write") as error:
        image_io._write_oiio(str(link), pixels, ["R", "G", "B"], "float")
    assert "gave no reason" not in str(error.value)
    monkeypatch.setattr(shutil, "disk_usage", lambda path: shutil._ntuple_diskusage(10**9, 10**9 - 100, 100))
    with pytest.raises(SpectralError, match=r"the disk is full \(100 bytes free, the image takes up to 48 KiB\)"):
        image_io._write_oiio(str(link), pixels, ["R", "G", "B"], "float")
