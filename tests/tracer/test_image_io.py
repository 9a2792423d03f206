"""Writing images: every output of one command is written, or none is, and failures name the file."""

import errno
import os
import stat

import numpy as np
import pytest

from addon.tracer import image_io
from addon.tracer.errors import SpectralError

XYZ = np.random.default_rng(1).random((4, 5, 3))


def test_outputs_are_written_together(tmp_path):
    written = image_io.write_all([image_io.exr(tmp_path / "a" / "image.exr", XYZ, XYZ, XYZ),
                                  image_io.png(tmp_path / "image.png", XYZ), image_io.npy(tmp_path / "xyz.npy", XYZ),
                                  image_io.text(tmp_path / "stats.json", "{}")])
    assert [path.name for path in written] == ["image.exr", "image.png", "xyz.npy", "stats.json"]
    np.testing.assert_allclose(image_io.read_exr(written[0])["ViewLayer.XYZ.Y"], XYZ[..., 1], rtol=1e-6)
    assert np.array_equal(np.load(written[2]), XYZ.astype(np.float32))
    assert sorted(path.name for path in tmp_path.iterdir()) == ["a", "image.png", "stats.json", "xyz.npy"]


def test_a_failing_output_leaves_every_file_as_it_was(tmp_path):
    """The EXR is written first and succeeds; the next output fails (a full disk): the existing EXR keeps
    its old contents, no temporary file stays, and the folder made for the failed output is removed."""
    keep = tmp_path / "keep.exr"
    keep.write_bytes(b"previous render")

    def full_disk(_name):
        raise OSError(errno.ENOSPC, "No space left on device")

    failing = image_io.Output(tmp_path / "new" / "deeper" / "stats.json", full_disk)
    with pytest.raises(SpectralError, match=r"cannot write .*new/deeper/stats.json: the disk is full \(no space left on the device\)"):
        image_io.write_all([image_io.exr(keep, XYZ, XYZ), failing])
    assert keep.read_bytes() == b"previous render"
    assert sorted(path.name for path in tmp_path.iterdir()) == ["keep.exr"]


@pytest.mark.parametrize(("name", "words"), [
    ("image.png", "image.png: the file is written as EXR, so its name must end in .exr"),
    ("folder", "folder: the file is written as EXR"),
])
def test_an_exr_needs_its_suffix(tmp_path, name, words):
    with pytest.raises(SpectralError, match=words):
        image_io.write_exr(tmp_path / name, XYZ, XYZ)
    assert list(tmp_path.iterdir()) == []


def test_destinations_are_checked_without_leaving_anything(tmp_path):
    (tmp_path / "file").write_text("x")
    (tmp_path / "dir.exr").mkdir()
    assert image_io.check_destination(tmp_path / "new" / "folders" / "x.exr", ".exr").name == "x.exr"
    for path, words in [(tmp_path / "file" / "x.exr", "is a file, not a folder"),
                        (tmp_path / "dir.exr", "it is a folder"), ("/proc/x.exr", "cannot write /proc/x.exr")]:
        with pytest.raises(SpectralError, match=words):
            image_io.check_destination(path, ".exr")
    assert sorted(path.name for path in tmp_path.iterdir()) == ["dir.exr", "file"]


def test_written_files_get_the_mode_of_a_new_file(tmp_path):
    """Not mkstemp's private 0600: 0666 less the umask, as Blender writes its own images."""
    umask = os.umask(0o022)
    os.umask(umask)
    written = image_io.write_all([image_io.npy(tmp_path / "xyz.npy", np.zeros((2, 2, 3)))])
    assert stat.S_IMODE(written[0].stat().st_mode) == 0o666 & ~umask


def test_a_png_with_alpha_stores_straight_colour_and_its_alpha(tmp_path):
    """A render's colour is premultiplied; PNG's alpha is straight, so the colour is divided by alpha first."""
    alpha = np.array([[1.0, 0.5, 0.0, 1.5]])
    premultiplied = np.full((1, 4, 3), 0.25) * alpha[..., None]
    path = image_io.write_png(tmp_path / "image.png", premultiplied, alpha=alpha)
    oiio = image_io._open_image_io()
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)  # the file's values, not multiplied by alpha on reading
    image = oiio.ImageInput.open(str(path), config)
    pixels = image.read_image(0, 0, 0, 4, "uint8")
    image.close()
    assert pixels.shape == (1, 4, 4)
    assert pixels[0, :, 3].tolist() == [255, 128, 0, 255]  # clipped to [0, 1]
    shown = image_io.srgb_display(np.full((1, 1, 3), 0.25))[0, 0]
    assert pixels[0, 0, :3].tolist() == pixels[0, 1, :3].tolist() == shown.tolist()
    assert pixels[0, 2, :3].tolist() == [0, 0, 0]
