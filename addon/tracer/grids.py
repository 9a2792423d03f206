"""Voxel grids on disk: reading and writing dense `.npy` arrays and OpenVDB `.vdb` files as `scene.Grid`.

Index convention (ours and OpenVDB's alike): the voxel with index (i, j, k) is centred at index-space
point (i, j, k), and `index_to_world` maps index space to world space. A `.vdb` grid becomes a dense
copy of its active voxel bounding box: our array index (0, 0, 0) is the VDB voxel at the box's minimum
corner, and `index_to_world` is the VDB's transform with that offset folded in. Values outside the
box (the VDB background) are dropped.

Also the one place that asks `bpy` for Blender's bundled `openvdb` module when no other is importable.
"""

import functools
import os
from pathlib import Path

import numpy as np

from .checks import affine_matrix, byte_size, grid_values
from .errors import SpectralError
from .files import GRID_LIMIT, regular_file
from .scene import Grid

_FLOAT_GRID_TYPES = ("FloatGrid", "DoubleGrid")
# What openvdb raises for unreadable files: OSError (missing, not a VDB), LookupError (truncated or
# unknown grid type), RuntimeError and ValueError (other corruption).
_VDB_READ_ERRORS = (OSError, LookupError, RuntimeError, ValueError)


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation now, or None when the platform cannot tell."""
    try:
        import psutil
    except ImportError:
        try:
            return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (AttributeError, ValueError, OSError):
            return None
    return int(psutil.virtual_memory().available)


def load_grid(path, grid_name: str | None = None, index_to_world=None, *, nonnegative: bool = True) -> Grid:
    """Read a grid from `.npy` or `.vdb`, checked: 3-D, not empty, finite and (unless `nonnegative` is
    False, as for temperatures that an offset makes positive) without negative values.

    `.npy`: a 3-D array indexed [x, y, z]; `index_to_world` is required and `grid_name` only names it
    (default: the file's stem). `.vdb`: `grid_name` selects the grid (default: the file's only grid);
    `index_to_world`, when given, replaces the VDB's own transform (it maps VDB index space to world).
    """
    path = regular_file(path, "grid file", GRID_LIMIT)
    suffix = path.suffix.lower()
    if suffix == ".npy":
        if index_to_world is None:
            raise SpectralError(f"grid file {path}: a .npy grid needs an index_to_world matrix")
        name = grid_name or path.stem
        values = _read_npy(path, name)
        matrix = affine_matrix(index_to_world, f"grid {name!r} in {path}: index_to_world")
    elif suffix == ".vdb":
        values, matrix, name = _read_vdb(path, grid_name, index_to_world)
    else:
        raise SpectralError(f"grid file {path}: unknown grid format {path.suffix!r} (use .npy or .vdb)")
    grid_values(values, f"grid {name!r} in {path}", nonnegative)
    return Grid(values=values, index_to_world=matrix, name=name)


def save_grid_npy(path, grid: Grid) -> Path:
    """Write `grid.values` as a float32 `.npy` array (its transform belongs in scene.json)."""
    path = Path(path)
    np.save(path, np.ascontiguousarray(grid.values, dtype=np.float32), allow_pickle=False)
    return path


def save_grid_vdb(path, *grids: Grid) -> Path:
    """Write grids into one `.vdb` file: FloatGrid fog volumes named `grid.name`, array index (i, j, k)
    at VDB voxel (i, j, k), with a linear transform equal to `grid.index_to_world`. Zero voxels are
    inactive."""
    vdb = openvdb_module()
    out = []
    for grid in grids:
        vdb_grid = vdb.FloatGrid()
        vdb_grid.name = grid.name
        vdb_grid.gridClass = vdb.GridClass.FOG_VOLUME
        vdb_grid.copyFromArray(np.ascontiguousarray(grid.values, dtype=np.float32))
        # OpenVDB's matrices act on row vectors (translation in the bottom row): ours, transposed.
        vdb_grid.transform = vdb.createLinearTransform(np.asarray(grid.index_to_world, dtype=np.float64).T.tolist())
        out.append(vdb_grid)
    path = Path(path)
    vdb.write(str(path), out)
    return path


@functools.cache
def openvdb_module():
    """The `openvdb` Python module: a standalone install, else the one bundled with Blender (via bpy)."""
    try:
        import openvdb
    except ImportError:
        pass
    else:
        return openvdb
    try:
        import bpy

        bpy.utils.expose_bundled_modules()
        import openvdb
    except (ImportError, AttributeError):
        raise SpectralError(
            "reading or writing .vdb files needs the openvdb Python module, and neither a standalone "
            "openvdb nor Blender's bundled one (through the bpy module) is available here: install the "
            "bpy module, run inside Blender, or use .npy grids"
        ) from None
    return openvdb


def _read_npy(path: Path, name: str) -> np.ndarray:
    where = f"grid {name!r} in {path}"
    shape, dtype = _npy_header(path, where)
    if not (np.issubdtype(dtype, np.floating) or np.issubdtype(dtype, np.integer)):
        raise SpectralError(f"{where} holds {dtype} values, not real numbers")
    count = int(np.prod(shape, dtype=object))
    # The array as stored, plus its float32 copy unless it is float32 already.
    needed = count * (dtype.itemsize + (0 if dtype == np.float32 else 4))
    _check_memory(needed, f"{where}: its {'×'.join(map(str, shape))} voxels")
    try:
        array = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError, MemoryError) as problem:
        raise SpectralError(f"{where} cannot be read as a NumPy array: {problem}") from None
    with np.errstate(over="ignore"):  # float64 beyond float32's range becomes inf, reported as such
        return np.ascontiguousarray(array, dtype=np.float32)


def _npy_header(path: Path, where: str) -> tuple[tuple[int, ...], np.dtype]:
    """(shape, dtype) from a .npy file's header, without reading its data; the file must hold them all."""
    try:
        with open(path, "rb") as file:
            version = np.lib.format.read_magic(file)
            reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, _fortran, dtype = reader(file)
            data_start = file.tell()
    except (OSError, ValueError, EOFError) as problem:
        reason = "an .npz archive, not a single .npy array" if path.read_bytes()[:2] == b"PK" else problem
        raise SpectralError(f"{where} cannot be read as a NumPy array: {reason}") from None
    if dtype.hasobject:
        raise SpectralError(f"{where} cannot be read: it holds Python objects, not real numbers")
    stored = int(np.prod(shape, dtype=object)) * dtype.itemsize
    size = path.stat().st_size - data_start
    if size < stored:
        raise SpectralError(f"{where} cannot be read: it is truncated (its header promises "
                            f"{'×'.join(map(str, shape))} values, {byte_size(stored)}; the file holds "
                            f"{byte_size(size)})")
    return shape, dtype


def _check_memory(needed: int, what: str) -> None:
    """SpectralError when `needed` bytes are more than the memory available now."""
    available = available_memory()
    if available is not None and needed > available:
        raise SpectralError(f"{what} need {byte_size(needed)} of memory, "
                            f"more than the {byte_size(available)} available")


def _read_vdb(path: Path, grid_name: str | None, index_to_world):
    vdb = openvdb_module()
    try:
        metadata = list(vdb.readAllGridMetadata(str(path)))
    except _VDB_READ_ERRORS as problem:
        raise SpectralError(f"grid file {path} cannot be read as OpenVDB: {problem}") from None
    if grid_name is None and len({grid.name for grid in metadata}) == 1:
        grid_name = metadata[0].name
    if grid_name is None:
        raise SpectralError(f"grid file {path} holds {_listing(metadata)}: name the grid to use")
    named = [grid for grid in metadata if grid.name == grid_name]
    if not named:
        raise SpectralError(f"grid file {path} has no grid {grid_name!r}; it holds {_listing(metadata)}")
    if len(named) > 1:
        raise SpectralError(f"grid file {path} holds {len(named)} grids named {grid_name!r}, so the name does not "
                            f"say which to read; it holds {_listing(metadata)}: give each grid its own name")
    where = f"grid {grid_name!r} in {path}"
    header = named[0]
    if type(header).__name__ not in _FLOAT_GRID_TYPES:
        raise SpectralError(f"{where} is a {type(header).__name__}, not a grid of floats")
    if header.gridClass == vdb.GridClass.LEVEL_SET:
        raise SpectralError(f"{where} is a level set (signed distances), not a density")
    if index_to_world is None:
        vdb_to_world = _vdb_transform(header.transform, where)
    else:
        vdb_to_world = affine_matrix(index_to_world, f"{where}: index_to_world")
    try:
        vdb_grid = vdb.read(str(path), grid_name)
    except _VDB_READ_ERRORS as problem:
        raise SpectralError(f"{where} cannot be read: {problem}") from None
    lo, hi = (np.array(corner, dtype=np.int64) for corner in vdb_grid.evalActiveVoxelBoundingBox())
    if vdb_grid.activeVoxelCount() == 0:
        raise SpectralError(f"{where} is empty (no active voxels)")
    values = _dense_buffer(hi - lo + 1, where)
    vdb_grid.copyToArray(values, tuple(int(c) for c in lo))  # needs a C-contiguous array
    shift = np.eye(4)
    shift[:3, 3] = lo
    return values, vdb_to_world @ shift, grid_name


def _vdb_transform(transform, where: str) -> np.ndarray:
    """The 4×4 index-to-world matrix (column-vector convention) of a linear OpenVDB transform."""
    if not transform.isLinear:
        raise SpectralError(f"{where} has a non-linear ({transform.typeName}) transform; only linear ones work")
    origin = np.array(transform.indexToWorld((0.0, 0.0, 0.0)))
    matrix = np.eye(4)
    for axis in range(3):
        unit = [0.0, 0.0, 0.0]
        unit[axis] = 1.0
        matrix[:3, axis] = np.array(transform.indexToWorld(tuple(unit))) - origin
    matrix[:3, 3] = origin
    return affine_matrix(matrix, f"{where}: transform")


def _dense_buffer(shape, where: str) -> np.ndarray:
    _check_memory(int(np.prod(shape, dtype=object)) * 4,
                  f"{where}: a dense copy of its {'×'.join(map(str, shape))} active voxel box would")
    return np.zeros(tuple(int(n) for n in shape), dtype=np.float32)


def _listing(grids: list) -> str:
    """A VDB's grids (their metadata) in words."""
    if not grids:
        return "no grids"
    return "grids " + ", ".join(f"{grid.name!r} ({type(grid).__name__})" for grid in grids)
