"""Grids on disk: .npy and .vdb orientation, transforms, the cell-centred convention, and bad files."""

import sys

import numpy as np
import pytest

from addon.tracer import grids
from addon.tracer.errors import SpectralError
from addon.tracer.grids import load_grid, save_grid_npy, save_grid_vdb
from addon.tracer.scene import Grid

# Non-uniform scale, a rotation about z by 90° and a translation: no axis can be confused with another.
ROTATE_SCALE = np.array(
    [
        [0.0, -0.5, 0.0, 1.0],
        [0.25, 0.0, 0.0, -2.0],
        [0.0, 0.0, 2.0, 3.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
)


def pattern(shape=(4, 3, 2)) -> np.ndarray:
    """Every cell different and non-zero, so the active box is the whole array."""
    return (np.arange(np.prod(shape), dtype=np.float32).reshape(shape) + 1.0) / 10.0


def translation(offset) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = offset
    return matrix


# ---------------------------------------------------------------------------------------------- .npy


def test_npy_round_trip_keeps_values_orientation_and_transform(tmp_path):
    grid = Grid(pattern(), ROTATE_SCALE, "smoke")
    path = save_grid_npy(tmp_path / "smoke.npy", grid)
    loaded = load_grid(path, "smoke", ROTATE_SCALE)
    assert loaded.values.dtype == np.float32 and loaded.values.shape == (4, 3, 2)
    np.testing.assert_array_equal(loaded.values, grid.values)
    assert loaded.values[3, 0, 1] == pattern()[3, 0, 1]
    np.testing.assert_array_equal(loaded.index_to_world, ROTATE_SCALE)
    assert loaded.name == "smoke"


def test_npy_name_defaults_to_stem_and_other_dtypes_become_float32(tmp_path):
    np.save(tmp_path / "ints.npy", np.arange(8, dtype=np.int64).reshape(2, 2, 2))
    loaded = load_grid(tmp_path / "ints.npy", index_to_world=np.eye(4))
    assert loaded.name == "ints" and loaded.values.dtype == np.float32
    assert loaded.values[1, 1, 1] == 7.0


def write_npy(tmp_path, array, name="bad.npy"):
    path = tmp_path / name
    np.save(path, array, allow_pickle=True)
    return path


@pytest.mark.parametrize(
    ("array", "words"),
    [
        (np.ones((3, 3), np.float32), ["3-D", "(3, 3)"]),
        (np.ones((2, 2, 2, 2), np.float32), ["3-D"]),
        (np.ones((0, 3, 3), np.float32), ["empty"]),
        (np.array([[[1.0, np.nan]]], np.float32), ["NaN or infinite", "(0, 0, 1)"]),
        (np.array([[[np.inf, 1.0]]]), ["NaN or infinite"]),
        (np.array([[[1e300]]]), ["NaN or infinite"]),
        (np.array([[[1.0, -0.5]]], np.float32), ["negative", "-0.5"]),
        (np.array([[[{"a": 1}]]], dtype=object), ["cannot be read"]),
        (np.array([[[True]]]), ["bool"]),
        (np.array([[[1 + 1j]]]), ["complex"]),
    ],
)
def test_bad_npy_arrays_are_named(tmp_path, array, words):
    path = write_npy(tmp_path, array)
    with pytest.raises(SpectralError) as error:
        load_grid(path, "dens", np.eye(4))
    message = str(error.value)
    assert "bad.npy" in message and "'dens'" in message
    for word in words:
        assert word in message


def test_microscopic_voxels_are_not_singular(tmp_path):
    path = save_grid_npy(tmp_path / "scan.npy", Grid(pattern(), np.eye(4)))
    tiny = np.diag([1e-7, 2e-7, 1e-7, 1.0])
    np.testing.assert_array_equal(load_grid(path, index_to_world=tiny).index_to_world, tiny)


def test_negative_values_allowed_when_asked(tmp_path):
    path = write_npy(tmp_path, np.array([[[1.0, -0.5]]], np.float32))
    assert load_grid(path, index_to_world=np.eye(4), nonnegative=False).values.min() == -0.5


def test_missing_corrupt_and_misnamed_files(tmp_path):
    with pytest.raises(SpectralError, match="does not exist"):
        load_grid(tmp_path / "nothing.npy", index_to_world=np.eye(4))
    (tmp_path / "garbage.npy").write_bytes(b"\x93NUMPY not really")
    with pytest.raises(SpectralError, match="garbage.npy.*cannot be read"):
        load_grid(tmp_path / "garbage.npy", index_to_world=np.eye(4))
    truncated = tmp_path / "truncated.npy"
    truncated.write_bytes(write_npy(tmp_path, pattern()).read_bytes()[:-7])
    with pytest.raises(SpectralError, match="truncated.npy.*cannot be read"):
        load_grid(truncated, index_to_world=np.eye(4))
    np.savez(tmp_path / "archive.npz", a=pattern())
    (tmp_path / "archive.npz").rename(tmp_path / "archive.npy")
    with pytest.raises(SpectralError, match="npz"):
        load_grid(tmp_path / "archive.npy", index_to_world=np.eye(4))
    (tmp_path / "grid.raw").write_bytes(b"")
    with pytest.raises(SpectralError, match="unknown grid format '.raw'"):
        load_grid(tmp_path / "grid.raw")


def test_an_npy_header_promising_more_than_the_file_holds_is_refused_before_reading(tmp_path):
    """A header claiming 100000³ float32 values (3.55 PiB) on a file of a few bytes: refused from the header,
    not by an allocation of 3.55 PiB."""
    path = tmp_path / "huge.npy"
    with open(path, "wb") as file:
        np.lib.format.write_array_header_1_0(file, {"descr": "<f4", "fortran_order": False,
                                                    "shape": (100000, 100000, 100000)})
        file.write(b"\0" * 64)
    with pytest.raises(SpectralError, match=r"huge.npy cannot be read: it is truncated .*100000×100000×100000 "
                                            r"values, 3.55 PiB; the file holds 64 bytes"):
        load_grid(path, index_to_world=np.eye(4))


def test_an_npy_grid_larger_than_memory_is_refused_with_its_size(tmp_path, monkeypatch):
    path = write_npy(tmp_path, np.ones((40, 30, 20), dtype=np.float64))
    monkeypatch.setattr(grids, "available_memory", lambda: 100_000)
    with pytest.raises(SpectralError, match=r"its 40×30×20 voxels need 281 KiB of memory, more than the 97.7 KiB"):
        load_grid(path, index_to_world=np.eye(4))


@pytest.mark.parametrize(
    ("matrix", "words"),
    [
        (None, ["needs an index_to_world"]),
        (np.eye(3), ["4 lists of 4", "(3, 3)"]),
        (ROTATE_SCALE.T, ["bottom row", "transposed"]),
        (np.diag([1.0, 0.0, 1.0, 1.0]), ["singular"]),
        ([[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], ["singular"]),
        ([[1, 0, 0, 0]] * 3 + [[0, 0, 0, "x"]], ["4 lists of 4"]),
        (np.where(np.eye(4) > 0, np.nan, 0.0), ["NaN"]),
    ],
)
def test_bad_npy_transforms(tmp_path, matrix, words):
    path = save_grid_npy(tmp_path / "g.npy", Grid(pattern(), np.eye(4)))
    with pytest.raises(SpectralError) as error:
        load_grid(path, index_to_world=matrix)
    for word in words:
        assert word in str(error.value)


# ---------------------------------------------------------------------------------------------- .vdb


def write_vdb_by_hand(openvdb, path, values, offset, matrix, name="density"):
    """A VDB built with openvdb directly (not with save_grid_vdb): values[0, 0, 0] at voxel `offset`."""
    grid = openvdb.FloatGrid()
    grid.name = name
    grid.copyFromArray(values, tuple(offset))
    grid.transform = openvdb.createLinearTransform(matrix.T.tolist())  # OpenVDB: row vectors
    openvdb.write(str(path), [grid])


def test_vdb_orientation_and_transform(openvdb, tmp_path):
    values, offset = pattern(), (5, -3, 2)
    path = tmp_path / "pattern.vdb"
    write_vdb_by_hand(openvdb, path, values, offset, ROTATE_SCALE)
    loaded = load_grid(path, "density")
    np.testing.assert_array_equal(loaded.values, values)
    np.testing.assert_allclose(loaded.index_to_world, ROTATE_SCALE @ translation(offset), atol=1e-12)
    # Cross-check every voxel against OpenVDB's own transform and accessor.
    vdb_grid = openvdb.read(str(path), "density")
    accessor = vdb_grid.getConstAccessor()
    for ijk in np.ndindex(values.shape):
        world = loaded.index_to_world @ [*ijk, 1.0]
        vdb_ijk = tuple(c + o for c, o in zip(ijk, offset))
        np.testing.assert_allclose(vdb_grid.transform.indexToWorld(tuple(map(float, vdb_ijk))), world[:3])
        voxel = vdb_grid.transform.worldToIndexCellCentered(tuple(world[:3]))
        assert voxel == vdb_ijk
        assert accessor.getValue(voxel) == loaded.values[ijk]


def test_vdb_voxels_are_centred_on_integer_index_coordinates(openvdb):
    """OpenVDB's convention, which ours copies: voxel i spans index coordinates (i - ½, i + ½)."""
    transform = openvdb.createLinearTransform(ROTATE_SCALE.T.tolist())
    for ijk in [(0, 0, 0), (3, -2, 7)]:
        for delta, expected in [(0.49, 0), (-0.49, 0), (0.51, 1), (-0.51, -1)]:
            point = ROTATE_SCALE @ [ijk[0] + delta, ijk[1], ijk[2], 1.0]
            assert transform.worldToIndexCellCentered(tuple(point[:3])) == (ijk[0] + expected, ijk[1], ijk[2])


def test_save_grid_vdb_round_trips(openvdb, tmp_path):
    density = Grid(pattern(), ROTATE_SCALE, "density")
    temperature = Grid(pattern((2, 2, 5)) * 3, np.diag([0.1, 0.2, 0.3, 1.0]), "temperature")
    path = save_grid_vdb(tmp_path / "both.vdb", density, temperature)
    for grid in (density, temperature):
        loaded = load_grid(path, grid.name)
        assert loaded.name == grid.name
        np.testing.assert_array_equal(loaded.values, grid.values)
        np.testing.assert_allclose(loaded.index_to_world, grid.index_to_world, atol=1e-12)


def test_vdb_zero_border_is_cropped_without_moving_the_cloud(openvdb, tmp_path):
    values = np.zeros((6, 5, 4), np.float32)
    values[2, 1, 3], values[4, 3, 1] = 1.0, 2.0
    path = save_grid_vdb(tmp_path / "sparse.vdb", Grid(values, ROTATE_SCALE))
    loaded = load_grid(path)
    assert loaded.values.shape == (3, 3, 3)  # the active box (2..4, 1..3, 1..3)
    for ijk in [(2, 1, 3), (4, 3, 1)]:
        inside = tuple(np.array(ijk) - [2, 1, 1])
        assert loaded.values[inside] == values[ijk]
        np.testing.assert_allclose(loaded.index_to_world @ [*inside, 1], ROTATE_SCALE @ [*ijk, 1], atol=1e-12)


def test_vdb_transform_override_replaces_the_files(openvdb, tmp_path):
    path = tmp_path / "offset.vdb"
    write_vdb_by_hand(openvdb, path, pattern(), (1, 2, 3), ROTATE_SCALE)
    override = np.diag([2.0, 2.0, 2.0, 1.0])
    loaded = load_grid(path, "density", override)
    np.testing.assert_allclose(loaded.index_to_world, override @ translation((1, 2, 3)))


def test_vdb_grid_choice(openvdb, tmp_path):
    density, flame = Grid(pattern(), np.eye(4), "density"), Grid(pattern(), np.eye(4), "flame")
    path = save_grid_vdb(tmp_path / "two.vdb", density, flame)
    with pytest.raises(SpectralError) as error:
        load_grid(path, "temperature")
    assert all(word in str(error.value) for word in ["two.vdb", "'temperature'", "'density'", "'flame'"])
    with pytest.raises(SpectralError, match="name the grid"):
        load_grid(path)
    single = save_grid_vdb(tmp_path / "one.vdb", Grid(pattern(), np.eye(4), "smoke"))
    assert load_grid(single).name == "smoke"


def test_bad_vdb_files(openvdb, tmp_path):
    (tmp_path / "garbage.vdb").write_bytes(b"not a vdb at all" * 8)
    with pytest.raises(SpectralError, match="garbage.vdb cannot be read as OpenVDB"):
        load_grid(tmp_path / "garbage.vdb")
    good = save_grid_vdb(tmp_path / "good.vdb", Grid(pattern(), np.eye(4)))
    truncated = tmp_path / "truncated.vdb"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(SpectralError, match="truncated.vdb"):
        load_grid(truncated, "density")
    with pytest.raises(SpectralError, match="does not exist"):
        load_grid(tmp_path / "missing.vdb")


def test_vdb_grid_kinds_and_contents(openvdb, tmp_path):
    velocity = openvdb.Vec3SGrid()
    velocity.name = "velocity"
    velocity.copyFromArray(np.ones((2, 2, 2, 3), np.float32))
    empty = openvdb.FloatGrid()
    empty.name = "empty"
    sphere = openvdb.createLevelSetSphere(1.0)
    sphere.name = "sphere"
    negative = openvdb.FloatGrid()
    negative.name = "negative"
    negative.copyFromArray(-pattern())
    holes = openvdb.FloatGrid()
    holes.name = "holes"
    holes.copyFromArray(pattern())
    holes.getAccessor().setValueOn((1, 2, 0), float("nan"))  # copyFromArray would leave NaN inactive
    path = tmp_path / "kinds.vdb"
    openvdb.write(str(path), [velocity, empty, sphere, negative, holes])
    cases = {
        "velocity": "Vec3SGrid, not a grid of floats",
        "empty": "is empty",
        "sphere": "level set",
        "negative": "negative values",
        "holes": "NaN or infinite",
    }
    for name, words in cases.items():
        with pytest.raises(SpectralError) as error:
            load_grid(path, name)
        assert f"grid {name!r} in {path}" in str(error.value) and words in str(error.value)


def test_vdb_frustum_transform_is_refused(openvdb, tmp_path):
    grid = openvdb.FloatGrid()
    grid.name = "density"
    grid.copyFromArray(pattern())
    grid.transform = openvdb.createFrustumTransform((0, 0, 0), (4, 3, 2), 0.5, 2.0)
    openvdb.write(str(tmp_path / "frustum.vdb"), [grid])
    with pytest.raises(SpectralError, match="non-linear"):
        load_grid(tmp_path / "frustum.vdb")


def test_missing_openvdb_is_explained(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "openvdb", None)  # makes `import openvdb` fail
    monkeypatch.setitem(sys.modules, "bpy", None)
    grids.openvdb_module.cache_clear()
    try:
        (tmp_path / "x.vdb").write_bytes(b"")
        with pytest.raises(SpectralError, match="needs the openvdb Python module.*use .npy grids"):
            load_grid(tmp_path / "x.vdb")
    finally:
        grids.openvdb_module.cache_clear()
