"""Hostile input files (issue 30, item 4): scene, spectrum, grid and image files are read only when they are
regular files within a stated size (a FIFO would hang the reader, /dev/zero never ends), one-row tables are
refused (a table is 0 outside the range its rows span), and a VDB whose grid names are ambiguous is a clear
error listing its grids."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from addon.tracer import files, grids, scene_io, spectra
from addon.tracer.errors import SpectralError

ROOT = Path(__file__).resolve().parents[2]


def validate(scene: Path):
    return subprocess.run([sys.executable, "-m", "addon.tracer", "validate", str(scene)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("target", ["fifo", "/dev/zero", "folder"])
def test_a_spectrum_file_that_is_not_a_regular_file_is_refused(write_scene, scene_data, tmp_path, target):
    """On main a FIFO hung `validate` for ever and /dev/zero was read until the memory ran out."""
    path = {"fifo": lambda: _fifo(tmp_path / "pipe.csv"), "/dev/zero": lambda: Path("/dev/zero"),
            "folder": lambda: (tmp_path / "dir.csv").mkdir() or tmp_path / "dir.csv"}[target]()
    scene_data["lights"][0]["spectrum"] = {"type": "csv", "path": str(path)}
    done = validate(write_scene(scene_data))
    assert done.returncode == 1, done.stderr
    kind = {"fifo": "a named pipe (FIFO)", "/dev/zero": "a character device", "folder": "a folder"}[target]
    assert f"spectrum file {path} is {kind}, not a regular file" in done.stderr
    assert "lights[0].spectrum" in done.stderr and "Traceback" not in done.stderr


def test_a_scene_file_grid_and_image_that_are_devices_are_refused(write_scene, scene_data, tmp_path):
    (tmp_path / "zero.npy").symlink_to("/dev/zero")
    with pytest.raises(SpectralError, match="grid file .*zero.npy is a character device"):
        grids.load_grid(tmp_path / "zero.npy", index_to_world=np.eye(4))
    with pytest.raises(SpectralError, match="scene file .*pipe.json is a named pipe"):
        scene_io.load_scene(_fifo(tmp_path / "pipe.json"))
    scene_data["lights"] = [{"kind": "envmap", "image": str(tmp_path / "zero.npy"),
                             "basis": [1, 1, 1]}]
    with pytest.raises(SpectralError, match=r"lights\[0\].image: image file .*zero.npy is a character device"):
        scene_io.load_scene(write_scene(scene_data))


def test_size_limits_are_stated(tmp_path, monkeypatch):
    path = tmp_path / "big.csv"
    path.write_text("400, 1\n700, 1\n")
    monkeypatch.setattr(spectra, "SPECTRUM_LIMIT", 8)
    with pytest.raises(SpectralError, match=f"spectrum file {path} is 14 bytes, more than the 8 bytes the tracer "
                                            "reads from a spectrum file"):
        spectra.from_csv(path)
    assert files.byte_size(files.GRID_LIMIT) == "64 GiB"


def test_one_row_tables_are_refused_not_made_constant(tmp_path):
    """Docs: a table is 0 outside its tabulated range; on main one row became that value at every wavelength."""
    with pytest.raises(SpectralError, match="a table needs at least 2 rows"):
        spectra.from_spec({"type": "table", "wavelengths": [500], "values": [1]})
    path = tmp_path / "one.csv"
    path.write_text("wavelength, value\n500, 1\n")
    with pytest.raises(SpectralError, match="at least 2 rows .* found 1"):
        spectra.from_csv(path)
    two = spectra.from_spec({"type": "table", "wavelengths": [500, 501], "values": [1, 1]})
    assert two(499) == 0 and two(500.5) == 1 and two(502) == 0


def _two_grids_named(openvdb, path: Path, names: tuple[str, str]) -> Path:
    out = []
    for name in names:
        grid = openvdb.FloatGrid()
        grid.name = name
        grid.copyFromArray(np.ones((2, 2, 2), dtype=np.float32))
        out.append(grid)
    openvdb.write(str(path), out)
    return path


def test_a_vdb_with_two_grids_of_one_name_is_a_clear_error(openvdb, tmp_path):
    path = _two_grids_named(openvdb, tmp_path / "twice.vdb", ("density", "density"))
    for asked in (None, "density"):
        with pytest.raises(SpectralError) as error:
            grids.load_grid(path, asked)
        assert (f"grid file {path} holds 2 grids named 'density', so the name does not say which to read; it holds "
                "grids 'density' (FloatGrid), 'density' (FloatGrid)") in str(error.value)
    other = _two_grids_named(openvdb, tmp_path / "other.vdb", ("density", "heat"))
    assert grids.load_grid(other, "heat").name == "heat"
    with pytest.raises(SpectralError, match="holds grids 'density' .*, 'heat' .*: name the grid"):
        grids.load_grid(other)


def test_a_vdb_with_two_grids_of_one_name_exits_1_from_the_command_line(openvdb, write_scene, scene_data, tmp_path):
    folder = tmp_path / "vdb_scene"
    folder.mkdir()
    _two_grids_named(openvdb, folder / "twice.vdb", ("density", "density"))
    scene_data["media"][0]["density"] = {"file": "twice.vdb", "grid": "density"}
    done = validate(write_scene(scene_data, folder=folder))
    assert done.returncode == 1 and "holds 2 grids named 'density'" in done.stderr, done.stderr
